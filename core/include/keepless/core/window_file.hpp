#pragma once
// The offline text format of a window or map, one record a line:
//   kf  <kf_id> <cx> <cy> <cz> [<qw> <qx> <qy> <qz>]   camera centre (m), orientation
//   obs <kf_id> <point_id> <u> <v>                      keypoint (px) of a point
// Ids are unsigned 64-bit decimal; an obs names a kf declared on an earlier
// line; '#' starts a comment; blank lines are ignored; a line holds at most
// WindowFileLimits::max_line_bytes. An orientation is a unit quaternion
// (within kQuaternionNormTolerance, as keepless_node checks it). Offline
// tooling only (CLI, generator, tests): it allocates and is not on the
// decision path. No file I/O here (core has none): WindowFileParser is fed
// lines or chunks; platform/window_file_io reads and writes files.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <unordered_map>
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
  std::uint32_t max_line_bytes = 4096;     // so a file without newlines costs no more
  // Memory: the parser's own bytes plus `solve_bytes(needs so far)` (what
  // the tool will allocate to decide the window, e.g. a Window and a
  // Sparsifier) may not exceed max_bytes; checked on every record, so the
  // line that crosses it is the error. 0 or an empty function: unchecked.
  std::uint64_t max_bytes = 0;
  std::function<double(const Capacities&)> solve_bytes;
};

// | |q|^2 - 1 | above this is not a unit quaternion (float-derived ones are
// off by ~1e-7). keepless_node applies the same bound.
constexpr double kQuaternionNormTolerance = 1e-3;

struct WindowFile {
  std::vector<Keyframe> keyframes;            // declaration order
  std::vector<std::uint64_t> keyframe_lines;  // line of each kf record (0 if built in code)
  std::vector<std::vector<Observation>> observations;  // per keyframe, file order
  // The exact needs of the file: keyframes, distinct points, observations and
  // pair arcs. Filled by the reader; recompute with compute_needs otherwise.
  Capacities needs{0, 0, 0, 0};
};

// A streaming reader of the format: memory grows with the records held, not
// with the input (a line is bounded by max_line_bytes). The first error
// sticks: every later call returns false and error() stays
// "NAME:LINE: reason".
class WindowFileParser {
 public:
  explicit WindowFileParser(std::string name, WindowFileLimits limits = {});

  // One line, without its '\n'.
  [[nodiscard]] bool feed_line(const char* data, std::size_t size);
  // Any chunk of the input; a line split across chunks is joined (bounded).
  [[nodiscard]] bool feed(const char* data, std::size_t size);
  // End of input (a last line without '\n' is parsed); moves the result out.
  [[nodiscard]] bool finish(WindowFile* out);
  // An error found outside the text (e.g. reading failed), on line `line`.
  void fail_at(std::uint64_t line, const std::string& reason);

  const std::string& error() const { return error_; }
  std::uint64_t line() const { return line_no_; }
  bool failed() const { return failed_; }
  // The parser's own bytes, estimated.
  double bytes() const;

 private:
  struct PointEntry {
    std::uint32_t index;  // order of first appearance
    std::uint32_t views;  // keyframes observing it so far
  };
  bool fail(const std::string& reason);
  bool parse_record(char* begin, char* end);
  bool keyframe_record(char** tokens, int values);
  bool observation_record(char** tokens);
  bool within_memory();
  // Why a line of which `before` bytes came earlier and `size` bytes are
  // here is refused, or null.
  const char* line_problem(const char* data, std::size_t size, std::size_t before);

  std::string name_;
  WindowFileLimits limits_;
  WindowFile file_;
  std::unordered_map<std::uint64_t, std::uint32_t> keyframe_index_;  // id -> declaration index
  std::unordered_map<std::uint64_t, PointEntry> points_;              // id -> entry
  std::unordered_map<std::uint64_t, std::uint64_t> observed_;         // (kf index, point index) -> line
  bool finished_ = false;  // finish() succeeded: later calls fail
  std::uint64_t observation_total_ = 0;
  std::uint64_t pair_arcs_ = 0;
  std::uint64_t line_no_ = 0;
  std::string partial_;  // a line split across feed() chunks
  std::string error_;
  std::string too_long_;
  bool failed_ = false;
};

// Parses `text` as if read from a file named `name` (for errors).
[[nodiscard]] bool parse_window_text(const std::string& name, const std::string& text, WindowFile* out,
                                     std::string* error, const WindowFileLimits& limits = {});

// The needs of `file` (does not validate it; ids are trusted), each saturated
// at UINT32_MAX.
Capacities compute_needs(const WindowFile& file);

// Why `file` (built in code) would not read back: one observation list per
// keyframe, unique keyframe ids, finite numbers, unit orientations, a point
// once per keyframe; "keyframe N: reason", or empty when it would.
std::string window_file_problem(const WindowFile& file);

// `file` in the format above: each kf line followed by its observations;
// doubles in shortest round-trip form, so reading the text back gives
// bit-identical values (-0 included). Orientation omitted when it is exactly
// (+1, +0, +0, +0). For a file with a window_file_problem() the text does
// not read back (a keyframe without an observation list gets none).
std::string format_window_file(const WindowFile& file);
// One keyframe's lines (for writers that stream a map keyframe by keyframe).
void append_window_keyframe(std::string* out, const Keyframe& keyframe, const std::vector<Observation>& observations);

// Strict number parsing shared by the reader and the command-line tools.
// An unsigned decimal: digits only (no sign, no spaces), at most 2^64-1.
[[nodiscard]] bool parse_uint64(const char* text, std::uint64_t* out);
// A finite double consumed entirely by strtod; no hex, nan, inf or overflow.
[[nodiscard]] bool parse_finite_double(const char* text, double* out);
// The same for a token cut from a file, which may hold any byte: a NUL inside
// it is malformed (read as a C string, "1<NUL>junk" would be 1).
[[nodiscard]] bool parse_uint64(const std::string& token, std::uint64_t* out);
[[nodiscard]] bool parse_finite_double(const std::string& token, double* out);
// "WxH", e.g. "64x48": two unsigned decimals that fit in int32.
[[nodiscard]] bool parse_box(const char* text, int* width, int* height);

}  // namespace keepless::core
