#include "vo_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace keepless::eval::vo {
namespace {

std::vector<double> field(const std::vector<RealRunResult>& runs, double (*get)(const RealRunResult&)) {
  std::vector<double> v;
  for (const RealRunResult& r : runs) v.push_back(get(r));
  return v;
}
double ate(const RealRunResult& r) { return r.ate_m; }
double points(const RealRunResult& r) { return r.map_points; }
double keyframes(const RealRunResult& r) { return r.keyframes; }
double ba(const RealRunResult& r) { return r.local_ba_seconds; }
double tracked(const RealRunResult& r) { return r.frames_tracked; }
double observations(const RealRunResult& r) { return double(r.observations); }

double mean_of(const std::vector<RealRunResult>& runs, double (*get)(const RealRunResult&)) {
  return runs.empty() ? NAN : mean_sd(field(runs, get)).mean;
}

// ours / original per seed, in percent, averaged.
double percent(const std::vector<RealRunResult>& ours, const std::vector<RealRunResult>& orig,
               double (*get)(const RealRunResult&)) {
  double s = 0;
  int n = 0;
  for (std::size_t i = 0; i < ours.size() && i < orig.size(); ++i) {
    if (get(orig[i]) > 0) s += 100.0 * get(ours[i]) / get(orig[i]), ++n;
  }
  return n ? s / n : NAN;
}

std::string num(double x) {
  if (!std::isfinite(x)) return "null";
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o;
}

}  // namespace

MeanSd mean_sd(const std::vector<double>& x) {
  MeanSd m;
  if (x.empty()) return m;
  for (double v : x) m.mean += v;
  m.mean /= double(x.size());
  if (x.size() > 1) {
    for (double v : x) m.sd += (v - m.mean) * (v - m.mean);
    m.sd = std::sqrt(m.sd / double(x.size() - 1));
  }
  return m;
}

std::string json_run(const Comparison& c) {
  int better = 0, worse = 0;
  double obs_ratio = 0;
  int n = 0;
  for (std::size_t i = 0; i < c.keepless.size() && i < c.original.size(); ++i) {
    better += c.keepless[i].ate_m < c.original[i].ate_m ? 1 : 0;
    worse += c.keepless[i].ate_m > c.original[i].ate_m ? 1 : 0;
    if (c.keepless[i].observations > 0) {
      obs_ratio += std::sqrt(double(c.original[i].observations) / double(c.keepless[i].observations));
      ++n;
    }
  }
  std::ostringstream o;
  o << "{\"input\":\"" << escape(c.input) << "\",\"name\":\"" << escape(c.name) << "\",\"kind\":\""
    << (c.rgbd ? "rgbd" : "images") << "\",\"seeds\":" << c.original.size() << ",\"M\":" << c.M
    << ",\"frames\":" << c.frames << ",\"mp_percent\":" << num(percent(c.keepless, c.original, points))
    << ",\"kf_percent\":" << num(percent(c.keepless, c.original, keyframes))
    << ",\"ba_time_percent\":" << num(percent(c.keepless, c.original, ba))
    << ",\"ate_original_m\":" << num(mean_of(c.original, ate))
    << ",\"ate_original_sd_m\":" << num(mean_sd(field(c.original, ate)).sd)
    << ",\"ate_ours_m\":" << num(mean_of(c.keepless, ate))
    << ",\"ate_ours_sd_m\":" << num(c.keepless.empty() ? NAN : mean_sd(field(c.keepless, ate)).sd)
    << ",\"ate_random_m\":" << num(mean_of(c.random, ate))
    << ",\"ate_longest_track_m\":" << num(mean_of(c.longest, ate))
    << ",\"ate_anms_m\":" << num(mean_of(c.anms, ate)) << ",\"better_seeds\":" << better
    << ",\"worse_seeds\":" << worse << ",\"sqrt_obs_ratio\":" << num(n ? obs_ratio / n : NAN)
    << ",\"frames_tracked\":" << num(mean_of(c.keepless.empty() ? c.original : c.keepless, tracked))
    << ",\"frames_tracked_original\":" << num(mean_of(c.original, tracked))
    << ",\"frames_tracked_random\":" << num(mean_of(c.random, tracked))
    << ",\"frames_tracked_longest_track\":" << num(mean_of(c.longest, tracked))
    << ",\"frames_tracked_anms\":" << num(mean_of(c.anms, tracked))
    << ",\"kept_fraction\":" << num(c.keepless.empty() ? NAN : c.keepless[0].mean_kept_fraction)
    << ",\"observations_original\":" << num(mean_of(c.original, observations))
    << ",\"observations_ours\":" << num(mean_of(c.keepless, observations)) << "}";
  return o.str();
}

