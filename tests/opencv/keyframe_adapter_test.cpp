// keepless::opencv: poses from cv::Mat / Eigen, keyframes into a window,
// input validation, capacities checked before any buffer grows, no
// allocation per keyframe, unmapped keypoints in N(p, f) (reserved ids and core's
// native list), intrinsics and depths, decisions back to ids.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "counting_new.hpp"  // this binary's only inclusion
#include "keepless/opencv/keyframe_adapter.hpp"

namespace keepless::opencv {
namespace {

// A camera at centre c, rotated by `angle` about the unit `axis` (world from camera).
Eigen::Isometry3d twc(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& c) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  T.translation() = c;
  return T;
}

cv::Mat to_mat(const Eigen::Isometry3d& T, int rows, int type) {
  cv::Mat m(rows, 4, CV_64F);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < 4; ++c) m.at<double>(r, c) = T.matrix()(r, c);
  cv::Mat out;
  m.convertTo(out, type);
  return out;
}

TEST(OpencvPose, TcwMatGivesCentreAndWorldFromCameraOrientation) {
  const Eigen::Isometry3d Twc = twc(0.7, {0.2, 1.0, -0.3}, {1.5, -2.0, 0.25});
  for (int rows : {4, 3}) {
    for (int type : {CV_64F, CV_32F}) {
      CameraPose pose;
      ASSERT_EQ(pose_from_tcw(to_mat(Twc.inverse(), rows, type), &pose), Status::kOk);
      const double tol = type == CV_32F ? 1e-5 : 1e-12;
      EXPECT_LT((pose.centre - Twc.translation()).norm(), tol);
      EXPECT_LT(pose.orientation.angularDistance(Eigen::Quaterniond(Twc.linear())), tol);
      EXPECT_NEAR(pose.orientation.norm(), 1.0, 1e-12);
    }
  }
  CameraPose from_eigen;
  ASSERT_EQ(pose_from_tcw(Twc.inverse(), &from_eigen), Status::kOk);
  EXPECT_LT((from_eigen.centre - Twc.translation()).norm(), 1e-12);
  CameraPose from_q;
  ASSERT_EQ(pose_from_orientation(Eigen::Quaterniond(Twc.linear()), Twc.translation(), &from_q), Status::kOk);
  EXPECT_LT(from_q.orientation.angularDistance(from_eigen.orientation), 1e-12);
}

TEST(OpencvPose, Matrix4OverloadsTakeSophusStyleTcw) {
  // ORB-SLAM3 holds Sophus::SE3f; its .matrix() is an Eigen::Matrix4f.
  const Eigen::Isometry3d Twc = twc(0.7, {0.2, 1.0, -0.3}, {1.5, -2.0, 0.25});
  CameraPose from_d, from_f;
  ASSERT_EQ(pose_from_tcw(Eigen::Matrix4d(Twc.inverse().matrix()), &from_d), Status::kOk);
  EXPECT_LT((from_d.centre - Twc.translation()).norm(), 1e-12);
  EXPECT_LT(from_d.orientation.angularDistance(Eigen::Quaterniond(Twc.linear())), 1e-12);
  const Eigen::Matrix4f Tcw_f = Twc.inverse().matrix().cast<float>();
  ASSERT_EQ(pose_from_tcw(Tcw_f, &from_f), Status::kOk);
  EXPECT_LT((from_f.centre - Twc.translation()).norm(), 1e-5);
  EXPECT_LT(from_f.orientation.angularDistance(from_d.orientation), 1e-5);

  CameraPose pose;
  pose.centre = {7, 8, 9};
  Eigen::Matrix4f bad_row = Tcw_f;
  bad_row(3, 3) = 2;
  EXPECT_EQ(pose_from_tcw(bad_row, &pose), Status::kBadMatrix);
  Eigen::Matrix4f nan = Tcw_f;
  nan(1, 3) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(pose_from_tcw(nan, &pose), Status::kNonFinite);
  Eigen::Matrix4d scaled = Twc.inverse().matrix();
  scaled.topLeftCorner<3, 3>() *= 1.01;
  EXPECT_EQ(pose_from_tcw(scaled, &pose), Status::kNotRotation);
  EXPECT_EQ(pose.centre, Eigen::Vector3d(7, 8, 9));
}

