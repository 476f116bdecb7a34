#include "keepless/platform/node_config.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

#include "keepless/core/use.hpp"
#include "keepless/core/window_file.hpp"
#include "keepless/platform/cpu_pinning.hpp"
#include "keepless/platform/memory_estimate.hpp"

namespace keepless::platform {

namespace {

// Digits only (core's parser: strtoull alone skips blanks and negates a '-', " -1" being 2^64 - 1).
bool parse_u64(const std::string& text, std::uint64_t min, std::uint64_t max, std::uint64_t& out) {
  std::uint64_t v = 0;
  if (!core::parse_uint64(text, &v) || v < min || v > max) return false;
  out = v;
  return true;
}

// Plain decimal only (core's parser: strtod alone takes leading blanks and hex floats).
bool parse_double(const std::string& text, double& out) { return core::parse_finite_double(text, &out); }

// "64x48"
bool parse_box(const std::string& text, std::int32_t& w, std::int32_t& h) {
  const auto x = text.find('x');
  if (x == std::string::npos) return false;
  std::uint64_t a = 0, b = 0;
  if (!parse_u64(text.substr(0, x), 0, 1u << 20, a) || !parse_u64(text.substr(x + 1), 0, 1u << 20, b)) {
    return false;
  }
  w = static_cast<std::int32_t>(a);
  h = static_cast<std::int32_t>(b);
  return true;
}

}  // namespace

std::string node_usage() {
  return "usage: keepless_node [options]\n"
         "  --url URL                 LCM URL (default udpm://239.255.76.67:7667?ttl=0, this host only)\n"
         "  --keyframe-channel NAME   keyframe_t input (default KEEPLESS_KEYFRAME)\n"
         "  --event-channel NAME      map_event_t input (default KEEPLESS_MAP_EVENT)\n"
         "  --decision-channel NAME   decision_t output (default KEEPLESS_DECISION)\n"
         "  --timing-channel NAME     decision_timing_t output (default KEEPLESS_DECISION_TIMING)\n"
         "  --status-channel NAME     status_t output (default KEEPLESS_STATUS)\n"
         "  --event-ack-channel NAME  map_event_ack_t output (default KEEPLESS_MAP_EVENT_ACK)\n"
         "  --window K                keyframes in the sliding window (default 20)\n"
         "  --max-observations N      observations per keyframe_t accepted (default 2000)\n"
         "  --max-event-ids N         ids per list of a map_event_t accepted (default 1024)\n"
         "  --max-unmapped N          unmapped keypoints per keyframe_t accepted (default 0; --cost authors\n"
         "                            counts them)\n"
         "  --profile NAME            a set of the capacities above and below, applied before the other flags:\n"
         "                            small (K 10, N 1000, 2000 points, 4500 observations, 7000 pair arcs;\n"
         "                            3.5 MB), default (K 20, N 2000, 6600, 19100, 51000; 15.5 MB),\n"
         "                            large (K 40, N 2000, 8100, 37000, 117000; 28.7 MB)\n"
         "  --use NAME                settings per use, from the budget sweep, applied before the other flags\n"
         "                            (they set --scope, --maturity, --defer and --track-share): paper (the\n"
         "                            default), monocular (--scope newest --maturity 2, and --track-share 0.5\n"
         "                            where the budget keeps >= 0.3 of the points), monocular-deferred\n"
         "                            (--defer 2 --scope auto, and --track-share 0.5 where the budget keeps\n"
         "                            <= 0.15 of the points), rgbd (--scope newest --maturity 2), offline\n"
         "                            (--track-share 1)\n"
         "  --max-points N            distinct points the window holds (default 6600; 0: K*N)\n"
         "  --max-window-observations N  observations the window holds (default 19100; 0: K*N)\n"
         "  --max-pair-arcs N         point -> pair arcs of the window's network, sum of n(n-1)/2 over its points\n"
         "                            (default 51000; 0: the worst case for the window's observations,\n"
         "                            W*(K-1)/2 with W = --max-window-observations, which also caps N). A\n"
         "                            window beyond a capacity is answered 'capacity exceeded' (status_t says\n"
         "                            which, needed and held)\n"
         "  --max-memory-mb N         refuse to start when the fixed memory would exceed N MB (default 1024)\n"
         "  --max-sequence-jump N     refuse a sequence more than N above the publisher's last (default 1000000)\n"
         "  --max-utime-jump-s X      refuse a utime more than X s above the publisher's last, plus the node's\n"
         "                            time since its order last accepted a message (default 600)\n"
         "  --restart-confirm N       N valid keyframes of the window's publisher refused by its order, in\n"
         "                            order among themselves, are a restart if they start again near\n"
         "                            sequence 0 (with later utimes, or after the order's silence below),\n"
         "                            else a resync (window kept) once the order has accepted nothing for\n"
         "                            1 s (--owner-timeout-s if shorter and not 0) (default 3, 2..64)\n"
         "  --owner-timeout-s X       another publisher id takes the window over only after its owner has\n"
         "                            been silent X s (default 1; 0 = never)\n"
         "  --cull-memory N           culled point ids remembered against in-flight keyframes\n"
         "                            (default 0: the window's point capacity)\n"
         "  --defer T                 deferred culling: a culled point is excluded from local BA at once\n"
         "                            (decision_t.excluded_point_id) and deleted once T keyframes in a row\n"
         "                            have not matched it (deleted_point_id); default 0: off, the culls are\n"
         "                            culled_point_id as before\n"
         "  --defer-memory N          with --defer: excluded points held until deleted (default 0: the\n"
         "                            window's point capacity); one that does not fit is deleted at once\n"
         "                            and counted\n"
         "  --M N                     pair -> sink capacity (default 100)\n"
         "  --keep-points K           keep budget instead of --M: the K evaluated points with the smallest\n"
         "                            keep threshold per window (ties to the smaller point id)\n"
         "  --keep-fraction F         keep budget: the map keeps the share F in [0, 1] of the points evaluated\n"
         "                            (F of those new to each decision, plus those it kept before)\n"
         "  --keep-observations B     keep budget: points in the same order while their window\n"
         "                            observations sum to <= B\n"
         "  --track-share S           with --keep-points or --keep-fraction: take the share S in [0, 1] of\n"
         "                            the count by track length (most window keyframes first) instead of\n"
         "                            the network's order (default 0), at every budget\n"
         "  --theta X                 keep iff flow > X * n(n-1)/2 (default 0.5)\n"
         "  --box WxH                 spatial-diversity box in pixels (default 64x48)\n"
         "  --scope window|newest|auto\n"
         "                            decide every window point, only the newest keyframe's, or the newest\n"
         "                            keyframe's while a third of the window's points come back (default window)\n"
         "  --floor L                 every keyframe keeps >= L of its evaluated points (default 0: off)\n"
         "  --cost paper|authors|information|track\n"
         "                            point -> pair costs (default paper; docs/design/policies.md)\n"
         "  --track-terms LIST        with --cost track: what it sums of keyframe_t's point quality,\n"
         "                            comma-separated from length, age, error, angle (default all four)\n"
         "  --cost-terms LIST         the costs summed, comma-separated from c_c, c_s, c_b (default all three,\n"
         "                            the paper's; without c_c a pair prefers spatial diversity over views)\n"
         "  --image WxH               the image the authors' 64x48 grid covers (default 640x480)\n"
         "  --maturity A              points first seen in the newest A window keyframes are not decided\n"
         "                            yet (default 0: off); a keyframe_t's tracked flags are always honoured\n"
         "  --tracked-first           with a keep budget: the newest keyframe's tracked points are kept first\n"
         "                            within the budget (they count toward it) instead of beside it\n"
         "  --budget-work N           solver work units per decision (default unlimited)\n"
         "  --latency-target-ms X     solve deadline from keyframe arrival (default 5; 0 = none)\n"
         "  --cpus LIST               pin to these CPUs, e.g. 0,1 or 2-3 (reported if refused)\n"
         "  --mlock                   lock memory with mlockall (reported if refused)\n"
         "  --queue N                 messages LCM queues per input channel while the node is busy\n"
         "                            (default 256; LCM drops beyond it, e.g. when a log is replayed fast)\n"
         "  --status-period-ms N      status_t period (default 1000)\n"
         "  --max-keyframes N         exit after N decisions (default 0: run until SIGINT/SIGTERM)\n"
         "  --quiet                   no log line per rejected message (they are still counted)\n"
         "  --help                    print this help and exit\n"
         "  --version                 print the version and exit\n";
}

// --profile and --use: applied before every other flag, wherever they are,
// so the others refine them.
namespace {

constexpr const char* kEarlyFlags[] = {"--profile", "--use"};

// The early flag `arg` is (spelled "--flag VALUE" or "--flag=VALUE"), or nullptr.
const char* early_flag(const std::string& arg) {
  for (const char* flag : kEarlyFlags) {
    const std::string f = flag;
    if (arg == f || arg.rfind(f + "=", 0) == 0) return flag;
  }
  return nullptr;
}

// Applies an early flag's value; false with `error` for an unknown name.
bool apply_early_flag(const char* flag, const std::string& name, NodeConfig& config, std::string& error) {
  if (std::strcmp(flag, "--profile") == 0) {
    if (apply_profile(name, config)) return true;
    error = "--profile '" + name + "': expected small, default or large";
    return false;
  }
  core::Use use{};
  if (!core::parse_use(name.c_str(), &use)) {
    error = "--use '" + name + "': expected " + core::kUseNames;
    return false;
  }
  core::apply_use(use, &config.params);
  return true;
}

// Every --profile, then every --use, in the order given.
ParseResult parse_early_flags(int argc, const char* const* argv, NodeConfig& config, std::string& error) {
  for (const char* flag : kEarlyFlags) {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (early_flag(arg) != flag) continue;
      std::string name;
      if (arg.size() > std::strlen(flag)) {
        name = arg.substr(std::strlen(flag) + 1);
      } else if (i + 1 < argc) {
        name = argv[i + 1];
      } else {
        error = std::string("option '") + flag + "' needs a value";
        return ParseResult::kError;
      }
      if (!apply_early_flag(flag, name, config, error)) return ParseResult::kError;
    }
  }
  return ParseResult::kOk;
}

}  // namespace