void print_table(const std::vector<Comparison>& all) {
  std::printf("\n| input | M | seeds | MP %% | KF %% | BA time %% | ATE original (m) | ATE keepless (m) | random | longest track | ANMS | better/worse | frames tracked (orig / ours) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Comparison& c : all) {
    const MeanSd o = mean_sd(field(c.original, ate)), k = mean_sd(field(c.keepless, ate));
    const MeanSd r = mean_sd(field(c.random, ate)), l = mean_sd(field(c.longest, ate)), a = mean_sd(field(c.anms, ate));
    int better = 0, worse = 0;
    for (std::size_t i = 0; i < c.keepless.size() && i < c.original.size(); ++i) {
      better += c.keepless[i].ate_m < c.original[i].ate_m, worse += c.keepless[i].ate_m > c.original[i].ate_m;
    }
    std::printf("| %s | %lld | %zu | %.1f | %.1f | %.1f | %.4f ± %.4f | %.4f ± %.4f | %.4f ± %.4f | %.4f ± %.4f | %.4f ± %.4f | %d/%d | %.1f / %.1f of %d |\n",
                c.name.c_str(), static_cast<long long>(c.M), c.original.size(),
                percent(c.keepless, c.original, points), percent(c.keepless, c.original, keyframes),
                percent(c.keepless, c.original, ba), o.mean, o.sd, k.mean, k.sd, r.mean, r.sd, l.mean, l.sd, a.mean,
                a.sd, better, worse, mean_of(c.original, tracked), mean_of(c.keepless, tracked), c.frames);
  }
}

namespace {

// The two axes along which the ground truth spreads most (top view).
void plot_axes(const std::vector<Pose>& gt, int* ax, int* ay) {
  Eigen::Vector3d lo = gt.front().t, hi = gt.front().t;
  for (const Pose& p : gt) lo = lo.cwiseMin(p.t), hi = hi.cwiseMax(p.t);
  const Eigen::Vector3d ext = hi - lo;
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int a, int b) { return ext[a] > ext[b]; });
  *ax = std::min(order[0], order[1]);
  *ay = std::max(order[0], order[1]);
}

}  // namespace

bool write_trajectory_svg(const std::string& path, const std::string& title, const RealRunResult& original,
                          const RealRunResult& ours) {
  const std::vector<Pose>& gt = original.ground_truth.size() >= ours.ground_truth.size() ? original.ground_truth
                                                                                          : ours.ground_truth;
  if (gt.empty()) return false;
  int ax = 0, ay = 2;
  plot_axes(gt, &ax, &ay);
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const auto* traj : {&gt, &original.estimate, &ours.estimate}) {
    for (const Pose& p : *traj) {
      x0 = std::min(x0, p.t[ax]), x1 = std::max(x1, p.t[ax]);
      y0 = std::min(y0, p.t[ay]), y1 = std::max(y1, p.t[ay]);
    }
  }
  const double span = std::max({x1 - x0, y1 - y0, 1e-6});
  const double W = 640, H = 640, m = 40, s = (W - 2 * m) / span;
  auto line = [&](const std::vector<Pose>& t, const char* colour, const char* dash) {
    std::ostringstream o;
    o << "<polyline fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"1.5\" stroke-dasharray=\"" << dash
      << "\" points=\"";
    for (const Pose& p : t) o << m + (p.t[ax] - x0) * s << "," << H - m - (p.t[ay] - y0) * s << " ";
    o << "\"/>\n";
    return o.str();
  };
  std::ofstream f(path);
  if (!f) return false;
  const char axis[3] = {'x', 'y', 'z'};
  f << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H + 30 << "\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"10\" y=\"20\" font-family=\"sans-serif\" font-size=\"13\">" << title << " (" << axis[ax] << "-"
    << axis[ay] << ", aligned; ATE original " << original.ate_m << " m, keepless " << ours.ate_m << " m)</text>\n"
    << line(gt, "black", "none") << line(original.estimate, "#1f77b4", "none") << line(ours.estimate, "#d62728", "4,2")
    << "<text x=\"10\" y=\"" << H + 20 << "\" font-family=\"sans-serif\" font-size=\"12\">black: ground truth; "
       "blue: original; red dashed: keepless</text>\n</svg>\n";
  return static_cast<bool>(f);
}

bool write_keypoints_svg(const std::string& path, const std::string& title, const RealRunResult& ours,
                         int width, int height) {
  std::ofstream f(path);
  if (!f) return false;
  f << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height + 40 << "\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<rect width=\"" << width << "\" height=\"" << height
    << "\" fill=\"#f4f4f4\" stroke=\"black\"/>\n";
  int kept = 0, culled = 0, unmapped = 0;
  for (const KeypointMark& k : ours.marks) {
    const char* colour = k.state == 2 ? "#d62728" : (k.state == 1 ? "#2ca02c" : "#bbbbbb");
    (k.state == 2 ? culled : (k.state == 1 ? kept : unmapped))++;
    f << "<circle cx=\"" << k.u << "\" cy=\"" << k.v << "\" r=\"" << (k.state == 0 ? 1.2 : 2.2) << "\" fill=\""
      << colour << "\"/>\n";
  }
  f << "<text x=\"10\" y=\"" << height + 25 << "\" font-family=\"sans-serif\" font-size=\"13\">" << title
    << ", frame " << ours.marked_frame << ": green kept " << kept << ", red culled " << culled << ", grey unmapped "
    << unmapped << "</text>\n</svg>\n";
  return static_cast<bool>(f);
}

}  // namespace keepless::eval::vo