TEST(OpencvPose, RejectsMalformedPosesAndLeavesOutputUnchanged) {
  const Eigen::Isometry3d Tcw = twc(0.3, {0, 0, 1}, {1, 2, 3});
  CameraPose pose;
  pose.centre = {7, 8, 9};
  const CameraPose before = pose;
  auto unchanged = [&] { return pose.centre == before.centre; };

  EXPECT_EQ(pose_from_tcw(cv::Mat::eye(3, 3, CV_64F), &pose), Status::kBadMatrix);
  EXPECT_EQ(pose_from_tcw(cv::Mat::eye(4, 4, CV_8U), &pose), Status::kBadMatrix);
  EXPECT_EQ(pose_from_tcw(cv::Mat::eye(4, 4, CV_64FC2), &pose), Status::kBadMatrix);
  cv::Mat bad_row = to_mat(Tcw, 4, CV_64F);
  bad_row.at<double>(3, 3) = 2;
  EXPECT_EQ(pose_from_tcw(bad_row, &pose), Status::kBadMatrix);
  cv::Mat nan = to_mat(Tcw, 4, CV_64F);
  nan.at<double>(1, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(pose_from_tcw(nan, &pose), Status::kNonFinite);
  cv::Mat inf = to_mat(Tcw, 3, CV_32F);
  inf.at<float>(0, 0) = std::numeric_limits<float>::infinity();
  EXPECT_EQ(pose_from_tcw(inf, &pose), Status::kNonFinite);
  // A NaN in the last row reads as the Eigen overload reads it: not finite.
  for (const int type : {CV_32F, CV_64F}) {
    cv::Mat last = to_mat(Tcw, 4, type);
    if (type == CV_32F) last.at<float>(3, 3) = std::numeric_limits<float>::quiet_NaN();
    if (type == CV_64F) last.at<double>(3, 3) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(pose_from_tcw(last, &pose), Status::kNonFinite);
  }
  Eigen::Matrix4d last = Tcw.matrix();
  last(3, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(pose_from_tcw(last, &pose), Status::kNonFinite);
  cv::Mat scaled = to_mat(Tcw, 4, CV_64F);
  scaled(cv::Rect(0, 0, 3, 3)) *= 1.01;  // a similarity, not a rotation
  EXPECT_EQ(pose_from_tcw(scaled, &pose), Status::kNotRotation);
  Eigen::Isometry3d mirror = Tcw;
  mirror.linear().col(2) *= -1;  // orthonormal but det -1
  EXPECT_EQ(pose_from_tcw(mirror, &pose), Status::kNotRotation);
  EXPECT_EQ(pose_from_orientation(Eigen::Quaterniond(1.1, 0, 0, 0), {0, 0, 0}, &pose), Status::kNotRotation);
  EXPECT_EQ(pose_from_orientation(Eigen::Quaterniond(1, 0, 0, 0), {0, NAN, 0}, &pose), Status::kNonFinite);
  EXPECT_TRUE(unchanged());
}

// A keyframe seeing points first..first+n-1 on a grid that shifts with k.
struct Frame {
  std::vector<cv::KeyPoint> keypoints;
  std::vector<core::PointId> ids;
};
Frame frame(int k, int first, int n) {
  Frame f;
  for (int i = 0; i < n; ++i) {
    const int p = first + i;
    f.keypoints.emplace_back(cv::Point2f(float(20 + 23 * (p % 20) - 30 * k), float(15 + 19 * (p % 11))), 31.f);
    f.ids.push_back(static_cast<core::PointId>(1000 + p));
  }
  return f;
}
CameraPose centre_at(double x) {
  CameraPose p;
  p.centre = {x, 0, 0};
  return p;
}

core::Capacities small_capacities() {
  core::Capacities c;
  c.max_keyframes = 8;
  c.max_points = 2048;
  c.max_observations = 4096;
  c.max_pair_arcs = 16384;
  return c;
}

TEST(OpencvKeyframes, ConvertsIntoTheWindowAndRejectsBadInputAtomically) {
  const core::Capacities caps = small_capacities();
  core::Window window(caps);
  KeyframeAdapter adapter(caps);
  Frame f = frame(0, 0, 30);
  ASSERT_EQ(adapter.add_keyframe(window, 7, centre_at(0), f.keypoints, f.ids), Status::kOk);
  ASSERT_EQ(window.keyframe_count(), 1u);
  EXPECT_EQ(window.keyframe(0).id, 7u);
  ASSERT_EQ(window.observation_count(0), 30u);
  EXPECT_EQ(window.observations(0)[3].point, 1003u);
  EXPECT_DOUBLE_EQ(window.observations(0)[3].u, f.keypoints[3].pt.x);
  EXPECT_DOUBLE_EQ(window.observations(0)[3].v, f.keypoints[3].pt.y);

  // Every rejection leaves the window as it was.
  Frame g = frame(1, 10, 30);
  Frame dup = g;
  dup.ids[5] = dup.ids[6];
  EXPECT_EQ(adapter.add_keyframe(window, 8, centre_at(1), dup.keypoints, dup.ids), Status::kDuplicatePoint);
  Frame reserved = g;
  reserved.ids[0] |= kUnmappedBit;
  EXPECT_EQ(adapter.add_keyframe(window, 8, centre_at(1), reserved.keypoints, reserved.ids),
            Status::kReservedPointId);
  Frame nan = g;
  nan.keypoints[2].pt.y = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(adapter.add_keyframe(window, 8, centre_at(1), nan.keypoints, nan.ids), Status::kNonFinite);
  std::vector<cv::KeyPoint> bad_unmapped = {cv::KeyPoint(cv::Point2f(NAN, 1), 31.f)};
  EXPECT_EQ(adapter.add_keyframe(window, 8, centre_at(1), g.keypoints, g.ids, &bad_unmapped),
            Status::kNonFinite);
  Frame short_ids = g;
  short_ids.ids.pop_back();
  EXPECT_EQ(adapter.add_keyframe(window, 8, centre_at(1), short_ids.keypoints, short_ids.ids),
            Status::kSizeMismatch);
  CameraPose bad_pose = centre_at(1);
  bad_pose.orientation.coeffs() *= 2;
  EXPECT_EQ(adapter.add_keyframe(window, 8, bad_pose, g.keypoints, g.ids), Status::kNotRotation);
  EXPECT_EQ(adapter.add_keyframe(window, 7, centre_at(1), g.keypoints, g.ids), Status::kWindowRejected);
  EXPECT_EQ(adapter.window_status(), core::Status::kDuplicateKeyframe);
  EXPECT_EQ(window.keyframe_count(), 1u);
  EXPECT_EQ(window.total_observations(), 30u);

  ASSERT_EQ(adapter.add_keyframe(window, 8, centre_at(1), g.keypoints, g.ids), Status::kOk);
  EXPECT_EQ(adapter.window_status(), core::Status::kOk);
  EXPECT_EQ(window.distinct_points(), 40u);
}

TEST(OpencvKeyframes, CapacityRefusalIsReportedWithTheWindowsReason) {
  core::Capacities caps = small_capacities();
  caps.max_observations = 40;
  core::Window window(caps);
  KeyframeAdapter adapter(caps);
  Frame f = frame(0, 0, 30);
  ASSERT_EQ(adapter.add_keyframe(window, 1, centre_at(0), f.keypoints, f.ids), Status::kOk);
  EXPECT_EQ(adapter.add_keyframe(window, 2, centre_at(1), f.keypoints, f.ids), Status::kWindowRejected);
  EXPECT_EQ(adapter.window_status(), core::Status::kCapacityExceeded);
  EXPECT_EQ(window.keyframe_count(), 1u);
}

// A keyframe beyond the adapter's capacities is refused before any buffer
// grows (mapped plus reserved-id unmapped keypoints against
// max_observations, a listed unmapped set against max_unmapped_keypoints),
// leaving the record as it was.
TEST(OpencvKeyframes, OverCapacityKeyframesAreRefusedBeforeAnyBufferGrows) {
  core::Capacities caps = small_capacities();
  caps.max_observations = 40;
  caps.max_unmapped_keypoints = 5;
  KeyframeAdapter adapter(caps);
  KeyframeRecord record(caps);
  const Frame fits = frame(0, 0, 30);
  ASSERT_EQ(adapter.convert(1, centre_at(0), fits.keypoints, fits.ids, nullptr, &record), Status::kOk);
  const Frame big = frame(1, 0, 41);
  const std::vector<cv::KeyPoint> eleven(11, cv::KeyPoint(cv::Point2f(3, 4), 31.f));
  const std::vector<cv::KeyPoint> six(6, cv::KeyPoint(cv::Point2f(3, 4), 31.f));
  KeyframeExtras listed;
  listed.unmapped = &six;
  listed.unmapped_as = UnmappedAs::kKeypointList;
  test::AllocationCounter allocations;
  EXPECT_EQ(adapter.convert(2, centre_at(1), big.keypoints, big.ids, nullptr, &record), Status::kCapacityExceeded);
  EXPECT_EQ(adapter.convert(2, centre_at(1), fits.keypoints, fits.ids, &eleven, &record), Status::kCapacityExceeded);
  EXPECT_EQ(adapter.convert(2, centre_at(1), fits.keypoints, fits.ids, listed, &record), Status::kCapacityExceeded);
  EXPECT_EQ(allocations.stop(), 0u);
  EXPECT_EQ(record.keyframe.id, 1u);
  EXPECT_EQ(record.observations.size(), 30u);
  // At the limits it converts.
  const std::vector<cv::KeyPoint> five(5, cv::KeyPoint(cv::Point2f(3, 4), 31.f));
  listed.unmapped = &five;
  EXPECT_EQ(adapter.convert(3, centre_at(1), fits.keypoints, fits.ids, listed, &record), Status::kOk);
  const std::vector<cv::KeyPoint> ten(10, cv::KeyPoint(cv::Point2f(3, 4), 31.f));
  EXPECT_EQ(adapter.convert(4, centre_at(1), fits.keypoints, fits.ids, &ten, &record), Status::kOk);
  EXPECT_EQ(record.observations.size(), 40u);
}

// The integration's per-keyframe calls (a cv::Mat pose, conversion into a
// record constructed from the capacities, the window, the decision, the
// culled ids into a reserved vector) allocate nothing once set up.
TEST(OpencvKeyframes, NothingAllocatesPerKeyframe) {
  const core::Capacities caps = small_capacities();
  core::Window window(caps);
  core::Params params;
  params.pair_capacity = 8;  // tight enough to cull
  core::Sparsifier sparsifier(caps, params, core::SolveMode::kIncremental);
  KeyframeAdapter adapter(caps);
  KeyframeRecord record(caps);
  std::vector<core::PointId> culled;
  culled.reserve(caps.max_points);
  std::vector<Frame> frames;
  std::vector<cv::Mat> poses;
  for (int k = 0; k < 12; ++k) {
    frames.push_back(frame(k, 12 * k, 40));
    poses.push_back(to_mat(twc(0.01 * k, {0, 1, 0}, {0.3 * k, 0, 0}).inverse(), k % 2 == 0 ? 4 : 3,
                           k % 3 == 0 ? CV_32F : CV_64F));
  }
  const std::size_t memory = adapter.memory_bytes();
  EXPECT_GE(memory, caps.max_observations * (sizeof(core::Observation) + sizeof(core::PointId)));
  test::AllocationCounter allocations;
  std::uint32_t culled_total = 0;
  for (int k = 0; k < 12; ++k) {
    CameraPose pose;
    ASSERT_EQ(pose_from_tcw(poses[k], &pose), Status::kOk);
    ASSERT_EQ(adapter.convert(static_cast<core::KeyframeId>(k), pose, frames[k].keypoints, frames[k].ids, nullptr,
                              &record),
              Status::kOk);
    if (window.keyframe_count() == 5) {
      ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), core::Status::kOk);
    }
    ASSERT_EQ(window.add_keyframe(record.keyframe, record.observations.data(),
                                  static_cast<std::uint32_t>(record.observations.size())),
              core::Status::kOk);
    ASSERT_EQ(sparsifier.update(window), core::Status::kOk);
    culled_points(sparsifier, &culled);
    culled_total += static_cast<std::uint32_t>(culled.size());
  }
  EXPECT_EQ(allocations.stop(), 0u);
  EXPECT_GT(culled_total, 0u);  // the decisions did something
  EXPECT_EQ(adapter.memory_bytes(), memory);  // fixed at construction
}

