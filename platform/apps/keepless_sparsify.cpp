// keepless_sparsify: decides one window (or a whole map) offline.
//
//   keepless_sparsify --window FILE [--M 100] [--theta 0.5] [--box 64x48] [--decisions OUT]
//                     [--scope window|newest] [--floor L] [--cost paper|authors|information]
//                     [--image 640x480] [--max-keyframes N] [--max-points N]
//                     [--max-observations N] [--max-pair-arcs N] [--max-memory-mb N]
//   keepless_sparsify --colmap DIR | --bal FILE [--mode replay|whole] [--K 20] [--order name|id|file]
//                     [--out DIR|FILE] [--out-format bin|txt] [--scale S | --sim3 FILE]
//                     [--min-obs-per-image F] (and the flags above; also with --window)
// The map path (sparsify/model_run.hpp) runs when a map flag is given;
// --window alone is the single-window path below, unchanged.
//
// The file is parsed as a stream (memory follows the records, not the file)
// and checked against the hard limits and, record by record, against the
// memory the decision will need (--max-memory-mb), then a Window and
// Sparsifier sized exactly to its needs decide it in one run. Only regular
// files are read (a FIFO or a device is refused, never waited on).
// Users' scripts read the output, so its shape is a contract:
//   --decisions OUT: "<point_id> <keep|cull|skip> <flow> <capacity>" a line, by
//   point id, written to OUT.tmp and renamed (never a partial OUT);
//   stdout: the last line is one JSON object (the summary; parse_ms reads and
//   checks the file, build_ms sizes the Window and Sparsifier and ingests the
//   keyframes, solve_ms is Sparsifier::run: network build, solve, decisions);
//   bad input or flags: exit 2, one stderr line ("FILE:LINE: reason", or a
//   usage line for flags); internal failure: exit 1.

#include <cerrno>
#include <charconv>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"
#include "keepless/core/window_file.hpp"
#include "keepless/platform/memory_estimate.hpp"
#include "keepless/platform/monotonic_clock.hpp"
#include "sparsify/model_run.hpp"
#include "keepless/platform/window_file_io.hpp"

