#include "scene.hpp"

#include <algorithm>
#include <cmath>

namespace keepless::vo_sim {

SceneConfig street_scene() { return SceneConfig{}; }

SceneConfig room_scene() {
  SceneConfig c;
  c.name = "room";
  c.cell = 0.5;
  c.free_radius = 1.9;
  c.floor_z = 0.0;
  c.wall_top = 2.8;
  c.ceiling = true;
  c.max_range = 9.0;
  c.wall_density = 160.0;
  c.floor_density = 30.0;
  c.ceiling_density = 10.0;
  c.cluster_density = 500.0;
  c.tile_spacing = 0.3;
  c.p_weak_face = 0.3;
  c.p_cluster_face = 0.25;
  c.p_tile_cell = 0.5;
  return c;
}

const char* to_string(PointKind k) {
  switch (k) {
    case PointKind::kWall: return "wall";
    case PointKind::kWallCluster: return "wall_cluster";
    case PointKind::kWeak: return "weak";
    case PointKind::kFloor: return "floor";
    case PointKind::kFloorTile: return "floor_tile";
    case PointKind::kCeiling: return "ceiling";
  }
  return "?";
}

World::World(const SceneConfig& config, const Camera& camera, const std::vector<Pose>& path, std::uint64_t seed)
    : config_(config), camera_(camera), seed_(seed), noise_(mix_seed(seed, 7, 7, 7)) {
  // Open space: every cell whose centre is within free_radius of a path pose.
  const auto reach = static_cast<std::int64_t>(std::ceil(config_.free_radius / config_.cell)) + 1;
  for (const Pose& p : path) {
    const std::int64_t pcx = cell_of(p.centre.x), pcy = cell_of(p.centre.y);
    for (std::int64_t cx = pcx - reach; cx <= pcx + reach; ++cx) {
      for (std::int64_t cy = pcy - reach; cy <= pcy + reach; ++cy) {
        const double x = (static_cast<double>(cx) + 0.5) * config_.cell - p.centre.x;
        const double y = (static_cast<double>(cy) + 0.5) * config_.cell - p.centre.y;
        if (x * x + y * y <= config_.free_radius * config_.free_radius) cells_[key(cx, cy)].free = true;
      }
    }
    // The camera's own cell is always open.
    cells_[key(pcx, pcy)].free = true;
  }
}

bool World::is_free(std::int64_t cx, std::int64_t cy) const {
  const auto it = cells_.find(key(cx, cy));
  return it != cells_.end() && it->second.free;
}

void World::add_point(Cell& cell, Vec3 p, Vec3 n, std::int64_t cx, std::int64_t cy, float strength, PointKind kind) {
  ScenePoint sp;
  sp.position = p;
  sp.normal = n;
  sp.home_cx = cx;
  sp.home_cy = cy;
  sp.strength = strength;
  sp.kind = kind;
  cell.points.push_back(static_cast<std::uint32_t>(points_.size()));
  points_.push_back(sp);
}

// Poisson-ish count for an expected value: floor plus a Bernoulli remainder.
static int draw_count(SplitMix64& rng, double expected) {
  const double f = std::floor(expected);
  return static_cast<int>(f) + (rng.uniform() < expected - f ? 1 : 0);
}

void World::generate(std::int64_t cx, std::int64_t cy, Cell& cell) {
  cell.generated = true;
  SplitMix64 rng(mix_seed(seed_, cx, cy, 11));
  const double s = config_.cell;
  const double x0 = static_cast<double>(cx) * s, y0 = static_cast<double>(cy) * s;
  const double area = s * s;
  const float weak_strength_cap = 0.3f;

  // Floor: random texture, or tiles whose corners are tight clusters of
  // corner-like features (the dense regions the paper's c_s penalises).
  const Vec3 up{0, 0, 1};
  const int floor_n = draw_count(rng, config_.floor_density * area);
  for (int i = 0; i < floor_n; ++i) {
    add_point(cell, {x0 + rng.uniform() * s, y0 + rng.uniform() * s, config_.floor_z}, up, cx, cy,
              static_cast<float>(rng.uniform(0.2, 1.0)), PointKind::kFloor);
  }
  if (rng.uniform() < config_.p_tile_cell) {
    const double t = config_.tile_spacing;
    const double ox = std::fmod(x0, t) < 0 ? std::fmod(x0, t) + t : std::fmod(x0, t);
    const double oy = std::fmod(y0, t) < 0 ? std::fmod(y0, t) + t : std::fmod(y0, t);
    for (double gx = x0 + (ox > 0 ? t - ox : 0); gx < x0 + s; gx += t) {
      for (double gy = y0 + (oy > 0 ? t - oy : 0); gy < y0 + s; gy += t) {
        const int k = 2 + static_cast<int>(rng.below(2));
        for (int j = 0; j < k; ++j) {
          add_point(cell, {gx + rng.uniform(-0.012, 0.012) * t / 0.3, gy + rng.uniform(-0.012, 0.012) * t / 0.3,
                           config_.floor_z},
                    up, cx, cy, static_cast<float>(rng.uniform(0.4, 1.0)), PointKind::kFloorTile);
        }
      }
    }
  }
  if (config_.ceiling) {
    const int n = draw_count(rng, config_.ceiling_density * area);
    for (int i = 0; i < n; ++i) {
      add_point(cell, {x0 + rng.uniform() * s, y0 + rng.uniform() * s, config_.wall_top}, {0, 0, -1}, cx, cy,
                static_cast<float>(rng.uniform(0.0, 0.5)), PointKind::kCeiling);
    }
  }

  // Walls on the sides that border a solid cell, facing into this cell.
  struct Side {
    std::int64_t dx, dy;
  };
  const Side sides[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  const double height = config_.wall_top - config_.floor_z;
  for (const Side& sd : sides) {
    if (is_free(cx + sd.dx, cy + sd.dy)) continue;
    SplitMix64 face(mix_seed(seed_, cx * 4 + sd.dx + 2, cy * 4 + sd.dy + 2, 13));
    const Vec3 normal{-static_cast<double>(sd.dx), -static_cast<double>(sd.dy), 0};
    // A point on the face at (a along the face, h above the floor).
    auto at = [&](double a, double h) -> Vec3 {
      if (sd.dx != 0) return {sd.dx > 0 ? x0 + s : x0, y0 + a, config_.floor_z + h};
      return {x0 + a, sd.dy > 0 ? y0 + s : y0, config_.floor_z + h};
    };
    const bool weak = face.uniform() < config_.p_weak_face;
    const double density = weak ? 0.08 * config_.wall_density : config_.wall_density;
    const int n = draw_count(face, density * s * height);
    for (int i = 0; i < n; ++i) {
      add_point(cell, at(face.uniform() * s, face.uniform() * height), normal, cx, cy,
                weak ? static_cast<float>(face.uniform(0.0, weak_strength_cap)) : static_cast<float>(face.uniform(0.2, 1.0)),
                weak ? PointKind::kWeak : PointKind::kWall);
    }
    if (!weak && face.uniform() < config_.p_cluster_face) {
      // A poster or window: a rectangle of dense, strong features.
      const double w = face.uniform(0.3, 0.8) * s, h = face.uniform(0.15, 0.4) * std::min(height, 4.0);
      const double a0 = face.uniform() * (s - w), h0 = face.uniform(0.2, 0.8) * (std::min(height, 6.0) - h);
      const int m = draw_count(face, config_.cluster_density * w * h);
      for (int i = 0; i < m; ++i) {
        add_point(cell, at(a0 + face.uniform() * w, h0 + face.uniform() * h), normal, cx, cy,
                  static_cast<float>(face.uniform(0.5, 1.0)), PointKind::kWallCluster);
      }
    }
  }
}

bool World::occluded(Vec3 from, std::int64_t to_cx, std::int64_t to_cy) const {
  const double tx = (static_cast<double>(to_cx) + 0.5) * config_.cell;
  const double ty = (static_cast<double>(to_cy) + 0.5) * config_.cell;
  const double dx = tx - from.x, dy = ty - from.y;
  const double dist = std::sqrt(dx * dx + dy * dy);
  const int steps = static_cast<int>(dist / (0.35 * config_.cell)) + 1;
  for (int i = 1; i < steps; ++i) {
    const double f = static_cast<double>(i) / steps;
    const std::int64_t cx = cell_of(from.x + f * dx), cy = cell_of(from.y + f * dy);
    if (cx == to_cx && cy == to_cy) return false;
    if (!is_free(cx, cy)) return true;
  }
  return false;
}

void World::observe(const Pose& pose, std::int32_t index, std::vector<SimObservation>& out) {
  out.clear();
  const Mat3 rt = transpose(pose.rotation);
  const auto reach = static_cast<std::int64_t>(std::ceil(config_.max_range / config_.cell));
  const std::int64_t pcx = cell_of(pose.centre.x), pcy = cell_of(pose.centre.y);
  struct Candidate {
    float score;
    std::uint32_t point;
    float u, v;
  };
  std::vector<Candidate> cand;
  const double margin = 2.0;
  for (std::int64_t cx = pcx - reach; cx <= pcx + reach; ++cx) {
    for (std::int64_t cy = pcy - reach; cy <= pcy + reach; ++cy) {
      if (!is_free(cx, cy)) continue;
      Cell& cell = cells_[key(cx, cy)];
      if (!cell.generated) generate(cx, cy, cell);
      for (std::uint32_t pi : cell.points) {
        const ScenePoint& sp = points_[pi];
        if (sp.state == PointState::kDeleted) continue;
        const Vec3 rel = sp.position - pose.centre;
        const Vec3 pc = rt * rel;
        if (pc.z < 0.3 || pc.z > config_.max_range) continue;
        const double u = camera_.fx * pc.x / pc.z + camera_.cx;
        const double v = camera_.fy * pc.y / pc.z + camera_.cy;
        if (u < margin || v < margin || u > camera_.width - 1 - margin || v > camera_.height - 1 - margin) continue;
        // Facing the camera, and not at a grazing angle.
        const double d = norm(rel);
        const double facing = -dot(sp.normal, rel) / d;
        if (facing < 0.12) continue;
        if (occluded(pose.centre, sp.home_cx, sp.home_cy)) continue;
        // Response falls with distance and obliquity, like a real detector.
        const double score = sp.strength * (0.5 + 0.5 * facing) / (1.0 + 0.05 * d);
        cand.push_back({static_cast<float>(score), pi, static_cast<float>(u), static_cast<float>(v)});
      }
    }
  }
  candidates_last_ = cand.size();
  // Strongest first; ties by point index, so the order is fixed.
  std::sort(cand.begin(), cand.end(), [](const Candidate& a, const Candidate& b) {
    return a.score != b.score ? a.score > b.score : a.point < b.point;
  });
  const std::size_t budget = static_cast<std::size_t>(std::max(config_.max_keypoints, 0));
  for (const Candidate& c : cand) {
    if (out.size() >= budget) break;
    // Repeatability: weak responses are missed more often.
    const double miss = 0.05 + 0.25 * (1.0 - static_cast<double>(points_[c.point].strength));
    if (noise_.uniform() < miss) continue;
    const float u = static_cast<float>(c.u + config_.pixel_noise * noise_.normal());
    const float v = static_cast<float>(c.v + config_.pixel_noise * noise_.normal());
    if (u < 0 || v < 0 || u > static_cast<float>(camera_.width - 1) || v > static_cast<float>(camera_.height - 1)) continue;
    out.push_back({c.point, u, v, false});
  }
  std::sort(out.begin(), out.end(), [](const SimObservation& a, const SimObservation& b) { return a.point < b.point; });
  for (SimObservation& o : out) {
    ScenePoint& sp = points_[o.point];
    const bool fresh = sp.state == PointState::kUnseen;
    const bool again = sp.state == PointState::kCulled && config_.retriangulate_after >= 0 &&
                       index - sp.culled_at >= config_.retriangulate_after;
    if (fresh || again) {
      landmark_feature_.push_back(o.point);
      sp.landmark = static_cast<std::int64_t>(landmark_feature_.size());
      sp.state = PointState::kMapped;
      ++sp.landmarks;
      if (fresh) sp.first_keyframe = index;
    }
    o.mapped = sp.state == PointState::kMapped;
    if (o.mapped) ++sp.observations;
  }
}

bool World::cull(std::int64_t landmark, std::int32_t index) {
  if (landmark < 1 || landmark > static_cast<std::int64_t>(landmark_feature_.size())) return false;
  ScenePoint& sp = points_[landmark_feature_[static_cast<std::size_t>(landmark - 1)]];
  if (sp.landmark != landmark || sp.state != PointState::kMapped) return false;
  sp.state = PointState::kCulled;
  sp.culled_at = index;
  sp.landmark = 0;
  return true;
}

void World::remove(std::uint32_t point) {
  ScenePoint& sp = points_[point];
  sp.state = PointState::kDeleted;
  sp.landmark = 0;
}

}  // namespace keepless::vo_sim
