// The real VO's baselines (baseline_culls): each culls exactly the count it is
// given, and ANMS judges a candidate among those of its own keyframe, the
// keyframes sharing the kept count in proportion to their candidates, as the
// synthetic back end's ANMS does (deciding a window, candidates from different
// keyframes at the same pixels do not suppress each other).

#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

#include "point_selection.hpp"
#include "ssc.hpp"

namespace vo = keepless::eval::vo;

namespace {

// `count` candidates of keyframe `keyframe` on a 4-wide grid, ids from `first`.
void add(std::vector<vo::Candidate>* out, int keyframe, int count, keepless::core::PointId first) {
  for (int i = 0; i < count; ++i) {
    vo::Candidate c;
    c.id = first + static_cast<keepless::core::PointId>(i);
    c.u = 20.f + 150.f * static_cast<float>(i % 4);
    c.v = 20.f + 100.f * static_cast<float>(i / 4);
    c.response = 1.f + static_cast<float>(i);
    c.track_length = 2 + i % 3;
    c.keyframe = keyframe;
    out->push_back(c);
  }
}

std::size_t culled_in(const std::vector<keepless::core::PointId>& culls, keepless::core::PointId first, int count) {
  return static_cast<std::size_t>(std::count_if(culls.begin(), culls.end(), [&](keepless::core::PointId id) {
    return id >= first && id < first + static_cast<keepless::core::PointId>(count);
  }));
}

TEST(VoBaselines, AnmsSharesTheCountAmongKeyframes) {
  std::vector<vo::Candidate> candidates;
  add(&candidates, 7, 12, 100);  // the same pixels in two keyframes
  add(&candidates, 3, 8, 200);
  // Keep 10 of 20: 6 of keyframe 7's 12 and 4 of keyframe 3's 8.
  const auto culls = vo::baseline_culls(vo::Selector::kAnms, candidates, 10, 1, 640, 480);
  ASSERT_EQ(culls.size(), 10u);
  EXPECT_TRUE(std::is_sorted(culls.begin(), culls.end()));
  EXPECT_EQ(culled_in(culls, 100, 12), 6u);
  EXPECT_EQ(culled_in(culls, 200, 8), 4u);
  // Keep 5 of 20: exact shares 3 and 2.
  const auto more = vo::baseline_culls(vo::Selector::kAnms, candidates, 15, 1, 640, 480);
  EXPECT_EQ(culled_in(more, 100, 12), 9u);
  EXPECT_EQ(culled_in(more, 200, 8), 6u);
}

TEST(VoBaselines, OneKeyframesAnmsIsSscOnItsImage) {
  std::vector<vo::Candidate> candidates;
  add(&candidates, 0, 12, 100);
  const auto culls = vo::baseline_culls(vo::Selector::kAnms, candidates, 8, 1, 640, 480);
  ASSERT_EQ(culls.size(), 8u);
  // What SSC keeps of the same points on the same image: 4 of 12.
  std::vector<keepless::eval::SscPoint> points;
  for (const vo::Candidate& c : candidates) points.push_back({c.u, c.v, c.response, c.id});
  std::vector<keepless::core::PointId> kept;
  for (std::uint32_t i : keepless::eval::ssc_select(points, 4, 640, 480)) kept.push_back(candidates[i].id);
  ASSERT_EQ(kept.size(), 4u);
  std::vector<keepless::core::PointId> expected;
  for (const vo::Candidate& c : candidates) {
    if (std::find(kept.begin(), kept.end(), c.id) == kept.end()) expected.push_back(c.id);
  }
  EXPECT_EQ(culls, expected);  // both ascending
  // The strongest response (id 111) survives SSC at any count.
  EXPECT_FALSE(std::binary_search(culls.begin(), culls.end(), keepless::core::PointId{111}));
}

TEST(VoBaselines, EveryBaselineCullsExactlyTheCount) {
  std::vector<vo::Candidate> candidates;
  add(&candidates, 1, 9, 100);
  add(&candidates, 2, 9, 200);
  for (const vo::Selector s : {vo::Selector::kRandom, vo::Selector::kLongestTrack, vo::Selector::kAnms}) {
    for (std::size_t cull : {std::size_t{0}, std::size_t{5}, std::size_t{18}, std::size_t{40}}) {
      std::vector<keepless::core::PointId> culls = vo::baseline_culls(s, candidates, cull, 3, 640, 480);
      EXPECT_EQ(culls.size(), std::min<std::size_t>(cull, 18));
      std::sort(culls.begin(), culls.end());
      EXPECT_EQ(std::adjacent_find(culls.begin(), culls.end()), culls.end()) << "a point culled twice";
      for (keepless::core::PointId id : culls) EXPECT_EQ(culled_in({id}, 100, 9) + culled_in({id}, 200, 9), 1u) << id;
    }
  }
}

}  // namespace