// Fills a window of `keyframes` overlapping keyframes, with `per` unmapped
// keypoints around each mapped one when `clutter`, passed as `as`.
void fill(core::Window& window, KeyframeAdapter& adapter, int keyframes, bool clutter,
          UnmappedAs as = UnmappedAs::kReservedIds, int per = 3) {
  for (int k = 0; k < keyframes; ++k) {
    Frame f = frame(k, 12 * k, 40);
    std::vector<cv::KeyPoint> unmapped;
    if (clutter) {
      for (const cv::KeyPoint& kp : f.keypoints) {
        for (int j = 0; j < per; ++j) unmapped.emplace_back(kp.pt + cv::Point2f(2.f + 0.5f * j, 1.f), 31.f);
      }
    }
    KeyframeExtras extras;
    extras.unmapped = clutter ? &unmapped : nullptr;
    extras.unmapped_as = as;
    ASSERT_EQ(adapter.add_keyframe(window, 100 + k, centre_at(0.3 * k), f.keypoints, f.ids, extras), Status::kOk);
  }
}

TEST(OpencvKeyframes, IntrinsicsAndDepthsReachTheWindow) {
  const core::Capacities caps = small_capacities();
  core::Window window(caps);
  KeyframeAdapter adapter(caps);
  Frame f = frame(0, 0, 30);
  std::vector<double> depths(30);
  for (std::size_t i = 0; i < depths.size(); ++i) depths[i] = 0.5 + 0.1 * double(i);
  depths[4] = 0;   // unknown, as core reads it
  depths[5] = -1;  // likewise
  KeyframeExtras extras;
  extras.intrinsics = {525.0, 524.5, 319.5, 239.5};
  extras.depths = &depths;
  ASSERT_EQ(adapter.add_keyframe(window, 3, centre_at(0), f.keypoints, f.ids, extras), Status::kOk);
  const core::Keyframe& k = window.keyframe(0);
  EXPECT_DOUBLE_EQ(k.fx, 525.0);
  EXPECT_DOUBLE_EQ(k.fy, 524.5);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);
  ASSERT_EQ(window.observation_count(0), 30u);
  for (std::uint32_t i = 0; i < 30; ++i) {
    EXPECT_EQ(window.observations(0)[i].point, f.ids[i]);
    EXPECT_DOUBLE_EQ(window.observations(0)[i].depth, depths[i]);
  }
  // Without extras nothing is known: core's "unknown" values.
  ASSERT_EQ(adapter.add_keyframe(window, 4, centre_at(1), f.keypoints, f.ids), Status::kOk);
  EXPECT_EQ(window.keyframe(1).fx, 0.0);
  EXPECT_EQ(window.observations(1)[0].depth, 0.0);
}