bool apply_profile(const std::string& name, NodeConfig& config) {
  // Sized from the largest windows of the real sequences (7-Scenes, KITTI 00
  // and 06) at that K: default and large 2x them (default within 16 MB),
  // small what fits 4 MB. NodeConfig's defaults are "default".
  struct Profile {
    const char* name;
    std::uint32_t window, max_observations, max_points, max_window_observations, max_pair_arcs;
  };
  static const Profile kProfiles[] = {
      {"small", 10, 1000, 2000, 4500, 7000},
      {"default", 20, 2000, 6600, 19100, 51000},
      {"large", 40, 2000, 8100, 37000, 117000},
  };
  for (const Profile& p : kProfiles) {
    if (name != p.name) continue;
    config.window = p.window;
    config.max_observations = p.max_observations;
    config.max_points = p.max_points;
    config.max_window_observations = p.max_window_observations;
    config.max_pair_arcs = p.max_pair_arcs;
    return true;
  }
  return false;
}

ParseResult parse_node_arguments(int argc, const char* const* argv, NodeConfig& config,
                                 std::string& error) {
  if (ParseResult r = parse_early_flags(argc, argv, config, error); r != ParseResult::kOk) return r;
  bool m_given = false;  // --M and a keep budget exclude each other
  bool track_terms_given = false;  // --track-terms: with --cost track only
  bool share_given = false;  // --track-share: the error's note on offline's share is then beside the point
  for (int i = 1; i < argc; ++i) {
    std::string flag = argv[i];
    if (const char* early = early_flag(flag)) {  // applied above
      if (flag == early) ++i;
      continue;
    }
    std::string value;
    bool has_inline_value = false;
    if (const auto eq = flag.find('='); flag.rfind("--", 0) == 0 && eq != std::string::npos) {
      value = flag.substr(eq + 1);
      flag = flag.substr(0, eq);
      has_inline_value = true;
    }
    if (flag == "--help" || flag == "-h") return ParseResult::kHelp;
    if (flag == "--version") return ParseResult::kVersion;
    // A flag is known when the usage documents it (one line each).
    if (node_usage().find("\n  " + flag + " ") == std::string::npos) {
      error = "unknown option '" + flag + "'";
      return ParseResult::kError;
    }
    const bool is_switch = flag == "--mlock" || flag == "--quiet" || flag == "--tracked-first";
    if (is_switch && has_inline_value) {  // --tracked-first=0 must not turn it on
      error = "option '" + flag + "' takes no value";
      return ParseResult::kError;
    }
    if (flag == "--mlock") {
      config.mlock = true;
      continue;
    }
    if (flag == "--quiet") {
      config.quiet = true;
      continue;
    }
    if (flag == "--tracked-first") {
      config.params.tracked_first = true;  // no use sets it
      continue;
    }
    if (!has_inline_value) {
      if (i + 1 >= argc) {
        error = "option '" + flag + "' needs a value";
        return ParseResult::kError;
      }
      value = argv[++i];
    }
    std::uint64_t n = 0;
    const auto bad = [&](const char* why) {
      error = flag + " '" + value + "': " + why;
      return ParseResult::kError;
    };
    if (flag == "--url") {
      if (value.empty()) return bad("empty");
      config.url = value;
    } else if (flag == "--keyframe-channel" || flag == "--event-channel" || flag == "--decision-channel" ||
               flag == "--timing-channel" || flag == "--status-channel" || flag == "--event-ack-channel") {
      if (value.empty()) return bad("empty channel name");
      std::string& target = flag == "--keyframe-channel" ? config.keyframe_channel
                            : flag == "--event-channel"  ? config.event_channel
                            : flag == "--decision-channel" ? config.decision_channel
                            : flag == "--timing-channel"   ? config.timing_channel
                            : flag == "--status-channel"   ? config.status_channel
                                                           : config.event_ack_channel;
      target = value;
    } else if (flag == "--window") {
      if (!parse_u64(value, 2, 256, n)) return bad("expected an integer in 2..256");
      config.window = static_cast<std::uint32_t>(n);
    } else if (flag == "--max-observations") {
      if (!parse_u64(value, 1, 1u << 20, n)) return bad("expected an integer in 1..1048576");
      config.max_observations = static_cast<std::uint32_t>(n);
    } else if (flag == "--max-event-ids") {
      if (!parse_u64(value, 1, 1u << 20, n)) return bad("expected an integer in 1..1048576");
      config.max_event_ids = static_cast<std::uint32_t>(n);
    } else if (flag == "--max-unmapped") {
      if (!parse_u64(value, 0, 1u << 20, n)) return bad("expected an integer in 0..1048576");
      config.max_unmapped = static_cast<std::uint32_t>(n);
    } else if (flag == "--max-pair-arcs") {
      if (!parse_u64(value, 0, 1u << 28, n)) return bad("expected an integer in 0..2^28");
      config.max_pair_arcs = static_cast<std::uint32_t>(n);
    } else if (flag == "--max-points" || flag == "--max-window-observations") {
      if (!parse_u64(value, 0, 1u << 26, n)) return bad("expected an integer in 0..2^26");
      (flag == "--max-points" ? config.max_points : config.max_window_observations) = static_cast<std::uint32_t>(n);
    } else if (flag == "--max-memory-mb") {
      if (!parse_u64(value, 1, 1u << 24, n)) return bad("expected an integer in 1..16777216");
      config.max_memory_mb = n;
    } else if (flag == "--max-sequence-jump") {
      if (!parse_u64(value, 1, std::numeric_limits<std::int64_t>::max(), n)) return bad("expected an integer >= 1");
      config.max_sequence_jump = n;
    } else if (flag == "--max-utime-jump-s") {
      double t = 0;
      if (!parse_double(value, t) || t <= 0 || t > 1e9) return bad("expected seconds in (0, 1e9]");
      config.max_utime_jump_s = t;
    } else if (flag == "--restart-confirm") {
      if (!parse_u64(value, 2, 64, n)) return bad("expected an integer in 2..64");
      config.restart_confirm = static_cast<std::uint32_t>(n);
    } else if (flag == "--owner-timeout-s") {
      double t = 0;
      if (!parse_double(value, t) || t < 0 || t > 1e6) return bad("expected seconds in [0, 1e6]");
      if (t > 0 && t < 1e-9) return bad("below a nanosecond, which would read as 0 (never)");
      config.owner_timeout_s = t;
    } else if (flag == "--cull-memory") {
      if (!parse_u64(value, 0, 1u << 26, n)) return bad("expected an integer in 0..2^26");
      config.cull_memory = static_cast<std::uint32_t>(n);
    } else if (flag == "--defer") {
      if (!parse_u64(value, 0, 1u << 30, n)) return bad("expected an integer in 0..2^30");
      config.params.defer_keyframes = static_cast<std::uint32_t>(n);
    } else if (flag == "--defer-memory") {
      if (!parse_u64(value, 0, 1u << 26, n)) return bad("expected an integer in 0..2^26");
      config.defer_memory = static_cast<std::uint32_t>(n);
    } else if (flag == "--M") {
      if (!parse_u64(value, 1, 1u << 30, n)) return bad("expected an integer >= 1");
      config.params.pair_capacity = static_cast<std::int64_t>(n);
      m_given = true;
    } else if (flag == "--keep-points" || flag == "--keep-observations" || flag == "--keep-fraction") {
      if (config.params.budget.kind != core::BudgetKind::kNone) return bad("only one keep budget may be given");
      if (flag == "--keep-fraction") {
        double f = 0;
        if (!parse_double(value, f) || !(f >= 0 && f <= 1)) return bad("expected a number in [0, 1]");
        config.params.budget.kind = core::BudgetKind::kFraction;  // field by field: the share stays
        config.params.budget.fraction = f;
      } else {
        if (!parse_u64(value, 0, std::numeric_limits<std::uint32_t>::max(), n)) return bad("expected an integer >= 0");
        config.params.budget.kind = flag == "--keep-points" ? core::BudgetKind::kPoints : core::BudgetKind::kObservations;
        config.params.budget.count = n;
      }
    } else if (flag == "--track-share") {
      double s = 0;
      if (!parse_double(value, s) || !(s >= 0 && s <= 1)) return bad("expected a number in [0, 1]");
      core::share_at_every_budget(s, &config.params.budget);
      share_given = true;
    } else if (flag == "--theta") {
      double t = 0;
      if (!parse_double(value, t) || t < 0 || t > 1) return bad("expected a number in [0, 1]");
      config.params.theta = t;
    } else if (flag == "--box") {
      if (!parse_box(value, config.params.box_width, config.params.box_height)) {
        return bad("expected WxH, e.g. 64x48");
      }
    } else if (flag == "--scope") {
      if (!core::parse_scope(value.c_str(), &config.params.scope)) return bad("expected window, newest or auto");
    } else if (flag == "--floor") {
      if (!parse_u64(value, 0, std::numeric_limits<std::uint32_t>::max(), n)) return bad("expected an integer >= 0");
      config.params.coverage_floor = static_cast<std::uint32_t>(n);
    } else if (flag == "--cost") {
      if (!core::parse_cost_model(value.c_str(), &config.params.cost_model)) {
        return bad("expected paper, authors, information or track");
      }
    } else if (flag == "--track-terms") {
      if (!core::parse_track_terms(value.c_str(), &config.params.track_terms)) {
        return bad("expected a comma-separated list of length, age, error, angle");
      }
      track_terms_given = true;
    } else if (flag == "--cost-terms") {
      if (!core::parse_cost_terms(value.c_str(), &config.params.cost_terms)) {
        return bad("expected a comma-separated list of c_c, c_s, c_b");
      }
    } else if (flag == "--maturity") {
      if (!parse_u64(value, 0, std::numeric_limits<std::uint32_t>::max(), n)) return bad("expected an integer >= 0");
      config.params.maturity_keyframes = static_cast<std::uint32_t>(n);
    } else if (flag == "--image") {
      if (!parse_box(value, config.params.image_width, config.params.image_height) ||
          config.params.image_width < 1 || config.params.image_height < 1) {
        return bad("expected WxH pixels, e.g. 640x480");
      }
    } else if (flag == "--budget-work") {
      if (!parse_u64(value, 1, std::numeric_limits<std::uint64_t>::max(), n)) return bad("expected an integer >= 1");
      config.budget_work_units = n;
    } else if (flag == "--latency-target-ms") {
      double t = 0;
      if (!parse_double(value, t) || t < 0 || t > 60000) return bad("expected milliseconds in [0, 60000]");
      config.latency_target_ms = t;
    } else if (flag == "--cpus") {
      // A malformed list is the user's, refused here; only what the OS refuses is reported at start.
      std::uint64_t mask[16];
      if (!parse_cpu_list(value, mask)) return bad("expected a CPU list, e.g. 0,1 or 2-3 (CPUs 0..1023)");
      config.cpus = value;
    } else if (flag == "--queue") {
      if (!parse_u64(value, 1, 1u << 20, n)) return bad("expected an integer in 1..1048576");
      config.queue_capacity = static_cast<std::uint32_t>(n);
    } else if (flag == "--status-period-ms") {
      if (!parse_u64(value, 1, 3600u * 1000u, n)) return bad("expected an integer in 1..3600000");
      config.status_period_ms = static_cast<std::uint32_t>(n);
    } else if (flag == "--max-keyframes") {
      if (!parse_u64(value, 0, std::numeric_limits<std::uint64_t>::max(), n)) return bad("expected an integer >= 0");
      config.max_keyframes = n;
    } else {
      error = "unknown option '" + flag + "'";
      return ParseResult::kError;
    }
  }
  // One keyframe_t within the limits always fits the window on its own.
  for (const auto& [name, value] : {std::pair<const char*, std::uint32_t>{"--max-points", config.max_points},
                                    {"--max-window-observations", config.max_window_observations}}) {
    if (value != 0 && value < config.max_observations) {
      error = std::string(name) + " " + std::to_string(value) + " is below --max-observations " +
              std::to_string(config.max_observations) + ": one keyframe would not fit the window";
      return ParseResult::kError;
    }
  }
  if (m_given && config.params.budget.kind != core::BudgetKind::kNone) {
    error = "--M and --keep-" + std::string(core::to_string(config.params.budget.kind)) +
            " exclude each other: a keep budget replaces M";
    return ParseResult::kError;
  }
  if (core::share_needs_a_count(config.params.budget) && !core::keeps_a_count(config.params.budget.kind)) {
    error = "--track-share needs --keep-points or --keep-fraction: it is a share of their count";
    if (!share_given) error += " (--use offline sets it to 1)";  // only offline's share applies at every budget
    return ParseResult::kError;
  }
  // Flags that would change nothing are refused, as the budget's are.
  if (track_terms_given && config.params.cost_model != core::CostModel::kTrack) {
    error = "--track-terms needs --cost track: they are what its cost sums";
    return ParseResult::kError;
  }
  if (config.defer_memory > 0 && config.params.defer_keyframes == 0) {
    error = "--defer-memory needs --defer (or --use monocular-deferred): it holds the excluded points";
    return ParseResult::kError;
  }
  if (config.params.tracked_first && config.params.budget.kind == core::BudgetKind::kNone) {
    error = "--tracked-first needs a keep budget (--keep-points, --keep-fraction or --keep-observations): "
            "the tracked are kept first within it";
    return ParseResult::kError;
  }
  // The worst-case window must stay addressable by the solver's int32 arc ids.
  const std::uint64_t arcs = static_cast<std::uint64_t>(config.window) * config.max_observations *
                             (config.window - 1) / 2;
  if (config.max_pair_arcs == 0 && arcs > (1ull << 28)) {
    error = "--window " + std::to_string(config.window) + " with --max-observations " +
            std::to_string(config.max_observations) + ": worst-case window too large (" +
            std::to_string(arcs) + " pair arcs > 2^28)";
    return ParseResult::kError;
  }
  return ParseResult::kOk;
}

