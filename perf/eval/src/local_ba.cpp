#include "local_ba.hpp"

#include <chrono>
#include <cmath>
#include <memory>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

namespace keepless::eval {
namespace {

constexpr double kChi2Mono = 5.991;
constexpr double kChi2Stereo = 7.815;

template <typename T>
void camera_point(const T* pose, const T* point, T* pc) {
  ceres::AngleAxisRotatePoint(pose, point, pc);
  pc[0] += pose[3];
  pc[1] += pose[4];
  pc[2] += pose[5];
}

struct MonoError {
  double fx, fy, cx, cy, u, v;
  template <typename T>
  bool operator()(const T* pose, const T* point, T* r) const {
    T pc[3];
    camera_point(pose, point, pc);
    const T iz = T(1) / pc[2];
    r[0] = T(fx) * pc[0] * iz + T(cx) - T(u);
    r[1] = T(fy) * pc[1] * iz + T(cy) - T(v);
    return true;
  }
};

struct StereoError {
  double fx, fy, cx, cy, bf, u, v, ur;
  template <typename T>
  bool operator()(const T* pose, const T* point, T* r) const {
    T pc[3];
    camera_point(pose, point, pc);
    const T iz = T(1) / pc[2];
    const T uh = T(fx) * pc[0] * iz + T(cx);
    r[0] = uh - T(u);
    r[1] = T(fy) * pc[1] * iz + T(cy) - T(v);
    r[2] = uh - T(bf) * iz - T(ur);
    return true;
  }
};

}  // namespace

std::array<double, 6> to_block(const Pose& T_wc) {
  const Pose T_cw = T_wc.inverse();
  const Eigen::AngleAxisd aa(T_cw.q);
  const Eigen::Vector3d r = aa.axis() * aa.angle();
  return {r.x(), r.y(), r.z(), T_cw.t.x(), T_cw.t.y(), T_cw.t.z()};
}

Pose from_block(const double* b) {
  Pose T_cw;
  T_cw.q = small_rotation(Eigen::Vector3d(b[0], b[1], b[2]));
  T_cw.t = Eigen::Vector3d(b[3], b[4], b[5]);
  return T_cw.inverse();
}

BaResult solve_local_ba(const Camera& cam, const BaInput& in, int max_iterations) {
  const auto t0 = std::chrono::steady_clock::now();
  BaResult out;
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  ceres::HuberLoss huber_mono(std::sqrt(kChi2Mono));
  ceres::HuberLoss huber_stereo(std::sqrt(kChi2Stereo));
  const double bf = cam.fx * cam.baseline;
  std::vector<bool> pose_used(in.poses.size(), false);
  for (const BaObservation& o : in.observations) {
    ceres::CostFunction* cf;
    ceres::LossFunction* loss;
    if (o.ur >= 0 && cam.baseline > 0) {
      cf = new ceres::AutoDiffCostFunction<StereoError, 3, 6, 3>(
          new StereoError{cam.fx, cam.fy, cam.cx, cam.cy, bf, o.u, o.v, o.ur});
      loss = &huber_stereo;
    } else {
      cf = new ceres::AutoDiffCostFunction<MonoError, 2, 6, 3>(
          new MonoError{cam.fx, cam.fy, cam.cx, cam.cy, o.u, o.v});
      loss = &huber_mono;
    }
    problem.AddResidualBlock(cf, loss, in.poses[static_cast<std::size_t>(o.pose)],
                             in.points[static_cast<std::size_t>(o.point)]);
    pose_used[static_cast<std::size_t>(o.pose)] = true;
  }
  for (std::size_t i = 0; i < in.poses.size(); ++i)
    if (pose_used[i] && in.pose_fixed[i]) problem.SetParameterBlockConstant(in.poses[i]);

  if (!in.observations.empty()) {
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::SPARSE_SCHUR;
    so.max_num_iterations = max_iterations;
    so.num_threads = 1;
    so.logging_type = ceres::SILENT;
    so.minimizer_progress_to_stdout = false;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    out.iterations = static_cast<int>(summary.iterations.size());
  }

  out.chi2.resize(in.observations.size());
  out.outlier.resize(in.observations.size());
  for (std::size_t i = 0; i < in.observations.size(); ++i) {
    const BaObservation& o = in.observations[i];
    const double* pose = in.poses[static_cast<std::size_t>(o.pose)];
    const double* X = in.points[static_cast<std::size_t>(o.point)];
    double pc[3];
    camera_point(pose, X, pc);
    double chi2;
    bool stereo = o.ur >= 0 && cam.baseline > 0;
    if (pc[2] <= 1e-9) {
      chi2 = 1e18;
    } else {
      const double uh = cam.fx * pc[0] / pc[2] + cam.cx, vh = cam.fy * pc[1] / pc[2] + cam.cy;
      chi2 = (uh - o.u) * (uh - o.u) + (vh - o.v) * (vh - o.v);
      if (stereo) {
        const double urh = uh - bf / pc[2];
        chi2 += (urh - o.ur) * (urh - o.ur);
      }
    }
    out.chi2[i] = chi2;
    out.outlier[i] = chi2 > (stereo ? kChi2Stereo : kChi2Mono);
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace keepless::eval
