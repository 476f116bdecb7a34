// Settings per use (core::Use): the names, which fields a use sets and which
// it leaves to the caller, and what the monocular and offline uses do to
// decisions on seeded windows.

#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <map>
#include <string>

#include "keepless/core/sparsifier.hpp"
#include "keepless/core/use.hpp"
#include "random_window.hpp"

namespace keepless::core {
namespace {

const Capacities kCaps{16, 2048, 8192, 32768, 4096};
constexpr Use kUses[] = {Use::kPaper, Use::kMonocular, Use::kMonocularDeferred, Use::kRgbd, Use::kOffline};

TEST(Use, NamesRoundTripAndOthersAreRefused) {
  for (Use u : kUses) {
    Use parsed = Use::kPaper;
    ASSERT_TRUE(parse_use(to_string(u), &parsed)) << to_string(u);
    EXPECT_EQ(parsed, u);
  }
  for (const char* bad : {"", "Monocular", "mono", "monocular ", "offline,rgbd"}) {
    Use out = Use::kOffline;
    EXPECT_FALSE(parse_use(bad, &out)) << "'" << bad << "'";
    EXPECT_EQ(out, Use::kOffline);
  }
}

// A use sets the policy fields, whatever an earlier use or the caller
// had there, and leaves everything else as the caller set it.
TEST(Use, SetsThePolicyAndLeavesTheRest) {
  Params caller;
  caller.pair_capacity = 7;
  caller.theta = 0.25;
  caller.box_width = 32;
  caller.cost_terms = kConnectivityCost | kBaselineCost;
  caller.coverage_floor = 5;
  caller.cost_model = CostModel::kTrack;
  caller.track_terms = kTrackAngle;
  caller.budget = KeepBudget{BudgetKind::kFraction, 0, 0.2, 0.0, 0.7};
  for (Use first : kUses) {
    for (Use u : kUses) {
      Params p = caller;
      apply_use(first, &p);
      apply_use(u, &p);
      SCOPED_TRACE(std::string(to_string(first)) + " then " + to_string(u));
      EXPECT_EQ(p.pair_capacity, 7);
      EXPECT_EQ(p.theta, 0.25);
      EXPECT_EQ(p.box_width, 32);
      EXPECT_EQ(p.cost_terms, kConnectivityCost | kBaselineCost);
      EXPECT_EQ(p.coverage_floor, 5u);
      EXPECT_EQ(p.cost_model, CostModel::kTrack);
      EXPECT_EQ(p.track_terms, kTrackAngle);
      EXPECT_EQ(p.budget.kind, BudgetKind::kFraction);
      EXPECT_EQ(p.budget.fraction, 0.2);
      const bool guarded = u == Use::kMonocular || u == Use::kRgbd;
      EXPECT_EQ(p.scope, guarded ? Scope::kNewest : u == Use::kMonocularDeferred ? Scope::kAuto : Scope::kWindow);
      EXPECT_EQ(p.maturity_keyframes, guarded ? 2u : 0u);
      EXPECT_EQ(p.defer_keyframes, u == Use::kMonocularDeferred ? 2u : 0u);
      const bool mono = u == Use::kMonocular || u == Use::kMonocularDeferred;
      EXPECT_EQ(p.budget.track_share, u == Use::kOffline ? 1.0 : mono ? 0.5 : 0.0);
      EXPECT_EQ(p.budget.track_share_from, u == Use::kMonocular ? 0.3 : 0.0);
      EXPECT_EQ(p.budget.track_share_to, u == Use::kMonocularDeferred ? 0.15 : 1.0);
    }
  }
  // The paper's are Params' defaults.
  {
    Params p;
    p.scope = Scope::kNewest;
    p.maturity_keyframes = 3;
    p.defer_keyframes = 4;
    apply_use(Use::kPaper, &p);
    const Params defaults;
    EXPECT_EQ(p.scope, defaults.scope);
    EXPECT_EQ(p.maturity_keyframes, defaults.maturity_keyframes);
    EXPECT_EQ(p.defer_keyframes, defaults.defer_keyframes);
  }
}

// Window slot where each point is first seen (the oldest keyframe observing it).
std::map<PointId, std::uint32_t> first_seen(const Window& w) {
  std::map<PointId, std::uint32_t> first;
  for (std::uint32_t slot = w.keyframe_count(); slot-- > 0;) {
    for (std::uint32_t i = 0; i < w.observation_count(slot); ++i) first[w.observations(slot)[i].point] = slot;
  }
  return first;
}

// Monocular: only the points of the keyframe two before the newest are
// decided, and none first seen after it, so nothing new to the newest two
// keyframes is culled; the paper's settings on the same windows cull such
// points.
TEST(Use, MonocularDecidesOnlyPointsTwoKeyframesOld) {
  Params tight;
  tight.pair_capacity = 2;  // so that there is something to cull
  Params mono = tight;
  apply_use(Use::kMonocular, &mono);
  Sparsifier monocular(kCaps, mono);
  Sparsifier paper(kCaps, tight);
  Window window(kCaps);
  std::uint32_t decided = 0, culled = 0, young_culled_by_paper = 0;
  for (std::uint64_t seed = 1; seed <= 200 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    ASSERT_EQ(monocular.run(window), Status::kOk) << "seed " << seed;
    ASSERT_EQ(paper.run(window), Status::kOk) << "seed " << seed;
    const std::uint32_t k = window.keyframe_count();
    const auto first = first_seen(window);
    for (std::uint32_t i = 0; i < monocular.decision_count(); ++i) {
      const PointDecision& d = monocular.decisions()[i];
      if (d.verdict == Verdict::kSkip) continue;
      ASSERT_GE(k, 3u) << "seed " << seed << ": decided with " << k << " keyframes";
      ASSERT_LE(first.at(d.point), k - 3) << "seed " << seed << " point " << d.point;
      bool seen = false;
      for (std::uint32_t j = 0; j < window.observation_count(k - 3); ++j) {
        seen = seen || window.observations(k - 3)[j].point == d.point;
      }
      ASSERT_TRUE(seen) << "seed " << seed << " point " << d.point << " not in the decided keyframe";
      ++decided;
      culled += d.verdict == Verdict::kCull;
    }
    for (std::uint32_t i = 0; i < paper.decision_count(); ++i) {
      const PointDecision& d = paper.decisions()[i];
      young_culled_by_paper += d.verdict == Verdict::kCull && first.at(d.point) + 2 >= k;
    }
  }
  EXPECT_GT(decided, 200u);
  EXPECT_GT(culled, 50u);
  EXPECT_GT(young_culled_by_paper, 100u);
}

// Where `applies(F)`, over a sequence of windows, the use decides as the
// same settings with its share at every budget; elsewhere, as without it.
void expect_share_where(Use use, std::initializer_list<double> fractions, bool (*applies)(double)) {
  std::uint32_t differ_in = 0, differ_out = 0;  // each side of the bound: both must tell the two apart
  for (double f : fractions) {
    Params mono;
    mono.budget = KeepBudget{BudgetKind::kFraction, 0, f};
    apply_use(use, &mono);
    Params always = mono;
    always.budget.track_share_from = 0.0;
    always.budget.track_share_to = 1.0;
    Params never = mono;
    never.budget.track_share = 0.0;
    Sparsifier used(kCaps, mono), with(kCaps, always), without(kCaps, never);
    Window window(kCaps);
    for (std::uint64_t seed = 1; seed <= 60 && !::testing::Test::HasFailure(); ++seed) {
      test::RandomCase c = test::random_case(seed);
      ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
      ASSERT_EQ(used.run(window), Status::kOk);
      ASSERT_EQ(with.run(window), Status::kOk);
      ASSERT_EQ(without.run(window), Status::kOk);
      const Sparsifier& expected = applies(f) ? with : without;
      ASSERT_EQ(used.decision_count(), expected.decision_count());
      for (std::uint32_t i = 0; i < used.decision_count(); ++i) {
        ASSERT_EQ(used.decisions()[i].verdict, expected.decisions()[i].verdict) << "F " << f << " seed " << seed;
        (applies(f) ? differ_in : differ_out) += with.decisions()[i].verdict != without.decisions()[i].verdict;
      }
    }
  }
  EXPECT_GT(differ_in, 50u);  // the share changes decisions
  EXPECT_GT(differ_out, 50u);
}

TEST(Use, MonocularTakesHalfByTrackLengthFromAKeptFractionOf03) {
  expect_share_where(Use::kMonocular, {0.1, 0.2, 0.29, 0.3, 0.4, 0.6}, [](double f) { return f >= 0.3; });
}

TEST(Use, MonocularDeferredTakesHalfByTrackLengthToAKeptFractionOf015) {
  expect_share_where(Use::kMonocularDeferred, {0.05, 0.1, 0.15, 0.16, 0.2, 0.4}, [](double f) { return f <= 0.15; });
}

// Offline: a share of a count, so it needs one; with one it keeps exactly
// the count the paper's order keeps, all of it by track length.
TEST(Use, OfflineNeedsACountAndKeepsItsSize) {
  Params none;
  apply_use(Use::kOffline, &none);
  EXPECT_EQ(Sparsifier::validate(none), Status::kInvalidArgument);
  Params offline;
  offline.budget = KeepBudget{BudgetKind::kPoints, 12, 0.0, 0.0};
  apply_use(Use::kOffline, &offline);
  ASSERT_EQ(Sparsifier::validate(offline), Status::kOk);
  Params order = offline;
  order.budget.track_share = 0.0;
  Sparsifier shared(kCaps, offline);
  Sparsifier ordered(kCaps, order);
  Window window(kCaps);
  std::uint32_t differ = 0;
  for (std::uint64_t seed = 1; seed <= 100 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(seed, 12, 60);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    ASSERT_EQ(shared.run(window), Status::kOk) << "seed " << seed;
    ASSERT_EQ(ordered.run(window), Status::kOk) << "seed " << seed;
    EXPECT_EQ(shared.summary().kept, ordered.summary().kept) << "seed " << seed;
    for (std::uint32_t i = 0; i < shared.decision_count(); ++i) {
      differ += shared.decisions()[i].verdict != ordered.decisions()[i].verdict;
    }
  }
  EXPECT_GT(differ, 50u);
}

}  // namespace
}  // namespace keepless::core