TEST(OpencvKeyframes, NonFiniteDepthsOrIntrinsicsAndShortDepthListsAreRefused) {
  const core::Capacities caps = small_capacities();
  core::Window window(caps);
  KeyframeAdapter adapter(caps);
  Frame f = frame(0, 0, 30);
  std::vector<double> depths(30, 2.0);
  KeyframeExtras extras;
  extras.intrinsics = {500, 500, 320, 240};
  extras.depths = &depths;
  // Beyond a float's range too: keyframe_t carries depths as floats, where it would be infinite.
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                     -std::numeric_limits<double>::infinity(), 1e39, -1e39}) {
    depths[7] = bad;
    EXPECT_EQ(adapter.add_keyframe(window, 1, centre_at(0), f.keypoints, f.ids, extras), Status::kNonFinite);
  }
  depths[7] = 2.0;
  KeyframeExtras bad_k = extras;
  bad_k.intrinsics.cy = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(adapter.add_keyframe(window, 1, centre_at(0), f.keypoints, f.ids, bad_k), Status::kNonFinite);
  std::vector<double> short_depths(29, 2.0);
  KeyframeExtras bad_n = extras;
  bad_n.depths = &short_depths;
  EXPECT_EQ(adapter.add_keyframe(window, 1, centre_at(0), f.keypoints, f.ids, bad_n), Status::kSizeMismatch);
  EXPECT_EQ(window.keyframe_count(), 0u);
  ASSERT_EQ(adapter.add_keyframe(window, 1, centre_at(0), f.keypoints, f.ids, extras), Status::kOk);
  EXPECT_EQ(window.keyframe_count(), 1u);
}

