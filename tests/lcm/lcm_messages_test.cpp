// The keepless LCM types: encode/decode round trips, and the wire layout the
// node's pre-decode checks rely on (count offsets, header sizes).

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include <cmath>
#include <cstring>

#include "keepless/decision_t.hpp"
#include "keepless/decision_timing_t.hpp"
#include "keepless/platform/message_validation.hpp"
#include "keepless/platform/node_config.hpp"
#include "keepless/status_t.hpp"
#include "message_builders.hpp"

namespace kt = keepless::testing;
namespace wire = keepless::platform::wire;

namespace {

std::int32_t be32_at(const std::vector<std::uint8_t>& b, std::size_t off) {
  return static_cast<std::int32_t>((std::uint32_t{b[off]} << 24) | (std::uint32_t{b[off + 1]} << 16) |
                                   (std::uint32_t{b[off + 2]} << 8) | std::uint32_t{b[off + 3]});
}

TEST(LcmMessages, KeyframeRoundTrip) {
  keepless::keyframe_t m = kt::make_keyframe(7, 42, {5, -3, 9000000000LL});
  m.centre[1] = -2.25;
  m.orientation[0] = std::sqrt(0.5);
  m.orientation[3] = std::sqrt(0.5);
  m.u[1] = 12.5f;
  m.publisher_id = -77;
  const auto bytes = kt::encode(m);
  ASSERT_EQ(bytes.size(), wire::kKeyframeHeaderBytes + 3 * wire::kKeyframeBytesPerObservation +
                              wire::kKeyframeOptionalCountBytes + wire::kKeyframeTrailerBytes +
                              wire::kKeyframeQualityCountBytes);

  keepless::keyframe_t d{};
  ASSERT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(d.sequence, 7);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.keyframe_id, 42);
  EXPECT_EQ(d.centre[1], -2.25);
  EXPECT_EQ(d.orientation[3], m.orientation[3]);
  EXPECT_EQ(d.image_width, 640);
  EXPECT_EQ(d.point_id, m.point_id);
  EXPECT_EQ(d.u, m.u);
  EXPECT_EQ(d.v, m.v);
  EXPECT_EQ(d.publisher_id, -77);
  // Re-encoding the decoded message gives the same bytes.
  EXPECT_EQ(kt::encode(d), bytes);
}

TEST(LcmMessages, KeyframeCountAtFixedOffset) {
  for (int n : {0, 1, 17, 2000}) {
    std::vector<std::int64_t> ids;
    for (int i = 0; i < n; ++i) ids.push_back(i);
    const auto bytes = kt::encode(kt::make_keyframe(1, 1, ids));
    ASSERT_EQ(bytes.size(), wire::kKeyframeHeaderBytes + wire::kKeyframeBytesPerObservation * n +
                                wire::kKeyframeOptionalCountBytes + wire::kKeyframeTrailerBytes +
                              wire::kKeyframeQualityCountBytes);
    EXPECT_EQ(be32_at(bytes, wire::kKeyframeCountOffset), n);
  }
}

// The optional arrays after the observations (depths, intrinsics, unmapped
// keypoints): a round trip, and the pre-decode checks of their counts.
// The tracked flags after publisher_id: a round trip, and the pre-decode
// check of their count (0 or num_observations).
TEST(LcmMessages, KeyframeTrackedFlags) {
  using keepless::platform::RejectReason;
  const keepless::platform::MessageLimits limits;
  keepless::keyframe_t m = kt::make_keyframe(1, 1, {5, 6, 7});
  m.publisher_id = 9;
  m.num_tracked = 3;
  m.tracked = {1, 0, 1};
  const auto bytes = kt::encode(m);
  ASSERT_EQ(bytes.size(), wire::kKeyframeHeaderBytes + 3 * wire::kKeyframeBytesPerObservation +
                              wire::kKeyframeOptionalCountBytes + wire::kKeyframeTrailerBytes + 3 +
                              wire::kKeyframeQualityCountBytes);
  EXPECT_EQ(keepless::platform::check_keyframe_bytes(bytes.data(), bytes.size(), limits), RejectReason::kNone);
  keepless::keyframe_t d{};
  ASSERT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(d.tracked, m.tracked);
  EXPECT_EQ(d.publisher_id, 9);
  m.num_tracked = 2;
  m.tracked = {1, 0};
  const auto bad = kt::encode(m);
  EXPECT_EQ(keepless::platform::check_keyframe_bytes(bad.data(), bad.size(), limits), RejectReason::kInvalidField);
  auto cut = bytes;
  cut.pop_back();
  EXPECT_EQ(keepless::platform::check_keyframe_bytes(cut.data(), cut.size(), limits), RejectReason::kTruncated);
}

