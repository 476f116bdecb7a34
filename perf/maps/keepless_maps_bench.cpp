// keepless_maps_bench: what map compression costs in accuracy on a real
// reconstruction, checked by COLMAP's own bundle adjuster.
//
//   keepless_maps_bench [--data DIR] [--colmap BIN] [--M 30,100,200 | --keep-fraction 0.1,0.3] [--K 20]
//                       [--seeds 5] [--work DIR] [--cost paper|authors|information|track] [--theta 0.5]
//                       [--model DIR --poses FILE] [--ba-iterations 100] [--exact-floor 30] [--tie-seeds 0]
//                       [--track-share 0.5,1] [--against-filter 1.1]
//
// On the shared fixture (DIR/colmap_kitti06_first51, 51 KITTI 06 images; or
// --model, a COLMAP model of KITTI frames, with their --poses):
// the full model is re-solved by `colmap bundle_adjuster` (fixed intrinsics,
// SOURCES.md's flags); then, per M (or per keep fraction F: keepless with
// that keep budget per window, M unused, reported as 0), keepless replay and whole (each with the
// per-image floor), and at replay's point count: random (--seeds seeds),
// longest-track-first and `colmap point_filtering` (the --min_track_len
// whose count is nearest); then keepless_exact, the whole model at exactly
// K points (F x the model's points, or replay's count under --M) with every
// image's floor, with longest-track-first at K and the filter nearest K
// (rows *_exact); with --tie-seeds N, those two rules again over N
// relabellings of the points, whose ids decide their ties (rows
// *_exact_ties, mean±sd); with --track-share, keepless_exact with part of
// the count by track length (rows keepless_exact_share<S>, and their ties);
// with --against-filter R, only the exact rows, at the count of the filter
// run nearest F x the model's points (so every row keeps the same number)
// and with the floor R x that run's poorest image's observations.
// Each sparsified model is bundle-adjusted the same
// way. Printed per row: points kept, min observations per image, BA time
// and termination, camera-centre deviation from the full solution (max and
// RMS, same gauge), and ATE (RMS) against the KITTI poses after the
// fixture's similarity. A BA that does not terminate by convergence is
// reported as such: "conv" NO, "converged" 0 and "failed" per row (for
// random, the seeds whose BA did not converge, which its means include),
// "not_converged" over all rows. Last line: a JSON summary.

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "cli/cli.hpp"
#include "keepless/io/atomic_file.hpp"
#include "keepless/io/colmap_model.hpp"
#include "keepless/io/keyframes.hpp"
#include "keepless/io/trajectory_alignment.hpp"
#include "keepless/platform/cpu_pinning.hpp"
#include "keepless/platform/monotonic_clock.hpp"
#include "sparsify/exact_count.hpp"
#include "sparsify/modes.hpp"
#include "sparsify/model_run.hpp"

namespace {

namespace io = keepless::io;
namespace core = keepless::core;
namespace sp = keepless::sparsify;
namespace platform = keepless::platform;

struct Options {
  std::string data = "../shared/data";
  std::string colmap = "colmap";
  std::vector<std::int64_t> Ms = {30, 100, 200};
  std::vector<double> fractions;  // --keep-fraction: keep budgets instead of Ms
  std::uint32_t K = 20;
  int seeds = 5;
  std::string work;
  std::string model;  // --model: a COLMAP model instead of the fixture (with --poses)
  std::string poses;
  core::CostModel cost = core::CostModel::kPaper;  // keepless's rows (as keepless_sparsify --cost)
  double theta = core::Params{}.theta;             // keepless's keep threshold (as keepless_sparsify --theta)
  std::uint64_t ba_iterations = 100;               // bundle_adjuster's limit (COLMAP's default)
  std::uint32_t exact_floor = sp::kDefaultFloor;   // observations per image the exact rows keep at least
  int tie_seeds = 0;                               // relabellings for the *_exact_ties rows
  std::vector<double> track_shares;                // --track-share: keepless_exact_share<S> rows
  double against_filter = 0;                       // --against-filter R: the filter's count, floor R x its minimum
  std::string cpus;                                // --cpus: pin this process and its colmap children
};

struct Ba {
  bool converged = false;
  double seconds = 0;
  io::ColmapModel model;
};

struct Row {
  std::string method;
  std::int64_t M = 0;
  std::uint64_t points = 0;
  std::uint32_t min_obs = 0;
  double ba_s = 0;
  bool converged = false;
  double dev_max = 0, dev_rms = 0, ate = 0;
};

[[noreturn]] void die(const std::string& why) {
  std::fprintf(stderr, "keepless_maps_bench: %s\n", why.c_str());
  std::exit(1);
}

std::string quote(const std::string& s) { return "'" + s + "'"; }

// `s` inside a JSON string: quotes, backslashes and control bytes escaped.
std::string json_escaped(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char u[8];
      std::snprintf(u, sizeof u, "\\u%04x", c);
      out += u;
    } else {
      out += c;
    }
  }
  return out;
}

