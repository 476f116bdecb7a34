// CostModel::kTrack: each quality's level at its edges, the order it gives a
// pair's points, the fallback without point quality, the window's copy of
// the arrays, and the decisions against the independent reference in
// tests/support (SSP on the naive network) on seeded random windows, both
// starts, run() and update() over sliding windows, and keep budgets.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "case_count.hpp"
#include "decision_checks.hpp"
#include "keepless/core/costs.hpp"
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"
#include "reference_policies.hpp"
#include "reference_sparsifier.hpp"

namespace keepless::core {
namespace {

const Capacities kCaps{16, 2048, 8192, 32768, 4096};

std::uint32_t level(const PointQuality& q, std::uint8_t terms) {
  Keyframe kf;
  kf.quality = &q;
  std::uint32_t out = 99;
  track_levels(kf, 1, terms, &out);
  return out;
}

// A random window, policies and point qualities (the track cost) from one seed.
test::RandomCase track_case(std::uint64_t seed, std::uint32_t max_keyframes, std::uint32_t max_points) {
  test::RandomCase c = test::random_case(seed, max_keyframes, max_points);
  test::random_policies(c, seed);
  test::random_quality(c, seed);
  return c;
}

PointQuality with_length(std::uint32_t t) {
  PointQuality q;
  q.track_length = t;
  return q;
}

TEST(TrackCost, EachQualityAtItsEdges) {
  const std::uint32_t lengths[][2] = {{1, 4}, {2, 3}, {3, 3}, {4, 2}, {7, 2}, {8, 1}, {15, 1}, {16, 0}, {1u << 31, 0}};
  for (const auto& [t, want] : lengths) EXPECT_EQ(level(with_length(t), kTrackLength), want) << "length " << t;
  const std::int32_t ages[][2] = {{0, 4}, {1, 3}, {2, 3}, {3, 2}, {6, 2}, {7, 1}, {14, 1}, {15, 0}, {1 << 30, 0}};
  for (const auto& [a, want] : ages) {
    PointQuality q;
    q.age = a;
    EXPECT_EQ(level(q, kTrackAge), static_cast<std::uint32_t>(want)) << "age " << a;
  }
  const std::pair<float, std::uint32_t> errors[] = {{0.f, 0},  {0.49f, 0}, {0.5f, 1}, {0.99f, 1}, {1.f, 2},
                                                    {1.99f, 2}, {2.f, 3},   {3.99f, 3}, {4.f, 4},   {1e30f, 4}};
  for (const auto& [e, want] : errors) {
    PointQuality q;
    q.reprojection_error = e;
    EXPECT_EQ(level(q, kTrackError), want) << "error " << e;
  }
  const std::pair<float, std::uint32_t> angles[] = {{0.01f, 4}, {0.99f, 4}, {1.f, 3}, {1.99f, 3}, {2.f, 2},
                                                    {3.99f, 2},  {4.f, 1},   {7.99f, 1}, {8.f, 0},   {180.f, 0}};
  for (const auto& [a, want] : angles) {
    PointQuality q;
    q.triangulation_angle = a;
    EXPECT_EQ(level(q, kTrackAngle), want) << "angle " << a;
  }
}

TEST(TrackCost, UnknownIsNeutralAndTermsSum) {
  const PointQuality unknown{};
  EXPECT_EQ(level(unknown, kTrackLength), kNeutralTrackLevel);
  EXPECT_EQ(level(unknown, kTrackAge), kNeutralTrackLevel);
  EXPECT_EQ(level(unknown, kTrackError), kNeutralTrackLevel);
  EXPECT_EQ(level(unknown, kTrackAngle), kNeutralTrackLevel);
  EXPECT_EQ(level(unknown, 15), 4 * kNeutralTrackLevel);
  EXPECT_EQ(level(unknown, 0), 0u);
  PointQuality q;
  q.age = -7;
  q.reprojection_error = -0.5f;
  q.triangulation_angle = -3.f;
  EXPECT_EQ(level(q, kTrackAge | kTrackError | kTrackAngle), 3 * kNeutralTrackLevel);
  q = {20, 0, 3.f, 5.f};  // levels 0, 4, 3, 1
  EXPECT_EQ(level(q, kTrackLength | kTrackAge), 4u);
  EXPECT_EQ(level(q, kTrackError | kTrackAngle), 4u);
  EXPECT_EQ(level(q, 15), 8u);
  // A keyframe without quality: every observation neutral in every term.
  Keyframe none;
  std::uint32_t out[3] = {9, 9, 9};
  track_levels(none, 3, kTrackLength | kTrackError, out);
  for (std::uint32_t v : out) EXPECT_EQ(v, 2 * kNeutralTrackLevel);
}

// Two keyframes sharing three points, M = 1: the pair keeps exactly its
// cheapest point, so the order is the cost's.
struct PairCase {
  Window window{kCaps};
  Params params;
  explicit PairCase(const PointQuality (&q)[3], bool with_quality = true) {
    params.cost_model = CostModel::kTrack;
    params.pair_capacity = 1;
    const Observation obs[3] = {{10, 100, 100, 0}, {11, 300, 200, 0}, {12, 500, 300, 0}};
    for (KeyframeId id : {1, 2}) {
      Keyframe kf;
      kf.id = id;
      kf.centre[0] = static_cast<double>(id);
      if (with_quality) kf.quality = q;
      EXPECT_EQ(window.add_keyframe(kf, obs, 3), Status::kOk);
    }
  }
  PointId kept() {
    Sparsifier s(kCaps, params);
    EXPECT_EQ(s.run(window), Status::kOk);
    PointId id = 0;
    std::uint32_t n = 0;
    for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
      if (s.decisions()[i].verdict != Verdict::kKeep) continue;
      id = s.decisions()[i].point;
      ++n;
    }
    EXPECT_EQ(n, 1u);
    fallback = s.summary().track_fallback;
    return id;
  }
  std::uint32_t fallback = 0;
};

TEST(TrackCost, PairKeepsTheBestKnownPoint) {
  {  // the longest track, whatever its id
    const PointQuality q[3] = {with_length(2), with_length(3), with_length(30)};
    EXPECT_EQ(PairCase(q).kept(), 12u);
  }
  {  // the smallest error
    PointQuality q[3] = {{}, {}, {}};
    q[0].reprojection_error = 3.f;
    q[1].reprojection_error = 0.2f;
    q[2].reprojection_error = 1.5f;
    EXPECT_EQ(PairCase(q).kept(), 11u);
  }
  {  // the widest angle beats an unknown one; with the angle off, a tie to the smaller id
    PointQuality q[3] = {{}, {}, {}};
    q[2].triangulation_angle = 12.f;
    PairCase c(q);
    EXPECT_EQ(c.kept(), 12u);
    c.params.track_terms = kTrackLength | kTrackAge | kTrackError;
    EXPECT_EQ(c.kept(), 10u);
  }
  {  // the terms sum: a long young point against a short old one
    const PointQuality q[3] = {{40, 0, -1.f, 0.f}, {2, 20, -1.f, 0.f}, {1, 0, -1.f, 0.f}};
    PairCase c(q);
    c.params.track_terms = kTrackLength;
    EXPECT_EQ(c.kept(), 10u);
    c.params.track_terms = kTrackAge;
    EXPECT_EQ(c.kept(), 11u);
    c.params.track_terms = kTrackLength | kTrackAge;  // 0 + 4 against 3 + 0
    EXPECT_EQ(c.kept(), 11u);
  }
}

TEST(TrackCost, WithoutQualityTheWindowAloneRanksAndIsCounted) {
  const PointQuality q[3] = {with_length(2), with_length(3), with_length(30)};
  PairCase bare(q, false);
  EXPECT_EQ(bare.kept(), 10u);  // every arc costs the same: the smallest id
  EXPECT_EQ(bare.fallback, 2u);
  PairCase full(q);
  EXPECT_EQ(full.kept(), 12u);
  EXPECT_EQ(full.fallback, 0u);
  bare.params.cost_model = CostModel::kPaper;  // counted only for kTrack
  bare.kept();
  EXPECT_EQ(bare.fallback, 0u);
}

TEST(TrackCost, WindowCopiesQualityAndRefusesNonFinite) {
  Window w(kCaps);
  const Observation obs[2] = {{1, 10, 10, 0}, {2, 20, 20, 0}};
  PointQuality q[2] = {{5, 1, 0.5f, 3.f}, {9, 4, 2.f, 10.f}};
  Keyframe kf;
  kf.quality = q;
  for (KeyframeId id : {1, 2, 3}) {
    kf.id = id;
    q[0].track_length = static_cast<std::uint32_t>(10 * id);
    ASSERT_EQ(w.add_keyframe(kf, obs, 2), Status::kOk);
  }
  q[0].track_length = 0;  // the caller's array may change: the window holds its copy
  ASSERT_NE(w.keyframe(0).quality, q);
  EXPECT_EQ(w.keyframe(0).quality[0].track_length, 10u);
  ASSERT_EQ(w.remove_keyframe(1), Status::kOk);
  EXPECT_EQ(w.keyframe(0).quality[0].track_length, 20u);
  EXPECT_EQ(w.keyframe(1).quality[0].track_length, 30u);
  EXPECT_EQ(w.keyframe(1).quality[1].triangulation_angle, 10.f);
  kf.id = 4;
  kf.quality = nullptr;
  ASSERT_EQ(w.add_keyframe(kf, obs, 2), Status::kOk);
  EXPECT_EQ(w.keyframe(2).quality, nullptr);
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    kf.id = 5;
    kf.quality = q;
    q[1].reprojection_error = bad;
    EXPECT_EQ(w.add_keyframe(kf, obs, 2), Status::kInvalidArgument);
    q[1].reprojection_error = 1.f;
    q[1].triangulation_angle = bad;
    EXPECT_EQ(w.add_keyframe(kf, obs, 2), Status::kInvalidArgument);
    q[1].triangulation_angle = 1.f;
  }
  EXPECT_EQ(w.keyframe_count(), 3u);
  // A window that does not hold quality takes the keyframe without it.
  Capacities caps = kCaps;
  caps.hold_quality = false;
  Window bare(caps);
  q[1].reprojection_error = 1.f;
  kf.quality = q;
  ASSERT_EQ(bare.add_keyframe(kf, obs, 2), Status::kOk);
  EXPECT_EQ(bare.keyframe(0).quality, nullptr);
  EXPECT_LT(bare.memory_bytes(), w.memory_bytes());
}

