// keepless_eval: the paper's evaluation on real trajectories, real images and
// a real BA problem (issues 6, 11), over several seeds, every variant compared
// at the same kept count. The last stdout line is the JSON contract
// (run_record.hpp); --out DIR receives tables.md, runs.csv and SVG plots.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bal_eval.hpp"
#include "cli/cli.hpp"
#include "keepless/core/config.hpp"
#include "keepless/core/use.hpp"
#include "keepless/platform/cpu_pinning.hpp"
#include "keepless/platform/node_config.hpp"
#include "kitti_images.hpp"
#include "prng.hpp"
#include "report.hpp"
#include "run_record.hpp"
#include "scenario.hpp"
#include "slam_sim.hpp"
#include "trajectory_io.hpp"
#include "window_sizes.hpp"
#include "vo_eval.hpp"

namespace ke = keepless::eval;

namespace {

constexpr const char* kTool = "keepless_eval";
namespace cli = keepless::cli;

const std::vector<cli::Flag> kFlags = {
    {"--quick", nullptr, "a small, fast subset (structure checks, never the paper's numbers)"},
    {"--data-root", "DIR", "add the standard inputs under DIR (../shared/data layout)"},
    {"--trajectory", "FILE", "a real trajectory (repeatable)"},
    {"--format", "tum|euroc|kitti", "the format of the --trajectory just before it (default: guessed)"},
    {"--image-tracks", "DIR", "the synthetic back end on ORB tracks of KITTI-layout images"},
    {"--images", "DIR", "the real VO on a KITTI-layout sequence (--calib, --poses follow it)"},
    {"--calib", "FILE", "calibration of the --images or --image-tracks before it"},
    {"--poses", "FILE", "ground-truth poses of the --images or --image-tracks before it"},
    {"--rgbd", "DIR", "the real VO on a 7-Scenes RGB-D sequence (frame-NNNNNN.*)"},
    {"--rgb", "DIR", "the real VO, monocular, on a 7-Scenes sequence's colour frames alone\n"
                     "(its depth unread; reported as NAME_mono)"},
    {"--frames", "A:B[:S]", "frames numbered A..B inclusive, wherever the sequence starts, every\n"
                            "S-th of them (a camera S times faster over the same scene; its frame\n"
                            "rate divided by S) (default all; --quick: the first 60 frames)"},
    {"--bal", "FILE", "a BAL problem (repeatable)"},
    {"--kept-fraction", "F[,F...]", "a keep budget: every selector keeps the share F of the points it\n"
                                    "evaluates (F of those new to each window, plus those it kept\n"
                                    "before; default 0.3; a list sweeps)"},
    {"--M", "N[,N...]", "pair capacities directly instead of --kept-fraction"},
    {"--seeds", "N", "seeds FIRST .. FIRST+N-1 (default 5, --quick 2); tables show mean +- sd"},
    {"--seed", "FIRST", "the first seed (default 1)"},
    {"--error-floor", "none|GROUP=METRES,...", "ATE added in quadrature to both sides of a ratio, per group\n"
                                               "(default: the paper's published original ATE: tum=0.0183,\n"
                                               "euroc_mh=0.0658,euroc_v=0.0658,kitti=0.537)"},
    {"--out", "DIR", "write tables.md, runs.csv and SVG plots there"},
    {"--cpus", "LIST", "pin to these CPUs, e.g. 0,1 or 2-3 (the settings say what was granted)"},
    {"--report", "DIR", "regenerate the tables and the JSON line from DIR's runs.csv (an earlier\n"
                        "--out; repeat to merge runs), without running anything"},
    {"--max-keyframes", "N", "keyframes per synthetic run (default 50, --quick 40)"},
    {"--keypoints", "N", "keypoints per frame of the synthetic back end (default 600, --quick 400)"},
    {"--window", "N", "the simulated local-mapping window in keyframes, 2..64 (default 8, --quick 6)"},
    {"--ba-iterations", "N", "local BA iterations (default 10, --quick 5)"},
    {"--image-frames", "N", "frames read from --image-tracks (default all, --quick 12)"},
    {"--noise-free", nullptr, "no synthetic pixel noise"},
    {"--no-baselines", nullptr, "keepless only, no baselines"},
    {"--vo-baselines", "LIST", "the real VO's baselines, comma-separated from random, longest-track, anms\n"
                               "(default all three; keepless and the original always run)"},
    {"--anms-variant", "ssc|spread|response|track",
     "what the real VO's ANMS ranks by: ssc, SSC on the keypoints' responses\n"
     "(default); spread, SSC on the random baseline's priorities (spread alone);\n"
     "response, the strongest responses without suppression (strength alone);\n"
     "track, SSC on the track lengths (spread and long tracks)"},
    {"--no-ablation", nullptr, "no ablation variants"},
    {"--ablation-all", nullptr, "every ablation variant"},
    {"--use", "NAME", "a use (core::apply_use) and what it asks of the real VO, applied before\n"
                      "the other flags, which refine it: monocular (--scope newest --maturity 2\n"
                      "--keyframe-culling count-culled, and --track-share 0.5 from a kept\n"
                      "fraction of 0.3), monocular-deferred (--defer 2 --defer-refine --decide\n"
                      "window --scope auto --keyframe-culling count-culled, and --track-share\n"
                      "0.5 to a kept fraction of 0.15), rgbd (as monocular without the share),\n"
                      "offline (--track-share 1), paper (the defaults)"},
    {"--scope", "S", "keepless's decision scope (core::Params scope): window, newest or auto;\n"
                     "with --decide window, auto decides the new keyframe's points while a\n"
                     "third of the window's come back, else the window's"},
    {"--floor", "L", "keepless's coverage floor (core::Params coverage_floor)"},
    {"--theta", "T", "keepless's keep threshold theta_f in [0, 1] (core::Params theta; default 0.5)"},
    {"--track-share", "S", "with --kept-fraction: keepless takes the share S in [0, 1] of its count by\n"
                           "track length (core::KeepBudget track_share; default 0), at every fraction"},
    {"--cost", "paper|authors|information|track", "keepless's cost model; with --kept-fraction the real VO\n"
                                                  "decides the new keyframe's points; track: the real VO\n"
                                                  "sends each point's map observations, age, reprojection\n"
                                                  "error and triangulation angle"},
    {"--track-terms", "LIST", "the qualities --cost track sums, comma-separated from length, age,\n"
                              "error, angle (default all four)"},
    {"--cost-terms", "LIST", "the real VO: the paper's cost terms keepless sums, comma-separated from\n"
                             "c_c, c_s, c_b (default all three; core::Params cost_terms)"},
    {"--spatial-weight", "W", "keepless's c_s times W, 1..65536 (core::Params spatial_weight; default 1,\n"
                              "the paper's; larger lets spatial diversity outrank connectivity)"},
    {"--maturity", "A", "tracking-safe culling: points first seen in the newest A window keyframes\n"
                        "are not decided yet (core::Params maturity_keyframes); every selector\n"
                        "culls only what keepless decided, so the baselines get the same guard\n"
                        "(default 0: off)"},
    {"--defer", "T", "deferred culling in the real VO, every selector alike: a culled point leaves\n"
                     "local BA at once (kept for tracking, re-triangulated after each local BA)\n"
                     "and the map once T keyframes in a row have not matched it\n"
                     "(core::Params defer_keyframes)"},
    {"--defer-fixed", nullptr, "with --defer: excluded points enter local BA as constant landmarks seen\n"
                               "by its keyframes (their observations constrain the poses) instead of\n"
                               "not at all"},
    {"--defer-refine", nullptr, "with --defer: each excluded point's re-triangulation is refined with the\n"
                                "poses held (robust, as local BA refines a point) and its outlier\n"
                                "observations are erased"},
    {"--defer-alternate", nullptr, "with --defer: then each local keyframe's pose is refined (motion-only)\n"
                                   "against all its points, excluded ones included, and the excluded\n"
                                   "points re-triangulated again (one round of resection-intersection)"},
    {"--decide", "newest|window", "which points every selector of the real VO decides at a keyframe:\n"
                                  "newest, the new keyframe's (the authors' integration; default), or\n"
                                  "window, every point of the local window, so a point kept before\n"
                                  "can be culled later (keepless with --scope window)"},
    {"--tie-order", "id|hash", "how keepless breaks ties in the real VO: by point id (default; the VO's\n"
                              "ids grow with the points' age) or by a bijective hash of it"},
    {"--tracked-flags", nullptr, "the real VO sends the new keyframe's tracked flags (the points it\n"
                                 "matched in that frame), which no selector culls"},
    {"--tracked-first", nullptr, "as --tracked-flags, but keepless keeps the tracked points first within\n"
                                 "its --kept-fraction budget (core::Params::tracked_first; not with --M) and\n"
                                 "every selector may cull them"},
    {"--keyframe-culling", "on|off|count-culled",
     "the real VO's culling of a keyframe 90 % of whose points three others\n"
     "see (ORB-SLAM's), every run alike: on (default); off, every keyframe it\n"
     "makes stays; count-culled, the test also counts each point a selector\n"
     "deleted, with the observations it had then"},
    {"--no-keyframe-culling", nullptr, "--keyframe-culling off"},
    {"--weak-keyframe", "N", "the real VO also makes a keyframe when a frame keeps fewer than N pose\n"
                             "inliers (ORB-SLAM3's weak-tracking rule for monocular-inertial input, N =\n"
                             "75; ORB-SLAM2's monocular test has none), every run alike (default 0: off)"},
    {"--keyframe-ratio", "R", "the real VO's monocular keyframe test: a keyframe when a frame's inliers fall\n"
                              "below R x the reference keyframe's points seen 3+ times, R in [0.3, 1]\n"
                              "(ORB-SLAM2's 0.9, the default; lower makes fewer keyframes), every run alike"},
    {"--window-sizes", nullptr, "instead of the comparison: the original run of the first seed on each\n"
                                "--trajectory, --images and --rgbd input, and the largest window it\n"
                                "gives (keyframes, points, observations, pair arcs, unmapped keypoints)\n"
                                "at K = 10, 20, 40, local (the local BA's) and sliding (the last K\n"
                                "keyframes); a table, then {\"window_sizes\":[...]} last"},
};

std::string usage() {
  return cli::usage("usage: keepless_eval [--quick] [--data-root DIR] [inputs...] [options]\n"
                    "       keepless_eval --report DIR [--report DIR]... [--error-floor ...] [--out DIR2]",
                    kFlags, "The last stdout line is the JSON summary.");
}

struct TrajectoryArg {
  std::string path;
  std::string format;  // empty: guess
};

// An operating point: a kept fraction (a keep budget per window) or an M.
struct OperatingPoint {
  double fraction = NAN;
  std::int64_t M = 0;
};

struct Args {
  bool quick = false;
  std::string data_root;
  std::vector<TrajectoryArg> trajectories;
  std::string images, calib, poses;  // --image-tracks
  std::vector<keepless::eval::vo::VoInput> vo;  // --images, --rgbd
  int frames_first = 0, frames_last = -2;  // --frames A:B[:S]; -2: not given (-1: to the end)
  int frames_step = 1;
  keepless::eval::vo::FrameSelection vo_frames() const {
    return {frames_first, frames_last != -2 ? frames_last : -1, frames_step, 0};
  }
  std::vector<std::string> bal;
  std::vector<OperatingPoint> ops;
  int seeds = -1;
  std::uint64_t first_seed = 1;
  std::map<std::string, double> error_floor{{"tum", 0.0183}, {"euroc_mh", 0.0658}, {"euroc_v", 0.0658}, {"kitti", 0.537}};
  std::string out;
  std::string cpus;  // --cpus
  std::vector<std::string> report;
  int max_keyframes = -1, keypoints = -1, window = -1, ba_iterations = -1, image_frames = -1;
  bool window_sizes = false;
  bool noise_free = false, baselines = true, ablation = true, ablation_all = false;
  std::vector<keepless::eval::vo::Selector> vo_baselines = keepless::eval::vo::VoEvalOptions{}.baselines;  // --vo-baselines
  keepless::core::Params policy;  // scope, coverage_floor, theta, cost_model, maturity_keyframes, track_terms, cost_terms (the real VO), spatial_weight; the rest is set per variant
  bool tracked_flags = false;     // --tracked-flags (the real VO)
  int weak_keyframe = 0;          // --weak-keyframe (the real VO)
  double keyframe_ratio = 0.9;    // --keyframe-ratio (the real VO)
  keepless::eval::vo::AnmsVariant anms_variant{};  // --anms-variant (the real VO; default kSsc)
  bool defer_fixed = false;       // --defer-fixed (the real VO)
  bool defer_refine = false;      // --defer-refine (the real VO)
  bool defer_alternate = false;   // --defer-alternate (the real VO)
  bool decide_window = false;     // --decide window (the real VO)
  bool hashed_ids = false;        // --tie-order hash (the real VO)
  ke::vo::KeyframeCulling keyframe_culling{};  // --keyframe-culling (the real VO)
};

[[noreturn]] void fail(const std::string& msg) {
  std::cerr << "keepless_eval: " << msg << "\n";
  std::exit(2);
}

long parse_int(const std::string& flag, const std::string& v, long lo, long hi) {
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || x < lo || x > hi) fail(flag + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" + v + "'");
  return x;
}

double parse_double(const std::string& flag, const std::string& v, double lo, double hi) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !(x >= lo && x <= hi)) {
    std::ostringstream range;  // shortest form: [0.01, 0.99], not [0.010000, 0.990000]
    range << "[" << lo << ", " << hi << "]";
    fail(flag + ": expected a number in " + range.str() + ", got '" + v + "'");
  }
  return x;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, sep)) out.push_back(tok);
  return out;
}

