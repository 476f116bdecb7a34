#include "vo_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace keepless::eval::vo {
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
