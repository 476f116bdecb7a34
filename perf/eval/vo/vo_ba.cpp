#include "vo_ba.hpp"

#include <cmath>
#include <limits>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "orb_frame.hpp"

namespace keepless::eval::vo {
namespace {

struct Reprojection {
  Reprojection(const PinholeCamera& c, const BaObservation& o)
      : fx(c.fx), fy(c.fy), cx(c.cx), cy(c.cy), bf(c.bf), u(o.u), v(o.v), ur(o.ur),
        w(1.0 / pyramid().scale[static_cast<std::size_t>(o.level)]) {}
  template <typename T>
  bool project(const T* pose, const T* X, T* r) const {
    T p[3];
    ceres::AngleAxisRotatePoint(pose, X, p);
    for (int i = 0; i < 3; ++i) p[i] += pose[3 + i];
    const T iz = T(1) / p[2];
    const T pu = fx * p[0] * iz + cx;
    r[0] = w * (pu - u);
    r[1] = w * (fy * p[1] * iz + cy - v);
    if (ur >= 0) r[2] = w * (pu - bf * iz - ur);
    return true;
  }
  double fx, fy, cx, cy, bf, u, v, ur, w;
};

template <int kResiduals>
struct Residual : Reprojection {
  using Reprojection::Reprojection;
  template <typename T>
  bool operator()(const T* pose, const T* X, T* r) const {
    return project(pose, X, r);
  }
};

ceres::CostFunction* cost(const PinholeCamera& c, const BaObservation& o) {
  if (o.ur >= 0) return new ceres::AutoDiffCostFunction<Residual<3>, 3, 6, 3>(new Residual<3>(c, o));
  return new ceres::AutoDiffCostFunction<Residual<2>, 2, 6, 3>(new Residual<2>(c, o));
}

double threshold(const BaObservation& o) { return o.ur >= 0 ? kChi2Stereo : kChi2Mono; }

ceres::Solver::Options options(int iterations) {
  ceres::Solver::Options opt;
  opt.linear_solver_type = ceres::SPARSE_SCHUR;
  opt.max_num_iterations = iterations;
  opt.num_threads = 1;
  opt.logging_type = ceres::SILENT;
  opt.minimizer_progress_to_stdout = false;
  return opt;
}

}  // namespace

PoseBlock to_block(const Eigen::Isometry3d& Tcw) {
  PoseBlock b{};
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(Tcw.linear()));
  const Eigen::Vector3d r = aa.angle() * aa.axis();
  for (int i = 0; i < 3; ++i) {
    b[static_cast<std::size_t>(i)] = r[i];
    b[static_cast<std::size_t>(3 + i)] = Tcw.translation()[i];
  }
  return b;
}

Eigen::Isometry3d from_block(const PoseBlock& b) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d r(b[0], b[1], b[2]);
  const double a = r.norm();
  T.linear() = a < 1e-15 ? Eigen::Matrix3d::Identity() : Eigen::AngleAxisd(a, r / a).toRotationMatrix();
  T.translation() = Eigen::Vector3d(b[3], b[4], b[5]);
  return T;
}

double chi2(const PinholeCamera& cam, const Eigen::Isometry3d& Tcw, const Eigen::Vector3d& X,
            const BaObservation& o) {
  const Eigen::Vector3d p = Tcw * X;
  if (p.z() <= 0) return std::numeric_limits<double>::infinity();
  const double pu = cam.fx * p.x() / p.z() + cam.cx, pv = cam.fy * p.y() / p.z() + cam.cy;
  double e = (pu - o.u) * (pu - o.u) + (pv - o.v) * (pv - o.v);
  if (o.ur >= 0) {
    const double r = pu - cam.bf / p.z() - o.ur;
    e += r * r;
  }
  return e * pyramid().inv_sigma2[static_cast<std::size_t>(o.level)];
}

