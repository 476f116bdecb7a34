// keepless_vo_sim's pieces: trajectory readers (real files from
// /work/shared/data, read by path, skipped when absent), keyframe selection,
// and the scene's determinism for a seed.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "vo_sim/scene.hpp"
#include "vo_sim/trajectory.hpp"

using namespace keepless::vo_sim;

namespace {

const std::string kData = KEEPLESS_VO_SIM_DATA;

bool exists(const std::string& path) { return std::ifstream(path).good(); }

std::vector<Pose> load(const std::string& path, TrajectoryFormat f) {
  std::vector<Pose> poses;
  std::string error;
  EXPECT_TRUE(load_trajectory(path, f, poses, error)) << error;
  return poses;
}

TEST(VoSimTrajectory, KittiPosesAreCameraPosesInAZUpFrame) {
  const std::string path = kData + "kitti_odom_eval/gt_poses/06.txt";
  if (!exists(path)) GTEST_SKIP() << "no data: " << path << " is missing";
  const std::vector<Pose> poses = load(path, TrajectoryFormat::kKitti);
  ASSERT_EQ(poses.size(), 1101u);
  EXPECT_NEAR(norm(poses[0].centre), 0.0, 1e-9);
  // KITTI's camera looks along its z, which is the simulator's +x; the
  // camera's y (down) is the simulator's -z.
  EXPECT_NEAR(poses[0].rotation.col(2).x, 1.0, 1e-6);
  EXPECT_NEAR(poses[0].rotation.col(1).z, -1.0, 1e-6);
  EXPECT_GT(poses[10].centre.x, 5.0);  // driving forward
  EXPECT_EQ(poses[10].utime, 1000000);
}

// TUM lines are "t tx ty tz qx qy qz qw": the first pose is the file's first
// line, the quaternion's scalar read last (its rotation written out here from
// the unit quaternion), a proper rotation.
TEST(VoSimTrajectory, TumGroundTruth) {
  const std::string path = kData + "evo/freiburg1_xyz-groundtruth.txt";
  if (!exists(path)) GTEST_SKIP() << "no data: " << path << " is missing";
  const std::vector<Pose> poses = load(path, TrajectoryFormat::kTum);
  ASSERT_EQ(poses.size(), 3000u);
  const Pose& p = poses.front();  // 1305031098.6659 1.3563 0.6305 1.6380 0.6132 0.5962 -0.3311 -0.3986
  EXPECT_EQ(p.utime, 1305031098665900);
  EXPECT_NEAR(p.centre.x, 1.3563, 1e-12);
  EXPECT_NEAR(p.centre.y, 0.6305, 1e-12);
  EXPECT_NEAR(p.centre.z, 1.6380, 1e-12);
  double x = 0.6132, y = 0.5962, z = -0.3311, w = -0.3986;
  const double n = std::sqrt(x * x + y * y + z * z + w * w);
  x /= n, y /= n, z /= n, w /= n;
  const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                          {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                          {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(p.rotation.m[r][c], R[r][c], 1e-9) << r << "," << c;
  for (const Pose& q : {poses.front(), poses.back()}) {
    const auto& m = q.rotation.m;
    EXPECT_NEAR(m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                    m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]),
                1.0, 1e-6);
  }
}

// The raw EuRoC ground truth (IMU body) with the cam0 mounting applied equals
// ORB-SLAM3's left-camera ground truth at the same timestamp.
TEST(VoSimTrajectory, EurocBodyAndLeftCameraFilesAgree) {
  const std::string raw = kData + "evo/V102_groundtruth.csv";
  const std::string cam = kData + "orbslam3_euroc_left_cam_gt/V102_GT.txt";
  if (!exists(raw) || !exists(cam)) GTEST_SKIP() << "no data: " << raw << " or " << cam << " is missing";
  const std::vector<Pose> body = load(raw, TrajectoryFormat::kEuroc);
  const std::vector<Pose> left = load(cam, TrajectoryFormat::kEurocCam);
  ASSERT_EQ(body.size(), 16702u);
  ASSERT_EQ(left.size(), 1671u);
  std::size_t compared = 0;
  std::size_t j = 0;
  for (const Pose& l : left) {
    while (j < body.size() && body[j].utime < l.utime) ++j;
    if (j == body.size() || body[j].utime != l.utime) continue;
    ++compared;
    EXPECT_NEAR(norm(body[j].centre - l.centre), 0.0, 1e-3) << l.utime;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(dot(body[j].rotation.col(c), l.rotation.col(c)), 1.0, 1e-3) << l.utime;
    if (compared >= 50) break;
  }
  EXPECT_GE(compared, 10u);
}

TEST(VoSimTrajectory, BadLinesNameFileAndLine) {
  const std::string path = ::testing::TempDir() + "keepless_bad_traj.txt";
  {
    std::ofstream f(path);
    f << "# comment\n1.0 0 0 0 0 0 0 1\n2.0 0 0 zero 0 0 0 1\n";
  }
  std::vector<Pose> poses;
  std::string error;
  EXPECT_FALSE(load_trajectory(path, TrajectoryFormat::kTum, poses, error));
  EXPECT_NE(error.find(path + ":3:"), std::string::npos) << error;
  EXPECT_FALSE(load_trajectory(path + ".missing", TrajectoryFormat::kTum, poses, error));
  TrajectoryFormat f;
  EXPECT_TRUE(parse_format("euroc-cam", f));
  EXPECT_FALSE(parse_format("bag", f));
}

TEST(VoSimTrajectory, KeyframeSelectionSpacing) {
  std::vector<Pose> dense;
  for (int i = 0; i < 101; ++i) {
    Pose p;
    p.centre = {0.01 * i, 0, 0};
    dense.push_back(p);
  }
  const std::vector<Pose> kfs = select_keyframes(dense, 0.095, 90, 1000);  // every 10th pose
  ASSERT_EQ(kfs.size(), 11u);
  EXPECT_NEAR(kfs[1].centre.x, 0.1, 1e-9);
  EXPECT_EQ(select_keyframes(dense, 0.095, 90, 4).size(), 4u);
}

std::vector<std::vector<SimObservation>> run(std::uint64_t seed, int keyframes) {
  const std::vector<Pose> path = street_path(static_cast<std::size_t>(keyframes), seed);
  World w(street_scene(), Camera{}, path, seed);
  std::vector<std::vector<SimObservation>> out;
  std::vector<SimObservation> obs;
  for (int i = 0; i < keyframes; ++i) {
    w.observe(path[static_cast<std::size_t>(i)], i, obs);
    out.push_back(obs);
  }
  return out;
}

TEST(VoSimScene, DeterministicForASeed) {
  const auto a = run(5, 15), b = run(5, 15), c = run(6, 15);
  ASSERT_EQ(a.size(), b.size());
  bool differs = false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].size(), b[k].size());
    for (std::size_t i = 0; i < a[k].size(); ++i) {
      EXPECT_EQ(a[k][i].point, b[k][i].point);
      EXPECT_EQ(a[k][i].u, b[k][i].u);
      EXPECT_EQ(a[k][i].v, b[k][i].v);
    }
    differs = differs || a[k].size() != c[k].size() || (!a[k].empty() && a[k][0].u != c[k][0].u);
  }
  EXPECT_TRUE(differs) << "another seed should give another stream";
}