// Runs `colmap bundle_adjuster` on `in` into `out` (fixed intrinsics).
Ba bundle_adjust(const Options& opt, const std::string& in, const std::string& out) {
  ::mkdir(out.c_str(), 0777);
  const std::string log = out + ".log";
  const std::string cmd = "QT_QPA_PLATFORM=offscreen " + quote(opt.colmap) + " bundle_adjuster --input_path " +
                          quote(in) + " --output_path " + quote(out) +
                          " --BundleAdjustment.refine_focal_length 0 --BundleAdjustment.refine_principal_point 0"
                          " --BundleAdjustment.refine_extra_params 0 --BundleAdjustment.max_num_iterations " +
                          std::to_string(opt.ba_iterations) + " > " + quote(log) + " 2>&1";
  Ba ba;
  const std::uint64_t t0 = platform::monotonic_ns();
  const int rc = std::system(cmd.c_str());
  ba.seconds = static_cast<double>(platform::monotonic_ns() - t0) / 1e9;
  std::string text, error;
  if (!io::read_file(log, &text, &error)) text.clear();  // no log: not counted as converged
  ba.converged = rc == 0 && text.find("Termination : Convergence") != std::string::npos;
  io::ColmapFormat format;
  if (rc != 0 || !io::read_colmap_model(out, &ba.model, &format, &error)) {
    die("bundle_adjuster failed on " + in + " (see " + log + ")");
  }
  return ba;
}

// KITTI camera centres by frame (3x4 camera-to-world, row-major, a line each).
std::vector<std::array<double, 3>> read_kitti_centres(const std::string& path) {
  std::ifstream in(path);
  if (!in) die("cannot read " + path);
  std::vector<std::array<double, 3>> c;
  double m[12];
  while (true) {
    for (double& v : m) in >> v;
    if (!in) break;
    c.push_back({m[3], m[7], m[11]});
  }
  return c;
}

// The model's camera centres and the KITTI frames its images name
// ("000012.png" = frame 12), pair by pair.
void centres_and_truth(const io::ColmapModel& model, const std::vector<std::array<double, 3>>& gt,
                       std::vector<std::array<double, 3>>* est, std::vector<std::array<double, 3>>* ref) {
  for (const io::ColmapImage& im : model.images) {
    const std::size_t frame = std::strtoul(im.name.c_str(), nullptr, 10);
    if (frame >= gt.size()) die("no KITTI pose for " + im.name);
    io::colmap_camera_centre(im, est->emplace_back().data());
    ref->push_back(gt[frame]);
  }
}

// RMS ATE: the model's centres aligned to the KITTI frames by the best
// similarity (Umeyama), as the fixture's own sim3_to_kitti_gt.txt was made.
double ate(const io::ColmapModel& model, const std::vector<std::array<double, 3>>& gt) {
  std::vector<std::array<double, 3>> est, ref;
  centres_and_truth(model, gt, &est, &ref);
  return io::aligned_deviation(ref, est).rms;
}

// That similarity itself, for a --model without a sim3 file: it puts the
// model in metres (the network's baseline cost, the deviations).
io::Similarity similarity_to_truth(const io::ColmapModel& model, const std::vector<std::array<double, 3>>& gt) {
  std::vector<std::array<double, 3>> est, ref;
  centres_and_truth(model, gt, &est, &ref);
  if (est.size() < 3) die("a --model needs at least 3 images with KITTI poses");
  const Eigen::Matrix4d T = io::umeyama_similarity(ref, est);
  io::Similarity s;
  s.scale = T.block<3, 1>(0, 0).norm();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) s.rotation[3 * i + j] = T(i, j) / s.scale;
    s.translation[i] = T(i, 3);
  }
  return s;
}

// Deviation of `model`'s centres from the full solution's, in metres: the
// full solution through the fixture's similarity, `model` aligned onto it.
io::AlignedDeviation deviation(const io::ColmapModel& full, const io::Similarity& sim, const io::ColmapModel& model) {
  std::vector<std::array<double, 3>> ref, est;
  io::matched_centres(full, model, &ref, &est);
  for (auto& c : ref) {
    const std::array<double, 3> u = c;
    io::to_metric(sim, u.data(), c.data());
  }
  return io::aligned_deviation(ref, est);
}

std::uint32_t min_observations(const io::ColmapModel& m) {
  const std::vector<std::uint32_t> n = io::observations_per_image(m);
  return n.empty() ? 0 : *std::min_element(n.begin(), n.end());
}

