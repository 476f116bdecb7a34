#include "vo_map.hpp"

#include <algorithm>
#include <cmath>

namespace keepless::eval::vo {

int Map::new_point(const Eigen::Vector3d& X, int kf, int keypoint) {
  MapPoint p;
  p.X = X;
  p.first_kf = kf;
  points.push_back(std::move(p));
  const int id = static_cast<int>(points.size()) - 1;
  add_observation(id, kf, keypoint);
  update_point(id);
  return id;
}

void Map::add_observation(int p, int kf, int keypoint) {
  MapPoint& m = points[static_cast<std::size_t>(p)];
  for (const auto& o : m.obs) {
    if (o.first == kf) return;
  }
  m.obs.emplace_back(kf, keypoint);
  kfs[static_cast<std::size_t>(kf)].mp[static_cast<std::size_t>(keypoint)] = p;
}

void Map::erase_observation(int p, int kf) {
  MapPoint& m = points[static_cast<std::size_t>(p)];
  for (std::size_t i = 0; i < m.obs.size(); ++i) {
    if (m.obs[i].first != kf) continue;
    auto& slot = kfs[static_cast<std::size_t>(kf)].mp[static_cast<std::size_t>(m.obs[i].second)];
    if (slot == p) slot = -1;
    m.obs.erase(m.obs.begin() + static_cast<std::ptrdiff_t>(i));
    break;
  }
  if (weighted_observations(p) <= 2) set_bad(p);
}

void Map::set_bad(int p) {
  MapPoint& m = points[static_cast<std::size_t>(p)];
  if (m.bad) return;
  m.bad = true;
  for (const auto& o : m.obs) {
    auto& slot = kfs[static_cast<std::size_t>(o.first)].mp[static_cast<std::size_t>(o.second)];
    if (slot == p) slot = -1;
  }
  m.obs.clear();
}

void Map::cull_remembered(int p) {
  MapPoint& m = points[static_cast<std::size_t>(p)];
  if (m.bad) return;
  m.culled_obs = m.obs;
  for (const auto& o : m.obs) {
    // One remembered cull per keypoint: a later point at the same keypoint,
    // culled too, replaces the earlier one (redundant() counts keypoints).
    auto& culled = kfs[static_cast<std::size_t>(o.first)].culled;
    const auto same = std::find_if(culled.begin(), culled.end(), [&](const auto& c) { return c.first == o.second; });
    if (same != culled.end()) same->second = p;
    else culled.emplace_back(o.second, p);
  }
  set_bad(p);
}

bool Map::redundant(int kf, double close_depth) const {
  const int th_obs = 3;
  const KeyFrame& f = kfs[static_cast<std::size_t>(kf)];
  int n = 0, redundant = 0;
  const auto count = [&](std::size_t i, const std::vector<std::pair<int, int>>& obs) {
    if (close_depth > 0 && (f.f.depth[i] <= 0 || f.f.depth[i] > close_depth)) return;
    ++n;
    int weighted = 0;  // weighted_observations, over the keyframes still alive
    for (const auto& [k2, j] : obs) {
      const KeyFrame& g = kfs[static_cast<std::size_t>(k2)];
      if (!g.bad) weighted += g.f.ur[static_cast<std::size_t>(j)] >= 0 ? 2 : 1;
    }
    if (weighted <= th_obs) return;
    const int level = f.f.keys[i].octave;
    int seen = 0;
    for (const auto& [k2, j] : obs) {
      const KeyFrame& g = kfs[static_cast<std::size_t>(k2)];
      if (k2 == kf || g.bad) continue;
      if (g.f.keys[static_cast<std::size_t>(j)].octave <= level + 1 && ++seen >= th_obs) break;
    }
    if (seen >= th_obs) ++redundant;
  };
  for (std::size_t i = 0; i < f.mp.size(); ++i) {
    const int p = f.mp[i];
    if (p >= 0 && !points[static_cast<std::size_t>(p)].bad) count(i, points[static_cast<std::size_t>(p)].obs);
  }
  for (const auto& [i, p] : f.culled) {  // unless the keypoint has an alive point again
    if (f.mp[static_cast<std::size_t>(i)] < 0) count(static_cast<std::size_t>(i), points[static_cast<std::size_t>(p)].culled_obs);
  }
  return n > 0 && redundant > 0.9 * n;
}

void Map::replace(int p, int by) {
  if (p == by) return;
  MapPoint& m = points[static_cast<std::size_t>(p)];
  const std::vector<std::pair<int, int>> obs = m.obs;
  m.obs.clear();
  m.bad = true;
  m.replaced_by = by;
  MapPoint& b = points[static_cast<std::size_t>(by)];
  b.visible += m.visible;
  b.found += m.found;
  for (const auto& o : obs) {
    auto& slot = kfs[static_cast<std::size_t>(o.first)].mp[static_cast<std::size_t>(o.second)];
    if (slot == p) slot = -1;
    const bool seen = std::any_of(b.obs.begin(), b.obs.end(), [&](const auto& x) { return x.first == o.first; });
    if (!seen) add_observation(by, o.first, o.second);
  }
  update_point(by);
}

int Map::resolve(int p) const {
  for (int hops = 0; p >= 0 && hops < 64; ++hops) {
    const MapPoint& m = points[static_cast<std::size_t>(p)];
    if (!m.bad) return p;
    p = m.replaced_by;
  }
  return -1;
}

int Map::weighted_observations(int p) const {
  int n = 0;
  for (const auto& o : points[static_cast<std::size_t>(p)].obs) {
    n += kfs[static_cast<std::size_t>(o.first)].f.ur[static_cast<std::size_t>(o.second)] >= 0 ? 2 : 1;
  }
  return n;
}

void Map::update_point(int p) {
  MapPoint& m = points[static_cast<std::size_t>(p)];
  if (m.bad || m.obs.empty()) return;
  // Normal and scale range (UpdateNormalAndDepth), from the first observer.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const auto& o : m.obs) normal += (m.X - kfs[static_cast<std::size_t>(o.first)].centre()).normalized();
  m.normal = normal.normalized();
  const auto& ref = m.obs.front();
  const KeyFrame& rk = kfs[static_cast<std::size_t>(ref.first)];
  const double dist = (m.X - rk.centre()).norm();
  const int level = rk.f.keys[static_cast<std::size_t>(ref.second)].octave;
  m.max_distance = dist * pyramid().scale[static_cast<std::size_t>(level)];
  m.min_distance = m.max_distance / pyramid().scale[kLevels - 1];
  // Descriptor with the least median distance to the others (ComputeDistinctiveDescriptors).
  const std::size_t n = m.obs.size();
  std::size_t best = 0;
  int best_median = 1 << 30;
  std::vector<int> d(n);
  for (std::size_t i = 0; i < n; ++i) {
    const KeyFrame& ki = kfs[static_cast<std::size_t>(m.obs[i].first)];
    for (std::size_t j = 0; j < n; ++j) {
      const KeyFrame& kj = kfs[static_cast<std::size_t>(m.obs[j].first)];
      d[j] = hamming(ki.f.descriptors, m.obs[i].second, kj.f.descriptors, m.obs[j].second);
    }
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2), d.end());
    if (d[(n - 1) / 2] < best_median) {
      best_median = d[(n - 1) / 2];
      best = i;
    }
  }
  const KeyFrame& kb = kfs[static_cast<std::size_t>(m.obs[best].first)];
  m.descriptor = kb.f.descriptors.row(m.obs[best].second).clone();
}