TEST(VoSimScene, AboutAThousandKeypointsInViewAndCullsStick) {
  const std::vector<Pose> path = street_path(30, 1);
  SceneConfig sc = street_scene();
  sc.retriangulate_after = -1;
  World w(sc, Camera{}, path, 1);
  std::vector<SimObservation> obs;
  std::size_t total = 0;
  for (int i = 0; i < 10; ++i) {
    w.observe(path[static_cast<std::size_t>(i)], i, obs);
    total += obs.size();
    for (const SimObservation& o : obs) {
      EXPECT_GE(o.u, 0.f);
      EXPECT_LE(o.u, 639.f);
      EXPECT_GE(o.v, 0.f);
      EXPECT_LE(o.v, 479.f);
    }
  }
  EXPECT_GT(total / 10, 700u);
  EXPECT_LE(total / 10, 1000u);
  // Cull every map point seen by keyframe 9: none is observed (mapped) again.
  std::vector<std::int64_t> culled;
  for (const SimObservation& o : obs) {
    if (o.mapped) culled.push_back(w.points()[o.point].landmark);
  }
  ASSERT_FALSE(culled.empty()) << "keyframe 9 maps no point";
  for (std::int64_t id : culled) EXPECT_TRUE(w.cull(id, 9));
  EXPECT_FALSE(w.cull(culled.front(), 9)) << "a map point is culled once";
  w.observe(path[10], 10, obs);
  for (const SimObservation& o : obs) {
    if (!o.mapped) continue;
    for (std::int64_t id : culled) EXPECT_NE(w.points()[o.point].landmark, id);
  }
}

}  // namespace