// The point quality after the tracked flags: a round trip, the pre-decode
// check of its count (0 or num_observations), the decoded checks (track
// length >= 0, finite error and angle), and a message without it (an old
// VO's fields only) accepted as before.
TEST(LcmMessages, KeyframePointQuality) {
  using keepless::platform::RejectReason;
  const keepless::platform::MessageLimits limits;
  keepless::keyframe_t m = kt::make_keyframe(1, 1, {5, 6, 7});
  const auto old = kt::encode(m);
  EXPECT_EQ(keepless::platform::check_keyframe_bytes(old.data(), old.size(), limits), RejectReason::kNone);
  const keepless::core::Window empty(keepless::core::Capacities{4, 16, 16, 16, 0});
  std::vector<std::uint64_t> scratch(3);
  EXPECT_EQ(keepless::platform::check_keyframe(m, empty, scratch.data()), RejectReason::kNone);
  m.num_quality = 3;
  m.track_length = {2, 0, 17};
  m.age = {0, -1, 9};
  m.reprojection_error = {0.25f, -1.0f, 3.5f};
  m.triangulation_angle = {1.5f, 0.0f, 12.0f};
  const auto bytes = kt::encode(m);
  ASSERT_EQ(bytes.size(), old.size() + 3 * wire::kKeyframeBytesPerQuality);
  EXPECT_EQ(keepless::platform::check_keyframe_bytes(bytes.data(), bytes.size(), limits), RejectReason::kNone);
  keepless::keyframe_t d{};
  ASSERT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(d.track_length, m.track_length);
  EXPECT_EQ(d.age, m.age);
  EXPECT_EQ(d.reprojection_error, m.reprojection_error);
  EXPECT_EQ(d.triangulation_angle, m.triangulation_angle);
  auto cut = bytes;
  cut.pop_back();
  EXPECT_EQ(keepless::platform::check_keyframe_bytes(cut.data(), cut.size(), limits), RejectReason::kTruncated);
  keepless::keyframe_t bad = m;
  bad.num_quality = 2;
  for (auto* v : {&bad.track_length, &bad.age}) v->pop_back();
  for (auto* v : {&bad.reprojection_error, &bad.triangulation_angle}) v->pop_back();
  const auto two = kt::encode(bad);
  EXPECT_EQ(keepless::platform::check_keyframe_bytes(two.data(), two.size(), limits), RejectReason::kInvalidField);
  EXPECT_EQ(keepless::platform::check_keyframe(bad, empty, scratch.data()), RejectReason::kInvalidField);
  EXPECT_STREQ(keepless::platform::invalid_keyframe_field(&bad), "num_quality (must be 0 or num_observations)");
  EXPECT_EQ(keepless::platform::check_keyframe(m, empty, scratch.data()), RejectReason::kNone);
  bad = m;
  bad.track_length[1] = -4;
  EXPECT_EQ(keepless::platform::check_keyframe(bad, empty, scratch.data()), RejectReason::kInvalidField);
  EXPECT_STREQ(keepless::platform::invalid_keyframe_field(&bad), "track_length (must be >= 0)");
  bad = m;
  bad.triangulation_angle[2] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(keepless::platform::check_keyframe(bad, empty, scratch.data()), RejectReason::kNonFinite);
}