std::vector<std::pair<int, int>> Map::covisibles(int kf, int min_weight) const {
  std::vector<int> weight(kfs.size(), 0);  // by keyframe index (a std::map cost a node per keyframe)
  for (int p : kfs[static_cast<std::size_t>(kf)].mp) {
    if (p < 0 || points[static_cast<std::size_t>(p)].bad) continue;
    for (const auto& o : points[static_cast<std::size_t>(p)].obs) {
      if (o.first != kf && !kfs[static_cast<std::size_t>(o.first)].bad) ++weight[static_cast<std::size_t>(o.first)];
    }
  }
  std::vector<std::pair<int, int>> out;
  for (std::size_t k = 0; k < weight.size(); ++k) {
    if (weight[k] > 0 && weight[k] >= min_weight) out.emplace_back(static_cast<int>(k), weight[k]);
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first > b.first;
  });
  return out;
}

void Map::cull_keyframe(int kf) {
  KeyFrame& k = kfs[static_cast<std::size_t>(kf)];
  const auto cov = covisibles(kf, 1);
  int parent = -1;
  for (const auto& c : cov) {
    if (c.first < kf || parent < 0) {  // prefer an older keyframe as parent
      parent = c.first;
      if (c.first < kf) break;
    }
  }
  if (parent < 0) {
    for (int j = kf - 1; j >= 0 && parent < 0; --j) {
      if (!kfs[static_cast<std::size_t>(j)].bad) parent = j;
    }
  }
  if (parent < 0) return;
  for (std::size_t i = 0; i < k.mp.size(); ++i) {
    if (k.mp[i] >= 0) erase_observation(k.mp[i], kf);
  }
  k.bad = true;
  k.parent = parent;
  k.T_cp = k.Tcw * kfs[static_cast<std::size_t>(parent)].Tcw.inverse();
}

std::vector<int> Map::points_of(const std::vector<int>& keyframes) const {
  std::vector<int> out;
  std::vector<char> seen(points.size(), 0);
  for (int k : keyframes) {
    for (int p : kfs[static_cast<std::size_t>(k)].mp) {
      if (p >= 0 && !seen[static_cast<std::size_t>(p)] && !points[static_cast<std::size_t>(p)].bad) {
        seen[static_cast<std::size_t>(p)] = 1;
        out.push_back(p);
      }
    }
  }
  return out;
}

int Map::alive_points() const {
  return static_cast<int>(std::count_if(points.begin(), points.end(), [](const MapPoint& m) { return !m.bad; }));
}

int Map::alive_keyframes() const {
  return static_cast<int>(std::count_if(kfs.begin(), kfs.end(), [](const KeyFrame& k) { return !k.bad; }));
}

int predict_level(const MapPoint& p, double distance) {
  const double ratio = p.max_distance / distance;
  const int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(kScaleFactor)));
  return std::clamp(level, 0, kLevels - 1);
}

bool Map::in_frustum(int p, const Eigen::Isometry3d& Tcw, const PinholeCamera& cam, double* u, double* v,
                     int* level, double* view_cos) const {
  const MapPoint& m = points[static_cast<std::size_t>(p)];
  const Eigen::Vector3d pc = Tcw * m.X;
  if (pc.z() <= 0) return false;
  *u = cam.fx * pc.x() / pc.z() + cam.cx;
  *v = cam.fy * pc.y() / pc.z() + cam.cy;
  if (*u < 0 || *v < 0 || *u >= cam.width || *v >= cam.height) return false;
  const Eigen::Vector3d po = m.X - Tcw.inverse().translation();
  const double dist = po.norm();
  if (dist < 0.8 * m.min_distance || dist > 1.2 * m.max_distance) return false;
  *view_cos = po.dot(m.normal) / dist;
  if (*view_cos < 0.5) return false;
  *level = predict_level(m, dist);
  return true;
}

}  // namespace keepless::eval::vo