// --use: the use's policy and what its docs ask of the VO (count the culled
// points in keyframe culling; with deferred culling keep excluded points
// refined and decide the window).
void apply_use(const std::string& name, Args* a) {
  namespace kc = keepless::core;
  kc::Use use{};
  if (!kc::parse_use(name.c_str(), &use)) {
    fail(std::string("--use: expected ") + kc::kUseNames + ", got '" + name + "'");
  }
  kc::apply_use(use, &a->policy);
  if (use != kc::Use::kPaper && use != kc::Use::kOffline) {
    a->keyframe_culling = ke::vo::KeyframeCulling::kCountCulled;
  }
  a->defer_refine = a->decide_window = use == kc::Use::kMonocularDeferred;
}

Args parse(int argc, char** argv) {
  Args a;
  bool by_M = false, by_fraction = false, tracks_last = false;
  if (const char* name = cli::last_value(argc, argv, "--use")) apply_use(name, &a);
  for (int i = 1; i < argc; ++i) {
    const cli::Flag* flag = nullptr;
    const char* value = nullptr;
    std::string error;
    switch (cli::next(kFlags, argc, argv, &i, &flag, &value, &error)) {
      case cli::Arg::kHelp:
        std::cout << usage();
        std::exit(0);
      case cli::Arg::kVersion: std::exit(cli::print_version(kTool));
      case cli::Arg::kError: std::exit(cli::usage_error(kTool, error));
      case cli::Arg::kFlag: break;
    }
    const std::string f = flag->name;
    auto val = [&]() -> std::string { return value; };
    if (f == "--use") continue;  // applied above
    else if (f == "--quick") a.quick = true;
    else if (f == "--data-root") a.data_root = val();
    else if (f == "--trajectory") a.trajectories.push_back({val(), ""});
    else if (f == "--format") {
      const std::string v = val();
      ke::TrajectoryFormat tf;
      if (!ke::parse_format(v, &tf)) fail("--format: expected tum, euroc or kitti, got '" + v + "'");
      if (a.trajectories.empty() || !a.trajectories.back().format.empty()) fail("--format must follow its --trajectory");
      a.trajectories.back().format = v;
    } else if (f == "--images" || f == "--rgbd" || f == "--rgb") {
      using L = ke::vo::VoLayout;
      a.vo.push_back({f == "--images" ? L::kKittiImages : f == "--rgbd" ? L::kRgbd : L::kColourOnly, val(), "", ""});
      tracks_last = false;
    } else if (f == "--image-tracks") {
      a.images = val();
      tracks_last = true;
    } else if (f == "--calib" || f == "--poses") {  // for the --images or --image-tracks before it
      const bool vo = !tracks_last && !a.vo.empty() && a.vo.back().layout == ke::vo::VoLayout::kKittiImages;
      if (!tracks_last && !vo) fail(f + " must follow its --images or --image-tracks");
      (f == "--calib" ? (vo ? a.vo.back().calib : a.calib) : (vo ? a.vo.back().poses : a.poses)) = val();
    } else if (f == "--frames") {
      const std::string v = val();
      const auto colon = v.find(':');
      if (colon == std::string::npos) fail("--frames: expected A:B[:S], got '" + v + "'");
      const auto step_colon = v.find(':', colon + 1);
      a.frames_first = static_cast<int>(parse_int(f, v.substr(0, colon), 0, 10000000));
      a.frames_last =
          static_cast<int>(parse_int(f, v.substr(colon + 1, step_colon - colon - 1), a.frames_first, 10000000));
      if (step_colon != std::string::npos)
        a.frames_step = static_cast<int>(parse_int(f, v.substr(step_colon + 1), 1, 100));
    }
    else if (f == "--bal") a.bal.push_back(val());
    else if (f == "--M") {
      by_M = true;
      for (const auto& t : split(val(), ',')) a.ops.push_back({NAN, parse_int("--M", t, 1, 1000000)});
    } else if (f == "--kept-fraction") {
      by_fraction = true;
      for (const auto& t : split(val(), ',')) a.ops.push_back({parse_double("--kept-fraction", t, 0.01, 0.99), 0});
    } else if (f == "--seeds") a.seeds = static_cast<int>(parse_int(f, val(), 1, 1000));
    else if (f == "--seed") a.first_seed = static_cast<std::uint64_t>(parse_int(f, val(), 0, 1L << 40));
    else if (f == "--error-floor") {
      const std::string v = val();
      a.error_floor.clear();
      if (v != "none")
        for (const auto& t : split(v, ',')) {
          const auto eq = t.find('=');
          if (eq == std::string::npos || eq == 0) fail("--error-floor: expected none or GROUP=METRES,..., got '" + t + "'");
          a.error_floor[t.substr(0, eq)] = parse_double("--error-floor", t.substr(eq + 1), 0, 1e3);
        }
    } else if (f == "--out") a.out = val();
    else if (f == "--cpus") a.cpus = val();
    else if (f == "--report") a.report.push_back(val());
    else if (f == "--max-keyframes") a.max_keyframes = static_cast<int>(parse_int(f, val(), 0, 1000000));
    else if (f == "--keypoints") a.keypoints = static_cast<int>(parse_int(f, val(), 10, 100000));
    else if (f == "--window") a.window = static_cast<int>(parse_int(f, val(), 2, 64));
    else if (f == "--ba-iterations") a.ba_iterations = static_cast<int>(parse_int(f, val(), 1, 1000));
    else if (f == "--image-frames") a.image_frames = static_cast<int>(parse_int(f, val(), 0, 100000));
    else if (f == "--noise-free") a.noise_free = true;
    else if (f == "--window-sizes") a.window_sizes = true;
    else if (f == "--no-baselines") a.baselines = false;
    else if (f == "--vo-baselines") {
      a.vo_baselines.clear();
      std::stringstream list(val());
      for (std::string item; std::getline(list, item, ',');) {
        using keepless::eval::vo::Selector;
        if (item == "random") a.vo_baselines.push_back(Selector::kRandom);
        else if (item == "longest-track") a.vo_baselines.push_back(Selector::kLongestTrack);
        else if (item == "anms") a.vo_baselines.push_back(Selector::kAnms);
        else fail("--vo-baselines: random, longest-track or anms, comma-separated, got '" + item + "'");
      }
    }
    else if (f == "--anms-variant") {
      using keepless::eval::vo::AnmsVariant;
      const std::string v = val();
      if (v == "ssc") a.anms_variant = AnmsVariant::kSsc;
      else if (v == "spread") a.anms_variant = AnmsVariant::kSpread;
      else if (v == "response") a.anms_variant = AnmsVariant::kResponse;
      else if (v == "track") a.anms_variant = AnmsVariant::kTrack;
      else fail("--anms-variant: ssc, spread, response or track, got '" + v + "'");
    }
    else if (f == "--no-ablation") a.ablation = false;
    else if (f == "--ablation-all") a.ablation_all = true;
    else if (f == "--scope") {
      const std::string v = val();
      if (!keepless::core::parse_scope(v.c_str(), &a.policy.scope)) fail("--scope: expected window, newest or auto, got '" + v + "'");
    } else if (f == "--floor") a.policy.coverage_floor = static_cast<std::uint32_t>(parse_int(f, val(), 0, 100000));
    else if (f == "--theta") a.policy.theta = parse_double(f, val(), 0, 1);
    else if (f == "--track-share") keepless::core::share_at_every_budget(parse_double(f, val(), 0, 1), &a.policy.budget);
    else if (f == "--maturity") a.policy.maturity_keyframes = static_cast<std::uint32_t>(parse_int(f, val(), 0, 1000));
    else if (f == "--tracked-flags") a.tracked_flags = true;
    else if (f == "--tracked-first") a.tracked_flags = a.policy.tracked_first = true;
    else if (f == "--weak-keyframe") a.weak_keyframe = static_cast<int>(parse_int(f, val(), 0, 100000));
    else if (f == "--keyframe-ratio") a.keyframe_ratio = parse_double(f, val(), 0.3, 1);
    else if (f == "--defer") a.policy.defer_keyframes = static_cast<std::uint32_t>(parse_int(f, val(), 1, 1000));
    else if (f == "--defer-fixed") a.defer_fixed = true;
    else if (f == "--defer-refine") a.defer_refine = true;
    else if (f == "--defer-alternate") a.defer_alternate = true;
    else if (f == "--no-keyframe-culling") a.keyframe_culling = ke::vo::KeyframeCulling::kOff;
    else if (f == "--keyframe-culling") {
      const std::string v = val();
      using KeyframeCulling = ke::vo::KeyframeCulling;
      if (v == "on") a.keyframe_culling = KeyframeCulling::kOn;
      else if (v == "off") a.keyframe_culling = KeyframeCulling::kOff;
      else if (v == "count-culled") a.keyframe_culling = KeyframeCulling::kCountCulled;
      else fail("--keyframe-culling: expected on, off or count-culled, got '" + v + "'");
    }
    else if (f == "--decide") {
      const std::string v = val();
      if (v != "newest" && v != "window") fail("--decide: expected newest or window, got '" + v + "'");
      a.decide_window = v == "window";
    }
    else if (f == "--cost-terms") {
      const std::string v = val();
      if (!keepless::core::parse_cost_terms(v.c_str(), &a.policy.cost_terms))
        fail("--cost-terms: expected a comma-separated list of c_c, c_s, c_b, got '" + v + "'");
    }
    else if (f == "--spatial-weight")
      a.policy.spatial_weight = static_cast<std::int32_t>(parse_int(f, val(), 1, keepless::core::kMaxSpatialWeight));
    else if (f == "--tie-order") {
      const std::string v = val();
      if (v != "id" && v != "hash") fail("--tie-order: expected id or hash, got '" + v + "'");
      a.hashed_ids = v == "hash";
    }
    else if (f == "--cost") {
      const std::string v = val();
      if (!keepless::core::parse_cost_model(v.c_str(), &a.policy.cost_model))
        fail("--cost: expected paper, authors, information or track, got '" + v + "'");
    } else if (f == "--track-terms") {
      const std::string v = val();
      if (!keepless::core::parse_track_terms(v.c_str(), &a.policy.track_terms))
        fail("--track-terms: expected a comma-separated list of length, age, error, angle, got '" + v + "'");
    }
    else std::exit(cli::usage_error(kTool, cli::unknown_option(f)));
  }
  if (by_M && by_fraction) fail("--M and --kept-fraction exclude each other");
  if (by_M && a.policy.tracked_first) fail("--tracked-first needs --kept-fraction: under --M there is no budget to keep the tracked first within (--tracked-flags skips them)");
  if (keepless::core::share_needs_a_count(a.policy.budget) && !by_fraction) {
    fail(cli::last_value(argc, argv, "--track-share") != nullptr
             ? "--track-share needs --kept-fraction: it is a share of its count"
             : "--use offline takes a share of a count: give --kept-fraction");
  }
  if (!a.images.empty() && (a.calib.empty() || a.poses.empty())) fail("--image-tracks needs --calib and --poses");
  for (const auto& v : a.vo) {
    if (v.layout == ke::vo::VoLayout::kKittiImages && (v.calib.empty() || v.poses.empty())) {
      fail("--images " + v.dir + " needs --calib and --poses");
    }
  }
  // runs.csv holds each input's path unquoted: refuse what it cannot hold before any run.
  std::vector<std::string> inputs = a.bal;
  for (const auto& t : a.trajectories) inputs.push_back(t.path);
  for (const auto& v : a.vo) inputs.push_back(v.dir);
  if (!a.images.empty()) inputs.push_back(a.images);
  for (const std::string& p : inputs)
    if (p.find_first_of(",\n") != std::string::npos) fail("'" + p + "': an input path with a comma or line break cannot be written to runs.csv");
  if (a.ops.empty()) a.ops.push_back({0.3, 0});
  if (a.seeds < 0) a.seeds = a.quick ? 2 : 5;
  return a;
}