namespace {

// The weighted residual of one observation of the camera point p, and its
// derivative with respect to p: rows u, v and u_r (zero for a monocular one).
struct Linearised {
  Eigen::Matrix3d J;
  Eigen::Vector3d e;
};

Linearised linearise(const PinholeCamera& cam, const Eigen::Vector3d& p, const BaObservation& o) {
  Linearised l;
  const double iz = 1.0 / p.z(), w = 1.0 / pyramid().scale[static_cast<std::size_t>(o.level)];
  const double pu = cam.fx * p.x() * iz + cam.cx;
  l.J.row(0) << cam.fx * iz, 0, -cam.fx * p.x() * iz * iz;
  l.J.row(1) << 0, cam.fy * iz, -cam.fy * p.y() * iz * iz;
  l.e << pu - o.u, cam.fy * p.y() * iz + cam.cy - o.v, 0;
  if (o.ur >= 0) {
    l.J.row(2) << cam.fx * iz, 0, (cam.bf - cam.fx * p.x()) * iz * iz;
    l.e(2) = pu - cam.bf * iz - o.ur;
  } else {
    l.J.row(2).setZero();
  }
  l.J *= w;
  l.e *= w;
  return l;
}

// Huber's IRLS weight at the chi-square 95 % threshold (1 past the robust stage).
double huber_weight(const Linearised& l, const BaObservation& o, bool robust) {
  const double delta = std::sqrt(threshold(o)), norm = l.e.norm();
  return robust && norm > delta ? delta / norm : 1.0;
}

}  // namespace

bool refine_point(const PinholeCamera& cam, const std::vector<Eigen::Isometry3d>& tcw,
                  const std::vector<BaObservation>& obs, Eigen::Vector3d* X, std::vector<bool>* outlier) {
  outlier->assign(obs.size(), false);
  Eigen::Vector3d x = *X;
  for (int stage = 0; stage < 2; ++stage) {
    for (int it = 0; it < 5; ++it) {
      Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      for (std::size_t i = 0; i < obs.size(); ++i) {
        if ((*outlier)[i]) continue;
        const Eigen::Vector3d p = tcw[i] * x;
        if (!(p.z() > 0)) return false;
        const Linearised l = linearise(cam, p, obs[i]);
        const Eigen::Matrix3d J = l.J * tcw[i].linear();
        const double rho = huber_weight(l, obs[i], stage == 0);
        H += rho * J.transpose() * J;
        g += rho * J.transpose() * l.e;
      }
      const Eigen::Vector3d dx = H.ldlt().solve(-g);
      if (!dx.allFinite()) return false;
      x += dx;
      if (dx.norm() < 1e-9 * (1.0 + x.norm())) break;
    }
    int inliers = 0;
    for (std::size_t i = 0; i < obs.size(); ++i) {
      (*outlier)[i] = chi2(cam, tcw[i], x, obs[i]) > threshold(obs[i]);
      inliers += (*outlier)[i] ? 0 : 1;
    }
    if (inliers < 2) return false;
  }
  if (!x.allFinite()) return false;
  *X = x;
  return true;
}

int refine_pose(const PinholeCamera& cam, const std::vector<Eigen::Vector3d>& points,
                const std::vector<BaObservation>& obs, Eigen::Isometry3d* Tcw, std::vector<bool>* outlier) {
  outlier->assign(obs.size(), false);
  Eigen::Isometry3d T = *Tcw;
  int inliers = 0;
  for (int stage = 0; stage < 2; ++stage) {
    for (int it = 0; it < 5; ++it) {
      Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
      for (std::size_t i = 0; i < obs.size(); ++i) {
        if ((*outlier)[i]) continue;
        const Eigen::Vector3d p = T * points[static_cast<std::size_t>(obs[i].point)];
        if (!(p.z() > 0)) continue;
        const Linearised l = linearise(cam, p, obs[i]);
        Eigen::Matrix<double, 3, 6> dp;  // d(exp(delta) p)/d(delta), delta = (omega, v) on the left
        dp.leftCols<3>() << 0, p.z(), -p.y(), -p.z(), 0, p.x(), p.y(), -p.x(), 0;
        dp.rightCols<3>().setIdentity();
        const Eigen::Matrix<double, 3, 6> J = l.J * dp;
        const double rho = huber_weight(l, obs[i], stage == 0);
        H += rho * J.transpose() * J;
        g += rho * J.transpose() * l.e;
      }
      const Eigen::Matrix<double, 6, 1> d = H.ldlt().solve(-g);
      if (!d.allFinite()) return 0;
      const double a = d.head<3>().norm();
      Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
      if (a > 1e-15) step.linear() = Eigen::AngleAxisd(a, d.head<3>() / a).toRotationMatrix();
      step.translation() = d.tail<3>();
      T = step * T;
      if (d.norm() < 1e-10) break;
    }
    inliers = 0;
    for (std::size_t i = 0; i < obs.size(); ++i) {
      (*outlier)[i] = chi2(cam, T, points[static_cast<std::size_t>(obs[i].point)], obs[i]) > threshold(obs[i]);
      inliers += (*outlier)[i] ? 0 : 1;
    }
    if (inliers < 10) return inliers;
  }
  if (T.matrix().allFinite()) *Tcw = T;
  return inliers;
}