// Tracked flags (KeyframeExtras::tracked) reach the window per mapped
// observation, 0 for reserved-id unmapped keypoints; a wrong length is
// refused; and the newest keyframe's tracked points are never culled.
TEST(OpencvKeyframes, TrackedFlagsReachTheWindowAndProtect) {
  const core::Capacities caps = small_capacities();
  core::Params params;
  params.pair_capacity = 1;
  core::Window window(caps);
  core::Sparsifier sparsifier(caps, params);
  KeyframeAdapter adapter(caps);
  Frame a = frame(0, 0, 30), b = frame(1, 0, 30);
  ASSERT_EQ(adapter.add_keyframe(window, 1, centre_at(0), a.keypoints, a.ids), Status::kOk);
  ASSERT_EQ(adapter.add_keyframe(window, 2, centre_at(1), b.keypoints, b.ids), Status::kOk);
  ASSERT_EQ(sparsifier.run(window), core::Status::kOk);
  std::vector<core::PointId> culled;
  culled_points(sparsifier, &culled);
  ASSERT_FALSE(culled.empty());

  std::vector<std::uint8_t> tracked(30, 0);
  for (std::size_t i = 0; i < tracked.size(); i += 2) tracked[i] = 1;
  std::vector<cv::KeyPoint> unmapped = {cv::KeyPoint(5.f, 5.f, 31.f)};
  KeyframeExtras extras;
  extras.unmapped = &unmapped;
  extras.tracked = &tracked;
  std::vector<std::uint8_t> short_tracked(29, 1);
  KeyframeExtras bad = extras;
  bad.tracked = &short_tracked;
  ASSERT_TRUE(window.remove_keyframe(2) == core::Status::kOk);
  EXPECT_EQ(adapter.add_keyframe(window, 2, centre_at(1), b.keypoints, b.ids, bad), Status::kSizeMismatch);
  EXPECT_EQ(window.keyframe_count(), 1u);
  ASSERT_EQ(adapter.add_keyframe(window, 2, centre_at(1), b.keypoints, b.ids, extras), Status::kOk);
  const core::Keyframe& k = window.keyframe(1);
  ASSERT_NE(k.tracked, nullptr);
  ASSERT_EQ(window.observation_count(1), 31u);
  for (std::uint32_t i = 0; i < 30; ++i) EXPECT_EQ(k.tracked[i], tracked[i]) << i;
  EXPECT_EQ(k.tracked[30], 0);  // the unmapped keypoint's reserved id

  ASSERT_EQ(sparsifier.run(window), core::Status::kOk);
  std::vector<core::PointId> after;
  culled_points(sparsifier, &after);
  for (std::size_t i = 0; i < tracked.size(); ++i) {
    if (tracked[i] == 0) continue;
    EXPECT_FALSE(std::binary_search(after.begin(), after.end(), b.ids[i])) << b.ids[i];
  }
  EXPECT_GT(sparsifier.summary().tracked, 0u);
}

