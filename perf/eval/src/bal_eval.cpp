#include "bal_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "geometry.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "metrics.hpp"
#include "prng.hpp"

namespace keepless::eval {
namespace {

struct BalProblem {
  std::uint32_t ncams = 0, npoints = 0;
  std::vector<std::uint32_t> cam, point;
  std::vector<double> x, y;
  std::vector<double> cameras;  // 9 per camera: r[3], t[3], f, k1, k2
  std::vector<double> points;   // 3 per point
};

bool read_bal(const std::string& path, BalProblem* p, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ":0: cannot open";
    return false;
  }
  std::uint32_t nobs = 0;
  if (!(in >> p->ncams >> p->npoints >> nobs) || p->ncams == 0 || p->npoints == 0) {
    *error = path + ":1: bad header";
    return false;
  }
  p->cam.resize(nobs);
  p->point.resize(nobs);
  p->x.resize(nobs);
  p->y.resize(nobs);
  for (std::uint32_t i = 0; i < nobs; ++i)
    if (!(in >> p->cam[i] >> p->point[i] >> p->x[i] >> p->y[i]) || p->cam[i] >= p->ncams ||
        p->point[i] >= p->npoints) {
      *error = path + ":" + std::to_string(i + 2) + ": bad observation";
      return false;
    }
  p->cameras.resize(9u * p->ncams);
  p->points.resize(3u * p->npoints);
  for (double& v : p->cameras)
    if (!(in >> v)) { *error = path + ": truncated camera block"; return false; }
  for (double& v : p->points)
    if (!(in >> v)) { *error = path + ": truncated point block"; return false; }
  return true;
}

struct SnavelyError {  // BAL's camera model: P = R X + t, p = -P/P.z, radial k1, k2
  double x, y;
  template <typename T>
  bool operator()(const T* camera, const T* point, T* r) const {
    T p[3];
    ceres::AngleAxisRotatePoint(camera, point, p);
    p[0] += camera[3];
    p[1] += camera[4];
    p[2] += camera[5];
    const T xp = -p[0] / p[2], yp = -p[1] / p[2];
    const T r2 = xp * xp + yp * yp;
    const T d = T(1) + r2 * (camera[7] + camera[8] * r2);
    r[0] = camera[6] * d * xp - T(x);
    r[1] = camera[6] * d * yp - T(y);
    return true;
  }
};

// Solves from the "-pre" values on the observations of the points flagged in
// `use`; returns the solved cameras.
BalRun solve(const BalProblem& p, const std::vector<char>& use, int max_iterations, std::vector<double>* cams) {
  BalRun run;
  *cams = p.cameras;
  std::vector<double> pts = p.points;
  ceres::Problem problem;
  for (std::size_t i = 0; i < p.cam.size(); ++i) {
    if (!use[p.point[i]]) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SnavelyError, 2, 9, 3>(new SnavelyError{p.x[i], p.y[i]}),
                             nullptr, cams->data() + 9u * p.cam[i], pts.data() + 3u * p.point[i]);
    ++run.observations;
  }
  for (std::uint32_t j = 0; j < p.npoints; ++j) run.points += use[j] ? 1 : 0;
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::SPARSE_SCHUR;
  so.max_num_iterations = max_iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  const auto t0 = std::chrono::steady_clock::now();
  ceres::Solve(so, &problem, &summary);
  run.solve_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.iterations = static_cast<int>(summary.iterations.size());
  run.final_cost = summary.final_cost;
  return run;
}

std::vector<Pose> camera_poses(const std::vector<double>& cams, std::uint32_t n) {
  std::vector<Pose> out(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const double* c = cams.data() + 9u * i;
    Pose T_cw;
    T_cw.q = small_rotation(Eigen::Vector3d(c[0], c[1], c[2]));
    T_cw.t = Eigen::Vector3d(c[3], c[4], c[5]);
    out[i] = T_cw.inverse();
  }
  return out;
}

void compare(const std::vector<double>& cams, const std::vector<Pose>& reference, std::uint32_t n, BalRun* run) {
  const Ate e = absolute_trajectory_error(camera_poses(cams, n), reference, true);
  run->pos_rms = e.rms_m;
  run->rot_rms_deg = e.rms_r_deg;
}

}  // namespace

