// The real VO's descriptor distance and triangulation search against plain
// references: hamming() against a bit-by-bit count, and
// search_for_triangulation() (which visits keypoints by level in epipolar
// bands) against the brute-force scan it replaced, pair for pair, on
// synthetic keyframes with forward, sideways and oblique motion, RGB-D and
// monocular keypoints, repeated descriptors (ties) and keypoints near the
// epipole.

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "matching.hpp"

namespace keepless::eval::vo {
namespace {

int bit_count_reference(const std::uint8_t* a, const std::uint8_t* b) {
  int d = 0;
  for (int i = 0; i < 32; ++i) {
    for (int bit = 0; bit < 8; ++bit) d += ((a[i] ^ b[i]) >> bit) & 1;
  }
  return d;
}

// The brute-force search as it was: every free keypoint of b in index order.
std::vector<std::pair<int, int>> triangulation_reference(const Map& map, int a, int b, const PinholeCamera& cam) {
  const KeyFrame& ka = map.kfs[static_cast<std::size_t>(a)];
  const KeyFrame& kb = map.kfs[static_cast<std::size_t>(b)];
  const EpipolarGeometry g = epipolar_geometry(ka, kb, cam);  // the search's, not what is compared
  const Eigen::Matrix3d& F = g.F;
  const double eu = g.epipole_u, ev = g.epipole_v;
  std::vector<int> free_b;
  for (std::size_t j = 0; j < kb.mp.size(); ++j) {
    if (kb.mp[j] < 0) free_b.push_back(static_cast<int>(j));
  }
  std::vector<int> taken(kb.mp.size(), -1);
  std::vector<int> taken_dist(kb.mp.size(), std::numeric_limits<int>::max());
  for (std::size_t i = 0; i < ka.mp.size(); ++i) {
    if (ka.mp[i] >= 0) continue;
    const cv::KeyPoint& pa = ka.f.keys[i];
    const Eigen::Vector3d line = F * Eigen::Vector3d(pa.pt.x, pa.pt.y, 1);
    const double norm2 = line.x() * line.x() + line.y() * line.y();
    if (norm2 <= 0) continue;
    int dist = std::numeric_limits<int>::max(), dist2 = dist, index = -1;
    for (int j : free_b) {
      const cv::KeyPoint& pb = kb.f.keys[static_cast<std::size_t>(j)];
      if (std::abs(pb.octave - pa.octave) > 1) continue;
      const double s = pyramid().scale[static_cast<std::size_t>(pb.octave)];
      const double num = line.x() * pb.pt.x + line.y() * pb.pt.y + line.z();
      if (num * num / norm2 >= 3.84 * s * s) continue;
      const int d = hamming(ka.f.descriptors, static_cast<int>(i), kb.f.descriptors, j);
      if (d > kHammingLow) continue;
      const double du = eu - pb.pt.x, dv = ev - pb.pt.y;
      if (ka.f.ur[i] < 0 && du * du + dv * dv < 100 * s) continue;
      if (d < dist) {
        dist2 = dist, dist = d, index = j;
      } else if (d < dist2) {
        dist2 = d;
      }
    }
    if (index < 0) continue;
    if (dist2 != std::numeric_limits<int>::max() && dist > 0.7 * dist2) continue;
    if (dist < taken_dist[static_cast<std::size_t>(index)]) {
      taken[static_cast<std::size_t>(index)] = static_cast<int>(i);
      taken_dist[static_cast<std::size_t>(index)] = dist;
    }
  }
  std::vector<std::pair<int, int>> out;
  for (std::size_t j = 0; j < taken.size(); ++j) {
    if (taken[j] >= 0) out.emplace_back(taken[j], static_cast<int>(j));
  }
  return out;
}

PinholeCamera kitti_like() {
  PinholeCamera cam;
  cam.fx = cam.fy = 707.1;
  cam.cx = 601.9;
  cam.cy = 183.1;
  cam.width = 1226;
  cam.height = 370;
  cam.bf = 0.5 * cam.fx;
  return cam;
}

// Keyframes 0 (identity) and 1 (moved by `motion`) seeing the same random
// points, plus clutter: random descriptors, a few flipped bits for true
// pairs, some exact repeats (ties), some keypoints already matched, half of
// a's keypoints with a depth (RGB-D) when `rgbd`.
Map two_keyframes(const PinholeCamera& cam, const Eigen::Isometry3d& motion, bool rgbd, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::uniform_int_distribution<int> byte(0, 255), level(0, kLevels - 1);
  Map map;
  map.kfs.resize(2);
  map.kfs[1].Tcw = motion;
  const auto add = [&](KeyFrame& k, double u, double v, int octave, const std::vector<std::uint8_t>& desc, float ur) {
    k.f.keys.emplace_back(cv::Point2f(static_cast<float>(u), static_cast<float>(v)), 31.f, -1.f, 0.f, octave);
    cv::Mat row(1, 32, CV_8U);
    for (int c = 0; c < 32; ++c) row.at<std::uint8_t>(0, c) = desc[static_cast<std::size_t>(c)];
    k.f.descriptors.push_back(row);
    k.f.ur.push_back(ur);
    k.mp.push_back(unit(rng) < 0.15 ? 0 : -1);
  };
  const auto random_desc = [&] {
    std::vector<std::uint8_t> d(32);
    for (auto& x : d) x = static_cast<std::uint8_t>(byte(rng));
    return d;
  };
  std::vector<std::uint8_t> repeated = random_desc();
  for (int n = 0; n < 900; ++n) {
    const Eigen::Vector3d X((unit(rng) - 0.5) * 30, (unit(rng) - 0.5) * 8, 3 + unit(rng) * 40);
    const Eigen::Vector3d xb = motion * X;
    const int octave = level(rng);
    std::vector<std::uint8_t> desc = unit(rng) < 0.1 ? repeated : random_desc();
    const double ua = cam.fx * X.x() / X.z() + cam.cx, va = cam.fy * X.y() / X.z() + cam.cy;
    const float ur = rgbd && unit(rng) < 0.5 ? static_cast<float>(ua - cam.bf / X.z()) : -1.f;
    add(map.kfs[0], ua, va, octave, desc, ur);
    if (xb.z() <= 0) continue;
    for (int flips = static_cast<int>(unit(rng) * 20); flips > 0; --flips) {
      desc[static_cast<std::size_t>(byte(rng) % 32)] ^= static_cast<std::uint8_t>(1 << (byte(rng) % 8));
    }
    const double noise = (unit(rng) - 0.5) * 4;
    add(map.kfs[1], cam.fx * xb.x() / xb.z() + cam.cx + noise, cam.fy * xb.y() / xb.z() + cam.cy - noise,
        std::clamp(octave + static_cast<int>(unit(rng) * 3) - 1, 0, kLevels - 1), desc, -1.f);
  }
  for (int n = 0; n < 300; ++n) {  // clutter in b, some of it around the epipole
    const bool near = n < 30;
    const Eigen::Vector3d ca = motion * map.kfs[0].centre();
    const double eu = ca.z() > 0 ? cam.fx * ca.x() / ca.z() + cam.cx : cam.cx;
    const double ev = ca.z() > 0 ? cam.fy * ca.y() / ca.z() + cam.cy : cam.cy;
    const double u = near ? eu + (unit(rng) - 0.5) * 20 : unit(rng) * cam.width;
    const double v = near ? ev + (unit(rng) - 0.5) * 20 : unit(rng) * cam.height;
    add(map.kfs[1], u, v, level(rng), unit(rng) < 0.2 ? repeated : random_desc(), -1.f);
  }
  return map;
}

TEST(VoMatching, HammingCountsDifferingBits) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uint8_t a[32], b[32];
  for (int trial = 0; trial < 2000; ++trial) {
    for (int i = 0; i < 32; ++i) {
      a[i] = static_cast<std::uint8_t>(byte(rng));
      b[i] = trial % 3 == 0 ? a[i] ^ static_cast<std::uint8_t>(1 << (i % 8)) : static_cast<std::uint8_t>(byte(rng));
    }
    ASSERT_EQ(hamming(a, b), bit_count_reference(a, b)) << "trial " << trial;
  }
  std::uint8_t zero[32] = {}, ones[32];
  for (auto& x : ones) x = 0xff;
  EXPECT_EQ(hamming(zero, ones), 256);
  EXPECT_EQ(hamming(ones, ones), 0);
}

TEST(VoMatching, TriangulationSearchFindsTheBruteForcePairs) {
  const PinholeCamera cam = kitti_like();
  struct Case {
    const char* name;
    Eigen::Isometry3d motion;
    bool rgbd;
  };
  std::vector<Case> cases;
  const auto moved = [](const Eigen::Vector3d& t, double yaw) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = t;
    return T;
  };
  cases.push_back({"forward", moved({0, 0, -1.0}, 0.01), false});
  cases.push_back({"forward rgbd", moved({0.02, 0.01, -0.8}, -0.02), true});
  cases.push_back({"sideways", moved({-0.5, 0, 0}, 0.0), false});
  cases.push_back({"oblique", moved({-0.4, 0.3, -0.4}, 0.05), false});
  cases.push_back({"vertical", moved({0, -0.5, 0.05}, 0.0), true});
  int pairs = 0;
  for (const Case& c : cases) {
    for (unsigned seed = 1; seed <= 4; ++seed) {
      const Map map = two_keyframes(cam, c.motion, c.rgbd, seed);
      for (const auto& [a, b] : {std::pair{0, 1}, std::pair{1, 0}}) {
        const auto expected = triangulation_reference(map, a, b, cam);
        EXPECT_EQ(search_for_triangulation(map, a, b, cam), expected) << c.name << " seed " << seed << " " << a;
        pairs += static_cast<int>(expected.size());
      }
    }
  }
  EXPECT_GT(pairs, 1000);  // the comparison saw real matches, not just empty lists
}

}  // namespace
}  // namespace keepless::eval::vo
