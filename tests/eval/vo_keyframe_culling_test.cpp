// The real VO's keyframe-culling test (Map::redundant, ORB-SLAM2's
// KeyFrameCulling: more than 90 % of a keyframe's points seen by three
// others) and what point culling does to it: a point deleted by set_bad
// leaves the test, so deleting a keyframe's few-view points makes it
// redundant; one deleted by cull_remembered still counts with the
// observations it had, unless its keypoint holds an alive point again or the
// keyframes that saw it are gone.

#include <gtest/gtest.h>

#include "vo_map.hpp"

namespace vo = keepless::eval::vo;

namespace {

constexpr int kPoints = 10;

// Five keyframes of kPoints monocular keypoints (level 0). Points 0-4 are
// seen by keyframes 1-4 (three others each for keyframe 1), points 5-9 by
// keyframes 1 and 2 only. Keyframe 1's keypoint i sees point i.
vo::Map five_keyframes() {
  vo::Map map;
  for (int k = 0; k < 5; ++k) {
    vo::KeyFrame f;
    f.f.keys.assign(kPoints, cv::KeyPoint(0, 0, 1, -1, 0, 0));
    f.f.ur.assign(kPoints, -1);
    f.f.depth.assign(kPoints, 0);
    f.f.descriptors = cv::Mat::zeros(kPoints, 32, CV_8U);
    f.mp.assign(kPoints, -1);
    map.kfs.push_back(f);
  }
  for (int i = 0; i < kPoints; ++i) {
    const int p = map.new_point(Eigen::Vector3d(i, 0, 10), 1, i);
    for (int k = 2; k <= (i < 5 ? 4 : 2); ++k) map.add_observation(p, k, i);
  }
  return map;
}

TEST(VoKeyframeCulling, HalfItsPointsSeenByThreeOthersIsNotRedundant) {
  const vo::Map map = five_keyframes();
  EXPECT_FALSE(map.redundant(1, 0));
}

TEST(VoKeyframeCulling, DeletingItsFewViewPointsMakesItRedundant) {
  vo::Map map = five_keyframes();
  for (int p = 5; p < kPoints; ++p) map.set_bad(p);
  EXPECT_TRUE(map.redundant(1, 0));
}

TEST(VoKeyframeCulling, PointsDeletedRememberedStillCount) {
  vo::Map map = five_keyframes();
  for (int p = 5; p < kPoints; ++p) map.cull_remembered(p);
  EXPECT_TRUE(map.points[5].bad);
  EXPECT_EQ(map.kfs[1].mp[5], -1);
  EXPECT_EQ(map.kfs[1].culled.size(), 5u);
  EXPECT_FALSE(map.redundant(1, 0));
}

TEST(VoKeyframeCulling, ARememberedPointIsNotCountedTwiceWhenItsKeypointMapsAgain) {
  vo::Map map = five_keyframes();
  for (int p = 5; p < kPoints; ++p) map.cull_remembered(p);
  // Keypoints 5-8 of keyframe 1 see new points that keyframes 2-4 see too:
  // 9 of 10 keypoints redundant, not more than 90 %; then the tenth.
  for (int i = 5; i < 9; ++i) {
    const int p = map.new_point(Eigen::Vector3d(i, 1, 10), 1, i);
    for (int k = 2; k <= 4; ++k) map.add_observation(p, k, i);
  }
  EXPECT_FALSE(map.redundant(1, 0));
  const int p = map.new_point(Eigen::Vector3d(9, 1, 10), 1, 9);
  for (int k = 2; k <= 4; ++k) map.add_observation(p, k, 9);
  EXPECT_TRUE(map.redundant(1, 0));
}

TEST(VoKeyframeCulling, ARememberedPointLosesTheKeyframesCulledSince) {
  vo::Map map = five_keyframes();
  // Every point seen by keyframes 1-4, then deleted remembered: redundant.
  for (int p = 5; p < kPoints; ++p) {
    for (int k = 3; k <= 4; ++k) map.add_observation(p, k, p);
  }
  for (int p = 0; p < kPoints; ++p) map.cull_remembered(p);
  EXPECT_TRUE(map.redundant(1, 0));
  // Keyframes 3 and 4 go: each point was seen by one other keyframe.
  map.cull_keyframe(3);
  map.cull_keyframe(4);
  ASSERT_TRUE(map.kfs[3].bad && map.kfs[4].bad);
  EXPECT_FALSE(map.redundant(1, 0));
}

TEST(VoKeyframeCulling, RgbdCountsOnlyCloseKeypoints) {
  vo::Map map = five_keyframes();
  // Only keypoints 0-4 (the redundant ones) have a close depth.
  for (int i = 0; i < kPoints; ++i) map.kfs[1].f.depth[static_cast<std::size_t>(i)] = i < 5 ? 2.0f : 50.0f;
  EXPECT_FALSE(map.redundant(1, 0));
  EXPECT_TRUE(map.redundant(1, 10.0));
}

}  // namespace