bool run_bal(const std::string& path, const BalOptions& o, BalResult* out, std::string* error) {
  BalProblem p;
  if (!read_bal(path, &p, error)) return false;
  out->input = path;
  out->cameras = p.ncams;
  out->points = p.npoints;
  out->observations = static_cast<std::uint32_t>(p.cam.size());

  std::vector<double> full_cams;
  out->full = solve(p, std::vector<char>(p.npoints, 1), o.max_iterations, &full_cams);
  out->full.variant = "full";
  const std::vector<Pose> reference = camera_poses(full_cams, p.ncams);
  {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Pose& q : reference) mean += q.t;
    mean /= double(p.ncams);
    double s = 0;
    for (const Pose& q : reference) s += (q.t - mean).squaredNorm();
    out->extent = std::sqrt(s / p.ncams);
  }

  // The window: every camera a keyframe (its "-pre" centre, as a SLAM
  // system would sparsify before solving), BAL's centred pixel offsets as u, v.
  std::vector<std::vector<core::Observation>> per_cam(p.ncams);
  std::vector<std::uint32_t> views(p.npoints, 0);
  for (std::size_t i = 0; i < p.cam.size(); ++i) {
    per_cam[p.cam[i]].push_back(core::Observation{p.point[i], p.x[i], p.y[i]});
    ++views[p.point[i]];
  }
  core::Capacities caps;
  caps.max_keyframes = p.ncams;
  caps.max_points = p.npoints;
  caps.max_observations = static_cast<std::uint32_t>(p.cam.size());
  std::uint64_t arcs = 0;
  for (std::uint32_t v : views) arcs += std::uint64_t(v) * (v - (v > 0 ? 1 : 0)) / 2;
  caps.max_pair_arcs = static_cast<std::uint32_t>(std::max<std::uint64_t>(arcs, 1));
  const std::vector<Pose> initial = camera_poses(p.cameras, p.ncams);

  for (std::int64_t M : o.Ms) {
    core::Params params;
    params.pair_capacity = M;
    core::Window window(caps);
    core::Sparsifier sparsifier(caps, params);
    const auto t0 = std::chrono::steady_clock::now();
    for (std::uint32_t c = 0; c < p.ncams; ++c) {
      core::Keyframe kf;
      kf.id = c;
      for (int a = 0; a < 3; ++a) kf.centre[a] = initial[c].t[a];
      kf.orientation[0] = initial[c].q.w(); kf.orientation[1] = initial[c].q.x();
      kf.orientation[2] = initial[c].q.y(); kf.orientation[3] = initial[c].q.z();
      if (window.add_keyframe(kf, per_cam[c].data(), static_cast<std::uint32_t>(per_cam[c].size())) != core::Status::kOk) {
        *error = path + ": keepless window rejected camera " + std::to_string(c);
        return false;
      }
    }
    if (sparsifier.run(window) != core::Status::kOk) {
      *error = path + ": keepless solve failed";
      return false;
    }
    out->sparsify_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::vector<char> keep(p.npoints, 0), evaluated(p.npoints, 0);
    const core::PointDecision* d = sparsifier.decisions();
    for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
      keep[d[i].point] = d[i].verdict != core::Verdict::kCull;
      evaluated[d[i].point] = d[i].verdict != core::Verdict::kSkip;
    }
    std::vector<double> cams;
    BalRun ours = solve(p, keep, o.max_iterations, &cams);
    ours.variant = "ours";
    ours.M = M;
    compare(cams, reference, p.ncams, &ours);
    out->ours.push_back(ours);

    // Random at the same count, a fixed priority per point.
    std::vector<std::uint32_t> order;
    std::uint32_t kept_evaluated = 0;
    for (std::uint32_t j = 0; j < p.npoints; ++j)
      if (evaluated[j]) {
        order.push_back(j);
        kept_evaluated += keep[j] ? 1 : 0;
      }
    std::sort(order.begin(), order.end(),
              [&](std::uint32_t a, std::uint32_t b) { return mix(o.seed, a) < mix(o.seed, b); });
    std::vector<char> rnd(p.npoints, 0);
    for (std::uint32_t j = 0; j < p.npoints; ++j) rnd[j] = !evaluated[j];
    for (std::uint32_t i = 0; i < kept_evaluated; ++i) rnd[order[i]] = 1;
    BalRun random = solve(p, rnd, o.max_iterations, &cams);
    random.variant = "random";
    random.M = M;
    compare(cams, reference, p.ncams, &random);
    out->random.push_back(random);
  }
  return true;
}

}  // namespace keepless::eval
