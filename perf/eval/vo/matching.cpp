#include "matching.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace keepless::eval::vo {
namespace {

// Brute force along the epipolar band (ORB-SLAM2 narrows by BoW node instead).
constexpr double kTriangulationRatio = 0.7;

struct Best {
  int dist = std::numeric_limits<int>::max(), dist2 = std::numeric_limits<int>::max();
  int index = -1, level = -1, level2 = -1;
  void offer(int d, int i, int level_i) {
    if (d < dist) {
      dist2 = dist, level2 = level;
      dist = d, index = i, level = level_i;
    } else if (d < dist2) {
      dist2 = d, level2 = level_i;
    }
  }
};

// Best with ties to the lowest index, so candidates may come in any order
// (the triangulation search visits b's keypoints level by level) and the
// outcome is that of offering them in index order.
struct BestOfAny {
  int dist = std::numeric_limits<int>::max(), dist2 = std::numeric_limits<int>::max();
  int index = -1;
  void offer(int d, int i) {
    if (d < dist || (d == dist && i < index)) {
      dist2 = dist;
      dist = d, index = i;
    } else if (d < dist2) {
      dist2 = d;
    }
  }
};

// Keypoints (`which`, of one level) flat and sorted by x or by y, with
// whether each lies within the monocular triangulation's epipole radius.
struct SortedKeys {
  std::vector<double> key, x, y;  // key: the sorted coordinate
  std::vector<int> index;
  std::vector<char> near_epipole;
  double other_min = 0, other_max = 0;  // range of the other coordinate

  SortedKeys() = default;
  SortedKeys(const std::vector<cv::KeyPoint>& keys, std::vector<int> which, double eu, double ev, bool by_x) {
    const auto coord = [&](int j, bool along_x) {
      const cv::Point2f& p = keys[static_cast<std::size_t>(j)].pt;
      return along_x ? p.x : p.y;
    };
    std::stable_sort(which.begin(), which.end(), [&](int a, int b) { return coord(a, by_x) < coord(b, by_x); });
    other_min = std::numeric_limits<double>::infinity();
    other_max = -other_min;
    for (int j : which) {
      const cv::KeyPoint& pb = keys[static_cast<std::size_t>(j)];
      const double du = eu - pb.pt.x, dv = ev - pb.pt.y;
      key.push_back(coord(j, by_x));
      x.push_back(pb.pt.x);
      y.push_back(pb.pt.y);
      index.push_back(j);
      near_epipole.push_back(du * du + dv * dv < 100 * pyramid().scale[static_cast<std::size_t>(pb.octave)]);
      other_min = std::min<double>(other_min, coord(j, !by_x));
      other_max = std::max<double>(other_max, coord(j, !by_x));
    }
  }

  // Index range of the keypoints within `bound` of a x + b y + c = 0
  // (|a x + b y + c| <= bound), a superset: the line crosses the sorted
  // coordinate over the other's range, widened by bound / |a| and a pixel.
  std::pair<std::size_t, std::size_t> band(const Eigen::Vector3d& line, bool steep, double bound) const {
    if (!std::isfinite(bound) || key.empty()) return {0, key.size()};
    const double a = steep ? line.x() : line.y(), b = steep ? line.y() : line.x();
    const double e0 = -(line.z() + b * other_min) / a, e1 = -(line.z() + b * other_max) / a;
    const double slack = bound / std::abs(a) * (1 + 1e-6) + 1;
    const auto lo = std::lower_bound(key.begin(), key.end(), std::min(e0, e1) - slack);
    const auto hi = std::upper_bound(lo, key.end(), std::max(e0, e1) + slack);
    return {static_cast<std::size_t>(lo - key.begin()), static_cast<std::size_t>(hi - key.begin())};
  }
};

bool project(const PinholeCamera& cam, const Eigen::Isometry3d& Tcw, const Eigen::Vector3d& X, double* u,
             double* v, double* z) {
  const Eigen::Vector3d p = Tcw * X;
  if (p.z() <= 0) return false;
  *z = p.z();
  *u = cam.fx * p.x() / p.z() + cam.cx;
  *v = cam.fy * p.y() / p.z() + cam.cy;
  return *u >= 0 && *v >= 0 && *u < cam.width && *v < cam.height;
}

}  // namespace

