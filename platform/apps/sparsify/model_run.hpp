#pragma once
// keepless_sparsify on a map: a COLMAP model, a BAL problem or a window
// file in; its decisions (replay or whole, see modes.hpp) and the floor;
// the sparsified map out in the input's format.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/window_file.hpp"
#include "keepless/io/keyframes.hpp"
#include "modes.hpp"

namespace keepless::sparsify {

enum class Input { kColmap, kBal, kWindow };

struct ModelOptions {
  Input input = Input::kColmap;
  std::string path;       // --colmap DIR / --bal FILE / --window FILE
  std::string out;        // --out DIR|FILE; empty: none
  std::string out_format;  // --out-format bin|txt (COLMAP); empty: the input's
  std::string decisions;  // --decisions OUT; empty: none
  Mode mode = Mode::kReplay;
  bool mode_given = false;  // default: replay for COLMAP/BAL, whole for a window file
  std::uint32_t K = 20;
  bool K_given = false;      // --K: replay only
  io::KeyframeOrder order = io::KeyframeOrder::kName;
  bool order_given = false;  // default: name for COLMAP, file order otherwise
  std::string sim3;          // --sim3 FILE
  double scale = 1;          // --scale S
  bool scale_given = false;  // --scale and --sim3 exclude each other
  std::int64_t floor = -1;   // --min-obs-per-image; -1: 30 for COLMAP/BAL, 0 for a window file
  // --floor-over-longest R (whole mode with a count): the floor is at least
  // ceil(R x longest_tracks_poorest); 0: off, -1: not given (--use offline: 1.1).
  double floor_over_longest = -1;
  core::Params params;
  // --image was given; else a COLMAP model's one camera size (all cameras
  // alike) sets params' image_width x image_height.
  bool image_given = false;
  core::WindowFileLimits limits;
  std::uint64_t max_memory_mb = 2048;  // --max-memory-mb: reading and deciding, estimated first
  bool compact = false;  // --compact (COLMAP): drop the 2D points no kept 3D point references
  bool map_flags = false;  // a flag above was given (parse_map_flag)
};

// Parses one of keepless_sparsify's map flags (--colmap, --bal, --out,
// --out-format, --mode, --K, --order, --scale, --sim3, --min-obs-per-image,
// --floor-over-longest)
// into *options. False if `flag` is none of them; else true, with *error
// empty or the reason its value is bad.
bool parse_map_flag(const std::string& flag, const char* value, ModelOptions* options, std::string* error);

// The mode a run takes: --mode, else whole for a window file, replay otherwise.
Mode mode_of(const ModelOptions& options);

// The default per-image floor for COLMAP and BAL inputs, and the floor
// below which a warning names the images left under it: COLMAP's
// Mapper.abs_pose_min_num_inliers.
constexpr std::uint32_t kDefaultFloor = 30;

// The offline use's --floor-over-longest: every image 10 % above where the
// longest tracks leave the poorest. With the whole count by track length,
// 0.96-1.08x point_filtering's camera deviation at its count on three
// models (perf/eval/results/maps/equal_count).
constexpr double kOfflineFloorOverLongest = 1.1;

// The smallest M at which a sparsified COLMAP model kept the full model's
// accuracy after colmap bundle_adjuster in the evidence (keepless_maps_bench
// on the KITTI 06 fixture: M = 200); below it keepless_sparsify warns.
constexpr std::int64_t kEvidenceM = 200;

// What reading a model holds at most (the files, the parsed model and its
// keyframes), checked against --max-memory-mb before reading: bytes per
// byte of its files and, for text, per whitespace-separated token and per
// line, counted first (a text model of short tokens or short lines holds
// more per byte: BAL keeps each value with its text, a COLMAP image line
// is a record). Measured peaks of the whole run (RSS, with the program's own
// ~7 MB) and what these give: COLMAP binary, the fixture 6.5x its bytes
// (reading and deciding alone 3.3x); COLMAP text, the fixture 51 MB (46),
// 300,000 images on short lines 164 MB (173), 3,000 images and 300,000
// points 296 MB (417); BAL, the zenslam problem 25 MB (24), 240,000 short
// tokens 28 MB (28) and 24-digit ones 47 MB (46), 4.5 M one-digit values
// 297 MB at a refusal after parsing (459).
struct ReadCost {
  double per_byte;
  double per_token;
  double per_line;
};
constexpr ReadCost kColmapBinaryRead{6.0, 0.0, 0.0};
constexpr ReadCost kColmapTextRead{2.5, 10.0, 200.0};
constexpr ReadCost kBalRead{6.0, 90.0, 0.0};

// --decisions' contents: "<point_id> <keep|cull|skip> <flow> <capacity>" a line.
std::string format_decisions(const core::PointDecision* decisions, std::size_t n);

// A path a run reads or writes, and the flag that named it.
struct NamedPath {
  std::string flag;
  std::string path;
};

// False with *error naming both when an output is one of the inputs (the
// same path once resolved, or a hard link to it) or two outputs are one
// file: checked before anything is read, so nothing is overwritten.
bool outputs_are_safe(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs, std::string* error);

// Runs it all; prints a line per mode and the JSON summary (last line) on
// stdout. Returns the exit status: 0, 2 (bad input or flags; one stderr line
// "FILE:OFFSET-or-LINE: reason"; nothing written), 1 (internal failure).
int run_model(const ModelOptions& options);

}  // namespace keepless::sparsify