TEST(LcmMessages, KeyframeOptionalFields) {
  keepless::keyframe_t m = kt::make_keyframe(1, 1, {5, 6, 7});
  m.num_depths = 3;
  m.depth = {1.5f, 0.0f, 12.25f};
  m.num_intrinsics = 4;
  m.intrinsics = {525.0, 525.0, 319.5, 239.5};
  m.num_unmapped = 2;
  m.unmapped_u = {10.0f, 20.0f};
  m.unmapped_v = {30.0f, 40.0f};
  const auto bytes = kt::encode(m);
  ASSERT_EQ(bytes.size(), wire::kKeyframeHeaderBytes + 3 * wire::kKeyframeBytesPerObservation +
                              wire::kKeyframeOptionalCountBytes + 3 * 4 + 4 * 8 + 2 * 8 +
                              wire::kKeyframeTrailerBytes + wire::kKeyframeQualityCountBytes);
  keepless::keyframe_t d{};
  ASSERT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(d.depth, m.depth);
  EXPECT_EQ(d.intrinsics, m.intrinsics);
  EXPECT_EQ(d.unmapped_v, m.unmapped_v);

  using keepless::platform::RejectReason;
  keepless::platform::MessageLimits limits;
  limits.max_unmapped = 2;
  const auto check = [&](const std::vector<std::uint8_t>& b) {
    return keepless::platform::check_keyframe_bytes(b.data(), b.size(), limits);
  };
  EXPECT_EQ(check(bytes), RejectReason::kNone);
  auto shorter = bytes;
  shorter.pop_back();
  EXPECT_EQ(check(shorter), RejectReason::kTruncated);
  limits.max_unmapped = 1;
  EXPECT_EQ(check(bytes), RejectReason::kOversizeCount);
  limits.max_unmapped = 2;
  keepless::keyframe_t bad = m;
  bad.num_depths = 2;  // neither 0 nor num_observations
  bad.depth = {1.0f, 2.0f};
  EXPECT_EQ(check(kt::encode(bad)), RejectReason::kInvalidField);
  bad = m;
  bad.num_intrinsics = 3;
  bad.intrinsics = {1.0, 2.0, 3.0};
  EXPECT_EQ(check(kt::encode(bad)), RejectReason::kInvalidField);
  bad = m;
  auto negative = kt::encode(bad);
  // num_unmapped sits 4 + 16 bytes (its two floats each) + the 8-byte
  // publisher_id + the 4-byte num_tracked (no flags) + the 4-byte
  // num_quality (no quality) before the end.
  negative[negative.size() - 36] = 0xff;
  EXPECT_EQ(check(negative), RejectReason::kInvalidField);
}

TEST(LcmMessages, InputsAtTheDefaultLimitsFitOneDatagram) {
  const keepless::platform::NodeConfig defaults;
  const auto kf = kt::encode(kt::make_keyframe(1, 1, kt::id_range(0, defaults.max_observations)));
  EXPECT_LT(kf.size(), 65000u);
  keepless::map_event_t e = kt::make_event(1);
  const auto n = static_cast<std::int64_t>(defaults.max_event_ids);
  e.deleted_point_id = kt::id_range(0, n);
  e.merged_from_id = kt::id_range(n, n);
  e.merged_into_id = kt::id_range(2 * n, n);
  e.removed_keyframe_id = kt::id_range(0, n);
  kt::finalize(e);
  EXPECT_LT(kt::encode(e).size(), 65000u);
  EXPECT_LT(kt::encode(keepless::status_t{}).size(), 65000u);
  EXPECT_LT(kt::encode(keepless::decision_timing_t{}).size(), 65000u);
}