int optimize_pose(const PinholeCamera& cam, const std::vector<Eigen::Vector3d>& points,
                  const std::vector<BaObservation>& obs, Eigen::Isometry3d* Tcw, std::vector<bool>* outlier) {
  outlier->resize(obs.size(), false);
  PoseBlock pose = to_block(*Tcw);
  std::vector<Eigen::Vector3d> X = points;  // held constant
  int inliers = 0;
  for (int round = 0; round < 4; ++round) {
    ceres::Problem problem;
    int used = 0;
    for (std::size_t i = 0; i < obs.size(); ++i) {
      if ((*outlier)[i]) continue;
      double* x = X[static_cast<std::size_t>(obs[i].point)].data();
      ceres::LossFunction* loss = round < 2 ? new ceres::HuberLoss(std::sqrt(threshold(obs[i]))) : nullptr;
      problem.AddResidualBlock(cost(cam, obs[i]), loss, pose.data(), x);
      problem.SetParameterBlockConstant(x);
      ++used;
    }
    if (used < 3) break;
    ceres::Solver::Options opt = options(10);
    opt.linear_solver_type = ceres::DENSE_QR;
    ceres::Solver::Summary summary;
    ceres::Solve(opt, &problem, &summary);
    const Eigen::Isometry3d T = from_block(pose);
    inliers = 0;
    for (std::size_t i = 0; i < obs.size(); ++i) {
      const bool bad = chi2(cam, T, X[static_cast<std::size_t>(obs[i].point)], obs[i]) > threshold(obs[i]);
      (*outlier)[i] = bad;
      inliers += bad ? 0 : 1;
    }
    if (inliers < 10) break;
  }
  const Eigen::Isometry3d T = from_block(pose);
  if (T.matrix().allFinite()) *Tcw = T;
  return inliers;
}

std::vector<bool> solve_local_ba(const PinholeCamera& cam, LocalBaProblem* p) {
  std::vector<bool> outlier(p->observations.size(), false);
  for (int stage = 0; stage < 2; ++stage) {
    ceres::Problem problem;
    for (std::size_t i = 0; i < p->observations.size(); ++i) {
      if (outlier[i]) continue;
      const BaObservation& o = p->observations[i];
      ceres::LossFunction* loss = stage == 0 ? new ceres::HuberLoss(std::sqrt(threshold(o))) : nullptr;
      problem.AddResidualBlock(cost(cam, o), loss, p->poses[static_cast<std::size_t>(o.pose)].data(),
                               p->points[static_cast<std::size_t>(o.point)].data());
    }
    for (std::size_t k = 0; k < p->poses.size(); ++k) {
      if (p->pose_fixed[k] && problem.HasParameterBlock(p->poses[k].data())) {
        problem.SetParameterBlockConstant(p->poses[k].data());
      }
    }
    for (std::size_t q = 0; q < p->point_fixed.size(); ++q) {
      if (p->point_fixed[q] && problem.HasParameterBlock(p->points[q].data())) {
        problem.SetParameterBlockConstant(p->points[q].data());
      }
    }
    ceres::Solver::Summary summary;
    ceres::Solve(options(stage == 0 ? 5 : 10), &problem, &summary);
    for (std::size_t i = 0; i < p->observations.size(); ++i) {
      const BaObservation& o = p->observations[i];
      outlier[i] = chi2(cam, from_block(p->poses[static_cast<std::size_t>(o.pose)]),
                        p->points[static_cast<std::size_t>(o.point)], o) > threshold(o);
    }
  }
  return outlier;
}

}  // namespace keepless::eval::vo