void add_data_root(Args* a) {
  namespace fs = std::filesystem;
  const fs::path r(a->data_root);
  auto need = [&](const fs::path& p) {
    if (!fs::exists(p)) fail("--data-root: missing " + p.string());
    return p.string();
  };
  a->trajectories.push_back({need(r / "evo/freiburg1_xyz-groundtruth.txt"), "tum"});
  if (!a->quick) {
    for (const char* s : {"MH01", "MH03", "V102", "V201"})
      a->trajectories.push_back({need(r / "orbslam3_euroc_left_cam_gt" / (std::string(s) + "_GT.txt")), "euroc"});
    a->trajectories.push_back({need(r / "evo/KITTI_00_gt.txt"), "kitti"});
    a->trajectories.push_back({need(r / "kitti_odom_eval/gt_poses/06.txt"), "kitti"});
    a->trajectories.push_back({need(r / "kitti_odom_eval/gt_poses/09.txt"), "kitti"});
  }
  if (a->images.empty()) {
    a->images = need(r / "kitti06_first51_niconielsen/image_l");
    a->calib = need(r / "kitti06_first51_niconielsen/calib.txt");
    a->poses = need(r / "kitti06_first51_niconielsen/poses.txt");
  }
  if (a->bal.empty()) a->bal.push_back(need(r / "bal_zenslam/problem-49-7776-pre.txt"));
}

