// platform::SlidingWindow slides and drops points in place, and rebuilds into
// its spare window for the other edits: either way, keyframes it carries over
// unchanged keep their stamps (so the incremental network knows them without
// comparing contents), those an edit changed get new ones.

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <vector>

#include "keepless/platform/sliding_window.hpp"

namespace keepless::platform {
namespace {

// Keyframe k sees points 10k .. 10k + 29 (each point in three keyframes).
std::vector<core::Observation> observations_of(std::uint32_t k) {
  std::vector<core::Observation> obs;
  for (std::uint32_t i = 0; i < 30; ++i) obs.push_back({10 * k + i, 5.0 + i, 7.0 + k, 0});
  return obs;
}

core::Status push(SlidingWindow& w, std::uint32_t k) {
  core::Keyframe kf;
  kf.id = k;
  kf.centre[0] = k;
  const std::vector<core::Observation> obs = observations_of(k);
  return w.push(kf, obs.data(), static_cast<std::uint32_t>(obs.size()));
}

std::map<core::KeyframeId, std::uint64_t> stamps(const core::Window& w) {
  std::map<core::KeyframeId, std::uint64_t> out;
  for (std::uint32_t s = 0; s < w.keyframe_count(); ++s) out[w.keyframe(s).id] = w.keyframe_stamp(s);
  return out;
}

TEST(SlidingWindow, UnchangedKeyframesKeepTheirStampsAcrossSlidesAndEdits) {
  core::Capacities caps;
  caps.max_keyframes = 4;
  caps.max_points = 256;
  caps.max_observations = 4 * 30;
  caps.max_pair_arcs = 4096;
  SlidingWindow w(caps, 30, 8);
  for (std::uint32_t k = 0; k < 4; ++k) ASSERT_EQ(push(w, k), core::Status::kOk);
  auto before = stamps(w.window());

  // A slide: keyframe 0 leaves, 4 enters; 1-3 are carried over as they were.
  ASSERT_EQ(push(w, 4), core::Status::kOk);
  auto after = stamps(w.window());
  ASSERT_EQ(after.size(), 4u);
  EXPECT_EQ(after.count(0), 0u);
  for (core::KeyframeId id : {1, 2, 3}) EXPECT_EQ(after[id], before[id]) << id;
  EXPECT_NE(after[4], 0u);

  // Dropping point 45 (10k + i for k = 2, 3, 4) changes those three keyframes only.
  before = after;
  const core::PointId dropped[] = {45};
  ASSERT_EQ(w.drop_points(dropped, 1), core::Status::kOk);
  after = stamps(w.window());
  EXPECT_EQ(after[1], before[1]);
  for (core::KeyframeId id : {2, 3, 4}) EXPECT_NE(after[id], before[id]) << id;
  for (std::uint32_t s = 0; s < w.window().keyframe_count(); ++s) {
    const core::KeyframeId id = w.window().keyframe(s).id;
    const std::uint32_t expected = id >= 2 ? 29u : 30u;  // keyframes 2-4 lost point 45
    EXPECT_EQ(w.window().observation_count(s), expected) << id;
    for (std::uint32_t i = 0; i < w.window().observation_count(s); ++i) {
      EXPECT_NE(w.window().observations(s)[i].point, 45u);
    }
  }

  // A map event's deletion (rebuilt into the spare window): point 31 is in
  // keyframes 1-3 only.
  before = after;
  const core::PointId deleted[] = {31};
  SlidingWindow::Edit e;
  e.deleted = deleted;
  e.deleted_count = 1;
  ASSERT_EQ(w.edit(e), core::Status::kOk);
  after = stamps(w.window());
  EXPECT_EQ(after[4], before[4]);
  for (core::KeyframeId id : {1, 2, 3}) EXPECT_NE(after[id], before[id]) << id;
  EXPECT_EQ(w.window().point_views(31), 0u);
}

}  // namespace
}  // namespace keepless::platform