namespace {

namespace core = keepless::core;

constexpr int kExitInput = 2;
constexpr int kExitInternal = 1;

constexpr const char* kUsage =
    "usage: keepless_sparsify --window FILE [--M 100] [--theta 0.5] [--box 64x48] "
    "[--decisions OUT] [--scope window|newest] [--floor 0] [--cost paper|authors|information] "
    "[--image 640x480] [--max-keyframes 10000] [--max-points 2000000] "
    "[--max-observations 10000000] [--max-pair-arcs 50000000] [--max-memory-mb 2048]; or --colmap DIR | --bal FILE "
    "(or --window FILE) [--mode replay|whole] [--K 20] [--order name|id|file] [--out DIR|FILE] "
    "[--out-format bin|txt] [--scale S | --sim3 FILE] [--min-obs-per-image 30]";

struct Options {
  std::string window;
  std::string decisions;  // empty: no decisions file
  core::Params params;
  core::WindowFileLimits limits;
  keepless::sparsify::ModelOptions model;  // the map flags (sparsify/model_run.hpp)
  std::uint64_t max_memory_mb = 2048;
};

int usage_error(const std::string& reason) {
  std::fprintf(stderr, "keepless_sparsify: %s; %s\n", reason.c_str(), kUsage);
  return kExitInput;
}

bool parse_limit(const char* text, std::uint32_t* out) {
  std::uint64_t v = 0;
  if (!core::parse_uint64(text, &v) || v < 1 || v > std::numeric_limits<std::uint32_t>::max()) {
    return false;
  }
  *out = static_cast<std::uint32_t>(v);
  return true;
}

// Returns -1 on success, else the exit status (after printing).
int parse_args(int argc, char** argv, Options* opt, bool* help) {
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      *help = true;
      return -1;
    }
    if (i + 1 >= argc) return usage_error("missing value for " + flag);
    const char* value = argv[++i];
    const std::string bad = "bad value for " + flag + ": '" + value + "'";
    std::string map_error;
    if (flag == "--window") {
      if (*value == '\0') return usage_error(bad);
      opt->window = value;
    } else if (keepless::sparsify::parse_map_flag(flag, value, &opt->model, &map_error)) {
      if (!map_error.empty()) return usage_error(map_error);
    } else if (flag == "--decisions") {
      if (*value == '\0') return usage_error(bad);
      opt->decisions = value;
    } else if (flag == "--M") {
      std::uint64_t m = 0;
      // The solver's capacities are int32.
      if (!core::parse_uint64(value, &m) || m < 1 ||
          m > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max())) {
        return usage_error(bad + " (an integer in 1..2147483647)");
      }
      opt->params.pair_capacity = static_cast<std::int64_t>(m);
    } else if (flag == "--theta") {
      double theta = 0;
      if (!core::parse_finite_double(value, &theta) || !(theta >= 0.0 && theta <= 1.0)) {
        return usage_error(bad + " (a number in [0, 1])");
      }
      opt->params.theta = theta;
    } else if (flag == "--box") {
      int w = 0, h = 0;
      if (!core::parse_box(value, &w, &h)) return usage_error(bad + " (WxH, e.g. 64x48)");
      opt->params.box_width = w;
      opt->params.box_height = h;
    } else if (flag == "--scope") {
      if (!core::parse_scope(value, &opt->params.scope)) return usage_error(bad + " (window or newest)");
    } else if (flag == "--floor") {
      std::uint64_t floor = 0;
      if (!core::parse_uint64(value, &floor) || floor > std::numeric_limits<std::uint32_t>::max()) {
        return usage_error(bad + " (an integer >= 0)");
      }
      opt->params.coverage_floor = static_cast<std::uint32_t>(floor);
    } else if (flag == "--cost") {
      if (!core::parse_cost_model(value, &opt->params.cost_model)) {
        return usage_error(bad + " (paper, authors or information)");
      }
    } else if (flag == "--image") {
      int w = 0, h = 0;
      if (!core::parse_box(value, &w, &h) || w < 1 || h < 1) {
        return usage_error(bad + " (WxH pixels, e.g. 640x480)");
      }
      opt->params.image_width = w;
      opt->params.image_height = h;
      opt->model.image_given = true;
    } else if (flag == "--max-keyframes") {
      if (!parse_limit(value, &opt->limits.max_keyframes)) return usage_error(bad);
    } else if (flag == "--max-points") {
      if (!parse_limit(value, &opt->limits.max_points)) return usage_error(bad);
    } else if (flag == "--max-observations") {
      if (!parse_limit(value, &opt->limits.max_observations)) return usage_error(bad);
    } else if (flag == "--max-pair-arcs") {
      if (!parse_limit(value, &opt->limits.max_pair_arcs)) return usage_error(bad);
    } else if (flag == "--max-memory-mb") {
      if (!core::parse_uint64(value, &opt->max_memory_mb) || opt->max_memory_mb < 1 ||
          opt->max_memory_mb > (1ull << 30)) {
        return usage_error(bad);
      }
    } else {
      return usage_error("unknown flag '" + flag + "'");
    }
  }
  if (opt->window.empty() == opt->model.path.empty()) {
    return usage_error("one of --window, --colmap, --bal is required");
  }
  if (opt->model.path.empty()) {
    opt->model.input = keepless::sparsify::Input::kWindow;
    opt->model.path = opt->window;
  }
  if (core::Sparsifier::validate(opt->params) != core::Status::kOk) {
    return usage_error("invalid parameters");
  }
  return -1;
}

double ms_since(std::uint64_t start_ns) {
  return static_cast<double>(keepless::platform::monotonic_ns() - start_ns) / 1e6;
}

// Writes OUT.tmp, then renames it over OUT; on any failure removes the tmp.
bool write_decisions(const std::string& path, const core::Sparsifier& sparsifier,
                     std::string* error) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) {
    *error = path + ":0: cannot write decisions: " + std::strerror(errno);
    return false;
  }
  const core::PointDecision* d = sparsifier.decisions();
  bool ok = true;
  for (std::uint32_t i = 0; ok && i < sparsifier.decision_count(); ++i) {
    ok = std::fprintf(f, "%" PRIu64 " %s %" PRId64 " %" PRId64 "\n", d[i].point,
                      core::to_string(d[i].verdict), d[i].flow, d[i].capacity) > 0;
  }
  int err = errno;
  if (std::fclose(f) != 0 && ok) {
    ok = false;
    err = errno;
  }
  if (ok && std::rename(tmp.c_str(), path.c_str()) != 0) {
    ok = false;
    err = errno;
  }
  if (!ok) {
    std::remove(tmp.c_str());
    *error = path + ":0: cannot write decisions: " + std::strerror(err != 0 ? err : EIO);
  }
  return ok;
}