std::string guess_format(const std::string& path) {
  if (path.size() > 4 && path.substr(path.size() - 4) == ".csv") return "euroc";
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (line.find(',') != std::string::npos) return "euroc";
    std::istringstream s(line);
    int n = 0;
    std::string t;
    while (s >> t) ++n;
    return n == 12 ? "kitti" : "tum";
  }
  return "tum";
}

std::string short_name(const std::string& path) {
  std::string n = std::filesystem::path(path).stem().string();
  for (const char* suffix : {"-groundtruth", "_groundtruth", "_GT", "_gt"}) {
    const std::string s(suffix);
    if (n.size() > s.size() && n.compare(n.size() - s.size(), s.size(), s) == 0) n.resize(n.size() - s.size());
  }
  if (n.rfind("freiburg", 0) == 0) n = "fr" + n.substr(8);
  return n;
}

std::string group_of(const std::string& format, const std::string& name) {
  if (format == "tum") return "tum";
  if (format == "kitti") return "kitti";
  if (name.rfind("MH", 0) == 0) return "euroc_mh";
  if (name.rfind("V", 0) == 0) return "euroc_v";
  return "euroc";
}

ke::RunRecord record_of(const ke::RunResult& r, std::uint64_t seed) {
  ke::RunRecord x;
  x.variant = r.spec.name;
  x.seed = seed;
  x.M = r.spec.selector == ke::Selector::kNone ? 0 : r.spec.params.pair_capacity;
  x.mps = r.mps;
  x.kfs = r.kfs;
  x.observations = r.ba_observations;
  x.ba_s = r.ba_s;
  x.ba_cpu_s = r.ba_cpu_s;
  x.total_s = r.total_s;
  x.ate_m = r.ate_m;
  x.ate_r_deg = r.ate_r_deg;
  x.C = r.C;
  x.F = r.F;
  x.S = r.S;
  x.selector = r.selector;
  return x;
}

