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

struct BalRun {
  std::uint32_t points = 0;
  std::uint32_t observations = 0;
  double solve_s = 0;
  int iterations = 0;
  double final_cost = 0;
  // Ceres gave no usable solution, or the cost ended non-finite or above
  // where it started: reported as a failed run, never averaged silently.
  bool diverged = false;
};

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
  run.diverged = !summary.IsSolutionUsable() || !std::isfinite(summary.final_cost) ||
                 summary.final_cost > summary.initial_cost;
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

void compare(const std::vector<double>& cams, const std::vector<Pose>& reference, std::uint32_t n, RunRecord* run) {
  const Ate e = absolute_trajectory_error(camera_poses(cams, n), reference, true);
  run->ate_m = e.rms_m;
  run->ate_r_deg = e.rms_r_deg;
}

// BAL solve as a RunRecord (solve time as BA time; observations used).
RunRecord record_of(const BalRun& b, const std::string& variant, std::int64_t M, std::uint32_t cameras) {
  RunRecord r;
  r.variant = variant;
  r.M = M;
  r.mps = b.points;
  r.kfs = cameras;
  r.observations = b.observations;
  r.ba_s = r.total_s = b.solve_s;
  r.diverged = b.diverged;
  return r;
}

// Keeps `count` of the evaluated points in `order`'s order; the rest of the
// points (not evaluated: seen once) are kept.
std::vector<char> keep_first(const std::vector<std::uint32_t>& order, std::uint32_t count,
                             const std::vector<char>& evaluated) {
  std::vector<char> keep(evaluated.size(), 0);
  for (std::size_t j = 0; j < evaluated.size(); ++j) keep[j] = !evaluated[j];
  for (std::uint32_t i = 0; i < count && i < order.size(); ++i) keep[order[i]] = 1;
  return keep;
}

}  // namespace

bool run_bal(const std::string& path, const BalOptions& o, Comparison* out, std::string* error) {
  BalProblem p;
  if (!read_bal(path, &p, error)) return false;
  out->info.input = path;
  out->info.name = "bal";
  out->info.group = "bal";
  out->info.kind = "bal";
  out->info.sim3 = true;
  out->target_fraction = o.target_fraction;

  std::vector<double> full_cams;
  const BalRun full = solve(p, std::vector<char>(p.npoints, 1), o.max_iterations, &full_cams);
  const std::vector<Pose> reference = camera_poses(full_cams, p.ncams);

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
  core::Window window(caps);
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
  std::vector<char> keep(p.npoints, 0), evaluated(p.npoints, 0);
  // A kept fraction is a keep budget over the evaluated points (no M).
  auto sparsify = [&](std::int64_t M) {
    core::Params params;
    params.pair_capacity = std::max<std::int64_t>(M, 1);
    if (std::isfinite(o.target_fraction)) params.budget = {core::BudgetKind::kFraction, 0, o.target_fraction};
    core::Sparsifier sparsifier(caps, params);
    if (sparsifier.run(window) != core::Status::kOk) return false;
    const core::PointDecision* d = sparsifier.decisions();
    for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
      keep[d[i].point] = d[i].verdict != core::Verdict::kCull;
      evaluated[d[i].point] = d[i].verdict != core::Verdict::kSkip;
    }
    return true;
  };
  const std::int64_t M = std::isfinite(o.target_fraction) ? 0 : o.M;
  if (!sparsify(M)) {
    *error = path + ": keepless solve failed";
    return false;
  }
  out->M = M;
  std::vector<double> cams;
  RunRecord ours = record_of(solve(p, keep, o.max_iterations, &cams), "ours", M, p.ncams);
  compare(cams, reference, p.ncams, &ours);
  std::vector<std::uint32_t> candidates;
  std::uint32_t kept_evaluated = 0;
  for (std::uint32_t j = 0; j < p.npoints; ++j)
    if (evaluated[j]) {
      candidates.push_back(j);
      kept_evaluated += keep[j] ? 1 : 0;
    }
  RunRecord longest;
  if (o.baselines) {
    std::vector<std::uint32_t> order = candidates;
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return views[a] > views[b]; });
    longest = record_of(solve(p, keep_first(order, kept_evaluated, evaluated), o.max_iterations, &cams), "longest_track", M, p.ncams);
    compare(cams, reference, p.ncams, &longest);
  }
  for (std::uint64_t seed : o.seeds) {
    RunRecord g = record_of(full, "original", 0, p.ncams);
    g.seed = seed;
    g.ate_m = g.ate_r_deg = 0;  // the reference itself
    out->original.push_back(g);
    ours.seed = seed;
    out->ours.push_back(ours);
    if (!o.baselines) continue;
    longest.seed = seed;
    out->longest_track.push_back(longest);
    std::vector<std::uint32_t> order = candidates;
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return mix(seed, a) < mix(seed, b); });
    RunRecord random = record_of(solve(p, keep_first(order, kept_evaluated, evaluated), o.max_iterations, &cams), "random", M, p.ncams);
    random.seed = seed;
    compare(cams, reference, p.ncams, &random);
    out->random.push_back(random);
  }
  return true;
}

}  // namespace keepless::eval