// Point quality (KeyframeExtras::quality) reaches the window per mapped
// observation, unknown for reserved-id unmapped keypoints; a wrong length
// or a non-finite value is refused; under --cost track a pair keeps the
// longest tracks first.
TEST(OpencvKeyframes, PointQualityReachesTheWindowAndRanks) {
  const core::Capacities caps = small_capacities();
  core::Params params;
  params.pair_capacity = 10;
  params.cost_model = core::CostModel::kTrack;
  params.track_terms = core::kTrackLength;
  core::Window window(caps);
  core::Sparsifier sparsifier(caps, params);
  KeyframeAdapter adapter(caps);
  Frame a = frame(0, 0, 30), b = frame(1, 0, 30);
  std::vector<core::PointQuality> quality(30);
  for (std::size_t i = 0; i < quality.size(); ++i) quality[i].track_length = static_cast<std::uint32_t>(1 + i);
  std::vector<cv::KeyPoint> unmapped = {cv::KeyPoint(5.f, 5.f, 31.f)};
  KeyframeExtras extras;
  extras.unmapped = &unmapped;
  extras.quality = &quality;
  std::vector<core::PointQuality> short_quality(29);
  KeyframeExtras bad = extras;
  bad.quality = &short_quality;
  EXPECT_EQ(adapter.add_keyframe(window, 1, centre_at(0), a.keypoints, a.ids, bad), Status::kSizeMismatch);
  std::vector<core::PointQuality> nan_quality = quality;
  nan_quality[3].reprojection_error = std::numeric_limits<float>::quiet_NaN();
  bad.quality = &nan_quality;
  EXPECT_EQ(adapter.add_keyframe(window, 1, centre_at(0), a.keypoints, a.ids, bad), Status::kNonFinite);
  EXPECT_EQ(window.keyframe_count(), 0u);
  ASSERT_EQ(adapter.add_keyframe(window, 1, centre_at(0), a.keypoints, a.ids, extras), Status::kOk);
  ASSERT_EQ(adapter.add_keyframe(window, 2, centre_at(1), b.keypoints, b.ids, extras), Status::kOk);
  const core::Keyframe& k = window.keyframe(1);
  ASSERT_NE(k.quality, nullptr);
  ASSERT_EQ(window.observation_count(1), 31u);
  for (std::uint32_t i = 0; i < 30; ++i) EXPECT_EQ(k.quality[i].track_length, quality[i].track_length) << i;
  EXPECT_EQ(k.quality[30].track_length, 0u);  // the unmapped keypoint's reserved id: unknown

  ASSERT_EQ(sparsifier.run(window), core::Status::kOk);
  EXPECT_EQ(sparsifier.summary().track_fallback, 0u);
  std::vector<core::PointId> kept;
  points_with_verdict(sparsifier, core::Verdict::kKeep, &kept);
  ASSERT_FALSE(kept.empty());
  // The pair keeps its 10 points of the longest tracks, by the level's
  // log2 steps (1, 2-3, 4-7, 8-15, >= 16), ties to the smaller id.
  const auto step = [](std::uint32_t t) { return std::min(4, static_cast<int>(std::floor(std::log2(t)))); };
  int lowest_kept = 4, highest_culled = 0;
  for (std::size_t i = 0; i < b.ids.size(); ++i) {
    if (std::binary_search(kept.begin(), kept.end(), b.ids[i])) {
      lowest_kept = std::min(lowest_kept, step(quality[i].track_length));
    } else {
      highest_culled = std::max(highest_culled, step(quality[i].track_length));
    }
  }
  EXPECT_EQ(kept.size(), 10u);
  EXPECT_GE(lowest_kept, highest_culled);
}

TEST(OpencvKeyframes, NativeUnmappedListCountsUnderAuthorsButNotInThePapersBox) {
  // Dense enough clutter (12 around each point) to move the authors' binned c_s.
  core::Capacities caps = small_capacities();
  caps.max_points = 4096;
  caps.max_unmapped_keypoints = 5 * 40 * 12;
  core::Window plain(caps), reserved(caps), native(caps);
  KeyframeAdapter a(caps), b(caps), c(caps);
  fill(plain, a, 5, false);
  fill(reserved, b, 5, true, UnmappedAs::kReservedIds, 12);
  fill(native, c, 5, true, UnmappedAs::kKeypointList, 12);
  EXPECT_EQ(native.total_unmapped(), 5u * 40u * 12u);
  EXPECT_EQ(native.total_observations(), plain.total_observations());
  EXPECT_EQ(native.distinct_points(), plain.distinct_points());
  EXPECT_EQ(native.keyframe(2).unmapped_count, 480u);
  EXPECT_EQ(reserved.total_unmapped(), 0u);
  EXPECT_EQ(c.last().unmapped.size(), 480u);
  EXPECT_EQ(c.last().mapped, static_cast<std::uint32_t>(c.last().observations.size()));

  auto decide = [&](const core::Window& w, core::CostModel model, core::Summary* s,
                    std::vector<core::PointId>* culled) {
    core::Params params;
    params.pair_capacity = 6;
    params.cost_model = model;
    core::Sparsifier sp(caps, params);
    ASSERT_EQ(sp.run(w), core::Status::kOk);
    *s = sp.summary();
    culled_points(sp, culled);
  };
  core::Summary sp, sr, sn;
  std::vector<core::PointId> cp, cr, cn;
  // kAuthors: the grid counts the native list as it counts reserved-id observations.
  decide(plain, core::CostModel::kAuthors, &sp, &cp);
  decide(reserved, core::CostModel::kAuthors, &sr, &cr);
  decide(native, core::CostModel::kAuthors, &sn, &cn);
  EXPECT_GT(sn.total_cost, sp.total_cost);
  EXPECT_EQ(sn.total_cost, sr.total_cost);
  EXPECT_EQ(sn.max_flow, sp.max_flow);
  EXPECT_EQ(cn, cr);
  EXPECT_EQ(sn.evaluated, sp.evaluated);
  // kPaper: the box counts observations only, so the native list changes nothing.
  decide(plain, core::CostModel::kPaper, &sp, &cp);
  decide(reserved, core::CostModel::kPaper, &sr, &cr);
  decide(native, core::CostModel::kPaper, &sn, &cn);
  EXPECT_EQ(sn.total_cost, sp.total_cost);
  EXPECT_EQ(cn, cp);
  EXPECT_GT(sr.total_cost, sp.total_cost);

  // Beyond max_unmapped_keypoints the adapter refuses the keyframe, and says so.
  core::Capacities none = small_capacities();  // max_unmapped_keypoints = 0
  core::Window w(none);
  KeyframeAdapter d(none);
  Frame f = frame(0, 0, 10);
  std::vector<cv::KeyPoint> extra = {cv::KeyPoint(cv::Point2f(5, 5), 31.f)};
  KeyframeExtras extras;
  extras.unmapped = &extra;
  extras.unmapped_as = UnmappedAs::kKeypointList;
  EXPECT_EQ(d.add_keyframe(w, 1, centre_at(0), f.keypoints, f.ids, extras), Status::kCapacityExceeded);
  EXPECT_EQ(w.keyframe_count(), 0u);
}

