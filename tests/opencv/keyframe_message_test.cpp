// keyframe_t from a KeyframeRecord: fields, unmapped keypoints on request,
// and an LCM encode/decode round trip.

#include <gtest/gtest.h>

#include <vector>

#include "keepless/opencv/keyframe_message.hpp"

namespace keepless::opencv {
namespace {

TEST(OpencvKeyframeMessage, CarriesPoseAndObservationsAndRoundTrips) {
  core::Capacities caps;
  caps.max_unmapped_keypoints = 8;  // the listed unmapped keypoints below
  KeyframeAdapter adapter(caps);
  CameraPose pose;
  ASSERT_EQ(pose_from_orientation(Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY())),
                                  {1, 2, 3}, &pose),
            Status::kOk);
  std::vector<cv::KeyPoint> kps = {cv::KeyPoint(10.5f, 20.25f, 31.f), cv::KeyPoint(300.f, 40.f, 31.f)};
  std::vector<core::PointId> ids = {5, core::PointId{1} << 40};
  std::vector<cv::KeyPoint> unmapped = {cv::KeyPoint(11.f, 21.f, 31.f)};
  KeyframeRecord record;
  ASSERT_EQ(adapter.convert(42, pose, kps, ids, &unmapped, &record), Status::kOk);

  // Every field is written, the optional arrays and publisher_id included
  // (a message left uninitialised here once encoded garbage counts).
  keepless::keyframe_t msg;
  msg.num_depths = -7;
  msg.num_intrinsics = 99;
  msg.num_unmapped = 1 << 30;
  to_keyframe_message(record, 9, 1000, 640, 480, false, &msg, 77);
  EXPECT_EQ(msg.keyframe_id, 42);
  EXPECT_EQ(msg.num_depths, 0);
  EXPECT_EQ(msg.num_intrinsics, 0);
  EXPECT_EQ(msg.num_unmapped, 0);
  EXPECT_EQ(msg.publisher_id, 77);
  EXPECT_EQ(msg.num_observations, 2);
  EXPECT_EQ(msg.point_id, (std::vector<std::int64_t>{5, std::int64_t{1} << 40}));
  EXPECT_FLOAT_EQ(msg.u[0], 10.5f);
  EXPECT_FLOAT_EQ(msg.v[0], 20.25f);
  EXPECT_DOUBLE_EQ(msg.centre[2], 3.0);
  EXPECT_DOUBLE_EQ(msg.orientation[0], pose.orientation.w());
  EXPECT_DOUBLE_EQ(msg.orientation[2], pose.orientation.y());

  std::vector<std::uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  ASSERT_EQ(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  keepless::keyframe_t back;
  ASSERT_EQ(back.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  EXPECT_EQ(back.point_id, msg.point_id);
  EXPECT_EQ(back.u, msg.u);
  EXPECT_EQ(back.image_width, 640);
  EXPECT_EQ(back.publisher_id, 77);

  EXPECT_EQ(msg.num_tracked, 0);  // no flags given
  EXPECT_TRUE(msg.tracked.empty());
  {  // with tracked flags: one per observation sent, the unmapped ones 0
    std::vector<std::uint8_t> flags = {1, 0};
    KeyframeExtras extras;
    extras.unmapped = &unmapped;
    extras.tracked = &flags;
    KeyframeRecord flagged;
    ASSERT_EQ(adapter.convert(43, pose, kps, ids, extras, &flagged), Status::kOk);
    keepless::keyframe_t t;
    to_keyframe_message(flagged, 11, 1500, 640, 480, true, &t);
    EXPECT_EQ(t.num_tracked, 3);
    EXPECT_EQ(t.tracked, (std::vector<std::int8_t>{1, 0, 0}));
    to_keyframe_message(flagged, 12, 1600, 640, 480, false, &t);
    EXPECT_EQ(t.num_tracked, 2);
    EXPECT_EQ(t.tracked, (std::vector<std::int8_t>{1, 0}));
    EXPECT_EQ(t.num_quality, 0);  // no quality given
  }
  {  // with point quality: one per observation sent, the unmapped ones unknown
    std::vector<core::PointQuality> quality = {{12, 3, 0.75f, 4.5f}, {2, 0, 1.25f, 0.5f}};
    KeyframeExtras extras;
    extras.unmapped = &unmapped;
    extras.quality = &quality;
    KeyframeRecord rated;
    ASSERT_EQ(adapter.convert(44, pose, kps, ids, extras, &rated), Status::kOk);
    keepless::keyframe_t t;
    to_keyframe_message(rated, 13, 1700, 640, 480, true, &t);
    EXPECT_EQ(t.num_quality, 3);
    EXPECT_EQ(t.track_length, (std::vector<std::int32_t>{12, 2, 0}));
    EXPECT_EQ(t.age, (std::vector<std::int32_t>{3, 0, -1}));
    EXPECT_EQ(t.reprojection_error, (std::vector<float>{0.75f, 1.25f, -1.f}));
    EXPECT_EQ(t.triangulation_angle, (std::vector<float>{4.5f, 0.5f, 0.f}));
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(t.getEncodedSize()));
    ASSERT_EQ(t.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
    keepless::keyframe_t back;
    ASSERT_EQ(back.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
    EXPECT_EQ(back.track_length, t.track_length);
    EXPECT_EQ(back.triangulation_angle, t.triangulation_angle);
    to_keyframe_message(rated, 14, 1800, 640, 480, false, &t);
    EXPECT_EQ(t.num_quality, 2);
  }
  to_keyframe_message(record, 10, 2000, 640, 480, true, &msg);
  ASSERT_EQ(msg.num_observations, 3);
  EXPECT_NE(static_cast<std::uint64_t>(msg.point_id[2]) & kUnmappedBit, 0u);
  EXPECT_EQ(msg.num_unmapped, 0);

  // Core's native list travels as unmapped_u/v, with depths and intrinsics.
  std::vector<double> depths = {1.5, 0};
  KeyframeExtras extras;
  extras.unmapped = &unmapped;
  extras.unmapped_as = UnmappedAs::kKeypointList;
  extras.intrinsics = {500, 501, 320, 240};
  extras.depths = &depths;
  ASSERT_EQ(adapter.convert(43, pose, kps, ids, extras, &record), Status::kOk);
  to_keyframe_message(record, 11, 3000, 640, 480, true, &msg);
  EXPECT_EQ(msg.num_observations, 2);
  ASSERT_EQ(msg.num_unmapped, 1);
  EXPECT_FLOAT_EQ(msg.unmapped_u[0], 11.f);
  EXPECT_FLOAT_EQ(msg.unmapped_v[0], 21.f);
  ASSERT_EQ(msg.num_depths, 2);
  EXPECT_FLOAT_EQ(msg.depth[0], 1.5f);
  ASSERT_EQ(msg.num_intrinsics, 4);
  EXPECT_DOUBLE_EQ(msg.intrinsics[1], 501.0);
  to_keyframe_message(record, 12, 4000, 640, 480, false, &msg);
  EXPECT_EQ(msg.num_unmapped, 0);
}

}  // namespace
}  // namespace keepless::opencv
