// keepless_eval: reproduces the paper's evaluation on real trajectories, real
// images and a real BA problem (issue 6). The last stdout line is a JSON
// summary; --out DIR receives tables.md, runs.csv and SVG plots.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "bal_eval.hpp"
#include "kitti_images.hpp"
#include "prng.hpp"
#include "report.hpp"
#include "scenario.hpp"
#include "slam_sim.hpp"
#include "trajectory_io.hpp"

namespace ke = keepless::eval;

namespace {

const char* kUsage =
    "usage: keepless_eval [--quick] [--data-root DIR] [--trajectory FILE [--format tum|euroc|kitti]]...\n"
    "                     [--images DIR --calib FILE --poses FILE] [--bal FILE]... [--M 100,200,300]\n"
    "                     [--seed N] [--out DIR] [--max-keyframes N] [--keypoints N] [--window N]\n"
    "                     [--ba-iterations N] [--image-frames N] [--noise-free] [--no-baselines] [--no-ablation]\n"
    "                     [--ablation-all]\n"
    "  --data-root DIR  add the standard inputs under DIR (../shared/data layout; --quick: a small subset)\n"
    "  --format         applies to the --trajectory just before it; without it the format is guessed\n";

struct TrajectoryArg {
  std::string path;
  std::string format;  // empty: guess
};

struct Args {
  bool quick = false;
  std::string data_root;
  std::vector<TrajectoryArg> trajectories;
  std::string images, calib, poses;
  std::vector<std::string> bal;
  std::vector<std::int64_t> Ms;
  std::uint64_t seed = 1;
  std::string out;
  int max_keyframes = -1, keypoints = -1, window = -1, ba_iterations = -1, image_frames = -1;
  bool noise_free = false, baselines = true, ablation = true, ablation_all = false;
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

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string f = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) fail(f + " needs a value");
      return argv[++i];
    };
    if (f == "--quick") a.quick = true;
    else if (f == "--data-root") a.data_root = val();
    else if (f == "--trajectory") a.trajectories.push_back({val(), ""});
    else if (f == "--format") {
      const std::string v = val();
      ke::TrajectoryFormat tf;
      if (!ke::parse_format(v, &tf)) fail("--format: expected tum, euroc or kitti, got '" + v + "'");
      if (a.trajectories.empty() || !a.trajectories.back().format.empty()) fail("--format must follow its --trajectory");
      a.trajectories.back().format = v;
    } else if (f == "--images") a.images = val();
    else if (f == "--calib") a.calib = val();
    else if (f == "--poses") a.poses = val();
    else if (f == "--bal") a.bal.push_back(val());
    else if (f == "--M") {
      std::stringstream ss(val());
      std::string tok;
      while (std::getline(ss, tok, ',')) a.Ms.push_back(parse_int("--M", tok, 1, 1000000));
    } else if (f == "--seed") {
      const std::string v = val();
      char* end = nullptr;
      a.seed = std::strtoull(v.c_str(), &end, 10);
      if (v.empty() || *end) fail("--seed: expected an unsigned integer");
    } else if (f == "--out") a.out = val();
    else if (f == "--max-keyframes") a.max_keyframes = static_cast<int>(parse_int(f, val(), 0, 1000000));
    else if (f == "--keypoints") a.keypoints = static_cast<int>(parse_int(f, val(), 10, 100000));
    else if (f == "--window") a.window = static_cast<int>(parse_int(f, val(), 2, 64));
    else if (f == "--ba-iterations") a.ba_iterations = static_cast<int>(parse_int(f, val(), 1, 1000));
    else if (f == "--image-frames") a.image_frames = static_cast<int>(parse_int(f, val(), 0, 100000));
    else if (f == "--noise-free") a.noise_free = true;
    else if (f == "--no-baselines") a.baselines = false;
    else if (f == "--no-ablation") a.ablation = false;
    else if (f == "--ablation-all") a.ablation_all = true;
    else if (f == "--help" || f == "-h") {
      std::cout << kUsage;
      std::exit(0);
    } else fail("unknown flag '" + f + "'\n" + kUsage);
  }
  if (!a.images.empty() && (a.calib.empty() || a.poses.empty())) fail("--images needs --calib and --poses");
  if (a.Ms.empty()) a.Ms = a.quick ? std::vector<std::int64_t>{100} : std::vector<std::int64_t>{100, 200, 300};
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