int run(const Options& opt) {
  const std::uint64_t t_parse = keepless::platform::monotonic_ns();
  core::WindowFile file;
  std::string error;
  core::WindowFileLimits limits = opt.limits;
  limits.max_bytes = opt.max_memory_mb << 20;
  const keepless::platform::MemoryModel model =
      keepless::platform::probe_memory_model(opt.params, core::SolveMode::kFromScratch, 1);
  limits.solve_bytes = [&model](const core::Capacities& c) { return model.bytes(c); };
  if (!keepless::platform::read_window_file(opt.window, &file, &error, limits)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return kExitInput;
  }
  const double parse_ms = ms_since(t_parse);

  // Sized to the file's exact needs (at least 1 each, an empty file is valid).
  core::Capacities caps = file.needs;
  if (caps.max_keyframes == 0) caps.max_keyframes = 1;
  if (caps.max_points == 0) caps.max_points = 1;
  if (caps.max_observations == 0) caps.max_observations = 1;
  if (caps.max_pair_arcs == 0) caps.max_pair_arcs = 1;

  const std::uint64_t t_build = keepless::platform::monotonic_ns();
  core::Window window(caps);
  core::Sparsifier sparsifier(caps, opt.params);
  for (std::size_t k = 0; k < file.keyframes.size(); ++k) {
    const auto& obs = file.observations[k];
    const core::Status s =
        window.add_keyframe(file.keyframes[k], obs.data(), static_cast<std::uint32_t>(obs.size()));
    if (s != core::Status::kOk) {
      std::fprintf(stderr, "%s:%" PRIu64 ": keyframe rejected: %s\n", opt.window.c_str(),
                   file.keyframe_lines[k], core::to_string(s));
      return kExitInput;
    }
  }
  const double build_ms = ms_since(t_build);

  const std::uint64_t t_solve = keepless::platform::monotonic_ns();
  const core::Status s = sparsifier.run(window);
  const double solve_ms = ms_since(t_solve);
  if (s != core::Status::kOk) {
    std::fprintf(stderr, "keepless_sparsify: solve failed: %s\n", core::to_string(s));
    return kExitInternal;
  }

  if (!opt.decisions.empty() && !write_decisions(opt.decisions, sparsifier, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return kExitInput;
  }

  const core::Summary& sum = sparsifier.summary();
  const std::size_t memory = window.memory_bytes() + sparsifier.memory_bytes();
  char theta[32];
  *std::to_chars(theta, theta + sizeof theta - 1, opt.params.theta).ptr = '\0';  // shortest exact
  std::printf(
      "{\"keyframes\":%u,\"points\":%u,\"evaluated\":%u,\"kept\":%u,\"culled\":%u,"
      "\"skipped\":%u,\"pairs\":%u,\"arcs\":%u,\"max_flow\":%" PRId64 ",\"total_cost\":%" PRId64
      ",\"M\":%" PRId64
      ",\"theta\":%s,\"box_width\":%d,\"box_height\":%d,"
      "\"parse_ms\":%.3f,\"build_ms\":%.3f,\"solve_ms\":%.3f,\"memory_bytes\":%zu,"
      "\"scope\":\"%s\",\"floor\":%u,\"cost\":\"%s\",\"out_of_scope\":%u,"
      "\"floor_keyframes\":%u,\"floor_promoted\":%u,\"floor_short\":%u}\n",
      sum.keyframes, sum.points, sum.evaluated, sum.kept, sum.culled, sum.skipped, sum.pairs,
      sum.arcs, sum.max_flow, sum.total_cost, opt.params.pair_capacity, theta, opt.params.box_width,
      opt.params.box_height, parse_ms, build_ms, solve_ms, memory, core::to_string(opt.params.scope),
      opt.params.coverage_floor, core::to_string(opt.params.cost_model), sum.out_of_scope,
      sum.floor_keyframes, sum.floor_promoted, sum.floor_short);
  return std::fflush(stdout) == 0 ? 0 : kExitInternal;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  bool help = false;
  const int status = parse_args(argc, argv, &opt, &help);
  if (status >= 0) return status;
  if (help) {
    std::printf("%s\n", kUsage);
    return 0;
  }
  try {
    if (opt.model.map_flags) {
      opt.model.params = opt.params;
      opt.model.limits = opt.limits;
      opt.model.decisions = opt.decisions;
      return keepless::sparsify::run_model(opt.model);
    }
    return run(opt);
  } catch (const std::bad_alloc&) {  // below --max-memory-mb, but the machine has less
    std::fprintf(stderr, "%s:0: cannot allocate the memory this window needs (lower --max-memory-mb)\n",
                 opt.window.c_str());
    return kExitInput;
  } catch (const std::length_error&) {  // the same on 32-bit: an array larger than the address space
    std::fprintf(stderr, "%s:0: cannot allocate the memory this window needs (lower --max-memory-mb)\n",
                 opt.window.c_str());
    return kExitInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "keepless_sparsify: %s\n", e.what());
    return kExitInternal;
  }
}