// A keep budget through the adapter: reserved-id unmapped keypoints are
// never candidates, so the budget's share is of the map points alone.
TEST(OpencvKeyframes, KeepBudgetCountsOnlyMapPoints) {
  const core::Capacities caps = small_capacities();
  core::Params params;
  params.budget = {core::BudgetKind::kFraction, 0, 0.3};
  core::Window cluttered(caps);
  KeyframeAdapter b(caps);
  fill(cluttered, b, 5, true);
  core::Sparsifier s(caps, params);
  ASSERT_EQ(s.run(cluttered), core::Status::kOk);
  std::vector<core::PointId> culled, kept;
  culled_points(s, &culled);
  points_with_verdict(s, core::Verdict::kKeep, &kept);
  const std::size_t evaluated = culled.size() + kept.size();
  EXPECT_EQ(evaluated, s.summary().evaluated);
  EXPECT_EQ(kept.size(), static_cast<std::size_t>(std::floor(0.3 * static_cast<double>(evaluated) + 0.5)));
  EXPECT_GT(culled.size(), 0u);
  for (core::PointId id : kept) EXPECT_EQ(id & kUnmappedBit, 0u);
}

TEST(OpencvKeyframes, UnmappedKeypointsCountInTheSpatialCostButAreNeverDecided) {
  const core::Capacities caps = small_capacities();
  core::Params params;
  params.pair_capacity = 6;
  core::Window plain(caps), cluttered(caps);
  KeyframeAdapter a(caps), b(caps);
  fill(plain, a, 5, false);
  fill(cluttered, b, 5, true);
  EXPECT_EQ(cluttered.total_observations(), plain.total_observations() * 4);

  core::Sparsifier sp(caps, params), sc(caps, params);
  ASSERT_EQ(sp.run(plain), core::Status::kOk);
  ASSERT_EQ(sc.run(cluttered), core::Status::kOk);
  // Same points and pairs, same flow; denser neighbourhoods cost more.
  EXPECT_EQ(sc.summary().evaluated, sp.summary().evaluated);
  EXPECT_EQ(sc.summary().max_flow, sp.summary().max_flow);
  EXPECT_GT(sc.summary().total_cost, sp.summary().total_cost);
  EXPECT_EQ(sc.summary().skipped - sp.summary().skipped, cluttered.total_observations() * 3 / 4);

  std::vector<core::PointId> culled, kept, skipped;
  culled_points(sc, &culled);
  points_with_verdict(sc, core::Verdict::kKeep, &kept);
  points_with_verdict(sc, core::Verdict::kSkip, &skipped);
  EXPECT_EQ(culled.size(), sc.summary().culled);
  EXPECT_EQ(kept.size(), sc.summary().kept);
  EXPECT_EQ(skipped.size(), sp.summary().skipped);  // only the map's own one-view points
  EXPECT_GT(culled.size(), 0u);
  EXPECT_GT(kept.size(), 0u);
  EXPECT_TRUE(std::is_sorted(culled.begin(), culled.end()));
  for (core::PointId id : culled) {
    EXPECT_EQ(id & kUnmappedBit, 0u);
    EXPECT_FALSE(std::binary_search(kept.begin(), kept.end(), id));
  }
  // The set agrees with the raw decisions.
  std::vector<core::PointId> raw;
  for (std::uint32_t i = 0; i < sc.decision_count(); ++i) {
    if (sc.decisions()[i].verdict == core::Verdict::kCull) raw.push_back(sc.decisions()[i].point);
  }
  EXPECT_EQ(raw, culled);
}

