#pragma once
// The offline text format of a window or map, one record a line:
//   kf  <kf_id> <cx> <cy> <cz> [<qw> <qx> <qy> <qz>]   camera centre (m), orientation
//   obs <kf_id> <point_id> <u> <v>                      keypoint (px) of a point
// Ids are unsigned 64-bit decimal; an obs names a kf declared on an earlier
// line; '#' starts a comment; blank lines are ignored. Offline tooling only
// (CLI, generator, tests): it allocates freely and is not on the decision path.

#include <cstdint>
#include <string>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/window.hpp"

namespace keepless::core {

// Hard limits checked while reading; crossing one is an error on the line
// that crossed it. Capacities are 32-bit, so are these.
struct WindowFileLimits {
  std::uint32_t max_keyframes = 10000;
  std::uint32_t max_points = 2000000;
  std::uint32_t max_observations = 10000000;
  std::uint32_t max_pair_arcs = 50000000;  // sum over points of n(n-1)/2
};

struct WindowFile {
  std::vector<Keyframe> keyframes;            // declaration order
  std::vector<std::uint64_t> keyframe_lines;  // line of each kf record (0 if built in code)
  std::vector<std::vector<Observation>> observations;  // per keyframe, file order
  // The exact needs of the file: keyframes, distinct points, observations and
  // pair arcs. Filled by the reader; recompute with compute_needs otherwise.
  Capacities needs{0, 0, 0, 0};
};

// Reads `path`. On failure returns false and sets *error to one line
// "PATH:LINE: reason" (LINE 0 when the file cannot be read); *out is then
// unspecified.
bool read_window_file(const std::string& path, WindowFile* out, std::string* error,
                      const WindowFileLimits& limits = {});

// Parses `text` as if read from a file named `name` (for errors).
bool parse_window_text(const std::string& name, std::string text, WindowFile* out,
                       std::string* error, const WindowFileLimits& limits = {});

// The needs of `file` (does not validate it; ids are trusted).
Capacities compute_needs(const WindowFile& file);

// Writes `file` in the format above: each kf line followed by its
// observations; doubles in shortest round-trip form, so reading the file
// back gives bit-identical values. Orientation omitted when it is exactly
// (1, 0, 0, 0). Writes to `path` directly; false + *error on I/O failure.
std::string format_window_file(const WindowFile& file);
bool write_window_file(const std::string& path, const WindowFile& file, std::string* error);

// Strict number parsing shared by the reader and the command-line tools.
// An unsigned decimal: digits only (no sign, no spaces), at most 2^64-1.
bool parse_uint64(const char* text, std::uint64_t* out);
// A finite double consumed entirely by strtod; no hex, nan, inf or overflow.
bool parse_finite_double(const char* text, double* out);
// "WxH", e.g. "64x48": two unsigned decimals that fit in int32.
bool parse_box(const char* text, int* width, int* height);

}  // namespace keepless::core