OrderBounds order_bounds(const NodeConfig& config) {
  OrderBounds b;
  b.max_sequence_jump = config.max_sequence_jump;
  b.max_utime_jump_us = static_cast<std::uint64_t>(config.max_utime_jump_s * 1e6);
  b.restart_confirm = config.restart_confirm;
  b.owner_timeout_ns = static_cast<std::uint64_t>(config.owner_timeout_s * 1e9);
  b.recent_keyframes = config.window;
  return b;
}

core::Capacities window_capacities(const NodeConfig& config) {
  core::Capacities c;
  const std::uint64_t k = config.window;
  const std::uint64_t worst = k * config.max_observations;  // K full keyframes
  const auto capped = [worst](std::uint32_t value) {
    return static_cast<std::uint32_t>(value != 0 ? std::min<std::uint64_t>(value, worst) : worst);
  };
  c.max_keyframes = config.window;
  c.max_observations = capped(config.max_window_observations);
  c.max_points = capped(config.max_points);
  c.max_unmapped_keypoints = static_cast<std::uint32_t>(k * config.max_unmapped);
  c.max_keyframe_observations = config.max_observations;  // a keyframe_t's, refused beyond
  c.hold_quality = config.params.cost_model == core::CostModel::kTrack;  // only --cost track reads it
  // Sum over points of n(n-1)/2 with sum n <= observations and n <= K.
  const std::uint64_t worst_arcs = std::uint64_t{c.max_observations} * (k - 1) / 2;
  c.max_pair_arcs = static_cast<std::uint32_t>(
      config.max_pair_arcs != 0 ? std::min<std::uint64_t>(config.max_pair_arcs, worst_arcs) : worst_arcs);
  return c;
}

}  // namespace keepless::platform