int search_by_projection(TrackedFrame& cur, const TrackedFrame& last, const Map& map,
                         const PinholeCamera& cam, double th) {
  int found = 0;
  std::vector<int> area;
  for (std::size_t i = 0; i < last.mp.size(); ++i) {
    const int p = last.mp[i] >= 0 ? map.resolve(last.mp[i]) : -1;
    if (p < 0 || last.outlier[i]) continue;
    const MapPoint& m = map.points[static_cast<std::size_t>(p)];
    double u, v, z;
    if (!project(cam, cur.Tcw, m.X, &u, &v, &z)) continue;
    const int level = last.f.keys[i].octave;
    const double r = th * pyramid().scale[static_cast<std::size_t>(level)];
    cur.f.features_in_area(u, v, r, std::max(0, level - 1), std::min(kLevels - 1, level + 1), &area);
    Best best;
    for (int j : area) {
      if (cur.mp[static_cast<std::size_t>(j)] >= 0) continue;
      const double ur = cur.f.ur[static_cast<std::size_t>(j)];
      if (ur >= 0 && std::abs(u - cam.bf / z - ur) > r) continue;
      best.offer(hamming(m.descriptor, 0, cur.f.descriptors, j), j, 0);
    }
    if (best.index >= 0 && best.dist <= kHammingHigh) {
      cur.mp[static_cast<std::size_t>(best.index)] = p;
      ++found;
    }
  }
  return found;
}

int search_local_points(TrackedFrame& cur, Map& map, const std::vector<int>& points,
                        const PinholeCamera& cam, double th) {
  for (int p : cur.mp) {  // matched already: visible, and not searched again
    if (p < 0) continue;
    MapPoint& m = map.points[static_cast<std::size_t>(p)];
    m.last_seen_frame = cur.index;
    ++m.visible;
  }
  int found = 0;
  std::vector<int> area;
  for (int p : points) {
    MapPoint& m = map.points[static_cast<std::size_t>(p)];
    if (m.bad || m.last_seen_frame == cur.index) continue;
    double u, v, view_cos;
    int level;
    if (!map.in_frustum(p, cur.Tcw, cam, &u, &v, &level, &view_cos)) continue;
    ++m.visible;
    const double r = th * (view_cos > 0.998 ? 2.5 : 4.0) * pyramid().scale[static_cast<std::size_t>(level)];
    cur.f.features_in_area(u, v, r, level - 1, level, &area);
    Best best;
    for (int j : area) {
      if (cur.mp[static_cast<std::size_t>(j)] >= 0) continue;
      best.offer(hamming(m.descriptor, 0, cur.f.descriptors, j), j, cur.f.keys[static_cast<std::size_t>(j)].octave);
    }
    if (best.index < 0 || best.dist > kHammingHigh) continue;
    if (best.level == best.level2 && best.dist > 0.8 * best.dist2) continue;
    cur.mp[static_cast<std::size_t>(best.index)] = p;
    ++found;
  }
  return found;
}

int fuse(Map& map, int kf, const std::vector<int>& points, const PinholeCamera& cam) {
  int changed = 0;
  std::vector<int> area;
  for (int p0 : points) {
    const int p = map.resolve(p0);
    if (p < 0) continue;
    KeyFrame& k = map.kfs[static_cast<std::size_t>(kf)];
    const MapPoint& m = map.points[static_cast<std::size_t>(p)];
    if (std::any_of(m.obs.begin(), m.obs.end(), [&](const auto& o) { return o.first == kf; })) continue;
    double u, v, view_cos;
    int level;
    if (!map.in_frustum(p, k.Tcw, cam, &u, &v, &level, &view_cos)) continue;
    const double z = (k.Tcw * m.X).z();
    const double r = 3.0 * pyramid().scale[static_cast<std::size_t>(level)];
    k.f.features_in_area(u, v, r, level - 1, level, &area);
    int best = -1, best_dist = std::numeric_limits<int>::max();
    for (int j : area) {
      const cv::KeyPoint& kp = k.f.keys[static_cast<std::size_t>(j)];
      const double inv = pyramid().inv_sigma2[static_cast<std::size_t>(kp.octave)];
      double e2 = (u - kp.pt.x) * (u - kp.pt.x) + (v - kp.pt.y) * (v - kp.pt.y);
      const double ur = k.f.ur[static_cast<std::size_t>(j)];
      if (ur >= 0) e2 += (u - cam.bf / z - ur) * (u - cam.bf / z - ur);
      if (e2 * inv > (ur >= 0 ? 7.8 : 5.99)) continue;
      const int d = hamming(m.descriptor, 0, k.f.descriptors, j);
      if (d < best_dist) best_dist = d, best = j;
    }
    if (best < 0 || best_dist > kHammingLow) continue;
    const int there = map.resolve(k.mp[static_cast<std::size_t>(best)]);
    if (there >= 0) {
      if (map.weighted_observations(there) > map.weighted_observations(p)) {
        map.replace(p, there);
      } else {
        map.replace(there, p);
      }
    } else {
      map.add_observation(p, kf, best);
      map.update_point(p);
    }
    ++changed;
  }
  return changed;
}

