#pragma once
// Internals shared by the binary and text COLMAP parsers and the model
// checks: where each record was read, for errors on cross-references.

#include <cstdint>
#include <string>
#include <vector>

#include "keepless/io/colmap_model.hpp"

namespace keepless::io::detail {

// Binary: byte offsets; text: 1-based lines.
struct Positions {
  bool binary = true;
  std::vector<std::uint64_t> camera;        // record start
  std::vector<std::uint64_t> image;         // record start
  std::vector<std::uint64_t> image_points;  // first 2D point (binary) / POINTS2D line (text)
  std::vector<std::uint64_t> point;         // record start
  std::vector<std::uint64_t> point_track;   // first track element (binary) / the line (text)
};

struct FileNames {
  std::string cameras, images, points3D;
};
FileNames file_names(const std::string& dir, ColmapFormat format);

// Each parses one file into *out (appending records and positions); false
// with *error "FILE:POS: reason".
bool parse_cameras_binary(const std::string& name, const std::string& bytes, ColmapModel* out,
                          Positions* pos, std::string* error);
bool parse_images_binary(const std::string& name, const std::string& bytes, ColmapModel* out,
                         Positions* pos, std::string* error);
bool parse_points_binary(const std::string& name, const std::string& bytes, ColmapModel* out,
                         Positions* pos, std::string* error);
bool parse_cameras_text(const std::string& name, const std::string& text, ColmapModel* out,
                        Positions* pos, std::string* error);
bool parse_images_text(const std::string& name, const std::string& text, ColmapModel* out,
                       Positions* pos, std::string* error);
bool parse_points_text(const std::string& name, const std::string& text, ColmapModel* out,
                       Positions* pos, std::string* error);

std::string format_binary_cameras(const ColmapModel& m);
std::string format_binary_images(const ColmapModel& m);
std::string format_binary_points(const ColmapModel& m);
std::string format_text_cameras(const ColmapModel& m);
std::string format_text_images(const ColmapModel& m);
std::string format_text_points(const ColmapModel& m);

// A camera's width or height: COLMAP keeps them as int in places, and 0 is no image.
constexpr std::uint64_t kMaxCameraSide = 2147483647;
inline bool camera_size_ok(std::uint64_t side) { return side >= 1 && side <= kMaxCameraSide; }

// Observations (2D points with a 3D point) over all images.
std::uint64_t count_observations(const ColmapModel& m);

}  // namespace keepless::io::detail