// "0.5,1" (shortest form) for a JSON array.
std::string join(const std::vector<double>& v) {
  std::string out;
  for (const double x : v) {
    char item[32];
    std::snprintf(item, sizeof item, "%s%g", out.empty() ? "" : ",", x);
    out += item;
  }
  return out;
}

// Comma-separated items, none empty ("", "30," and "1,,2" are refused).
bool split_list(const char* s, std::vector<std::string>* items) {
  items->clear();
  std::string item;
  for (const char* c = s;; ++c) {
    if (*c != ',' && *c != '\0') {
      item += *c;
      continue;
    }
    if (item.empty()) return false;
    items->push_back(item);
    item.clear();
    if (*c == '\0') return true;
  }
}

// Comma-separated integers, each whole (a stray character, e.g. "30x", or an
// empty item makes the list empty: the caller reports the bad value).
std::vector<std::int64_t> parse_list(const char* s) {
  std::vector<std::string> items;
  if (!split_list(s, &items)) return {};
  std::vector<std::int64_t> v;
  for (const std::string& item : items) {
    std::int64_t n = 0;
    const auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), n);
    if (ec != std::errc() || end != item.data() + item.size()) return {};
    v.push_back(n);
  }
  return v;
}

// The model's points under one labelling: ids as read (seed 0) or permuted
// by a seeded shuffle. Which points tie in an order (the network's per-pair
// tie order, longest-track-first's equal lengths) is decided by the ids
// alone, so relabelled runs show how far the ties move a figure.
struct Labelled {
  io::Keyframes kfs;                               // image-name order, metric
  std::vector<std::vector<core::PointId>> images;  // each keyframe's observed point ids
  std::vector<std::uint64_t> ids;                  // by point index
  std::vector<std::size_t> longest;                // point indices, longest track first (ties: lower id)
};

Labelled label(const io::ColmapModel& original, const io::Similarity& sim, bool unmapped, int seed) {
  io::ColmapModel m = original;
  Labelled l;
  l.ids.resize(m.points.size());
  if (seed == 0) {
    for (std::size_t i = 0; i < l.ids.size(); ++i) l.ids[i] = m.points[i].id;
  } else {
    std::iota(l.ids.begin(), l.ids.end(), std::uint64_t{1});
    std::mt19937_64 rng(0x5eed0000u + static_cast<std::uint64_t>(seed));  // not the random baseline's stream
    std::shuffle(l.ids.begin(), l.ids.end(), rng);
    std::map<std::uint64_t, std::uint64_t> relabel;
    for (std::size_t i = 0; i < l.ids.size(); ++i) relabel[m.points[i].id] = l.ids[i];
    for (io::ColmapPoint3D& p : m.points) p.id = relabel[p.id];
    for (io::ColmapImage& im : m.images) {
      for (io::ColmapPoint2D& p : im.points2D) {
        if (p.point3D_id != io::kNoPoint3D) p.point3D_id = relabel[p.point3D_id];
      }
    }
  }
  l.kfs = io::keyframes_from_colmap(m, io::KeyframeOrder::kName, sim, unmapped);
  l.images = io::observed_point_ids(m, l.kfs);
  l.longest.resize(m.points.size());
  std::iota(l.longest.begin(), l.longest.end(), 0);
  std::stable_sort(l.longest.begin(), l.longest.end(), [&](std::size_t x, std::size_t y) {
    const auto& p = m.points;
    return p[x].track.size() != p[y].track.size() ? p[x].track.size() > p[y].track.size() : l.ids[x] < l.ids[y];
  });
  return l;
}

struct Bench {
  Options opt;
  io::ColmapModel original;
  io::Similarity sim;
  std::vector<std::array<double, 3>> gt;
  io::ColmapModel full;  // the full model after BA
  int runs = 0;

  // Bundle-adjusts the original model minus `culled` and scores it.
  Row score(const std::string& method, std::int64_t M, const std::vector<bool>& culled) {
    io::ColmapModel m = original;
    io::remove_points(&m, culled);
    const std::string dir = opt.work + "/run" + std::to_string(runs++);
    std::string error;
    if (!io::write_colmap_model(dir, m, io::ColmapFormat::kBinary, &error)) die(error);
    const Ba ba = bundle_adjust(opt, dir, dir + "_ba");
    const io::AlignedDeviation d = deviation(full, sim, ba.model);
    Row r{method, M, m.points.size(), min_observations(m), ba.seconds, ba.converged, d.max, d.rms, ate(ba.model, gt)};
    std::printf("%-22s %5" PRId64 " %7" PRIu64 " %7u %8.2f %-5s %10.4f %10.4f %8.4f\n", r.method.c_str(), r.M, r.points,
                r.min_obs, r.ba_s, r.converged ? "yes" : "NO", r.dev_max, r.dev_rms, r.ate);
    std::fflush(stdout);
    return r;
  }

