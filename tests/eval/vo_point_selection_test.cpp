// The real VO's baselines (baseline_culls): each culls exactly the count it is
// given, and ANMS judges a candidate among those of its own keyframe, the
// keyframes sharing the kept count in proportion to their candidates, as the
// synthetic back end's ANMS does (deciding a window, candidates from different
// keyframes at the same pixels do not suppress each other). Its variants rank
// by one ingredient each: spread alone, or response alone.

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

// Response alone: the weakest go, wherever they are. Spread alone: SSC on the
// random baseline's priorities, so the keypoints' responses change nothing,
// and where random keeps a clump SSC spreads the same count.
TEST(VoBaselines, AnmsVariantsRankByOneIngredientEach) {
  std::vector<vo::Candidate> candidates;
  add(&candidates, 0, 12, 100);  // responses 1..12 by id
  const auto weakest =
      vo::baseline_culls(vo::Selector::kAnms, candidates, 8, 1, 640, 480, vo::AnmsVariant::kResponse);
  EXPECT_EQ(weakest, (std::vector<keepless::core::PointId>{100, 101, 102, 103, 104, 105, 106, 107}));

  const auto spread = vo::baseline_culls(vo::Selector::kAnms, candidates, 8, 5, 640, 480, vo::AnmsVariant::kSpread);
  ASSERT_EQ(spread.size(), 8u);
  std::vector<vo::Candidate> reversed = candidates;
  for (vo::Candidate& c : reversed) c.response = 100.f - c.response;
  EXPECT_EQ(vo::baseline_culls(vo::Selector::kAnms, reversed, 8, 5, 640, 480, vo::AnmsVariant::kSpread), spread);
  EXPECT_NE(vo::baseline_culls(vo::Selector::kAnms, reversed, 8, 5, 640, 480),
            vo::baseline_culls(vo::Selector::kAnms, candidates, 8, 5, 640, 480))
      << "the default ranks by response";
  // A clump of 12 candidates within 3 pixels plus 4 far apart: keeping 4,
  // SSC on any priority keeps at most one of the clump.
  std::vector<vo::Candidate> clumped;
  for (int i = 0; i < 16; ++i) {
    vo::Candidate c;
    c.id = static_cast<keepless::core::PointId>(300 + i);
    c.u = i < 12 ? 320.f + static_cast<float>(i % 3) : 40.f + 180.f * static_cast<float>(i - 12);
    c.v = i < 12 ? 240.f + static_cast<float>(i / 4) : 60.f;
    c.response = 1.f;
    clumped.push_back(c);
  }
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto culls = vo::baseline_culls(vo::Selector::kAnms, clumped, 12, seed, 640, 480, vo::AnmsVariant::kSpread);
    ASSERT_EQ(culls.size(), 12u);
    EXPECT_GE(culled_in(culls, 300, 12), 11u) << "seed " << seed;
  }
}

TEST(VoBaselines, EveryBaselineCullsExactlyTheCount) {
  std::vector<vo::Candidate> candidates;
  add(&candidates, 1, 9, 100);
  add(&candidates, 2, 9, 200);
  for (const vo::Selector s : {vo::Selector::kRandom, vo::Selector::kLongestTrack, vo::Selector::kAnms}) {
    for (const vo::AnmsVariant a :
         {vo::AnmsVariant::kSsc, vo::AnmsVariant::kSpread, vo::AnmsVariant::kResponse, vo::AnmsVariant::kTrack}) {
      for (std::size_t cull : {std::size_t{0}, std::size_t{5}, std::size_t{18}, std::size_t{40}}) {
        std::vector<keepless::core::PointId> culls = vo::baseline_culls(s, candidates, cull, 3, 640, 480, a);
        EXPECT_EQ(culls.size(), std::min<std::size_t>(cull, 18));
        std::sort(culls.begin(), culls.end());
        EXPECT_EQ(std::adjacent_find(culls.begin(), culls.end()), culls.end()) << "a point culled twice";
        for (keepless::core::PointId id : culls) EXPECT_EQ(culled_in({id}, 100, 9) + culled_in({id}, 200, 9), 1u) << id;
      }
    }
  }
}

}  // namespace
