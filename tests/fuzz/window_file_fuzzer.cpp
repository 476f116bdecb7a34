// libFuzzer: the window-file parser (core::WindowFileParser).
// Oracles beyond "no crash":
//   - chunking: the input fed in two chunks split at a fuzzed point gives
//     the same result (window or error line) as fed whole;
//   - on success, the window is self-consistent (needs == compute_needs) and
//     round-trips: format -> parse -> format gives the same text, bit for bit;
//   - on failure, one line "fuzz.txt:LINE: reason".

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <string>

#include "keepless/core/window_file.hpp"

namespace core = keepless::core;

namespace {

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "window_file_fuzzer: oracle failed: %s\n", what);
  std::abort();
}

core::WindowFileLimits limits() {
  core::WindowFileLimits l;
  l.max_keyframes = 64;
  l.max_points = 4096;
  l.max_observations = 16384;
  l.max_pair_arcs = 65536;
  l.max_line_bytes = 512;
  l.max_bytes = 4u << 20;
  l.solve_bytes = [](const core::Capacities& c) { return 100.0 * c.max_pair_arcs + 50.0 * c.max_observations; };
  return l;
}

bool same_needs(const core::Capacities& a, const core::Capacities& b) {
  return a.max_keyframes == b.max_keyframes && a.max_points == b.max_points &&
         a.max_observations == b.max_observations && a.max_pair_arcs == b.max_pair_arcs;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::size_t split = data[0] % size;  // where the second chunk begins
  const char* text = reinterpret_cast<const char*>(data + 1);
  const std::size_t n = size - 1;

  core::WindowFile whole;
  std::string error;
  const bool ok = core::parse_window_text("fuzz.txt", std::string(text, n), &whole, &error, limits());

  core::WindowFileParser parser("fuzz.txt", limits());
  core::WindowFile chunked;
  const std::size_t first = split < n ? split : n;
  const bool ok2 = parser.feed(text, first) && parser.feed(text + first, n - first) && parser.finish(&chunked);
  check(ok == ok2, "chunked and whole parses disagree");
  if (!ok) {
    check(parser.error() == error, "chunked and whole errors differ");
    check(error.rfind("fuzz.txt:", 0) == 0 && error.find('\n') == std::string::npos, "error is not one FILE:LINE line");
    return 0;
  }
  const std::string formatted = core::format_window_file(whole);
  check(formatted == core::format_window_file(chunked), "chunked and whole windows differ");
  check(same_needs(whole.needs, core::compute_needs(whole)), "needs differ from compute_needs");

  core::WindowFile again;
  check(core::parse_window_text("fuzz.txt", formatted, &again, &error, limits()), "formatted window does not parse");
  check(core::format_window_file(again) == formatted, "round trip is not bit-identical");
  check(same_needs(again.needs, whole.needs), "round trip changed the needs");
  return 0;
}