TEST(TrackCost, TermNames) {
  std::uint8_t terms = 0;
  EXPECT_TRUE(parse_track_terms("length", &terms));
  EXPECT_EQ(terms, kTrackLength);
  EXPECT_TRUE(parse_track_terms("angle,error,age,length", &terms));
  EXPECT_EQ(terms, 15);
  EXPECT_TRUE(parse_track_terms("length,error", &terms));
  EXPECT_EQ(terms, kTrackLength | kTrackError);
  for (const char* bad : {"", "length,", ",age", "length,length", "len", "Length", "age error"}) {
    EXPECT_FALSE(parse_track_terms(bad, &terms)) << bad;
    EXPECT_EQ(terms, kTrackLength | kTrackError);
  }
  CostModel model = CostModel::kPaper;
  EXPECT_TRUE(parse_cost_model("track", &model));
  EXPECT_EQ(model, CostModel::kTrack);
  EXPECT_STREQ(to_string(CostModel::kTrack), "track");
  EXPECT_EQ(Sparsifier::validate(Params{}), Status::kOk);
}

::testing::AssertionResult agrees(const Sparsifier& s, const test::RefResult& ref) {
  std::uint32_t verdicts[3];
  if (auto match = test::decisions_match(s, ref, verdicts); !match) return match;
  const Summary& sum = s.summary();
  if (sum.max_flow != ref.max_flow || sum.total_cost != ref.total_cost) {
    return ::testing::AssertionFailure() << "max flow " << sum.max_flow << " vs " << ref.max_flow << ", cost "
                                         << sum.total_cost << " vs " << ref.total_cost;
  }
  if (sum.kept != verdicts[0] || sum.culled != verdicts[1] || sum.skipped != verdicts[2] ||
      sum.floor_promoted != ref.floor_promoted || sum.guarded != ref.guarded || sum.tracked != ref.tracked) {
    return ::testing::AssertionFailure() << "summary differs";
  }
  return ::testing::AssertionSuccess();
}