EpipolarGeometry epipolar_geometry(const KeyFrame& a, const KeyFrame& b, const PinholeCamera& cam) {
  // F_ba = K^-T [t]x R K^-1 with T_ba = T_b T_a^-1.
  const Eigen::Isometry3d Tba = b.Tcw * a.Tcw.inverse();
  Eigen::Matrix3d tx;
  const Eigen::Vector3d t = Tba.translation();
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  Eigen::Matrix3d K;
  K << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1;
  const Eigen::Matrix3d Kinv = K.inverse();
  EpipolarGeometry g;
  g.F = Kinv.transpose() * tx * Tba.linear() * Kinv;
  const Eigen::Vector3d ca = b.Tcw * a.centre();
  g.epipole_u = cam.fx * ca.x() / ca.z() + cam.cx;
  g.epipole_v = cam.fy * ca.y() / ca.z() + cam.cy;
  return g;
}

std::vector<std::pair<int, int>> search_for_triangulation(const Map& map, int a, int b,
                                                          const PinholeCamera& cam) {
  const KeyFrame& ka = map.kfs[static_cast<std::size_t>(a)];
  const KeyFrame& kb = map.kfs[static_cast<std::size_t>(b)];
  const EpipolarGeometry g = epipolar_geometry(ka, kb, cam);
  const Eigen::Matrix3d& F = g.F;
  const double eu = g.epipole_u, ev = g.epipole_v;

  // b's unmatched keypoints by level, flat (the loop below runs |a| x |b|
  // times per neighbour), sorted by x and by y: a line's band is then a range
  // of the coordinate it crosses faster.
  std::array<std::vector<int>, kLevels> level_b;
  for (std::size_t j = 0; j < kb.mp.size(); ++j) {
    if (kb.mp[j] < 0) level_b[static_cast<std::size_t>(kb.f.keys[j].octave)].push_back(static_cast<int>(j));
  }
  std::array<SortedKeys, kLevels> by_x, by_y;
  std::array<double, kLevels> max_e2{};  // chi2 3.84 x sigma^2 of the level
  for (std::size_t l = 0; l < kLevels; ++l) {
    const double s = pyramid().scale[l];
    max_e2[l] = 3.84 * s * s;
    by_x[l] = SortedKeys(kb.f.keys, level_b[l], eu, ev, true);
    by_y[l] = SortedKeys(kb.f.keys, level_b[l], eu, ev, false);
  }
  std::vector<std::pair<int, int>> out;
  std::vector<int> taken(kb.mp.size(), -1);
  std::vector<int> taken_dist(kb.mp.size(), std::numeric_limits<int>::max());
  for (std::size_t i = 0; i < ka.mp.size(); ++i) {
    if (ka.mp[i] >= 0) continue;
    const cv::KeyPoint& pa = ka.f.keys[i];
    const Eigen::Vector3d line = F * Eigen::Vector3d(pa.pt.x, pa.pt.y, 1);
    const double norm2 = line.x() * line.x() + line.y() * line.y();
    if (norm2 <= 0) continue;
    const bool monocular = ka.f.ur[i] < 0;
    const bool steep = std::abs(line.x()) >= std::abs(line.y());
    const std::uint8_t* da = ka.f.descriptors.ptr(static_cast<int>(i));
    BestOfAny best;
    for (int l = std::max(0, pa.octave - 1); l <= std::min(kLevels - 1, pa.octave + 1); ++l) {
      const SortedKeys& keys = (steep ? by_x : by_y)[static_cast<std::size_t>(l)];
      const double max_e2_l = max_e2[static_cast<std::size_t>(l)];
      // |num| beyond this bound fails the chi2 test below for certain (the
      // margin dwarfs rounding), so most keypoints skip the division; a
      // non-finite bound (degenerate line) visits every keypoint as before.
      const double bound = line.allFinite() && norm2 > 1e-300 ? std::sqrt(max_e2_l * norm2) * (1 + 1e-6)
                                                              : std::numeric_limits<double>::infinity();
      const auto [k0, k1] = keys.band(line, steep, bound);
      for (std::size_t k = k0; k < k1; ++k) {
        const double num = line.x() * keys.x[k] + line.y() * keys.y[k] + line.z();
        if (std::abs(num) > bound || num * num / norm2 >= max_e2_l) continue;
        if (monocular && keys.near_epipole[k]) continue;
        const int j = keys.index[k];
        const int d = hamming(da, kb.f.descriptors.ptr(j));
        if (d <= kHammingLow) best.offer(d, j);
      }
    }
    if (best.index < 0) continue;
    if (best.dist2 != std::numeric_limits<int>::max() && best.dist > kTriangulationRatio * best.dist2) continue;
    const auto j = static_cast<std::size_t>(best.index);
    if (best.dist < taken_dist[j]) {
      taken[j] = static_cast<int>(i);
      taken_dist[j] = best.dist;
    }
  }
  for (std::size_t j = 0; j < taken.size(); ++j) {
    if (taken[j] >= 0) out.emplace_back(taken[j], static_cast<int>(j));
  }
  return out;
}

}  // namespace keepless::eval::vo