TEST(LcmMessages, MapEventRoundTripAndOffsets) {
  keepless::map_event_t e = kt::make_event(3);
  e.reset = true;
  e.deleted_point_id = {1, 2};
  e.merged_from_id = {10, 11, 12};
  e.merged_into_id = {20, 21, 22};
  e.removed_keyframe_id = {99};
  kt::finalize(e);
  const auto bytes = kt::encode(e);
  e.publisher_id = 5;
  const auto with_id = kt::encode(e);
  ASSERT_EQ(with_id.size(), bytes.size());
  ASSERT_EQ(bytes.size(), wire::kMapEventHeaderBytes + 8 * (2 + 2 * 3 + 1) + wire::kMapEventTrailerBytes);
  EXPECT_EQ(be32_at(bytes, wire::kMapEventCountOffset), 2);
  EXPECT_EQ(be32_at(bytes, wire::kMapEventCountOffset + 4), 3);
  EXPECT_EQ(be32_at(bytes, wire::kMapEventCountOffset + 8), 1);

  keepless::map_event_t d{};
  ASSERT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_TRUE(d.reset);
  EXPECT_EQ(d.deleted_point_id, e.deleted_point_id);
  EXPECT_EQ(d.merged_from_id, e.merged_from_id);
  EXPECT_EQ(d.merged_into_id, e.merged_into_id);
  EXPECT_EQ(d.removed_keyframe_id, e.removed_keyframe_id);
}

