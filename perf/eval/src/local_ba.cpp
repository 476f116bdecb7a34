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

// A fixed point for motion-only BA: the residual depends on the pose alone.
template <typename E>
struct FixedPoint {
  E e;
  double X[3];
  template <typename T>
  bool operator()(const T* pose, T* r) const {
    const T p[3] = {T(X[0]), T(X[1]), T(X[2])};
    return e(pose, p, r);
  }
};

bool is_stereo(const Camera& cam, double ur) { return ur >= 0 && cam.baseline > 0; }

// One residual block of either kind; a non-null `fixed_X` holds the point fixed.
ceres::CostFunction* reprojection_cost(const Camera& cam, double u, double v, double ur, const double* fixed_X) {
  const double bf = cam.fx * cam.baseline;
  if (is_stereo(cam, ur)) {
    const StereoError e{cam.fx, cam.fy, cam.cx, cam.cy, bf, u, v, ur};
    if (fixed_X)
      return new ceres::AutoDiffCostFunction<FixedPoint<StereoError>, 3, 6>(
          new FixedPoint<StereoError>{e, {fixed_X[0], fixed_X[1], fixed_X[2]}});
    return new ceres::AutoDiffCostFunction<StereoError, 3, 6, 3>(new StereoError(e));
  }
  const MonoError e{cam.fx, cam.fy, cam.cx, cam.cy, u, v};
  if (fixed_X)
    return new ceres::AutoDiffCostFunction<FixedPoint<MonoError>, 2, 6>(
        new FixedPoint<MonoError>{e, {fixed_X[0], fixed_X[1], fixed_X[2]}});
  return new ceres::AutoDiffCostFunction<MonoError, 2, 6, 3>(new MonoError(e));
}

ceres::Solver::Options solver_options(int iterations, ceres::LinearSolverType type) {
  ceres::Solver::Options so;
  so.linear_solver_type = type;
  so.max_num_iterations = iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  return so;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

double chi2_threshold(const Camera& cam, double ur) { return is_stereo(cam, ur) ? kChi2Stereo : kChi2Mono; }

double reprojection_chi2(const Camera& cam, const double* pose, const double* X, double u, double v, double ur) {
  double pc[3];
  camera_point(pose, X, pc);
  if (pc[2] <= 1e-9) return 1e18;
  const double uh = cam.fx * pc[0] / pc[2] + cam.cx, vh = cam.fy * pc[1] / pc[2] + cam.cy;
  double chi2 = (uh - u) * (uh - u) + (vh - v) * (vh - v);
  if (is_stereo(cam, ur)) {
    const double urh = uh - cam.fx * cam.baseline / pc[2];
    chi2 += (urh - ur) * (urh - ur);
  }
  return chi2;
}

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

BaResult solve_local_ba(const Camera& cam, const BaInput& in, int robust_iterations, int iterations) {
  const auto t0 = std::chrono::steady_clock::now();
  BaResult out;
  out.outlier.assign(in.observations.size(), false);
  if (in.observations.empty()) return out;
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.enable_fast_removal = true;  // stage 2 removes the outliers' blocks
  ceres::Problem problem(po);
  // Wrappers, so stage 2 can drop the robust kernel on every block at once.
  ceres::LossFunctionWrapper loss_mono(new ceres::HuberLoss(std::sqrt(kChi2Mono)), ceres::TAKE_OWNERSHIP);
  ceres::LossFunctionWrapper loss_stereo(new ceres::HuberLoss(std::sqrt(kChi2Stereo)), ceres::TAKE_OWNERSHIP);
  std::vector<ceres::ResidualBlockId> blocks(in.observations.size());
  std::vector<bool> pose_used(in.poses.size(), false);
  for (std::size_t i = 0; i < in.observations.size(); ++i) {
    const BaObservation& o = in.observations[i];
    blocks[i] = problem.AddResidualBlock(reprojection_cost(cam, o.u, o.v, o.ur, nullptr),
                                         is_stereo(cam, o.ur) ? &loss_stereo : &loss_mono,
                                         in.poses[static_cast<std::size_t>(o.pose)],
                                         in.points[static_cast<std::size_t>(o.point)]);
    pose_used[static_cast<std::size_t>(o.pose)] = true;
  }
  for (std::size_t i = 0; i < in.poses.size(); ++i)
    if (pose_used[i] && in.pose_fixed[i]) problem.SetParameterBlockConstant(in.poses[i]);

  auto chi2_of = [&](std::size_t i) {
    const BaObservation& o = in.observations[i];
    return reprojection_chi2(cam, in.poses[static_cast<std::size_t>(o.pose)],
                             in.points[static_cast<std::size_t>(o.point)], o.u, o.v, o.ur);
  };
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(robust_iterations, ceres::SPARSE_SCHUR), &problem, &summary);
  out.iterations = static_cast<int>(summary.iterations.size());
  // Stage 2: outliers out, no robust kernel (ORB-SLAM2 LocalBundleAdjustment).
  std::size_t kept = 0;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    if (chi2_of(i) > chi2_threshold(cam, in.observations[i].ur)) problem.RemoveResidualBlock(blocks[i]);
    else ++kept;
  }
  loss_mono.Reset(nullptr, ceres::TAKE_OWNERSHIP);
  loss_stereo.Reset(nullptr, ceres::TAKE_OWNERSHIP);
  if (kept > 0) {
    ceres::Solve(solver_options(iterations, ceres::SPARSE_SCHUR), &problem, &summary);
    out.iterations += static_cast<int>(summary.iterations.size());
  }
  for (std::size_t i = 0; i < in.observations.size(); ++i)
    out.outlier[i] = chi2_of(i) > chi2_threshold(cam, in.observations[i].ur);
  out.seconds = seconds_since(t0);
  return out;
}

PoseResult optimize_pose(const Camera& cam, const std::vector<PoseObservation>& obs, double* pose) {
  const auto t0 = std::chrono::steady_clock::now();
  PoseResult out;
  out.outlier.assign(obs.size(), false);
  // ORB-SLAM2 PoseOptimization: 4 rounds of 10 iterations, outliers
  // re-classified after each (they may come back), Huber in the first two.
  bool solved = false;
  for (int round = 0; round < 4; ++round) {
    ceres::Problem problem;
    int used = 0;
    for (std::size_t i = 0; i < obs.size(); ++i) {
      if (out.outlier[i]) continue;
      ceres::LossFunction* loss =
          round < 2 ? new ceres::HuberLoss(std::sqrt(chi2_threshold(cam, obs[i].ur))) : nullptr;
      problem.AddResidualBlock(reprojection_cost(cam, obs[i].u, obs[i].v, obs[i].ur, obs[i].X), loss, pose);
      ++used;
    }
    if (used < 10) break;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options(10, ceres::DENSE_QR), &problem, &summary);
    solved = true;
    for (std::size_t i = 0; i < obs.size(); ++i)
      out.outlier[i] = reprojection_chi2(cam, pose, obs[i].X, obs[i].u, obs[i].v, obs[i].ur) > chi2_threshold(cam, obs[i].ur);
  }
  for (bool o : out.outlier) out.inliers += (solved && !o) ? 1 : 0;
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace keepless::eval
