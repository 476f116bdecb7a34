// keepless_vo_eval: the real VO on real sequences, original vs keepless vs
// random / longest-track-first / ANMS at equal count per window, over seeds.
// The last stdout line is {"runs":[...]} (issue 11's keys). Development
// driver; the lead folds run_real_vo into keepless_eval.

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "real_vo.hpp"
#include "vo_report.hpp"

using namespace keepless::eval::vo;

namespace {

const char* kUsage =
    "usage: keepless_vo_eval [--images DIR --calib FILE --poses FILE]... [--rgbd DIR]...\n"
    "  [--frames A:B] [--seeds N] [--first-seed S] [--M 50,100] [--kept-fraction F] [--variants original,keepless,random,\n"
    "  longest_track,anms] [--quick] [--out DIR] [--verbose]\n"
    "  --frames A:B   frames A..B inclusive of every input (default all; --quick: 0:59)\n"
    "  --seeds N      seeds S..S+N-1 (RANSAC order, random priorities; default 3, --quick 1)\n"
    "  --first-seed S the first seed (default 1; --kept-fraction calibrates on it)\n"
    "  --M list       keepless pair capacities (default 100)\n"
    "  --kept-fraction F  instead of --M: per input, the M of {5,10,20,30,50,75,100,150,200,300} whose\n"
    "                 mean kept fraction of the new keyframes' evaluated points (seen >= twice in the\n"
    "                 window), on the original run's windows (seed 1), is nearest F\n";

struct Input {
  bool rgbd = false;
  std::string dir, calib, poses;
};

bool parse_list(const std::string& s, std::vector<std::int64_t>* out) {
  std::stringstream ss(s);
  std::string tok;
  out->clear();
  while (std::getline(ss, tok, ',')) {
    char* end = nullptr;
    const long long v = std::strtoll(tok.c_str(), &end, 10);
    if (end == tok.c_str() || *end != '\0' || v < 1) return false;
    out->push_back(v);
  }
  return !out->empty();
}

void print_run(const RealSequence& s, const char* variant, std::int64_t M, std::uint64_t seed,
               const RealRunResult& r) {
  std::printf("%-28s %-13s M=%-4lld seed=%llu  tracked %d/%d (losses %d)  MPs %d  KFs %d (made %d)  obs %lld  "
              "culled %lld (windows refused %d)  local BA %.2f s (%d)  total %.1f s  ATE %.4f m  ATE_r %.2f deg\n",
              s.name.c_str(), variant, static_cast<long long>(M), static_cast<unsigned long long>(seed),
              r.frames_tracked, r.frames, r.tracking_losses, r.map_points, r.keyframes, r.keyframes_created,
              static_cast<long long>(r.observations), static_cast<long long>(r.points_culled_by_selector),
              r.window_rejections, r.local_ba_seconds, r.local_bas, r.total_seconds, r.ate_m, r.ate_r_deg);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<Input> inputs;
  std::string frames, out_dir;
  int seeds = -1, first_seed = 1;
  bool quick = false, verbose = false;
  double kept_fraction = -1;
  std::vector<std::int64_t> Ms = {100};
  std::set<std::string> variants = {"original", "keepless", "random", "longest_track", "anms"};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](std::string* v) {
      if (i + 1 >= argc) return false;
      *v = argv[++i];
      return true;
    };
    std::string v;
    if (a == "--images" && value(&v)) {
      inputs.push_back({false, v, "", ""});
    } else if ((a == "--calib" || a == "--poses") && value(&v)) {
      if (inputs.empty() || inputs.back().rgbd) {
        std::fprintf(stderr, "%s must follow --images\n%s", a.c_str(), kUsage);
        return 2;
      }
      (a == "--calib" ? inputs.back().calib : inputs.back().poses) = v;
    } else if (a == "--rgbd" && value(&v)) {
      inputs.push_back({true, v, "", ""});
    } else if (a == "--frames" && value(&v)) {
      frames = v;
    } else if (a == "--seeds" && value(&v)) {
      seeds = std::atoi(v.c_str());
    } else if (a == "--first-seed" && value(&v)) {
      first_seed = std::atoi(v.c_str());
    } else if (a == "--M" && value(&v)) {
      if (!parse_list(v, &Ms)) {
        std::fprintf(stderr, "--M: a comma-separated list of integers >= 1\n");
        return 2;
      }
    } else if (a == "--kept-fraction" && value(&v)) {
      kept_fraction = std::atof(v.c_str());
      if (!(kept_fraction > 0 && kept_fraction < 1)) {
        std::fprintf(stderr, "--kept-fraction: a fraction in (0, 1)\n");
        return 2;
      }
    } else if (a == "--variants" && value(&v)) {
      variants.clear();
      std::stringstream ss(v);
      std::string tok;
      while (std::getline(ss, tok, ',')) variants.insert(tok);
    } else if (a == "--out" && value(&v)) {
      out_dir = v;
    } else if (a == "--quick") {
      quick = true;
    } else if (a == "--verbose") {
      verbose = true;
    } else {
      std::fprintf(stderr, "unknown or incomplete argument %s\n%s", a.c_str(), kUsage);
      return 2;
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "no input\n%s", kUsage);
    return 2;
  }
  variants.insert("original");  // every comparison is against it
  if (seeds < 0) seeds = quick ? 1 : 3;
  if (seeds < 1) {
    std::fprintf(stderr, "--seeds: at least 1\n");
    return 2;
  }
  int first = 0, last = -1;
  if (frames.empty() && quick) frames = "0:59";
  if (!frames.empty() && std::sscanf(frames.c_str(), "%d:%d", &first, &last) != 2) {
    std::fprintf(stderr, "--frames: A:B\n");
    return 2;
  }
  if (!out_dir.empty()) std::filesystem::create_directories(out_dir);

  std::vector<Comparison> all;
  for (const Input& in : inputs) {
    RealSequence seq;
    std::string error;
    const bool loaded = in.rgbd ? load_rgbd_sequence(in.dir, first, last, &seq, &error)
                                : load_kitti_sequence(in.dir, in.calib, in.poses, first, last, &seq, &error);
    if (!loaded) {
      std::fprintf(stderr, "keepless_vo_eval: %s\n", error.c_str());
      return 1;
    }
    std::printf("# %s: %zu frames (%s), path %.2f m, %dx%d, fx %.1f\n", seq.name.c_str(), seq.image_files.size(),
                seq.rgbd ? "rgbd, SE(3) ATE" : "monocular, Sim(3) ATE", seq.path_length(), seq.camera.width,
                seq.camera.height, seq.camera.fx);
    const std::vector<std::int64_t> ladder = {5, 10, 20, 30, 50, 75, 100, 150, 200, 300};
    std::vector<std::int64_t> input_Ms = Ms;
    std::vector<Comparison> cmp;
    for (int seed = first_seed; seed < first_seed + seeds; ++seed) {
      RealVoOptions o;
      o.seed = static_cast<std::uint64_t>(seed);
      o.verbose = verbose;
      o.selector = Selector::kOriginal;
      if (kept_fraction > 0 && seed == first_seed) o.calibrate_M = ladder;
      const RealRunResult orig = run_real_vo(seq, o);
      if (!orig.error.empty()) {
        std::fprintf(stderr, "keepless_vo_eval: %s\n", orig.error.c_str());
        return 1;
      }
      if (kept_fraction > 0 && seed == first_seed) {
        std::size_t best = 0;
        for (std::size_t m = 0; m < ladder.size(); ++m) {
          std::printf("#   calibration M=%lld keeps %.3f of the new keyframes' evaluated points\n",
                      static_cast<long long>(ladder[m]), orig.calibration_kept_fraction[m]);
          if (std::abs(orig.calibration_kept_fraction[m] - kept_fraction) <
              std::abs(orig.calibration_kept_fraction[best] - kept_fraction)) {
            best = m;
          }
        }
        input_Ms = {ladder[best]};
        std::printf("#   --kept-fraction %.2f: M = %lld\n", kept_fraction, static_cast<long long>(ladder[best]));
      }
      print_run(seq, "original", 0, o.seed, orig);
      if (cmp.empty()) {
        for (std::int64_t M : input_Ms) {
          Comparison c;
          c.input = in.dir;
          c.name = seq.name;
          c.rgbd = seq.rgbd;
          c.M = M;
          c.frames = static_cast<int>(seq.image_files.size());
          cmp.push_back(c);
        }
      }
      for (Comparison& c : cmp) {
        c.original.push_back(orig);
        o.calibrate_M.clear();
        o.params.pair_capacity = c.M;
        const std::pair<Selector, std::vector<RealRunResult>*> runs[] = {
            {Selector::kKeepless, &c.keepless}, {Selector::kRandom, &c.random},
            {Selector::kLongestTrack, &c.longest}, {Selector::kAnms, &c.anms}};
        for (const auto& [selector, into] : runs) {
          if (!variants.count(to_string(selector))) continue;
          o.selector = selector;
          into->push_back(run_real_vo(seq, o));
          print_run(seq, to_string(selector), c.M, o.seed, into->back());
        }
      }
    }
    if (!out_dir.empty() && !cmp.empty() && !cmp[0].original.empty()) {
      const Comparison& c = cmp[0];
      const RealRunResult& ours = c.keepless.empty() ? c.original[0] : c.keepless[0];
      const std::string base = out_dir + "/" + seq.name;
      if (!write_trajectory_svg(base + "_trajectory.svg", seq.name + ", seed 1, M " + std::to_string(c.M),
                                c.original[0], ours) ||
          !write_keypoints_svg(base + "_keypoints.svg", seq.name + " keepless M " + std::to_string(c.M), ours,
                               seq.camera.width, seq.camera.height)) {
        std::fprintf(stderr, "keepless_vo_eval: cannot write %s_*.svg\n", base.c_str());
        return 1;
      }
    }
    all.insert(all.end(), cmp.begin(), cmp.end());
  }
  print_table(all);
  std::string json = "{\"runs\":[";
  for (std::size_t i = 0; i < all.size(); ++i) json += (i ? "," : "") + json_run(all[i]);
  json += "]}";
  std::printf("%s\n", json.c_str());
  return 0;
}