  std::vector<bool> keepless_culls(sp::Mode mode, std::int64_t M, double fraction, const Labelled& l) {
    core::Params params;
    params.pair_capacity = std::max<std::int64_t>(M, 1);
    if (std::isfinite(fraction)) params.budget = {core::BudgetKind::kFraction, 0, fraction};
    params.cost_model = opt.cost;
    params.theta = opt.theta;
    params.image_width = static_cast<std::int32_t>(original.cameras.front().width);
    params.image_height = static_cast<std::int32_t>(original.cameras.front().height);
    sp::ModeResult r;
    if (sp::decide(l.kfs.file, mode, params, opt.K, &r) != core::Status::kOk) die("decide failed");
    sp::apply_floor(l.images, sp::kDefaultFloor, &r.decisions);
    return culls_of(r.decisions, l);
  }

  // The whole model at exactly `count` points with every image's `floor`
  // (sparsify::keep_exactly on one budgeted whole-model decision).
  std::vector<bool> exact_culls(std::uint64_t count, std::uint32_t floor, const Labelled& l, double track_share = 0.0) {
    core::Params params;
    params.budget = {core::BudgetKind::kPoints, count, 0.0};
    params.cost_model = opt.cost;
    params.theta = opt.theta;
    params.image_width = static_cast<std::int32_t>(original.cameras.front().width);
    params.image_height = static_cast<std::int32_t>(original.cameras.front().height);
    sp::ModeResult r;
    if (sp::decide(l.kfs.file, sp::Mode::kWhole, params, opt.K, &r) != core::Status::kOk) die("decide failed");
    const sp::ExactCount e =
        sp::keep_exactly(l.images, floor, count, r.thresholds, &r.decisions, track_share);
    std::printf("exact whole: %llu kept (%llu by the order, %u by the floor)%s\n",
                static_cast<unsigned long long>(e.kept), static_cast<unsigned long long>(e.from_order), e.restored,
                e.floor_fits ? "" : ": the floor alone keeps more");
    return culls_of(r.decisions, l);
  }

  // Which of the model's points (by index) `decisions` cull.
  std::vector<bool> culls_of(const std::vector<core::PointDecision>& decisions, const Labelled& l) const {
    std::vector<bool> culled(l.ids.size());
    for (std::size_t i = 0; i < culled.size(); ++i) {
      const std::int64_t s = sp::find_decision(decisions, l.ids[i]);
      culled[i] = s >= 0 && decisions[s].verdict == core::Verdict::kCull;
    }
    return culled;
  }

  // Keeps `order`'s first n points.
  std::vector<bool> keep_first(const std::vector<std::size_t>& order, std::uint64_t n) const {
    std::vector<bool> culled(original.points.size(), true);
    for (std::uint64_t i = 0; i < n && i < order.size(); ++i) culled[order[i]] = false;
    return culled;
  }
};