namespace keepless::platform {

double estimate_node_bytes(const NodeConfig& config) {
  const core::Capacities caps = window_capacities(config);
  const MemoryModel model = probe_memory_model(config.params, core::SolveMode::kIncremental, 2);
  const double ids = config.cull_memory != 0 ? config.cull_memory : caps.max_points;
  // Sliding-window scratch, message objects and buffers, decision arrays, cull memory,
  // the order's record of the window's keyframes (sequence and hash).
  const double messages = 158.0 * config.max_observations + 148.0 * config.max_event_ids +
                          16.0 * (caps.max_points + 2.0 * caps.max_keyframes) + 8.0 * caps.max_points;
  // Deferred culling: the held points (a 16-byte slot table at <= 1/2 load,
  // id and last match) and the decision's two lists.
  const double deferred = config.params.defer_keyframes == 0 ? 0.0
                          : (config.defer_memory != 0 ? config.defer_memory : caps.max_points);
  double slots = 2;
  while (slots < 2 * deferred) slots *= 2;
  const double deferred_bytes =
      deferred > 0 ? 16.0 * slots + 16.0 * deferred + 8.0 * (2.0 * caps.max_points + deferred) : 0.0;
  return model.bytes(caps) + messages + 40.0 * ids + deferred_bytes;
}

}  // namespace keepless::platform
