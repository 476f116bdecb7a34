#include "scenario.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <unordered_map>

#include "prng.hpp"

namespace keepless::eval {
namespace {

constexpr double kDeg = 3.141592653589793 / 180.0;

struct Landmark {
  Eigen::Vector3d p;
  double response;
};

class World {
 public:
  explicit World(double voxel) : voxel_(voxel) {}

  void add(const Landmark& l) {
    const auto idx = static_cast<std::uint32_t>(points_.size());
    points_.push_back(l);
    grid_[key(l.p)].push_back(idx);
  }
  const std::vector<Landmark>& points() const { return points_; }

  // Landmark indices within `radius` (as voxels) of `c`, ascending.
  void near(const Eigen::Vector3d& c, double radius, std::vector<std::uint32_t>* out) const {
    out->clear();
    const int r = static_cast<int>(std::ceil(radius / voxel_));
    const long cx = cell(c.x()), cy = cell(c.y()), cz = cell(c.z());
    for (long x = cx - r; x <= cx + r; ++x)
      for (long y = cy - r; y <= cy + r; ++y)
        for (long z = cz - r; z <= cz + r; ++z) {
          auto it = grid_.find(pack(x, y, z));
          if (it != grid_.end()) out->insert(out->end(), it->second.begin(), it->second.end());
        }
    std::sort(out->begin(), out->end());
  }

 private:
  long cell(double v) const { return static_cast<long>(std::floor(v / voxel_)); }
  static std::uint64_t pack(long x, long y, long z) {
    const auto m = [](long v) { return static_cast<std::uint64_t>(v + (1l << 20)) & 0x1FFFFFull; };
    return (m(x) << 42) | (m(y) << 21) | m(z);
  }
  std::uint64_t key(const Eigen::Vector3d& p) const { return pack(cell(p.x()), cell(p.y()), cell(p.z())); }