TEST(OpencvKeyframes, UnmappedIdsStayUniqueAcrossKeyframes) {
  const core::Capacities caps = small_capacities();
  core::Window window(caps);
  KeyframeAdapter adapter(caps);
  fill(window, adapter, 3, true);
  // Each unmapped keypoint is its own one-view point.
  EXPECT_EQ(window.distinct_points(), 40u + 2 * 12u + 3u * 40u * 3u);
}

// Deferred culling through the adapter: culls become excluded, a full
// memory deletes at once, tracked flags decide what counts as matched.
TEST(OpencvDeferred, CullsAreExcludedThenDeletedByTheRule) {
  core::DeferredCulls deferred(2, 1);
  std::vector<core::PointId> excluded, deleted;
  ASSERT_EQ(note_keyframe(deferred, {1, 2, 3}, nullptr), Status::kOk);
  defer_culls({9, 3, 7}, deferred, &excluded, &deleted);
  EXPECT_EQ(excluded, (std::vector<core::PointId>{3, 9}));  // held, ascending
  EXPECT_EQ(deleted, std::vector<core::PointId>{7});         // no room: deleted at once
  EXPECT_EQ(deferred.refused(), 1u);
  // 3 matched (flag 1), 9 observed unmatched (flag 0): 9 is deleted.
  const std::vector<std::uint8_t> flags = {1, 0};
  ASSERT_EQ(note_keyframe(deferred, {3, 9}, &flags), Status::kOk);
  defer_culls({}, deferred, &excluded, &deleted);
  EXPECT_TRUE(excluded.empty());
  EXPECT_EQ(deleted, std::vector<core::PointId>{9});
  const std::vector<std::uint8_t> short_flags = {1};
  EXPECT_EQ(note_keyframe(deferred, {3, 9}, &short_flags), Status::kSizeMismatch);
  EXPECT_EQ(deferred.tick(), 2u);  // the refused call changed nothing
  ASSERT_EQ(note_keyframe(deferred, {}, nullptr), Status::kOk);
  defer_culls({}, deferred, &excluded, &deleted);
  EXPECT_EQ(deleted, std::vector<core::PointId>{3});
  EXPECT_EQ(deferred.size(), 0u);
}

// With the id sets reserved as the header says (the culls, and the culls plus
// the deferred capacity), the deferred step never allocates, however many it culls.
TEST(OpencvDeferred, ReservedIdSetsNeverGrow) {
  constexpr std::uint32_t kMaxPoints = 64;
  core::DeferredCulls deferred(kMaxPoints, 1);
  std::vector<core::PointId> culled, excluded, deleted, ids;
  culled.reserve(kMaxPoints);
  excluded.reserve(kMaxPoints);
  deleted.reserve(kMaxPoints + deferred.capacity());
  ids.reserve(kMaxPoints);
  test::AllocationCounter allocations;
  std::uint64_t deleted_total = 0;
  for (std::uint32_t k = 0; k < 8; ++k) {
    ids.clear();
    culled.clear();
    for (std::uint32_t i = 0; i < kMaxPoints; ++i) ids.push_back(1000 * k + i);
    for (std::uint32_t i = 0; i < (k % 2 == 0 ? kMaxPoints : 3u); ++i) culled.push_back(1000 * k + i);
    ASSERT_EQ(note_keyframe(deferred, ids, nullptr), Status::kOk);
    defer_culls(culled, deferred, &excluded, &deleted);
    deleted_total += deleted.size();
  }
  EXPECT_EQ(allocations.stop(), 0u);
  EXPECT_GT(deleted_total, 0u);  // the rule deleted, the refusals too
}

// Review: a finite translation near DBL_MAX, rotated, overflowed the
// centre to infinity and the pose was kOk. Refused as non-finite.
TEST(OpencvPose, ACentreThatOverflowsIsRefused) {
  Eigen::Matrix4d Tcw = Eigen::Matrix4d::Identity();
  Tcw.topLeftCorner<3, 3>() = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Tcw(0, 3) = Tcw(1, 3) = 1.7e308;
  CameraPose pose;
  pose.centre = Eigen::Vector3d(1, 2, 3);
  EXPECT_EQ(pose_from_tcw(Tcw, &pose), Status::kNonFinite);
  EXPECT_EQ(pose.centre, Eigen::Vector3d(1, 2, 3)) << "unchanged";
  cv::Mat m(4, 4, CV_64F);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m.at<double>(r, c) = Tcw(r, c);
  EXPECT_EQ(pose_from_tcw(m, &pose), Status::kNonFinite);
}

}  // namespace
}  // namespace keepless::opencv