struct Stat {
  double mean = 0, sd = 0;
};
Stat stat(const std::vector<double>& v) {
  Stat s;
  for (double x : v) s.mean += x / v.size();
  for (double x : v) s.sd += (x - s.mean) * (x - s.mean);
  s.sd = v.size() > 1 ? std::sqrt(s.sd / (v.size() - 1)) : 0;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  Bench b;
  Options& opt = b.opt;
  namespace cli = keepless::cli;
  constexpr const char* kTool = "keepless_maps_bench";
  const std::vector<cli::Flag> flags = {
      {"--model", "DIR", "a COLMAP model (cameras, images, points3D) instead of the fixture; its\n"
                         "images named by KITTI frame (000012.png = frame 12); needs --poses"},
      {"--poses", "FILE", "with --model: the KITTI poses of its frames (the similarity to them is\n"
                          "fitted, as the fixture's sim3_to_kitti_gt.txt was)"},
      {"--data", "DIR", "the data folder holding colmap_kitti06_first51 and\n"
                        "kitti06_first51_niconielsen (default ../shared/data)"},
      {"--colmap", "BIN", "the colmap executable (default colmap, on PATH)"},
      {"--cpus", "LIST", "pin to these CPUs, e.g. 0,1 or 2-3, colmap's runs too (the JSON's \"cpus\"\n"
                         "says what was granted)"},
      {"--M", "LIST", "comma-separated pair capacities (default 30,100,200)"},
      {"--keep-fraction", "LIST", "comma-separated keep budgets F in [0, 1] instead of --M (keepless\n"
                                  "keeps F of the points its replay evaluates, every baseline as many)"},
      {"--K", "N", "replay window in keyframes (default 20)"},
      {"--seeds", "N", "seeds of the random baseline (default 5)"},
      {"--work", "DIR", "where the models and BA runs go (default: a new /tmp/keepless_maps_bench_*)"},
      {"--cost", "paper|authors|information|track", "keepless's cost model (default paper)"},
      {"--theta", "T", "keepless's keep threshold theta_f in [0, 1] (default 0.5)"},
      {"--ba-iterations", "N", "bundle_adjuster's iteration limit for every model (default 100,\n"
                               "COLMAP's; raise it where the full model does not converge)"},
      {"--exact-floor", "L", "observations every image keeps in the keepless_exact rows, taken from\n"
                             "within the count (default 30, COLMAP's minimum inliers to register)"},
      {"--tie-seeds", "N", "also the keepless_exact and longest_track_exact rules over N relabellings\n"
                           "of the points (ids shuffled by seeds 1..N; rows *_exact_ties, mean±sd):\n"
                           "how far the orders' ties move the figures (default 0: off)"},
      {"--track-share", "LIST", "also keepless_exact with these track shares S in [0, 1] (S of the count\n"
                                "by track length, as keepless_sparsify --track-share; rows\n"
                                "keepless_exact_share<S>, and their ties with --tie-seeds)"},
      {"--against-filter", "R", "only the comparison at COLMAP's filter's own count: per F, the exact rows\n"
                                "keep exactly the points of the filter run nearest F x the model's points,\n"
                                "with the floor ceil(R x that run's poorest image's observations) instead of\n"
                                "--exact-floor (R >= 1: above the filter's minimum); no replay, whole or\n"
                                "random rows, and keepless_exact only without --track-share"},
  };
  const std::string help =
      cli::usage("usage: keepless_maps_bench [options]", flags,
                 "Sparsifies the 51-image KITTI 06 COLMAP fixture (or --model) at each M (replay, whole,\n"
                 "and baselines at replay's count), re-solves every model with `colmap\n"
                 "bundle_adjuster` and prints accuracy per row; the last line is a JSON summary.");
  for (int i = 1; i < argc; ++i) {
    const cli::Flag* flag = nullptr;
    const char* value = nullptr;
    int status = 0;
    if (!cli::next_flag(kTool, help, flags, argc, argv, &i, &flag, &value, &status)) return status;
    const std::string f = flag->name;
    std::uint64_t n = 0;
    const auto count = [&](std::uint64_t lo, std::uint64_t hi) {
      if (!core::parse_uint64(value, &n) || n < lo || n > hi) {
        std::exit(cli::usage_error(kTool, "bad value for " + f + ": '" + value + "' (an integer in " +
                                              std::to_string(lo) + ".." + std::to_string(hi) + ")"));
      }
      return n;
    };
    if (f == "--data") opt.data = value;
    else if (f == "--model") opt.model = value;
    else if (f == "--poses") opt.poses = value;
    else if (f == "--colmap") opt.colmap = value;
    else if (f == "--cpus") opt.cpus = value;
    else if (f == "--M") {
      opt.Ms = parse_list(value);
      if (opt.Ms.empty() || std::any_of(opt.Ms.begin(), opt.Ms.end(), [](std::int64_t m) { return m < 1; })) {
        std::exit(cli::usage_error(kTool, std::string("bad value for --M: '") + value + "' (integers >= 1)"));
      }
    } else if (f == "--keep-fraction" || f == "--track-share") {
      std::vector<double>& list = f == "--keep-fraction" ? opt.fractions : opt.track_shares;
      list.clear();
      std::vector<std::string> items;
      bool ok = split_list(value, &items);
      for (const std::string& t : items) {
        double x = 0;
        ok = ok && core::parse_finite_double(t, &x) && x >= 0 && x <= 1;
        list.push_back(x);
      }
      if (!ok) {
        return cli::usage_error(kTool, "bad value for " + f + ": '" + value + "' (numbers in [0, 1])");
      }
    } else if (f == "--K") opt.K = static_cast<std::uint32_t>(count(1, 100000));
    else if (f == "--seeds") opt.seeds = static_cast<int>(count(1, 1000));
    else if (f == "--work") opt.work = value;
    else if (f == "--ba-iterations") opt.ba_iterations = count(1, 100000);
    else if (f == "--exact-floor") opt.exact_floor = static_cast<std::uint32_t>(count(0, 1000000));
    else if (f == "--tie-seeds") opt.tie_seeds = static_cast<int>(count(0, 1000));
    else if (f == "--against-filter") {
      if (!core::parse_finite_double(value, &opt.against_filter) || !(opt.against_filter >= 1 && opt.against_filter <= 100)) {
        return cli::usage_error(kTool, std::string("bad value for --against-filter: '") + value + "' (a number in [1, 100])");
      }
    } else if (f == "--theta") {
      if (!core::parse_finite_double(value, &opt.theta) || !(opt.theta >= 0 && opt.theta <= 1)) {
        return cli::usage_error(kTool, std::string("bad value for --theta: '") + value + "' (a number in [0, 1])");
      }
    } else if (f == "--cost") {
      if (!core::parse_cost_model(value, &opt.cost)) {
        return cli::usage_error(kTool, std::string("bad value for --cost: '") + value + "' (paper, authors, information or track)");
      }
    }
  }
  if (opt.model.empty() != opt.poses.empty()) {
    return cli::usage_error(kTool, "--model and --poses go together");
  }
  if (opt.against_filter > 0 && opt.fractions.empty()) {
    return cli::usage_error(kTool, "--against-filter needs --keep-fraction");
  }
  if (opt.work.empty()) {
    char tmpl[] = "/tmp/keepless_maps_bench_XXXXXX";
    if (::mkdtemp(tmpl) == nullptr) die("mkdtemp failed");
    opt.work = tmpl;
  } else if (::mkdir(opt.work.c_str(), 0777) != 0 && errno != EEXIST) {
    die("cannot create --work " + opt.work + ": " + std::strerror(errno));
  }
  const std::string fixture = opt.data + "/colmap_kitti06_first51";
  const std::string model = opt.model.empty() ? fixture + "/sparse" : opt.model;
  std::string error;
  io::ColmapFormat format;
  if (!io::read_colmap_model(model, &b.original, &format, &error)) die(error);
  if (opt.model.empty()) {
    if (!io::read_similarity(fixture + "/sim3_to_kitti_gt.txt", &b.sim, &error)) die(error);
    b.gt = read_kitti_centres(opt.data + "/kitti06_first51_niconielsen/poses.txt");
  } else {
    b.gt = read_kitti_centres(opt.poses);
    b.sim = similarity_to_truth(b.original, b.gt);
  }

  std::string cpus = platform::current_cpus();
  if (!opt.cpus.empty()) {  // colmap's runs inherit the affinity
    const platform::PinResult pin = platform::pin_to_cpus(opt.cpus);
    cpus = pin.granted;
    if (!pin.ok) std::printf("cpus: pinning to %s refused: %s\n", opt.cpus.c_str(), pin.error.c_str());
  }
  std::printf("work dir %s; cpus %s\n", opt.work.c_str(), cpus.c_str());
  const Ba full = bundle_adjust(opt, model, opt.work + "/full_ba");
  b.full = full.model;
  const io::AlignedDeviation moved = deviation(b.full, b.sim, b.original);
  std::printf("full model: %zu points, BA %.2f s (%s), ATE %.4f m (mapper's model %.4f m; BA moved centres by max %.4f m)\n",
              b.original.points.size(), full.seconds, full.converged ? "converged" : "NOT converged",
              ate(b.full, b.gt), ate(b.original, b.gt), moved.max);

  // The points as read, and under --tie-seeds relabellings.
  const bool unmapped = opt.cost == core::CostModel::kAuthors;
  const Labelled as_read = label(b.original, b.sim, unmapped, 0);
  std::vector<Labelled> relabelled;
  for (int seed = 1; seed <= opt.tie_seeds; ++seed) relabelled.push_back(label(b.original, b.sim, unmapped, seed));
  // COLMAP's point_filtering: the count each --min_track_len leaves, from 2
  // until it keeps under 2 % of the points (a longer sequence has longer tracks).
  std::map<int, std::uint64_t> filter_count;
  for (int t = 2; t <= 64; ++t) {
    const std::string out = opt.work + "/filter" + std::to_string(t);
    ::mkdir(out.c_str(), 0777);
    const std::string cmd = "QT_QPA_PLATFORM=offscreen " + quote(opt.colmap) + " point_filtering --input_path " +
                            quote(model) + " --output_path " + quote(out) + " --min_track_len " +
                            std::to_string(t) + " > " + quote(out + ".log") + " 2>&1";
    io::ColmapModel m;
    if (std::system(cmd.c_str()) != 0 || !io::read_colmap_model(out, &m, &format, &error)) {
      die("point_filtering failed (" + out + ".log)");
    }
    filter_count[t] = m.points.size();
    if (m.points.size() * 50 < b.original.points.size()) break;
  }

  std::printf("%-22s %5s %7s %7s %8s %-5s %10s %10s %8s\n", "method", "M", "points", "min_obs", "BA_s", "conv",
              "dev_max_m", "dev_rms_m", "ATE_m");
  std::string json = "{\"rows\":[";
  int not_converged = 0;
  double fraction = NAN;  // the operating point's keep fraction (NaN: an M)
  // A row of the summary; the *_sd_m are 0 but for the rows over seeds.
  const auto add_json = [&](const std::string& method, std::int64_t M, std::uint64_t points, double min_obs,
                            double ba_s, Stat dev_max, Stat dev_rms, Stat ate_m, int converged, int failed) {
    // A number, or null where it is not finite (a failed BA's figures): valid JSON either way.
    const auto num = [](double v, const char* format) {
      char text[48] = "null";
      if (std::isfinite(v)) std::snprintf(text, sizeof text, format, v);
      return std::string(text);
    };
    char line[768];
    std::snprintf(line, sizeof line,
                  "%s{\"method\":\"%s\",\"M\":%" PRId64 ",\"points\":%" PRIu64
                  ",\"min_obs\":%s,\"ba_s\":%s,\"dev_max_m\":%s,\"dev_rms_m\":%s,\"ate_m\":%s,"
                  "\"ate_sd_m\":%s,\"dev_max_sd_m\":%s,\"dev_rms_sd_m\":%s,\"converged\":%d,\"failed\":%d,"
                  "\"keep_fraction\":%s}",
                  json.back() == '[' ? "" : ",", method.c_str(), M, points, num(min_obs, "%.1f").c_str(),
                  num(ba_s, "%.3f").c_str(), num(dev_max.mean, "%.5f").c_str(), num(dev_rms.mean, "%.5f").c_str(),
                  num(ate_m.mean, "%.5f").c_str(), num(ate_m.sd, "%.5f").c_str(), num(dev_max.sd, "%.5f").c_str(),
                  num(dev_rms.sd, "%.5f").c_str(), converged, failed, num(fraction, "%f").c_str());
    json += line;
    not_converged += failed;
  };
  const auto add_row = [&](const Row& r) {
    add_json(r.method, r.M, r.points, r.min_obs, r.ba_s, {r.dev_max, 0}, {r.dev_rms, 0}, {r.ate, 0},
             r.converged ? 1 : 0, r.converged ? 0 : 1);
  };
  // Rows over seeds (each printed as it is scored): one line and one JSON
  // row of means, with the sd of the deviations and the ATE.
  const auto add_seeds = [&](const std::string& method, std::int64_t M, std::uint64_t points,
                             const std::vector<Row>& runs) {
    std::vector<double> dmax, drms, at, mins, ba_s;
    int converged = 0;
    for (const Row& r : runs) {
      dmax.push_back(r.dev_max);
      drms.push_back(r.dev_rms);
      at.push_back(r.ate);
      mins.push_back(r.min_obs);
      ba_s.push_back(r.ba_s);
      converged += r.converged;
    }
    const int n = static_cast<int>(runs.size());
    const Stat sm = stat(dmax), sr = stat(drms), sa = stat(at), smin = stat(mins);
    std::printf("%-22s %5" PRId64 " %7" PRIu64 " %7.1f %8.2f %d/%d   %5.4f±%.4f %5.4f±%.4f %.4f±%.4f%s\n",
                (method + " (mean±sd)").c_str(), M, points, smin.mean, stat(ba_s).mean, converged, n, sm.mean, sm.sd,
                sr.mean, sr.sd, sa.mean, sa.sd, converged < n ? "  (includes seeds whose BA did not converge)" : "");
    add_json(method, M, points, smin.mean, stat(ba_s).mean, sm, sr, sa, converged, n - converged);
  };
  Row full_row{"full", 0, b.original.points.size(), min_observations(b.original), full.seconds, full.converged, 0, 0,
               ate(b.full, b.gt)};
  add_row(full_row);
  std::vector<std::pair<std::int64_t, double>> ops;  // (M, NaN) or (0, F)
  if (opt.fractions.empty()) {
    for (const std::int64_t M : opt.Ms) ops.emplace_back(M, NAN);
  } else {
    for (const double F : opt.fractions) ops.emplace_back(0, F);
  }
  for (const auto& [M, F] : ops) {
    fraction = F;
    if (std::isfinite(F)) std::printf("keep fraction %.2f (a keep budget per window; M unused)\n", F);
    // COLMAP's own filter: the run whose count is nearest `target`, read into
    // *filtered; its track length.
    const auto nearest_filter = [&](std::uint64_t target, io::ColmapModel* filtered) {
      int best = 2;
      for (const auto& [t, count] : filter_count) {
        const auto gap = [&](std::uint64_t c) { return c > target ? c - target : target - c; };
        if (gap(count) < gap(filter_count[best])) best = t;
      }
      if (!io::read_colmap_model(opt.work + "/filter" + std::to_string(best), filtered, &format, &error)) die(error);
      return best;
    };
    const auto filter_row = [&](std::uint64_t target, const std::string& suffix) {
      io::ColmapModel filtered;
      const int best = nearest_filter(target, &filtered);
      std::vector<bool> culled(b.original.points.size(), true);
      std::map<std::uint64_t, bool> in;
      for (const auto& p : filtered.points) in[p.id] = true;
      for (std::size_t i = 0; i < culled.size(); ++i) culled[i] = in.count(b.original.points[i].id) == 0;
      add_row(b.score("colmap_filter_len" + std::to_string(best) + suffix, M, culled));
    };
    // The whole model at exactly K points with every image's floor, against
    // longest-track-first at K and COLMAP's filter nearest K: K = F x the
    // model's points (or replay's count under --M), or under --against-filter
    // the count of the filter run nearest that, so all three keep the same.
    const std::uint64_t target =
        std::isfinite(F) ? static_cast<std::uint64_t>(std::floor(F * b.original.points.size() + 0.5)) : 0;
    std::uint64_t exact = target;
    std::uint32_t exact_floor = opt.exact_floor;
    if (opt.against_filter > 0) {
      io::ColmapModel filtered;
      const int t = nearest_filter(target, &filtered);
      const std::uint32_t poorest = min_observations(filtered);
      exact = filtered.points.size();
      exact_floor = sp::floor_over(opt.against_filter, poorest);
      std::printf("against the filter: --min_track_len %d keeps %" PRIu64 " points (F x points %" PRIu64
                  "), its poorest image %u observations; exact rows at %" PRIu64 " points, floor %u\n",
                  t, exact, target, poorest, exact, exact_floor);
    } else {
      const Row replay = b.score("keepless_replay", M, b.keepless_culls(sp::Mode::kReplay, M, F, as_read));
      add_row(replay);
      add_row(b.score("keepless_whole", M, b.keepless_culls(sp::Mode::kWhole, M, F, as_read)));
      const std::uint64_t n = replay.points;
      add_row(b.score("longest_track", M, b.keep_first(as_read.longest, n)));
      std::vector<Row> runs;
      for (int seed = 1; seed <= opt.seeds; ++seed) {
        std::vector<std::size_t> order(b.original.points.size());
        std::iota(order.begin(), order.end(), 0);
        std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
        std::shuffle(order.begin(), order.end(), rng);
        runs.push_back(b.score("random_seed" + std::to_string(seed), M, b.keep_first(order, n)));
      }
      add_seeds("random", M, n, runs);
      filter_row(n, "");
      if (!std::isfinite(F)) exact = n;
    }
    if (opt.against_filter == 0 || opt.track_shares.empty()) {
      add_row(b.score("keepless_exact", M, b.exact_culls(exact, exact_floor, as_read)));
    }
    add_row(b.score("longest_track_exact", M, b.keep_first(as_read.longest, exact)));
    filter_row(exact, "_exact");
    // The same two rules over relabellings: how far their ties move them.
    if (!relabelled.empty() && opt.against_filter == 0) {
      std::vector<Row> keepless_runs, longest_runs;
      for (std::size_t k = 0; k < relabelled.size(); ++k) {
        const std::string seed = "_ties" + std::to_string(k + 1);
        keepless_runs.push_back(b.score("keepless_exact" + seed, M, b.exact_culls(exact, exact_floor, relabelled[k])));
        longest_runs.push_back(b.score("longest_track_exact" + seed, M, b.keep_first(relabelled[k].longest, exact)));
      }
      add_seeds("keepless_exact_ties", M, exact, keepless_runs);
      add_seeds("longest_track_exact_ties", M, exact, longest_runs);
    }
    // The whole model's order with part of the count by track length.
    for (const double S : opt.track_shares) {
      char name[48];
      std::snprintf(name, sizeof name, "keepless_exact_share%g", S);
      add_row(b.score(name, M, b.exact_culls(exact, exact_floor, as_read, S)));
      std::vector<Row> runs;
      for (std::size_t k = 0; k < relabelled.size(); ++k) {
        runs.push_back(b.score(name + std::string("_ties") + std::to_string(k + 1), M,
                               b.exact_culls(exact, exact_floor, relabelled[k], S)));
      }
      if (!runs.empty()) add_seeds(name + std::string("_ties"), M, exact, runs);
    }
  }
  json += "],\"full_ba_s\":" + std::to_string(full.seconds) + ",\"K\":" + std::to_string(opt.K) +
          ",\"seeds\":" + std::to_string(opt.seeds) + ",\"tie_seeds\":" + std::to_string(opt.tie_seeds) +
          ",\"track_shares\":[" + join(opt.track_shares) + "]" +
          ",\"not_converged\":" + std::to_string(not_converged) +
          ",\"floor\":" + std::to_string(sp::kDefaultFloor) + ",\"exact_floor\":" + std::to_string(opt.exact_floor) +
          ",\"against_filter\":" + std::to_string(opt.against_filter) +
          ",\"cost\":\"" + core::to_string(opt.cost) + "\",\"theta\":" + std::to_string(opt.theta) +
          ",\"ba_iterations\":" + std::to_string(opt.ba_iterations) + ",\"model\":\"" + json_escaped(model) +
          "\",\"cpus\":\"" + cpus + "\"}";
  std::printf("%s\n", json.c_str());
  return 0;
}