// `policy`: the flags' scope, floor and cost model, for every variant alike.
// A finite `fraction` is a keep budget (M unused); NaN runs at M.
ke::VariantSpec variant(const keepless::core::Params& policy, const std::string& name, ke::Selector sel, std::int64_t M,
                        double fraction, std::uint8_t costs = 7) {
  ke::VariantSpec v;
  v.name = name;
  v.selector = sel;
  v.params.scope = policy.scope;
  v.params.coverage_floor = policy.coverage_floor;
  v.params.theta = policy.theta;
  v.params.cost_model = policy.cost_model;
  v.params.track_terms = policy.track_terms;
  v.params.maturity_keyframes = policy.maturity_keyframes;
  v.params.pair_capacity = std::isfinite(fraction) ? keepless::core::Params{}.pair_capacity : M;
  if (std::isfinite(fraction)) {
    v.params.budget = policy.budget;  // its track share
    v.params.budget.kind = keepless::core::BudgetKind::kFraction;
    v.params.budget.fraction = fraction;
  }
  v.params.cost_terms = costs;
  v.params.spatial_weight = policy.spatial_weight;
  return v;
}

ke::RunResult run(const ke::Scenario& sc, const ke::VariantSpec& spec, const ke::SimOptions& o, std::uint64_t seed) {
  ke::SimOptions so = o;
  so.seed = seed;
  ke::RunResult r = ke::run_slam(sc, spec, so);
  std::cerr << "  " << sc.name << " seed " << seed << " " << spec.name << " M=" << spec.params.pair_capacity << ": mps "
            << r.mps << "/" << r.mps_created << " culled " << r.selector_culled << " kfs " << r.kfs << " lost "
            << r.track_failures << " ate " << r.ate_m << " m, ba " << r.ba_s << " s, total " << r.total_s << " s\n";
  return r;
}