TEST(LcmMessages, DecisionRoundTrip) {
  keepless::decision_t m{};
  m.sequence = 11;
  m.keyframe_id = 5;
  m.utime = 123;
  m.status = keepless::decision_t::STATUS_BUDGET_EXHAUSTED;
  m.reject_reason = -1;
  m.points = 10;
  m.evaluated = 8;
  m.kept = 6;
  m.culled = 2;
  m.skipped = 2;
  m.pairs = 3;
  m.max_flow = 17;
  m.total_cost = 99;
  m.window_keyframe_id = {3, 4, 5};
  m.num_window_keyframes = 3;
  m.culled_point_id = {-1, 7};  // -1: the bit pattern of 2^64 - 1
  m.num_culled = 2;
  const auto bytes = kt::encode(m);
  keepless::decision_t d{};
  ASSERT_GT(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  EXPECT_EQ(d.status, keepless::decision_t::STATUS_BUDGET_EXHAUSTED);
  EXPECT_EQ(d.window_keyframe_id, m.window_keyframe_id);
  EXPECT_EQ(d.culled_point_id, m.culled_point_id);
  EXPECT_EQ(static_cast<std::uint64_t>(d.culled_point_id[0]), ~std::uint64_t{0});
  EXPECT_EQ(d.total_cost, 99);
  EXPECT_EQ(kt::encode(d), bytes);
}

// Deferred culling's arrays are appended: every earlier field keeps its
// bytes and offset, so a reader of the earlier layout (offsets, or code
// generated from the earlier .lcm after regenerating) reads the same values;
// with the mode off both lists are empty, 8 bytes of zero counts.
TEST(LcmMessages, DecisionDeferredArraysAreAppended) {
  keepless::decision_t m{};
  m.sequence = 3;
  m.keyframe_id = 9;
  m.status = keepless::decision_t::STATUS_OPTIMAL;
  m.reject_reason = -1;
  m.window_keyframe_id = {8, 9};
  m.num_window_keyframes = 2;
  m.culled_point_id = {4};
  m.num_culled = 1;
  m.publisher_id = 77;
  const auto off = kt::encode(m);
  m.excluded_point_id = {5, 6};
  m.num_excluded = 2;
  m.deleted_point_id = {-1};
  m.num_deleted = 1;
  const auto on = kt::encode(m);
  ASSERT_EQ(on.size(), off.size() + 3 * 8);
  const std::size_t earlier = off.size() - 8;  // everything up to publisher_id
  EXPECT_TRUE(std::equal(off.begin(), off.begin() + static_cast<std::ptrdiff_t>(earlier), on.begin()));
  EXPECT_TRUE(std::all_of(off.begin() + static_cast<std::ptrdiff_t>(earlier), off.end(),
                          [](std::uint8_t b) { return b == 0; }));
  keepless::decision_t d{};
  ASSERT_GT(d.decode(on.data(), 0, static_cast<int>(on.size())), 0);
  EXPECT_EQ(d.culled_point_id, m.culled_point_id);
  EXPECT_EQ(d.publisher_id, 77);
  EXPECT_EQ(d.excluded_point_id, m.excluded_point_id);
  EXPECT_EQ(static_cast<std::uint64_t>(d.deleted_point_id[0]), ~std::uint64_t{0});
}

TEST(LcmMessages, StatusAndTimingRoundTrip) {
  keepless::status_t s{};
  s.is_final = true;
  s.rejected[keepless::status_t::REJECT_TRUNCATED] = 4;
  s.latency_p99_ns = 1234567;
  s.memory_bytes = 1 << 20;
  const auto bytes = kt::encode(s);
  keepless::status_t d{};
  ASSERT_GT(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  EXPECT_TRUE(d.is_final);
  EXPECT_EQ(d.rejected[keepless::status_t::REJECT_TRUNCATED], 4);
  EXPECT_EQ(d.latency_p99_ns, 1234567);

  keepless::decision_timing_t t{};
  t.sequence = 2;
  t.sparsify_ns = 555;
  const auto tb = kt::encode(t);
  keepless::decision_timing_t td{};
  ASSERT_GT(td.decode(tb.data(), 0, static_cast<int>(tb.size())), 0);
  EXPECT_EQ(td.sparsify_ns, 555);
}

TEST(LcmMessages, DecodeRefusesOtherTypes) {
  const auto bytes = kt::encode(kt::make_keyframe(1, 1, {1, 2}));
  keepless::decision_t d{};
  EXPECT_LT(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
}

// A keyframe refused as "invalid field" is logged with the field at fault.
TEST(MessageValidation, InvalidFieldNamesTheField) {
  using keepless::platform::invalid_keyframe_field;
  keepless::keyframe_t m = kt::make_keyframe(1, 1, {5, 6});
  m.image_width = 0;
  EXPECT_STREQ(invalid_keyframe_field(&m), "image_width (must be > 0)");
  m.image_width = 640;
  m.image_height = -1;
  EXPECT_STREQ(invalid_keyframe_field(&m), "image_height (must be > 0)");
  m.image_height = 480;
  m.orientation[0] = 2;
  EXPECT_STREQ(invalid_keyframe_field(&m), "orientation (not a unit quaternion)");
  m.orientation[0] = 1;
  m.num_intrinsics = 3;
  m.intrinsics = {1, 2, 3};
  EXPECT_STREQ(invalid_keyframe_field(&m), "num_intrinsics (must be 0 or 4)");
  m.num_intrinsics = 0;
  m.intrinsics.clear();
  m.num_tracked = 1;  // neither 0 nor num_observations (2)
  m.tracked = {1};
  EXPECT_STREQ(invalid_keyframe_field(&m), "num_tracked (must be 0 or num_observations)");
  m.num_tracked = 2;
  m.tracked = {1, 2};
  EXPECT_STREQ(invalid_keyframe_field(&m), "tracked (a flag is 0 or 1)");
  EXPECT_NE(std::string(invalid_keyframe_field(nullptr)).find("num_observations"), std::string::npos);
  EXPECT_NE(std::string(invalid_keyframe_field(nullptr)).find("num_tracked"), std::string::npos);
  keepless::map_event_t e = kt::make_event(1);
  e.num_deleted_points = -1;
  EXPECT_NE(std::string(keepless::platform::invalid_map_event_field(&e)).find("num_deleted_points"),
            std::string::npos);
}

}  // namespace
