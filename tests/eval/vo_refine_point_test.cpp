// The real VO's structure-only refinement of an excluded point
// (refine_point, deferred culling): with the poses held it moves a point
// from a poor start back onto its observations, flags the observation that
// does not fit as an outlier, and refuses a point behind a camera; and the
// motion-only refinement of a pose (refine_pose).

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "real_sequence.hpp"
#include "vo_ba.hpp"

namespace vo = keepless::eval::vo;

namespace {

vo::PinholeCamera kitti_like() {
  vo::PinholeCamera c;
  c.fx = c.fy = 718.856;
  c.cx = 607.19;
  c.cy = 185.22;
  c.width = 1241;
  c.height = 376;
  return c;
}

// Cameras along x, looking down +z, 0.5 m apart.
std::vector<Eigen::Isometry3d> cameras(int n) {
  std::vector<Eigen::Isometry3d> tcw;
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(-0.5 * i, 0, 0);
    tcw.push_back(T);
  }
  return tcw;
}

vo::BaObservation project(const vo::PinholeCamera& c, const Eigen::Isometry3d& T, const Eigen::Vector3d& X) {
  const Eigen::Vector3d p = T * X;
  return {0, 0, c.fx * p.x() / p.z() + c.cx, c.fy * p.y() / p.z() + c.cy, -1, 0};
}

}  // namespace

TEST(VoRefinePoint, RecoversThePointAndFlagsTheOutlier) {
  const vo::PinholeCamera cam = kitti_like();
  const std::vector<Eigen::Isometry3d> tcw = cameras(5);
  const Eigen::Vector3d truth(1.0, -0.5, 12.0);
  std::vector<vo::BaObservation> obs;
  for (const auto& T : tcw) obs.push_back(project(cam, T, truth));
  obs[2].u += 40;  // a wrong match
  Eigen::Vector3d X = truth + Eigen::Vector3d(0.3, 0.2, 2.5);  // a poor two-view depth
  std::vector<bool> outlier;
  ASSERT_TRUE(vo::refine_point(cam, tcw, obs, &X, &outlier));
  EXPECT_LT((X - truth).norm(), 1e-3);
  ASSERT_EQ(outlier.size(), obs.size());
  for (std::size_t i = 0; i < obs.size(); ++i) EXPECT_EQ(outlier[i], i == 2) << i;
}

TEST(VoRefinePoint, RefusesAPointBehindACameraAndLeavesItUnchanged) {
  const vo::PinholeCamera cam = kitti_like();
  const std::vector<Eigen::Isometry3d> tcw = cameras(3);
  std::vector<vo::BaObservation> obs;
  for (const auto& T : tcw) obs.push_back(project(cam, T, Eigen::Vector3d(0, 0, 10)));
  const Eigen::Vector3d start(0, 0, -4);
  Eigen::Vector3d X = start;
  std::vector<bool> outlier;
  EXPECT_FALSE(vo::refine_point(cam, tcw, obs, &X, &outlier));
  EXPECT_EQ(X, start);
}

TEST(VoRefinePoint, RefusesWhenFewerThanTwoObservationsFit) {
  const vo::PinholeCamera cam = kitti_like();
  const std::vector<Eigen::Isometry3d> tcw = cameras(2);
  const Eigen::Vector3d truth(0.5, 0.2, 8.0);
  std::vector<vo::BaObservation> obs;
  for (const auto& T : tcw) obs.push_back(project(cam, T, truth));
  obs[1].v += 60;  // off the epipolar line: no point fits both views
  Eigen::Vector3d X = truth;
  std::vector<bool> outlier;
  EXPECT_FALSE(vo::refine_point(cam, tcw, obs, &X, &outlier));
  EXPECT_EQ(X, truth);
}

// The motion-only counterpart (refine_pose, --defer-alternate): with the
// points held it brings a perturbed pose back onto the observations and
// flags the wrong match; against fewer than 10 fitting points it keeps the
// pose it was given.
namespace {

std::vector<Eigen::Vector3d> scene(int n) {
  std::vector<Eigen::Vector3d> X;
  for (int i = 0; i < n; ++i) X.emplace_back(-4.0 + 0.37 * i, -1.5 + 0.11 * (i % 7), 8.0 + 0.9 * (i % 5));
  return X;
}

Eigen::Isometry3d camera_pose() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.3, -0.1, 0.5);
  return T;
}

std::vector<vo::BaObservation> observe(const vo::PinholeCamera& c, const Eigen::Isometry3d& T,
                                       const std::vector<Eigen::Vector3d>& X) {
  std::vector<vo::BaObservation> obs;
  for (std::size_t i = 0; i < X.size(); ++i) {
    vo::BaObservation o = project(c, T, X[i]);
    o.point = static_cast<int>(i);
    obs.push_back(o);
  }
  return obs;
}

Eigen::Isometry3d perturbed(const Eigen::Isometry3d& T) {
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.linear() = Eigen::AngleAxisd(0.02, Eigen::Vector3d(1, -0.5, 0.3).normalized()).toRotationMatrix();
  d.translation() = Eigen::Vector3d(0.05, 0.03, -0.08);
  return d * T;
}

}  // namespace

TEST(VoRefinePose, RecoversThePoseAndFlagsTheOutlier) {
  const vo::PinholeCamera cam = kitti_like();
  const std::vector<Eigen::Vector3d> X = scene(30);
  const Eigen::Isometry3d truth = camera_pose();
  std::vector<vo::BaObservation> obs = observe(cam, truth, X);
  obs[7].v += 50;  // a wrong match
  Eigen::Isometry3d T = perturbed(truth);
  std::vector<bool> outlier;
  EXPECT_EQ(vo::refine_pose(cam, X, obs, &T, &outlier), 29);
  EXPECT_LT((T.translation() - truth.translation()).norm(), 1e-6);
  EXPECT_LT(Eigen::AngleAxisd(T.linear() * truth.linear().transpose()).angle(), 1e-8);
  ASSERT_EQ(outlier.size(), obs.size());
  for (std::size_t i = 0; i < obs.size(); ++i) EXPECT_EQ(outlier[i], i == 7) << i;
}

TEST(VoRefinePose, KeepsThePoseWhenTooFewPointsFit) {
  const vo::PinholeCamera cam = kitti_like();
  const std::vector<Eigen::Vector3d> X = scene(12);
  std::vector<vo::BaObservation> obs = observe(cam, camera_pose(), X);
  for (int i = 0; i < 4; ++i) obs[static_cast<std::size_t>(3 * i)].u += 80.0 + 20 * i;  // 8 of 12 fit
  const Eigen::Isometry3d start = perturbed(camera_pose());
  Eigen::Isometry3d T = start;
  std::vector<bool> outlier;
  EXPECT_LT(vo::refine_pose(cam, X, obs, &T, &outlier), 10);
  EXPECT_TRUE(T.isApprox(start, 0));
}