// The paper's ablation (section IV-F) besides all costs (ours): c_c, c_c + c_s, c_c + c_b.
const std::pair<const char*, std::uint8_t> kAblation[3] = {{"c_c", 1}, {"c_c+c_s", 3}, {"c_c+c_b", 5}};

// Runs one input over every seed: the original, then per operating point
// keepless and the equal-count baselines; the ablation on TUM.
void evaluate(const std::function<ke::Scenario(std::uint64_t)>& make, const ke::InputInfo& info, const Args& a,
              const ke::SimOptions& o, ke::EvalSummary* summary) {
  const std::size_t first = summary->comparisons.size();
  const bool ablate = a.ablation && info.kind == "trajectory" && (info.group == "tum" || a.ablation_all);
  for (int si = 0; si < a.seeds; ++si) {
    const std::uint64_t seed = a.first_seed + static_cast<std::uint64_t>(si);
    const ke::Scenario sc = make(seed);
    ke::SimOptions so = o;
    so.snapshot_frame = static_cast<int>(sc.frames.size() / 2);
    const ke::RunResult original = run(sc, variant(a.policy, "original", ke::Selector::kNone, 0, NAN), so, seed);
    for (std::size_t p = 0; p < a.ops.size(); ++p) {
      if (si == 0) {
        ke::Comparison c;
        c.info = info;
        c.target_fraction = a.ops[p].fraction;
        c.M = std::isfinite(c.target_fraction) ? 0 : a.ops[p].M;  // a fraction is a keep budget
        summary->comparisons.push_back(c);
      }
      ke::Comparison& c = summary->comparisons[first + p];
      c.original.push_back(record_of(original, seed));
      const ke::RunResult ours = run(sc, variant(a.policy, "ours", ke::Selector::kKeepless, c.M, c.target_fraction), so, seed);
      c.ours.push_back(record_of(ours, seed));
      if (a.baselines) {
        const ke::RunResult anms = run(sc, variant(a.policy, "anms", ke::Selector::kAnms, c.M, c.target_fraction), so, seed);
        c.random.push_back(record_of(run(sc, variant(a.policy, "random", ke::Selector::kRandom, c.M, c.target_fraction), so, seed), seed));
        c.longest_track.push_back(record_of(run(sc, variant(a.policy, "longest_track", ke::Selector::kLongestTrack, c.M, c.target_fraction), so, seed), seed));
        c.anms.push_back(record_of(anms, seed));
        if (si == 0 && p == 0) summary->snapshots.push_back(ke::Snapshot{info.name, info.kind, sc.cam.width, sc.cam.height, c.M, ours.snapshot, anms.snapshot});
      }
      if (ablate && p == 0)
        for (const auto& [costs, terms] : kAblation)
          c.ablation.push_back(record_of(run(sc, variant(a.policy, costs, ke::Selector::kKeepless, c.M, c.target_fraction, terms), so, seed), seed));
    }
  }
}

double error_floor_of(const Args& a, const std::string& group) {
  const auto it = a.error_floor.find(group);
  return it == a.error_floor.end() ? 0.0 : it->second;
}

// Prints (and writes to --out) the outputs of the runs in `summary`.
int finish(const Args& a, ke::EvalSummary* summary) {
  for (ke::Comparison& c : summary->comparisons) {
    c.info.error_floor_m = error_floor_of(a, c.info.group);
    summary->runs.push_back(ke::summarize(c));
  }
  summary->error_floor = a.error_floor;
  if (!a.out.empty()) {
    std::string err;
    if (!ke::write_outputs(*summary, a.out, &err)) fail(err);
  }
  if (summary->mode != "quick") std::cout << ke::markdown_tables(*summary) << "\n";
  std::cout << ke::json_summary(*summary) << std::endl;
  return 0;
}

int report_again(const Args& a) {
  ke::EvalSummary summary;
  std::string err;
  for (const std::string& dir : a.report)
    if (!ke::read_outputs(dir, &summary, &err)) fail(err);
  return finish(a, &summary);
}

}  // namespace