ke::InputReport run_scenario(const ke::Scenario& sc, const Args& a, const ke::SimOptions& base) {
  ke::InputReport rep;
  rep.input = sc.input;
  rep.name = sc.name;
  rep.group = sc.group;
  rep.kind = sc.kind;
  rep.keyframes = static_cast<std::uint32_t>(sc.frames.size());
  rep.landmarks = sc.landmark_count;
  rep.width = static_cast<std::uint32_t>(sc.cam.width);
  rep.height = static_cast<std::uint32_t>(sc.cam.height);
  rep.op_index = 0;
  for (std::size_t i = 0; i < a.Ms.size(); ++i)
    if (a.Ms[i] == 100) rep.op_index = i;
  rep.op_M = a.Ms[rep.op_index];
  ke::SimOptions o = base;
  o.snapshot_frame = static_cast<int>(sc.frames.size() / 2);
  auto run = [&](const std::string& name, ke::Selector sel, std::int64_t M, std::uint8_t costs) {
    const ke::VariantSpec spec{name, sel, M, costs};
    ke::RunResult r = ke::run_slam(sc, spec, o);
    std::cerr << "  " << sc.name << " " << name << " M=" << M << ": mps " << r.mps << "/" << r.mps_created << " culled " << r.selector_culled << " kfs " << r.kfs << " ate "
              << r.ate_m << " m, ba " << r.ba_s << " s, total " << r.total_s << " s\n";
    return r;
  };
  rep.original = run("original", ke::Selector::kNone, 0, 7);
  for (std::int64_t M : a.Ms) rep.ours.push_back(run("ours", ke::Selector::kKeepless, M, 7));
  if (a.baselines) {
    rep.has_baselines = true;
    rep.anms = run("anms", ke::Selector::kAnms, rep.op_M, 7);
    rep.random = run("random", ke::Selector::kRandom, rep.op_M, 7);
  }
  // The paper runs its ablation on TUM; so do we (every trajectory with --ablation-all).
  if (a.ablation && sc.kind == "trajectory" && (sc.group == "tum" || a.ablation_all)) {
    rep.ablation.push_back(run("c_c", ke::Selector::kKeepless, rep.op_M, 1));
    rep.ablation.push_back(run("c_c+c_s", ke::Selector::kKeepless, rep.op_M, 3));
    rep.ablation.push_back(run("c_c+c_b", ke::Selector::kKeepless, rep.op_M, 5));
  }
  return rep;
}

}  // namespace

int main(int argc, char** argv) {
  const auto t0 = std::chrono::steady_clock::now();
  Args a = parse(argc, argv);
  if (!a.data_root.empty()) add_data_root(&a);
  if (a.trajectories.empty() && a.images.empty() && a.bal.empty())
    fail(std::string("no input: give --data-root, --trajectory, --images or --bal\n") + kUsage);

  ke::EvalSummary summary;
  summary.mode = a.quick ? "quick" : "full";
  summary.seed = a.seed;
  summary.Ms = a.Ms;
  for (int i = 0; i < argc; ++i) summary.command += (i ? " " : "") + std::string(argv[i]);

  ke::SimOptions sim;
  sim.window = a.window > 0 ? a.window : (a.quick ? 6 : 10);
  sim.ba_iterations = a.ba_iterations > 0 ? a.ba_iterations : (a.quick ? 5 : 10);
  sim.seed = a.seed;

  for (std::size_t i = 0; i < a.trajectories.size(); ++i) {
    const auto& t = a.trajectories[i];
    const std::string fmt = t.format.empty() ? guess_format(t.path) : t.format;
    ke::TrajectoryFormat tf;
    if (!ke::parse_format(fmt, &tf)) fail("bad format " + fmt);
    ke::Trajectory traj;
    std::string err;
    if (!ke::read_trajectory(t.path, tf, &traj, &err)) fail(err);
    ke::WorldOptions w = ke::world_defaults(tf);
    w.seed = ke::mix(a.seed, i);
    w.keypoints_per_frame = a.keypoints > 0 ? a.keypoints : (a.quick ? 400 : 1000);
    w.max_keyframes = a.max_keyframes >= 0 ? a.max_keyframes : (a.quick ? 40 : 150);
    if (a.noise_free) {
      w.pixel_noise = 0;
      w.outlier_ratio = 0;
      w.odom_noise_t = 0;
      w.odom_noise_r_deg = 0;
    }
    const std::string name = short_name(t.path);
    std::cerr << "keepless_eval: " << t.path << " (" << fmt << ")\n";
    const ke::Scenario sc = ke::make_synthetic_scenario(traj, w, t.path, name, group_of(fmt, name));
    summary.inputs.push_back(run_scenario(sc, a, sim));
  }

  if (!a.images.empty()) {
    ke::ImageOptions io;
    io.max_frames = a.image_frames >= 0 ? a.image_frames : (a.quick ? 12 : 0);
    io.features = a.quick ? 1000 : 2000;
    io.seed = ke::mix(a.seed, 0x1A);
    if (a.noise_free) io.odom_noise_t = io.odom_noise_r_deg = 0;
    ke::Scenario sc;
    std::string err;
    std::cerr << "keepless_eval: images " << a.images << "\n";
    if (!ke::make_image_scenario(a.images, a.calib, a.poses, io, &sc, &err)) fail(err);
    summary.inputs.push_back(run_scenario(sc, a, sim));
  }

  for (const std::string& b : a.bal) {
    ke::BalOptions bo;
    bo.Ms = {a.Ms[0]};
    for (std::int64_t M : a.Ms)
      if (M == 100) bo.Ms = {100};
    if (!a.quick)
      for (std::int64_t M : a.Ms)
        if (M != bo.Ms[0]) bo.Ms.push_back(M);
    bo.max_iterations = a.quick ? 10 : 50;
    bo.seed = a.seed;
    ke::BalResult r;
    std::string err;
    std::cerr << "keepless_eval: BAL " << b << "\n";
    if (!ke::run_bal(b, bo, &r, &err)) fail(err);
    summary.bal.push_back(std::move(r));
  }

  summary.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!a.out.empty()) {
    std::string err;
    if (!ke::write_outputs(summary, a.out, &err)) fail(err);
  }
  if (!a.quick) std::cout << ke::markdown_tables(summary) << "\n";
  std::cout << ke::json_summary(summary) << std::endl;
  return 0;
}
