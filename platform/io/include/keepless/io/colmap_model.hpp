#pragma once
// COLMAP sparse models (cameras, images, points3D) in COLMAP's documented
// layouts, binary (.bin, little-endian) and text (.txt), as COLMAP 3.8 reads
// and writes them. Records keep their file order and values exactly, so a
// model read and written in the same format is byte-identical (for files
// COLMAP wrote; text numbers are written as COLMAP does, "%.17g").
// Offline tooling: allocates freely, not on the decision path.

#include <cstdint>
#include <string>
#include <vector>

namespace keepless::io {

// COLMAP's "no 3D point" (kInvalidPoint3DId); "-1" in images.txt.
constexpr std::uint64_t kNoPoint3D = ~std::uint64_t{0};

// A camera model's COLMAP id and name, its parameter count, and its focal
// lengths: 1 (params f, cx, cy, ...) or 2 (fx, fy, cx, cy, ...). Lookups
// return nullptr for an unknown model.
struct CameraModelInfo {
  int id;
  const char* name;
  int num_params;
  int focal_lengths;
};
const CameraModelInfo* camera_model_by_id(int id);
const CameraModelInfo* camera_model_by_name(const std::string& name);

struct ColmapCamera {
  std::uint32_t id = 0;
  int model_id = 0;
  std::uint64_t width = 0;
  std::uint64_t height = 0;
  std::vector<double> params;  // exactly the model's count
};

struct ColmapPoint2D {
  double x = 0;
  double y = 0;
  std::uint64_t point3D_id = kNoPoint3D;
};

struct ColmapImage {
  std::uint32_t id = 0;
  double qvec[4] = {1, 0, 0, 0};  // world-to-camera rotation (w, x, y, z)
  double tvec[3] = {0, 0, 0};     // world-to-camera translation
  std::uint32_t camera_id = 0;
  std::string name;
  std::vector<ColmapPoint2D> points2D;
};

struct ColmapTrackElement {
  std::uint32_t image_id = 0;
  std::uint32_t point2D_idx = 0;
};

struct ColmapPoint3D {
  std::uint64_t id = 0;
  double xyz[3] = {0, 0, 0};
  std::uint8_t rgb[3] = {0, 0, 0};
  double error = 0;
  std::vector<ColmapTrackElement> track;
};

struct ColmapModel {
  std::vector<ColmapCamera> cameras;  // file order
  std::vector<ColmapImage> images;
  std::vector<ColmapPoint3D> points;
};

enum class ColmapFormat { kBinary, kText };
const char* extension(ColmapFormat format);  // "bin" / "txt"

// The three files' contents, in one format.
struct ColmapFiles {
  std::string cameras;
  std::string images;
  std::string points3D;
};

// Parses and cross-checks the three files (`dir` names them in errors as
// DIR/cameras.bin etc.). On failure returns false and sets *error to one line
// "FILE:OFFSET: reason" (binary, byte offset of the bad field) or
// "FILE:LINE: reason" (text, 1-based). Checks: layout and counts against the
// bytes present (a huge count cannot allocate), known camera models and
// their parameter counts, finite numbers, unique ids, every image's camera,
// and that images and tracks reference each other exactly (each 2D point
// naming a 3D point appears once in that point's track, and back).
[[nodiscard]] bool parse_colmap(const std::string& dir, const ColmapFiles& files, ColmapFormat format,
                  ColmapModel* out, std::string* error);

// The model in COLMAP's layout; the text header comments carry the counts
// and means COLMAP writes.
ColmapFiles format_colmap(const ColmapModel& model, ColmapFormat format);

// Reads DIR/{cameras,images,points3D}.bin, or the .txt files when the .bin
// ones are absent (COLMAP's own preference). A DIR holding none of the six
// files is "DIR: no COLMAP model (...)"; one with some is read in that
// format and the missing file named.
[[nodiscard]] bool read_colmap_model(const std::string& dir, ColmapModel* out, ColmapFormat* format,
                       std::string* error);

// Writes the three files into a temporary directory beside DIR (when absent),
// then renames it to DIR, or inside DIR (when it exists, so that a mount point
// works), then renames the files into DIR: a failure leaves no partial file in
// DIR (the three renames into an existing DIR are one at a time, on one file
// system). A trailing '/' names the same DIR.
// Refused when DIR is a file, holds a file of the other format (it would
// shadow ours) or something other than a file by one of ours (it could not
// be replaced after the others were), and in text when an image name holds
// a blank (COLMAP's text reader would cut it there).
// write_colmap_model's refusals, checked before it writes anything (a caller
// writing other outputs first checks them before those, too).
[[nodiscard]] bool colmap_model_writable(const std::string& dir, const ColmapModel& model, ColmapFormat format,
                           std::string* error);
[[nodiscard]] bool write_colmap_model(const std::string& dir, const ColmapModel& model, ColmapFormat format,
                        std::string* error);

// Removes the points whose `culled[i]` is set (i indexes model->points) and
// sets every 2D point that referenced one to kNoPoint3D; all else unchanged.
void remove_points(ColmapModel* model, const std::vector<bool>& culled);

// Drops every 2D point that names no 3D point and renumbers the tracks'
// POINT2D_IDX to match; returns how many were dropped. The dropped
// keypoints' positions are lost, and 2D point indices no longer match the
// feature database the model was built from.
std::uint64_t compact_points2D(ColmapModel* model);

// Observations (2D points with a 3D point) per image, in model->images order.
std::vector<std::uint32_t> observations_per_image(const ColmapModel& model);

}  // namespace keepless::io