  double voxel_;
  std::vector<Landmark> points_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid_;
};

bool project(const Camera& cam, const Pose& T_cw, const Eigen::Vector3d& pw, double min_depth,
             double max_depth, double margin, double* u, double* v, double* z) {
  const Eigen::Vector3d pc = T_cw * pw;
  if (pc.z() < min_depth || pc.z() > max_depth) return false;
  *u = cam.fx * pc.x() / pc.z() + cam.cx;
  *v = cam.fy * pc.y() / pc.z() + cam.cy;
  *z = pc.z();
  return *u >= margin && *v >= margin && *u < cam.width - margin && *v < cam.height - margin;
}

}  // namespace

WorldOptions world_defaults(TrajectoryFormat format) {
  WorldOptions o;
  switch (format) {
    case TrajectoryFormat::kTum:  // Kinect, ORB-SLAM2's TUM1.yaml (bf = 40)
      o.cam = Camera{640, 480, 517.3, 516.5, 318.6, 255.3, 40.0 / 517.3};
      o.min_depth = 0.5; o.max_depth = 5.0; o.kf_translation = 0.1;
      break;
    case TrajectoryFormat::kEuroc:  // rectified left camera, 11 cm baseline
      o.cam = Camera{752, 480, 435.2, 435.2, 367.2, 252.2, 0.110};
      o.min_depth = 1.0; o.max_depth = 12.0; o.kf_translation = 0.25;
      break;
    case TrajectoryFormat::kKitti:  // KITTI odometry P0, 54 cm baseline
      o.cam = Camera{1241, 376, 718.856, 718.856, 607.19, 185.22, 0.537};
      o.min_depth = 4.0; o.max_depth = 60.0; o.kf_translation = 2.5;
      break;
  }
  return o;
}

void add_odometry(Scenario* s, double noise_t, double noise_r_deg, std::uint64_t seed) {
  Rng rng(mix(seed, 0x0D0));
  s->odometry.assign(s->frames.size(), Pose{});
  for (std::size_t k = 1; k < s->frames.size(); ++k) {
    Pose rel = s->frames[k - 1].gt.inverse() * s->frames[k].gt;
    const double step = rel.t.norm();
    Eigen::Vector3d dt(rng.gaussian(), rng.gaussian(), rng.gaussian());
    Eigen::Vector3d dr(rng.gaussian(), rng.gaussian(), rng.gaussian());
    rel.t += dt * (noise_t * step);
    rel.q = (rel.q * small_rotation(dr * (noise_r_deg * kDeg))).normalized();
    s->odometry[k] = rel;
  }
}

Scenario make_synthetic_scenario(const Trajectory& trajectory, const WorldOptions& o,
                                 const std::string& input, const std::string& name,
                                 const std::string& group) {
  Scenario s;
  s.input = input;
  s.name = name;
  s.group = group;
  s.kind = "trajectory";
  s.cam = o.cam;

  // Deterministic keyframe rule on the ground truth (paper, section IV-A).
  std::vector<std::size_t> kf_index{0};
  for (std::size_t i = 1; i < trajectory.poses.size(); ++i) {
    const Pose& last = trajectory.poses[kf_index.back()];
    const Pose rel = last.inverse() * trajectory.poses[i];
    if (rel.t.norm() > o.kf_translation || rotation_angle(rel.q) > o.kf_rotation_deg * kDeg) {
      kf_index.push_back(i);
      if (o.max_keyframes > 0 && static_cast<int>(kf_index.size()) >= o.max_keyframes) break;
    }
  }

  Rng rng(mix(o.seed, 0x5CE));
  World world(o.max_depth / 2.0);
  const int target_visible = 2 * o.keypoints_per_frame;
  const double margin = 2.0;
  std::vector<std::uint32_t> near;
  Rng noise(mix(o.seed, 0x401));

  for (std::size_t kf = 0; kf < kf_index.size(); ++kf) {
    ScenarioFrame f;
    f.source_index = kf_index[kf];
    f.gt = trajectory.poses[f.source_index];
    const Pose T_cw = f.gt.inverse();
    double u, v, z;

    // Populate the frustum: patches until ~3x the keypoint budget is visible.
    world.near(f.gt.t, o.max_depth, &near);
    int visible = 0;
    for (std::uint32_t i : near)
      if (project(o.cam, T_cw, world.points()[i].p, o.min_depth, o.max_depth, margin, &u, &v, &z)) ++visible;
    for (int guard = 0; visible < target_visible && guard < 100000; ++guard) {
      const double pu = rng.uniform(0, o.cam.width), pv = rng.uniform(0, o.cam.height);
      // Depth biased towards the near half, as indoor and road scenes are.
      const double a = rng.uniform();
      const double depth = o.min_depth + (o.max_depth - o.min_depth) * a * a;
      const double kind = rng.uniform();
      int count;
      double spread_px, r_lo, r_hi;
      if (kind < 0.25) { count = 24; spread_px = 6; r_lo = 60; r_hi = 100; }       // dense texture cluster
      else if (kind < 0.85) { count = 6; spread_px = 25; r_lo = 20; r_hi = 60; }   // ordinary texture
      else { count = 1; spread_px = 0; r_lo = 5; r_hi = 20; }                      // weak texture
      for (int j = 0; j < count; ++j) {
        const double du = spread_px * rng.gaussian(), dv = spread_px * rng.gaussian();
        const double dz = depth * (1.0 + 0.03 * rng.gaussian());
        const Eigen::Vector3d pc(((pu + du) - o.cam.cx) / o.cam.fx * dz, ((pv + dv) - o.cam.cy) / o.cam.fy * dz, dz);
        Landmark l{f.gt * pc, rng.uniform(r_lo, r_hi)};
        world.add(l);
        if (project(o.cam, T_cw, l.p, o.min_depth, o.max_depth, margin, &u, &v, &z)) ++visible;
      }
    }

    // Observe: projection, noise, outliers; then grid extraction.
    world.near(f.gt.t, o.max_depth, &near);
    std::vector<KeyPoint> cand;
    for (std::uint32_t i : near) {
      const Landmark& l = world.points()[i];
      if (!project(o.cam, T_cw, l.p, o.min_depth, o.max_depth, margin, &u, &v, &z)) continue;
      KeyPoint kp;
      kp.landmark = i;
      kp.u = u + o.pixel_noise * noise.gaussian();
      kp.v = v + o.pixel_noise * noise.gaussian();
      if (noise.uniform() < o.outlier_ratio) {  // a wrong match: a gross offset
        const double ang = noise.uniform(0, 6.283185307179586), mag = noise.uniform(8, 40);
        kp.u += mag * std::cos(ang);
        kp.v += mag * std::sin(ang);
      }
      kp.u = std::clamp(kp.u, 0.0, o.cam.width - 1e-6);
      kp.v = std::clamp(kp.v, 0.0, o.cam.height - 1e-6);
      if (o.cam.baseline > 0 && z < 40.0 * o.cam.baseline)  // ORB-SLAM2's close-point limit
        kp.ur = kp.u - o.cam.fx * o.cam.baseline / z + o.pixel_noise * noise.gaussian();
      kp.response = l.response * noise.uniform(0.95, 1.05);
      cand.push_back(kp);
    }
    // ORB-SLAM2 spreads its keypoints over the image; here: cells, each
    // sorted by response, taken round-robin until the budget is reached.
    const double cell = std::sqrt(double(o.cam.width) * o.cam.height / (o.keypoints_per_frame / 2.0));
    const int ncol = static_cast<int>(std::ceil(o.cam.width / cell)), nrow = static_cast<int>(std::ceil(o.cam.height / cell));
    std::vector<std::vector<std::uint32_t>> cells(static_cast<std::size_t>(ncol * nrow));
    for (std::uint32_t i = 0; i < cand.size(); ++i) {
      const int cc = std::min(ncol - 1, static_cast<int>(cand[i].u / cell));
      const int rr = std::min(nrow - 1, static_cast<int>(cand[i].v / cell));
      cells[static_cast<std::size_t>(rr * ncol + cc)].push_back(i);
    }
    for (auto& c : cells)
      std::sort(c.begin(), c.end(), [&](std::uint32_t a, std::uint32_t b) {
        return cand[a].response != cand[b].response ? cand[a].response > cand[b].response : a < b;
      });
    for (std::size_t round = 0; static_cast<int>(f.keypoints.size()) < o.keypoints_per_frame; ++round) {
      bool any = false;
      for (const auto& c : cells) {
        if (round >= c.size()) continue;
        any = true;
        f.keypoints.push_back(cand[c[round]]);
        if (static_cast<int>(f.keypoints.size()) >= o.keypoints_per_frame) break;
      }
      if (!any) break;
    }
    s.frames.push_back(std::move(f));
  }
  s.landmark_count = world.points().size();
  if (std::getenv("KEEPLESS_EVAL_DEBUG")) {
    double rep = 0;
    for (std::size_t k = 1; k < s.frames.size(); ++k) {
      std::vector<std::uint64_t> a;
      for (const auto& p : s.frames[k - 1].keypoints) a.push_back(p.landmark);
      std::sort(a.begin(), a.end());
      int hit = 0;
      for (const auto& p : s.frames[k].keypoints) hit += std::binary_search(a.begin(), a.end(), p.landmark);
      rep += double(hit) / std::max<std::size_t>(1, s.frames[k].keypoints.size());
    }
    std::fprintf(stderr, "scenario %s: %zu keyframes, %zu landmarks, repeatability %.3f\n", name.c_str(),
                 s.frames.size(), world.points().size(), rep / std::max<std::size_t>(1, s.frames.size() - 1));
  }
  add_odometry(&s, o.odom_noise_t, o.odom_noise_r_deg, o.seed);
  return s;
}

}  // namespace keepless::eval