std::uint32_t without_quality(const std::vector<test::RefKeyframe>& frames) {
  std::uint32_t n = 0;
  for (const auto& f : frames) n += f.quality.empty();
  return n;
}

TEST(TrackCost, RandomWindowsMatchReference) {
  Window window(kCaps);
  std::uint32_t culled = 0, fallback = 0, tracked = 0;
  for (std::uint64_t seed = 1; seed <= test::cases(300) && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(seed);
    test::random_policies(c, seed);
    if (seed % 3 == 0) test::random_guard(c, seed);
    test::random_quality(c, seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    const test::RefResult ref = test::reference_decide(c.frames, c.params);
    for (Start start : {Start::kClosedForm, Start::kZeroFlow}) {
      Sparsifier s(kCaps, c.params, SolveMode::kFromScratch, start);
      ASSERT_EQ(s.run(window), Status::kOk) << "seed " << seed;
      ASSERT_TRUE(agrees(s, ref)) << "seed " << seed << " start " << static_cast<int>(start) << " terms "
                                  << int{c.params.track_terms};
      ASSERT_EQ(s.summary().track_fallback, without_quality(c.frames)) << "seed " << seed;
    }
    for (const auto& p : ref.points) culled += p.verdict == Verdict::kCull;
    fallback += without_quality(c.frames);
    tracked += ref.tracked;
  }
  // The cases the check is for.
  EXPECT_GT(culled, test::cases(1000));
  EXPECT_GT(fallback, test::cases(100));
  EXPECT_GT(tracked, test::cases(20));
}

TEST(TrackCost, UpdateMatchesRunAndReference) {
  std::uint32_t windows = 0;
  for (std::uint64_t seed = 1; seed <= 40 && !HasFailure(); ++seed) {
    test::RandomCase c = track_case(7300 + seed, 16, 200);
    const std::uint32_t size = 3 + static_cast<std::uint32_t>(seed % 6);
    Window window(kCaps);
    Sparsifier run(kCaps, c.params);
    Sparsifier closed(kCaps, c.params, SolveMode::kIncremental, Start::kClosedForm);
    Sparsifier zero(kCaps, c.params, SolveMode::kIncremental, Start::kZeroFlow);
    for (const auto& f : c.frames) {
      if (window.keyframe_count() == size) {
        ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
      }
      ASSERT_EQ(test::add_frame(window, f), Status::kOk);
      ASSERT_EQ(run.run(window), Status::kOk);
      ASSERT_EQ(closed.update(window), Status::kOk);
      ASSERT_EQ(zero.update(window), Status::kOk);
      const test::RefResult ref = test::reference_decide(test::ref_frames_of(window), c.params);
      ASSERT_TRUE(agrees(run, ref)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(agrees(closed, ref)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(agrees(zero, ref)) << "seed " << seed << " keyframe " << f.id;
      ++windows;
    }
  }
  EXPECT_GT(windows, 300u);
}

// A VO that rebuilds its window per keyframe re-sends each keyframe with the
// same observations and its points' quality as the map now knows it (older,
// longer tracks): the incremental network must take the new quality, not keep
// the levels it first saw (it compared only the observations once).
TEST(TrackCost, UpdateTakesTheQualityOfAKeyframeSentAgain) {
  std::uint32_t windows = 0, requalified = 0;
  for (std::uint64_t seed = 1; seed <= 60 && !HasFailure(); ++seed) {
    test::RandomCase c = track_case(8100 + seed, 12, 200);
    c.params.track_terms = kTrackLength | kTrackAge;  // the terms that change as a map ages
    const std::size_t size = 3 + seed % 4;
    Sparsifier closed(kCaps, c.params, SolveMode::kIncremental, Start::kClosedForm);
    Sparsifier zero(kCaps, c.params, SolveMode::kIncremental, Start::kZeroFlow);
    for (std::size_t last = 0; last < c.frames.size(); ++last) {
      const std::size_t first = last + 1 > size ? last + 1 - size : 0;
      std::vector<test::RefKeyframe> frames;
      for (std::size_t k = first; k <= last; ++k) {
        test::RefKeyframe f = c.frames[k];
        const auto since = static_cast<std::uint32_t>(last - k);  // keyframes made since this one
        for (PointQuality& q : f.quality) {
          q.track_length += 3 * since;
          if (q.age >= 0) q.age += static_cast<std::int32_t>(since);
        }
        requalified += since > 0 && !f.quality.empty();
        frames.push_back(std::move(f));
      }
      Window window(kCaps);  // a new window: no stamp vouches for an unchanged keyframe
      ASSERT_TRUE(test::load(window, frames)) << "seed " << seed;
      ASSERT_EQ(closed.update(window), Status::kOk);
      ASSERT_EQ(zero.update(window), Status::kOk);
      const test::RefResult ref = test::reference_decide(frames, c.params);
      ASSERT_TRUE(agrees(closed, ref)) << "seed " << seed << " keyframe " << last;
      ASSERT_TRUE(agrees(zero, ref)) << "seed " << seed << " keyframe " << last;
      ++windows;
    }
  }
  EXPECT_GT(windows, 300u);
  EXPECT_GT(requalified, 300u);
}

// A window copied from one that holds quality into one that does not
// (hold_quality off) has the same keyframes without their quality: update()
// of the copy after the original decides as the reference on what the copy
// holds (the stamps, which the copy kept before, vouched for the quality).
TEST(TrackCost, ACopyWithoutQualityIsDecidedOnWhatItHolds) {
  std::uint32_t windows = 0;
  for (std::uint64_t seed = 1; seed <= 40 && !HasFailure(); ++seed) {
    test::RandomCase c = track_case(8400 + seed, 8, 120);
    Capacities without = kCaps;
    without.hold_quality = false;
    Window original(kCaps), copy(without);
    ASSERT_TRUE(test::load(original, c.frames));
    for (std::uint32_t k = 0; k < original.keyframe_count(); ++k) {
      ASSERT_EQ(copy.copy_keyframe(original, k), Status::kOk);
    }
    std::vector<test::RefKeyframe> bare = c.frames;
    for (test::RefKeyframe& f : bare) f.quality.clear();
    Sparsifier s(kCaps, c.params, SolveMode::kIncremental);
    ASSERT_EQ(s.update(original), Status::kOk);
    ASSERT_EQ(s.update(copy), Status::kOk);
    ASSERT_TRUE(agrees(s, test::reference_decide(bare, c.params))) << "seed " << seed;
    ++windows;
  }
  EXPECT_EQ(windows, 40u);
}

// A keep budget with the track cost: the K smallest keep thresholds, which
// the closed form's M sweep confirms (kept_at(M) = the points kept at M).
TEST(TrackCost, BudgetKeepsWhatSomeMKeeps) {
  std::uint32_t checked = 0;
  for (std::uint64_t seed = 1; seed <= 60 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(8800 + seed, 12, 120);
    test::random_quality(c, 8800 + seed);
    c.params.theta = 0.5;
    Window window(kCaps);
    ASSERT_TRUE(test::load(window, c.frames));
    Params budgeted = c.params;
    budgeted.budget = {BudgetKind::kFraction, 0, 0.3};
    Sparsifier b(kCaps, budgeted);
    ASSERT_EQ(b.run(window), Status::kOk) << "seed " << seed;
    const std::int64_t m = b.summary().budget_m;
    if (m < 1) continue;
    // Every point the budget kept is kept at M = budget_m by the solve.
    Params at_m = c.params;
    at_m.pair_capacity = m;
    const test::RefResult ref = test::reference_decide(c.frames, at_m);
    for (std::uint32_t i = 0; i < b.decision_count(); ++i) {
      if (b.decisions()[i].verdict != Verdict::kKeep) continue;
      for (const auto& p : ref.points) {
        if (p.id == b.decisions()[i].point) {
          ASSERT_EQ(p.verdict, Verdict::kKeep) << "seed " << seed;
        }
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 30u);
}

}  // namespace
}  // namespace keepless::core
