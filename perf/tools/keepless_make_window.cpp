// keepless_make_window: writes a deterministic synthetic window or map in the
// keepless_sparsify input format (see synthetic_window.hpp for the scene).
//
//   keepless_make_window [--workload small|orbslam|large|map] [--keyframes K]
//                        [--points P] [--obs-per-kf N] [--seed S] --out FILE
//
// Explicit counts override the preset. Prints one JSON line with the counts.

#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "cli/cli.hpp"
#include "keepless/core/window_file.hpp"
#include "keepless/platform/window_file_io.hpp"
#include "synthetic_window.hpp"

namespace {

constexpr const char* kTool = "keepless_make_window";

const std::vector<keepless::cli::Flag> kFlags = {
    {"--out", "FILE", "the window file to write (required)"},
    {"--workload", "small|orbslam|large|map", "the preset scene (default orbslam)"},
    {"--keyframes", "K", "keyframes (default: the preset's)"},
    {"--points", "P", "distinct points (default: the preset's)"},
    {"--obs-per-kf", "N", "observations per keyframe (default: the preset's)"},
    {"--seed", "S", "random seed (default 1)"},
};

int usage_error(const std::string& reason) { return keepless::cli::usage_error(kTool, reason); }

bool parse_count(const char* text, std::uint32_t* out) {
  std::uint64_t v = 0;
  if (!keepless::core::parse_uint64(text, &v) || v < 1 ||
      v > std::numeric_limits<std::uint32_t>::max()) {
    return false;
  }
  *out = static_cast<std::uint32_t>(v);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  keepless::perf::SyntheticSpec spec;
  std::string out;
  // Preset first, so explicit counts override it wherever they appear.
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--workload" &&
        !keepless::perf::workload_spec(argv[i + 1], &spec)) {
      return usage_error(keepless::perf::unknown_workload(argv[i + 1]));
    }
  }
  const std::string help =
      keepless::cli::usage("usage: keepless_make_window --out FILE [options]", kFlags,
                           "Explicit counts override the preset. Prints one JSON line with the counts.");
  for (int i = 1; i < argc; ++i) {
    const keepless::cli::Flag* entry = nullptr;
    const char* value = nullptr;
    int status = 0;
    if (!keepless::cli::next_flag(kTool, help, kFlags, argc, argv, &i, &entry, &value, &status)) return status;
    const std::string flag = entry->name;
    const std::string bad = "bad value for " + flag + ": '" + value + "'";
    if (flag == "--workload") {
      continue;  // applied above
    } else if (flag == "--keyframes") {
      if (!parse_count(value, &spec.keyframes)) return usage_error(bad);
    } else if (flag == "--points") {
      if (!parse_count(value, &spec.points)) return usage_error(bad);
    } else if (flag == "--obs-per-kf") {
      if (!parse_count(value, &spec.obs_per_kf)) return usage_error(bad);
    } else if (flag == "--seed") {
      if (!keepless::core::parse_uint64(value, &spec.seed)) return usage_error(bad);
    } else if (flag == "--out") {
      out = value;
    } else {
      return usage_error(keepless::cli::unknown_option(flag));
    }
  }
  if (out.empty()) return usage_error("--out is required");

  const keepless::core::WindowFile file = keepless::perf::make_synthetic_window(spec);
  std::string error;
  if (!keepless::platform::write_window_file(out, file, &error)) {
    std::fprintf(stderr, "keepless_make_window: %s\n", error.c_str());
    return 1;
  }
  std::uint64_t max_track = 0;
  {
    std::unordered_map<std::uint64_t, std::uint32_t> views;  // point -> keyframes seeing it
    for (const auto& list : file.observations) {
      for (const auto& o : list) {
        const std::uint32_t n = ++views[o.point];
        if (n > max_track) max_track = n;
      }
    }
  }
  const auto& n = file.needs;
  std::printf(
      "{\"keyframes\":%u,\"points\":%u,\"observations\":%u,\"obs_per_kf\":%.1f,"
      "\"pair_arcs\":%u,\"max_track\":%" PRIu64 ",\"seed\":%" PRIu64 "}\n",
      n.max_keyframes, n.max_points, n.max_observations,
      n.max_keyframes ? static_cast<double>(n.max_observations) / n.max_keyframes : 0.0,
      n.max_pair_arcs, max_track, spec.seed);
  return 0;
}