int main(int argc, char** argv) {
  const auto t0 = std::chrono::steady_clock::now();
  Args a = parse(argc, argv);
  if (!a.data_root.empty()) add_data_root(&a);
  if (!a.report.empty()) return report_again(a);
  if (a.window_sizes && !a.data_root.empty()) {  // the real images are measured by --images / --rgbd
    a.images.clear();
    a.bal.clear();
  }
  if (a.trajectories.empty() && a.images.empty() && a.vo.empty() && a.bal.empty())
    fail("no input: give --data-root, --trajectory, --images, --rgbd, --image-tracks or --bal");

  ke::EvalSummary summary;
  summary.mode = a.quick ? "quick" : "full";
  for (int i = 0; i < a.seeds; ++i) summary.seeds.push_back(a.first_seed + static_cast<std::uint64_t>(i));
  for (int i = 0; i < argc; ++i) summary.command += (i ? " " : "") + std::string(argv[i]);

  ke::SimOptions sim;
  sim.window = a.window > 0 ? a.window : (a.quick ? 6 : 8);
  sim.ba_iterations = a.ba_iterations > 0 ? a.ba_iterations : (a.quick ? 5 : 10);
  sim.ba_robust_iterations = std::max(1, sim.ba_iterations / 2);
  summary.settings = "window " + std::to_string(sim.window) + ", local BA " + std::to_string(sim.ba_robust_iterations) +
                     " + " + std::to_string(sim.ba_iterations) + " iterations";
  summary.scope = keepless::core::to_string(a.policy.scope);
  summary.cost_model = keepless::core::to_string(a.policy.cost_model);
  summary.coverage_floor = a.policy.coverage_floor;
  summary.settings += "; keepless scope " + summary.scope + ", coverage floor " +
                      std::to_string(summary.coverage_floor) + ", cost " + summary.cost_model;
  // The real VO's own scope (vo_eval.cpp): a kept fraction decides the new
  // keyframe's points unless --decide window; its local BA is its own.
  const bool fraction_ops = std::any_of(a.ops.begin(), a.ops.end(), [](const auto& op) { return std::isfinite(op.fraction); });
  if (!a.vo.empty() && a.decide_window)
    summary.settings += a.policy.scope == keepless::core::Scope::kAuto ? " (the real VO: deciding its window, scope auto)"
                                                                       : " (the real VO: scope window, deciding its window)";
  else if (!a.vo.empty() && fraction_ops && a.policy.scope != keepless::core::Scope::kNewest)
    summary.settings += " (the real VO: scope newest under a kept fraction)";
  if (a.policy.theta != keepless::core::Params{}.theta) summary.settings += ", theta " + std::to_string(a.policy.theta);
  if (a.policy.budget.track_share > 0) summary.settings += ", track share " + std::to_string(a.policy.budget.track_share);
  if (a.policy.budget.track_share > 0 && a.policy.budget.track_share_from > 0)
    summary.settings += " from F " + std::to_string(a.policy.budget.track_share_from);
  if (a.policy.budget.track_share > 0 && a.policy.budget.track_share_to < 1)
    summary.settings += " to F " + std::to_string(a.policy.budget.track_share_to);
  if (a.policy.maturity_keyframes > 0) summary.settings += ", maturity " + std::to_string(a.policy.maturity_keyframes);
  if (a.tracked_flags) summary.settings += a.policy.tracked_first ? ", tracked first" : ", tracked flags";
  if (a.weak_keyframe > 0) summary.settings += ", a keyframe below " + std::to_string(a.weak_keyframe) + " inliers";
  if (a.keyframe_ratio != 0.9) summary.settings += ", keyframe ratio " + std::to_string(a.keyframe_ratio);
  if (a.anms_variant == keepless::eval::vo::AnmsVariant::kSpread) summary.settings += ", ANMS by spread alone";
  if (a.anms_variant == keepless::eval::vo::AnmsVariant::kResponse) summary.settings += ", ANMS by response alone";
  if (a.anms_variant == keepless::eval::vo::AnmsVariant::kTrack) summary.settings += ", ANMS by track length";
  if (a.policy.defer_keyframes > 0) summary.settings += ", defer " + std::to_string(a.policy.defer_keyframes);
  if (a.defer_fixed) summary.settings += ", excluded points fixed in BA";
  if (a.defer_refine) summary.settings += ", excluded points refined";
  if (a.defer_alternate) summary.settings += ", local poses refined against them";
  if (a.decide_window) summary.settings += ", the window's points decided";
  if (a.hashed_ids) summary.settings += ", ties by hashed id";
  if (a.policy.spatial_weight != 1) summary.settings += ", spatial weight " + std::to_string(a.policy.spatial_weight);
  if (a.policy.cost_terms != keepless::core::Params{}.cost_terms)
    summary.settings += ", cost terms " + std::to_string(a.policy.cost_terms);
  if (a.keyframe_culling == ke::vo::KeyframeCulling::kOff) summary.settings += ", no keyframe culling";
  if (a.keyframe_culling == ke::vo::KeyframeCulling::kCountCulled) {
    summary.settings += ", keyframe culling counts culled points";
  }
  if (a.policy.cost_model == keepless::core::CostModel::kTrack) {
    summary.settings += ", track terms " + std::to_string(a.policy.track_terms);
  }
  if (!a.cpus.empty()) {  // the CPU times are per thread; pinning keeps other work off their cores
    const keepless::platform::PinResult pin = keepless::platform::pin_to_cpus(a.cpus);
    summary.settings += "; cpus " + pin.granted;
    if (!pin.ok) summary.settings += " (pinning to " + a.cpus + " refused: " + pin.error + ")";
  }

  std::vector<std::pair<std::string, ke::WindowSizes>> sizes;  // --window-sizes
  std::map<std::string, ke::WindowSizes> group_sizes;
  for (const auto& t : a.trajectories) {
    const std::string fmt = t.format.empty() ? guess_format(t.path) : t.format;
    ke::TrajectoryFormat tf;
    if (!ke::parse_format(fmt, &tf)) fail("bad format " + fmt);
    ke::Trajectory traj;
    std::string err;
    if (!ke::read_trajectory(t.path, tf, &traj, &err)) fail(err);
    ke::WorldOptions w = ke::world_defaults(tf);
    w.keypoints_per_frame = a.keypoints > 0 ? a.keypoints : (a.quick ? 400 : 600);
    w.max_keyframes = a.max_keyframes >= 0 ? a.max_keyframes : (a.quick ? 40 : 50);
    if (a.noise_free) {
      w.pixel_noise = 0;
      w.outlier_ratio = 0;
      w.odom_noise_t = 0;
      w.odom_noise_r_deg = 0;
    }
    ke::InputInfo info;
    info.input = t.path;
    info.name = short_name(t.path);
    info.group = group_of(fmt, info.name);
    info.kind = "trajectory";
    info.sim3 = w.cam.baseline <= 0;
    std::cerr << "keepless_eval: " << t.path << " (" << fmt << ")\n";
    summary.settings_inputs.push_back(info.name + ": " + std::to_string(w.keypoints_per_frame) + " keypoints, first " +
                                      std::to_string(w.max_keyframes) + " keyframes");
    const auto make = [&](std::uint64_t seed) {
      ke::WorldOptions ws = w;
      ws.seed = ke::input_seed(seed, info.name);  // by name, never by list position
      return ke::make_synthetic_scenario(traj, ws, t.path, info.name, info.group);
    };
    if (a.window_sizes) {
      ke::SimOptions so = sim;
      so.measure_windows = true;
      const ke::RunResult r = run(make(a.first_seed), variant(a.policy, "original", ke::Selector::kNone, 0, NAN), so, a.first_seed);
      sizes.emplace_back(info.name, r.window_sizes);
      group_sizes[info.group].max_with(r.window_sizes);
      continue;
    }
    evaluate(make, info, a, sim, &summary);
  }
  if (a.window_sizes) {
    for (const auto& in : a.vo) {
      std::string name, err;
      ke::WindowSizes w;
      // Replayed at keepless_node's default capacities (K = 20).
      if (!keepless::eval::vo::measure_real_windows(in, a.vo_frames(), a.first_seed,
                                                    keepless::platform::window_capacities({}), &name, &w, &err))
        fail(err);
      sizes.emplace_back(name, w);
    }
    for (const auto& [group, w] : group_sizes) sizes.emplace_back("group " + group, w);
    std::cout << (a.trajectories.empty() ? std::string() : "synthetic back end: " + summary.settings + "; ")
              << (a.vo.empty() ? "" : "real VO: its defaults (local BA of at most 20 keyframes); ") << "seed "
              << a.first_seed << ", original runs\n\n"
              << ke::window_sizes_table(sizes) << "\n"
              << ke::window_sizes_json(sizes) << std::endl;
    return 0;
  }

  if (!a.images.empty()) {
    ke::ImageOptions io;
    io.max_frames = a.image_frames >= 0 ? a.image_frames : (a.quick ? 12 : 0);
    io.features = a.quick ? 1000 : 2000;
    if (a.noise_free) io.odom_noise_t = io.odom_noise_r_deg = 0;
    ke::Scenario base;
    std::string err;
    std::cerr << "keepless_eval: image tracks " << a.images << "\n";
    io.seed = ke::input_seed(a.first_seed, "images");
    if (!ke::make_image_scenario(a.images, a.calib, a.poses, io, &base, &err)) fail(err);
    ke::InputInfo info;
    info.input = base.input;
    info.name = base.name;
    info.group = base.group;
    info.kind = base.kind;
    info.sim3 = base.cam.baseline <= 0;  // monocular: scale is not observable
    // The ORB tracks are fixed; each seed draws its own odometry noise.
    evaluate([&](std::uint64_t seed) {
               ke::Scenario sc = base;
               ke::add_odometry(&sc, io.odom_noise_t, io.odom_noise_r_deg, ke::input_seed(seed, info.name));
               return sc;
             },
             info, a, sim, &summary);
  }

  if (!a.vo.empty()) {  // the real VO, closed loop on real images
    keepless::eval::vo::VoEvalOptions vo;
    vo.frames = a.vo_frames();
    if (a.frames_last == -2 && a.quick) vo.frames.max_frames = 60;  // --quick: the first 60 frames
    vo.seeds = summary.seeds;
    for (const OperatingPoint& op : a.ops) vo.ops.emplace_back(op.fraction, op.M);
    if (a.baselines) vo.baselines = a.vo_baselines;
    else vo.baselines.clear();
    vo.policy = a.policy;
    vo.tracked_flags = a.tracked_flags;
    vo.weak_keyframe = a.weak_keyframe;
    vo.keyframe_ratio = a.keyframe_ratio;
    vo.anms_variant = a.anms_variant;
    vo.defer_fixed = a.defer_fixed;
    vo.defer_refine = a.defer_refine;
    vo.defer_alternate = a.defer_alternate;
    vo.decide_window = a.decide_window;
    vo.hashed_ids = a.hashed_ids;
    vo.keyframe_culling = a.keyframe_culling;
    vo.out = a.out;
    std::string err;
    for (const auto& in : a.vo)
      if (!keepless::eval::vo::evaluate_real_vo(in, vo, &summary.comparisons, &err)) fail(err);
  }

  for (const std::string& b : a.bal)
    for (const OperatingPoint& op : a.ops) {
      ke::BalOptions bo;
      bo.target_fraction = op.fraction;
      bo.M = op.M;
      bo.max_iterations = a.quick ? 10 : 50;
      bo.seeds = summary.seeds;
      bo.baselines = a.baselines;
      ke::Comparison c;
      std::string err;
      std::cerr << "keepless_eval: BAL " << b << "\n";
      if (!ke::run_bal(b, bo, &c, &err)) fail(err);
      summary.comparisons.push_back(std::move(c));
    }

  summary.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return finish(a, &summary);
}
