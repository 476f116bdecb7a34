#include "metrics.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace keepless::eval {

Alignment umeyama(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                  bool with_scale) {
  Alignment a;
  const std::size_t n = src.size();
  if (n == 0 || dst.size() != n) return a;
  Eigen::Vector3d ms = Eigen::Vector3d::Zero(), md = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    ms += src[i];
    md += dst[i];
  }
  ms /= double(n);
  md /= double(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double var_s = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d ds = src[i] - ms, dd = dst[i] - md;
    cov += dd * ds.transpose();
    var_s += ds.squaredNorm();
  }
  cov /= double(n);
  var_s /= double(n);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  a.R = svd.matrixU() * S * svd.matrixV().transpose();
  a.s = (with_scale && var_s > 0) ? (svd.singularValues().asDiagonal() * S).trace() / var_s : 1.0;
  a.t = md - a.s * a.R * ms;
  return a;
}

Ate absolute_trajectory_error(const std::vector<Pose>& estimate, const std::vector<Pose>& ground_truth,
                              bool with_scale) {
  Ate out;
  const std::size_t n = std::min(estimate.size(), ground_truth.size());
  if (n == 0) return out;
  std::vector<Eigen::Vector3d> src(n), dst(n);
  for (std::size_t i = 0; i < n; ++i) {
    src[i] = estimate[i].t;
    dst[i] = ground_truth[i].t;
  }
  const Alignment a = umeyama(src, dst, with_scale);
  // Positions: Umeyama's least squares, as evo. Orientations: where the
  // estimated positions are nearly collinear (a straight road) Umeyama
  // leaves the rotation about their line to noise, which moves no position
  // but every orientation; ATE_r then takes the rotation from the
  // orientations (the chordal mean of Q_i P_i^-1).
  Eigen::Matrix3d R_orient = a.R;
  {
    Eigen::Vector3d ms = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i) ms += src[i];
    ms /= double(n);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < n; ++i) cov += (src[i] - ms) * (src[i] - ms).transpose();
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();  // ascending
    if (ev(1) < 1e-3 * ev(2)) {
      Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
      for (std::size_t i = 0; i < n; ++i) sum += ground_truth[i].R() * estimate[i].R().transpose();
      Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
      if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) S(2, 2) = -1;
      R_orient = svd.matrixU() * S * svd.matrixV().transpose();
    }
  }
  const Eigen::Quaterniond qa(R_orient);
  double se = 0, sr = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = a.s * (a.R * src[i]) + a.t;
    se += (p - dst[i]).squaredNorm();
    const Eigen::Quaterniond e = ground_truth[i].q.conjugate() * (qa * estimate[i].q);
    const double ang = rotation_angle(e) * 180.0 / 3.141592653589793;
    sr += ang * ang;
  }
  out.rms_m = std::sqrt(se / double(n));
  out.rms_r_deg = std::sqrt(sr / double(n));
  return out;
}

std::vector<Pose> resolve_keyframe_poses(const std::vector<Pose>& pose, const std::vector<CulledLink>& link) {
  const std::size_t n = pose.size();
  std::vector<Pose> out(pose);
  std::vector<char> done(n, 0);
  std::vector<std::size_t> chain;
  for (std::size_t k = 0; k < n; ++k) {
    // Walk up to an alive (or resolved) ancestor, then compose back down.
    // A parent was alive when its child was culled, so the walk ends; the
    // bound guards a malformed link table.
    chain.clear();
    std::size_t c = k;
    while (!done[c] && c < link.size() && link[c].parent >= 0 && static_cast<std::size_t>(link[c].parent) < n &&
           chain.size() <= n) {
      chain.push_back(c);
      c = static_cast<std::size_t>(link[c].parent);
    }
    done[c] = 1;
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      out[*it] = out[static_cast<std::size_t>(link[*it].parent)] * link[*it].rel;
      done[*it] = 1;
    }
  }
  return out;
}

}  // namespace keepless::eval
