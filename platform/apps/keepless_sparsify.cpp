// keepless_sparsify: decides one window (or a whole map) offline. Its flags
// are the table kFlags below (--help prints it).
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
//   point id, written to a temporary name and renamed (never a partial OUT;
//   an OUT that is the input is refused before anything is read);
//   stdout: the last line is one JSON object (the summary; parse_ms reads and
//   checks the file, build_ms sizes the Window and Sparsifier and ingests the
//   keyframes, solve_ms is Sparsifier::run: network build, solve, decisions);
//   bad input or flags: exit 2, one stderr line ("FILE:LINE: reason", or
//   the flag's problem and a pointer to --help); internal failure: exit 1.

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
#include <vector>

#include "cli/cli.hpp"
#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/use.hpp"
#include "keepless/core/window.hpp"
#include "keepless/core/window_file.hpp"
#include "keepless/io/atomic_file.hpp"
#include "keepless/platform/memory_estimate.hpp"
#include "keepless/platform/monotonic_clock.hpp"
#include "sparsify/model_run.hpp"
#include "sparsify/modes.hpp"
#include "keepless/platform/window_file_io.hpp"

namespace {

namespace core = keepless::core;

constexpr int kExitInput = 2;
constexpr int kExitInternal = 1;

constexpr const char* kTool = "keepless_sparsify";

const std::vector<keepless::cli::Flag> kFlags = {
    {"--window", "FILE", "a window file: decide it as one window (see the window file format)"},
    {"--colmap", "DIR", "a COLMAP model (cameras, images, points3D as .bin or .txt): sparsify it"},
    {"--bal", "FILE", "a BAL problem: sparsify it"},
    {"--out", "DIR|FILE", "write the sparsified map there, in the input's format (never the input's\n"
                          "own folder or file)"},
    {"--out-format", "bin|txt", "COLMAP output format (default: the input's)"},
    {"--compact", nullptr, "COLMAP: also drop the 2D points no kept 3D point references; lost:\n"
                           "those unmatched keypoints' positions, and 2D point indices no longer\n"
                           "match the feature database (default: keep every 2D point)"},
    {"--use", "NAME", "settings per use from the budget sweep, applied before the other flags\n"
                      "(they refine it): paper (the default), monocular (--scope newest\n"
                      "--maturity 2, and --track-share 0.5 where the budget keeps >= 0.3 of\n"
                      "the points), rgbd (--scope newest --maturity 2), monocular-deferred\n"
                      "(--scope auto here, and --track-share 0.5 where the budget keeps\n"
                      "<= 0.15 of the points), offline (--mode whole --track-share 1\n"
                      "--floor-over-longest 1.1; needs --keep-points or --keep-fraction)"},
    {"--mode", "replay|whole", "replay: the onboard node's sliding window; whole: one window\n"
                               "(default: replay for maps, whole for --window)"},
    {"--K", "N", "replay window in keyframes (default 20)"},
    {"--order", "name|id|file", "replay order of the keyframes (default: name for COLMAP, else file)"},
    {"--scale", "S", "multiply camera centres by S to get metres (default 1)"},
    {"--sim3", "FILE", "a similarity to metres: s, R row-major, t (13 numbers)"},
    {"--min-obs-per-image", "F", "give culled points back until every image has F observations\n"
                                 "(default 30 for COLMAP and BAL, 0 for a window file); in whole mode\n"
                                 "with --keep-points or --keep-fraction from within the count: the\n"
                                 "order's last points make way"},
    {"--floor-over-longest", "R", "whole mode with --keep-points or --keep-fraction: raise that floor\n"
                                  "to R x the observations of the image the count's longest tracks\n"
                                  "(COLMAP's point_filtering at that count) leave poorest, rounded up;\n"
                                  "0 or R in [1, 100] (default 0; --use offline on a COLMAP or BAL\n"
                                  "model without --min-obs-per-image: 1.1)"},
    {"--decisions", "OUT", "write '<point_id> <keep|cull|skip> <flow> <capacity>' a line"},
    {"--M", "N", "pair -> sink capacity, 1..2147483647 (default 100)"},
    {"--keep-points", "K", "instead of --M: keep exactly K of the evaluated points (or all)"},
    {"--keep-fraction", "F", "instead of --M: keep the share F in [0, 1] of the points evaluated over the\n"
                             "windows (F of those new to each window, plus those kept before)"},
    {"--keep-observations", "B", "instead of --M: keep points while their observations sum to <= B"},
    {"--track-share", "S", "with --keep-points or --keep-fraction: take the share S in [0, 1] of the\n"
                           "count by track length (replay: most keyframes of the window first;\n"
                           "whole: most observations, COLMAP's track length) instead of the\n"
                           "network's order (default 0), at every budget"},
    {"--theta", "X", "keep iff flow > X * n(n-1)/2, in [0, 1] (default 0.5)"},
    {"--box", "WxH", "spatial-diversity box in pixels (default 64x48)"},
    {"--scope", "S", "window: decide every point; newest: only the newest keyframe's; auto: the\nnewest keyframe's while a third of the window's points come back (default window)"},
    {"--floor", "L", "every keyframe keeps >= L of its evaluated points (default 0: off)"},
    {"--cost", "paper|authors|information|track", "point -> pair costs (default paper)"},
    {"--track-terms", "LIST", "what --cost track sums: length,age,error,angle (default all; COLMAP\n"
                              "gives length and error, BAL length)"},
    {"--cost-terms", "LIST", "the costs summed: c_c,c_s,c_b (default all three, the paper's; without\n"
                             "c_c a pair prefers spatial diversity over its points' views)"},
    {"--maturity", "A", "tracking-safe culling: points first seen in the newest A keyframes of a\n"
                        "window are not decided yet (default 0: off)"},
    {"--image", "WxH", "the image the authors' grid covers (default 640x480; COLMAP: its cameras')"},
    {"--max-keyframes", "N", "refuse an input with more keyframes (default 10000)"},
    {"--max-points", "N", "refuse an input with more points (default 2000000)"},
    {"--max-observations", "N", "refuse an input with more observations (default 10000000)"},
    {"--max-pair-arcs", "N", "refuse a window with more pair arcs (default 50000000)"},
    {"--max-memory-mb", "N", "refuse an input whose decision would need more than N MiB (2^20 bytes; default 2048)"},
};

std::string usage() {
  return keepless::cli::usage(
      "usage: keepless_sparsify --window FILE [options]\n"
      "       keepless_sparsify --colmap DIR | --bal FILE [--out DIR|FILE] [options]",
      kFlags,
      "Exit 0 on success, 2 on bad input or flags (one stderr line: FILE:LINE-or-OFFSET: reason),\n"
      "1 on an internal failure. The last stdout line is a JSON summary.");
}

struct Options {
  std::string window;
  std::string decisions;  // empty: no decisions file
  core::Params params;
  core::WindowFileLimits limits;
  keepless::sparsify::ModelOptions model;  // the map flags (sparsify/model_run.hpp)
  std::uint64_t max_memory_mb = 2048;
};

int usage_error(const std::string& reason) { return keepless::cli::usage_error(kTool, reason); }

bool parse_limit(const char* text, std::uint32_t* out) {
  std::uint64_t v = 0;
  if (!core::parse_uint64(text, &v) || v < 1 || v > std::numeric_limits<std::uint32_t>::max()) {
    return false;
  }
  *out = static_cast<std::uint32_t>(v);
  return true;
}

// Returns -1 on success, else the exit status (after printing).
int parse_args(int argc, char** argv, Options* opt, bool* help, bool* version) {
  // --use first, wherever it stands, so the other flags refine it.
  core::Use use = core::Use::kPaper;
  if (const char* name = keepless::cli::last_value(argc, argv, "--use")) {
    if (!core::parse_use(name, &use)) {
      return usage_error(std::string("bad value for --use: '") + name + "' (" + core::kUseNames + ")");
    }
    core::apply_use(use, &opt->params);
  }
  bool m_given = false;  // --M and a keep budget exclude each other
  for (int i = 1; i < argc; ++i) {
    const keepless::cli::Flag* entry = nullptr;
    const char* value = nullptr;
    std::string error;
    switch (keepless::cli::next(kFlags, argc, argv, &i, &entry, &value, &error)) {
      case keepless::cli::Arg::kHelp: *help = true; return -1;
      case keepless::cli::Arg::kVersion: *version = true; return -1;
      case keepless::cli::Arg::kError: return usage_error(error);
      case keepless::cli::Arg::kFlag: break;
    }
    const std::string flag = entry->name;
    if (flag == "--compact") {
      opt->model.compact = true;
      opt->model.map_flags = true;
      continue;
    }
    const std::string bad = "bad value for " + flag + ": '" + value + "'";
    std::string map_error;
    if (flag == "--use") {
      continue;  // applied above
    } else if (flag == "--window") {
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
      m_given = true;
    } else if (flag == "--keep-points" || flag == "--keep-fraction" || flag == "--keep-observations") {
      if (opt->params.budget.kind != core::BudgetKind::kNone) {
        return usage_error(bad + " (only one keep budget may be given)");
      }
      if (flag == "--keep-fraction") {
        double f = 0;
        if (!core::parse_finite_double(value, &f) || !(f >= 0.0 && f <= 1.0)) {
          return usage_error(bad + " (a number in [0, 1])");
        }
        opt->params.budget.kind = core::BudgetKind::kFraction;  // field by field: the use's share stays
        opt->params.budget.fraction = f;
      } else {
        std::uint64_t n = 0;
        if (!core::parse_uint64(value, &n) || n > std::numeric_limits<std::uint32_t>::max()) {
          return usage_error(bad + " (an integer >= 0)");
        }
        opt->params.budget.kind = flag == "--keep-points" ? core::BudgetKind::kPoints : core::BudgetKind::kObservations;
        opt->params.budget.count = n;
      }
    } else if (flag == "--track-share") {
      double s = 0;
      if (!core::parse_finite_double(value, &s) || !(s >= 0.0 && s <= 1.0)) return usage_error(bad + " (a number in [0, 1])");
      core::share_at_every_budget(s, &opt->params.budget);
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
      if (!core::parse_scope(value, &opt->params.scope)) return usage_error(bad + " (window, newest or auto)");
    } else if (flag == "--floor") {
      std::uint64_t floor = 0;
      if (!core::parse_uint64(value, &floor) || floor > std::numeric_limits<std::uint32_t>::max()) {
        return usage_error(bad + " (an integer >= 0)");
      }
      opt->params.coverage_floor = static_cast<std::uint32_t>(floor);
    } else if (flag == "--maturity") {
      std::uint64_t maturity = 0;
      if (!core::parse_uint64(value, &maturity) || maturity > std::numeric_limits<std::uint32_t>::max()) {
        return usage_error(bad + " (an integer >= 0)");
      }
      opt->params.maturity_keyframes = static_cast<std::uint32_t>(maturity);
    } else if (flag == "--cost") {
      if (!core::parse_cost_model(value, &opt->params.cost_model)) {
        return usage_error(bad + " (paper, authors, information or track)");
      }
    } else if (flag == "--track-terms") {
      if (!core::parse_track_terms(value, &opt->params.track_terms)) {
        return usage_error(bad + " (a comma-separated list of length, age, error, angle)");
      }
    } else if (flag == "--cost-terms") {
      if (!core::parse_cost_terms(value, &opt->params.cost_terms)) {
        return usage_error(bad + " (a comma-separated list of c_c, c_s, c_b)");
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
      return usage_error(keepless::cli::unknown_option(flag));
    }
  }
  if (m_given && opt->params.budget.kind != core::BudgetKind::kNone) {
    return usage_error(std::string("--M and --keep-") + core::to_string(opt->params.budget.kind) +
                       " exclude each other: a keep budget replaces M");
  }
  if (core::share_needs_a_count(opt->params.budget) && !core::keeps_a_count(opt->params.budget.kind)) {
    return usage_error(std::string("--track-share needs --keep-points or --keep-fraction: it is a share of their count") +
                       (use == core::Use::kOffline ? " (--use offline sets it to 1)" : ""));
  }
  if (use == core::Use::kOffline && !opt->model.mode_given) {
    opt->model.mode = keepless::sparsify::Mode::kWhole;
    opt->model.mode_given = true;
  }
  if (opt->window.empty() == opt->model.path.empty()) {
    return usage_error(opt->window.empty() ? "one of --window, --colmap, --bal is required"
                                           : "give one of --window, --colmap, --bal, not two");
  }
  if (opt->model.path.empty()) {
    opt->model.input = keepless::sparsify::Input::kWindow;
    opt->model.path = opt->window;
  }
  // The whole mode is the default for a window file; a floor given replaces
  // the offline use's R, which applies to COLMAP and BAL models (a window
  // file alone takes the single-window path, without a floor).
  double& over_longest = opt->model.floor_over_longest;
  const bool whole = keepless::sparsify::mode_of(opt->model) == keepless::sparsify::Mode::kWhole;
  if (over_longest > 0 && (!whole || !core::keeps_a_count(opt->params.budget.kind))) {
    return usage_error("--floor-over-longest needs --mode whole and --keep-points or --keep-fraction");
  }
  if (over_longest < 0) {
    // Only with a count, as when given: without one (--track-share 0) R is off and reported 0.
    const bool use_sets = use == core::Use::kOffline && whole && core::keeps_a_count(opt->params.budget.kind) &&
                          opt->model.floor < 0 && opt->model.input != keepless::sparsify::Input::kWindow;
    over_longest = use_sets ? keepless::sparsify::kOfflineFloorOverLongest : 0;
  }
  if (core::Sparsifier::validate(opt->params) != core::Status::kOk) {
    return usage_error("invalid parameters");
  }
  return -1;
}

double ms_since(std::uint64_t start_ns) {
  return static_cast<double>(keepless::platform::monotonic_ns() - start_ns) / 1e6;
}

// Written whole to a temporary name, then renamed over OUT (never a partial OUT).
bool write_decisions(const std::string& path, const core::Sparsifier& sparsifier, std::string* error) {
  const core::PointDecision* d = sparsifier.decisions();
  return keepless::io::write_file_atomically(path, keepless::sparsify::format_decisions(d, sparsifier.decision_count()),
                                             error);
}

int decide_window(const Options& opt, const core::WindowFile& file, const core::Capacities& caps, double need,
                  double parse_ms, std::uint64_t t_build);
int decide_window_unguarded(const Options& opt, const core::WindowFile& file, const core::Capacities& caps,
                            double parse_ms, std::uint64_t t_build);

int run(const Options& opt) {
  const std::uint64_t t_parse = keepless::platform::monotonic_ns();
  core::WindowFile file;
  std::string error;
  std::vector<keepless::sparsify::NamedPath> in(1), out(1);
  in[0] = {"--window", opt.window};
  out[0] = {"--decisions", opt.decisions};
  if (!opt.decisions.empty() && !keepless::sparsify::outputs_are_safe(in, out, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return kExitInput;
  }
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

  // One window: a point seen by more than core::kMaxPointViews keyframes is refused by name.
  if (const std::string why = keepless::sparsify::point_views_refusal(file, opt.params, opt.window); !why.empty()) {
    std::fprintf(stderr, "%s\n", why.c_str());
    return kExitInput;
  }
  const std::uint64_t t_build = keepless::platform::monotonic_ns();
  return decide_window(opt, file, caps, model.bytes(caps), parse_ms, t_build);
}

// Below --max-memory-mb the allocation can still fail (ulimit -v, a small
// machine): say so with the file and the estimate.
int decide_window(const Options& opt, const core::WindowFile& file, const core::Capacities& caps, double need,
                  double parse_ms, std::uint64_t t_build) {
  try {
    return decide_window_unguarded(opt, file, caps, parse_ms, t_build);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "%s: out of memory while deciding it (about %.0f MiB needed; --max-memory-mb %llu allowed it, but the "
                 "process got less: check `ulimit -v` and free memory)\n",
                 opt.window.c_str(), need / 1048576.0, static_cast<unsigned long long>(opt.max_memory_mb));
    return kExitInput;
  }
}

int decide_window_unguarded(const Options& opt, const core::WindowFile& file, const core::Capacities& caps,
                            double parse_ms, std::uint64_t t_build) {
  std::string error;
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
      "\"floor_keyframes\":%u,\"floor_promoted\":%u,\"floor_short\":%u,"
      "\"budget\":\"%s\",\"budget_value\":%s,\"budget_m\":%" PRId64 ",\"budget_observations\":%" PRIu64 ","
      "\"maturity\":%u,\"guarded\":%u,\"track_fallback\":%u,\"track_share_from\":%g,\"track_share_to\":%g,\"track_share\":%g}\n",
      sum.keyframes, sum.points, sum.evaluated, sum.kept, sum.culled, sum.skipped, sum.pairs,
      sum.arcs, sum.max_flow, sum.total_cost, opt.params.pair_capacity, theta, opt.params.box_width,
      opt.params.box_height, parse_ms, build_ms, solve_ms, memory, core::to_string(opt.params.scope),
      opt.params.coverage_floor, core::to_string(opt.params.cost_model), sum.out_of_scope,
      sum.floor_keyframes, sum.floor_promoted, sum.floor_short,
      core::to_string(opt.params.budget.kind), keepless::sparsify::budget_value(opt.params.budget).c_str(),
      sum.budget_m, sum.budget_observations, opt.params.maturity_keyframes, sum.guarded, sum.track_fallback, opt.params.budget.track_share_from,
      opt.params.budget.track_share_to, opt.params.budget.track_share);
  return std::fflush(stdout) == 0 ? 0 : kExitInternal;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  bool help = false, version = false;
  const int status = parse_args(argc, argv, &opt, &help, &version);
  if (status >= 0) return status;
  if (help) {
    std::fputs(usage().c_str(), stdout);
    return 0;
  }
  if (version) return keepless::cli::print_version(kTool);
  try {
    if (opt.model.map_flags) {
      opt.model.params = opt.params;
      opt.model.limits = opt.limits;
      opt.model.decisions = opt.decisions;
      opt.model.max_memory_mb = opt.max_memory_mb;
      return keepless::sparsify::run_model(opt.model);
    }
    return run(opt);
  } catch (const std::bad_alloc&) {  // below --max-memory-mb, but the process got less
    std::fprintf(stderr,
                 "%s: out of memory (--max-memory-mb %llu allowed it, but the process got less: check `ulimit -v` "
                 "and free memory)\n",
                 opt.model.path.c_str(), static_cast<unsigned long long>(opt.max_memory_mb));
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
