// Window::keyframe_stamp and copy_keyframe: stamps are unique across
// windows and additions, follow their keyframe when slots shift, survive a
// copy into another window (and only a copy), and a refused copy changes
// nothing.

#include <gtest/gtest.h>

#include <cstdint>
#include <set>
#include <vector>

#include "keepless/core/window.hpp"

namespace keepless::core {
namespace {

Keyframe keyframe(KeyframeId id) {
  Keyframe k;
  k.id = id;
  k.centre[0] = static_cast<double>(id);
  return k;
}

std::vector<Observation> observations(PointId first, std::uint32_t n) {
  std::vector<Observation> obs;
  for (std::uint32_t i = 0; i < n; ++i) obs.push_back({first + i, 1.5 * i, 2.0 * i});
  return obs;
}

TEST(WindowStamp, UniqueAcrossAdditionsAndWindows) {
  const Capacities caps{4, 100, 100, 100};
  Window a(caps), b(caps);
  const auto obs = observations(1, 5);
  std::set<std::uint64_t> seen;
  for (KeyframeId id = 1; id <= 4; ++id) {
    ASSERT_EQ(a.add_keyframe(keyframe(id), obs.data(), 5), Status::kOk);
    ASSERT_EQ(b.add_keyframe(keyframe(id), obs.data(), 5), Status::kOk);  // same contents
  }
  for (std::uint32_t s = 0; s < 4; ++s) {
    EXPECT_NE(a.keyframe_stamp(s), 0u);
    EXPECT_TRUE(seen.insert(a.keyframe_stamp(s)).second);
    EXPECT_TRUE(seen.insert(b.keyframe_stamp(s)).second);
  }
  // Removed and added again: a new stamp.
  const std::uint64_t old = a.keyframe_stamp(3);
  ASSERT_EQ(a.remove_keyframe(4), Status::kOk);
  ASSERT_EQ(a.add_keyframe(keyframe(4), obs.data(), 5), Status::kOk);
  EXPECT_NE(a.keyframe_stamp(3), old);
  EXPECT_TRUE(seen.insert(a.keyframe_stamp(3)).second);
}

TEST(WindowStamp, FollowsItsKeyframeWhenSlotsShift) {
  const Capacities caps{4, 100, 100, 100};
  Window w(caps);
  const auto obs = observations(1, 3);
  for (KeyframeId id = 1; id <= 4; ++id)
    ASSERT_EQ(w.add_keyframe(keyframe(id), obs.data(), 3), Status::kOk);
  const std::uint64_t third = w.keyframe_stamp(2), fourth = w.keyframe_stamp(3);
  ASSERT_EQ(w.remove_keyframe(2), Status::kOk);
  EXPECT_EQ(w.keyframe(1).id, 3u);
  EXPECT_EQ(w.keyframe_stamp(1), third);
  EXPECT_EQ(w.keyframe_stamp(2), fourth);
}

TEST(WindowStamp, CopyKeepsKeyframeObservationsAndStamp) {
  const Capacities caps{4, 100, 100, 100};
  Window from(caps), to(caps);
  const auto first = observations(1, 6), second = observations(4, 6);
  ASSERT_EQ(from.add_keyframe(keyframe(7), first.data(), 6), Status::kOk);
  ASSERT_EQ(from.add_keyframe(keyframe(9), second.data(), 6), Status::kOk);
  ASSERT_EQ(to.copy_keyframe(from, 1), Status::kOk);
  ASSERT_EQ(to.copy_keyframe(from, 0), Status::kOk);
  ASSERT_EQ(to.keyframe_count(), 2u);
  EXPECT_EQ(to.keyframe(0).id, 9u);
  EXPECT_EQ(to.keyframe_stamp(0), from.keyframe_stamp(1));
  EXPECT_EQ(to.keyframe_stamp(1), from.keyframe_stamp(0));
  EXPECT_EQ(to.keyframe(1).centre[0], 7.0);
  ASSERT_EQ(to.observation_count(0), 6u);
  for (std::uint32_t i = 0; i < 6; ++i) {
    EXPECT_EQ(to.observations(0)[i].point, second[i].point);
    EXPECT_EQ(to.observations(0)[i].u, second[i].u);
  }
  EXPECT_EQ(to.distinct_points(), 9u);
  EXPECT_EQ(to.total_observations(), 12u);
}

// A stamp vouches for the quality too: a copy into a window that does not
// hold quality holds other contents, so it gets a new stamp (a Sparsifier
// with the track cost that saw the stamp with quality would otherwise reuse
// the levels it read then); a copy that keeps the quality keeps the stamp.
TEST(WindowStamp, ACopyThatDropsTheQualityGetsANewStamp) {
  Capacities with{4, 100, 100, 100};
  with.hold_quality = true;
  Capacities without = with;
  without.hold_quality = false;
  Window from(with), keeps(with), drops(without);
  const auto obs = observations(1, 6);
  std::vector<PointQuality> quality(6);
  for (std::uint32_t i = 0; i < 6; ++i) quality[i].track_length = 2 + i;
  Keyframe k = keyframe(7);
  k.quality = quality.data();
  ASSERT_EQ(from.add_keyframe(k, obs.data(), 6), Status::kOk);
  ASSERT_EQ(keeps.copy_keyframe(from, 0), Status::kOk);
  ASSERT_EQ(drops.copy_keyframe(from, 0), Status::kOk);
  EXPECT_EQ(keeps.keyframe_stamp(0), from.keyframe_stamp(0));
  ASSERT_NE(keeps.keyframe(0).quality, nullptr);
  EXPECT_EQ(drops.keyframe(0).quality, nullptr);
  EXPECT_NE(drops.keyframe_stamp(0), from.keyframe_stamp(0));
  // Without quality to drop, a copy keeps its stamp in either window.
  Window plain(with), plain_copy(without);
  ASSERT_EQ(plain.add_keyframe(keyframe(8), obs.data(), 6), Status::kOk);
  ASSERT_EQ(plain_copy.copy_keyframe(plain, 0), Status::kOk);
  EXPECT_EQ(plain_copy.keyframe_stamp(0), plain.keyframe_stamp(0));
}

TEST(WindowStamp, RefusedCopiesChangeNothing) {
  Window from(Capacities{4, 100, 100, 100});
  const auto obs = observations(1, 8);
  ASSERT_EQ(from.add_keyframe(keyframe(1), obs.data(), 8), Status::kOk);
  ASSERT_EQ(from.add_keyframe(keyframe(2), obs.data(), 4), Status::kOk);
  Window small(Capacities{4, 6, 100, 100});  // room for 6 distinct points
  EXPECT_EQ(small.copy_keyframe(from, 0), Status::kCapacityExceeded);
  EXPECT_EQ(small.copy_keyframe(from, 2), Status::kInvalidArgument);
  EXPECT_EQ(small.keyframe_count(), 0u);
  EXPECT_EQ(small.distinct_points(), 0u);
  ASSERT_EQ(small.copy_keyframe(from, 1), Status::kOk);
  EXPECT_EQ(small.copy_keyframe(from, 1), Status::kDuplicateKeyframe);
  EXPECT_EQ(from.copy_keyframe(from, 0), Status::kDuplicateKeyframe);
  EXPECT_EQ(small.keyframe_count(), 1u);
  EXPECT_EQ(small.total_observations(), 4u);
}

}  // namespace
}  // namespace keepless::core
