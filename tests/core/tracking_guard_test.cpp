// Tracking-safe culling (core::Params::maturity_keyframes, core::Keyframe::
// tracked) against the independent reference (tests/support/
// reference_policies.hpp) on seeded tie-heavy windows with every scope,
// floor and cost model; run() and update() over sliding windows; and the
// rule's meaning on hand-made windows.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <tuple>
#include <vector>

#include "case_count.hpp"
#include "decision_checks.hpp"
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"
#include "reference_policies.hpp"
#include "reference_sparsifier.hpp"

namespace keepless::core {
namespace {

const Capacities kCaps{16, 2048, 8192, 32768, 4096};

::testing::AssertionResult agrees(const Sparsifier& s, const test::RefResult& ref) {
  std::uint32_t verdicts[3];
  if (auto match = test::decisions_match(s, ref, verdicts); !match) return match;
  const Summary& sum = s.summary();
  if (sum.kept != verdicts[0] || sum.culled != verdicts[1] || sum.skipped != verdicts[2] ||
      sum.max_flow != ref.max_flow || sum.total_cost != ref.total_cost ||
      sum.guarded != ref.guarded || sum.tracked != ref.tracked || sum.out_of_scope != ref.out_of_scope ||
      sum.floor_keyframes != ref.floor_keyframes || sum.floor_promoted != ref.floor_promoted ||
      sum.floor_short != ref.floor_short) {
    return ::testing::AssertionFailure()
           << "summary: guarded " << sum.guarded << "/" << ref.guarded << " tracked " << sum.tracked
           << "/" << ref.tracked << " out of scope " << sum.out_of_scope << "/" << ref.out_of_scope
           << " promoted " << sum.floor_promoted << "/" << ref.floor_promoted;
  }
  return ::testing::AssertionSuccess();
}

// test::same_decisions, and the guard's counts.
::testing::AssertionResult same(const Sparsifier& a, const Sparsifier& b) {
  if (::testing::AssertionResult r = test::same_decisions(a, b); !r) return r;
  if (a.summary().guarded != b.summary().guarded || a.summary().tracked != b.summary().tracked) {
    return ::testing::AssertionFailure() << "guard counts differ";
  }
  return ::testing::AssertionSuccess();
}

// The guarantees, read from the window: no point first seen in the newest A
// keyframes and no point the newest keyframe flags tracked is culled.
::testing::AssertionResult protected_points_stay(const Window& w, const Sparsifier& s) {
  const std::uint32_t k = w.keyframe_count();
  const std::uint32_t a = s.params().maturity_keyframes;
  std::map<PointId, std::uint32_t> first;
  for (std::uint32_t slot = k; slot-- > 0;) {
    for (std::uint32_t i = 0; i < w.observation_count(slot); ++i) first[w.observations(slot)[i].point] = slot;
  }
  std::map<PointId, bool> tracked;
  if (k > 0 && w.keyframe(k - 1).tracked != nullptr) {
    for (std::uint32_t i = 0; i < w.observation_count(k - 1); ++i) {
      if (w.keyframe(k - 1).tracked[i] != 0) tracked[w.observations(k - 1)[i].point] = true;
    }
  }
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    const PointDecision& d = s.decisions()[i];
    if (d.verdict != Verdict::kCull) continue;
    if (first[d.point] + a >= k) return ::testing::AssertionFailure() << "young point " << d.point << " culled";
    if (tracked.count(d.point) != 0) return ::testing::AssertionFailure() << "tracked point " << d.point << " culled";
  }
  return ::testing::AssertionSuccess();
}

TEST(TrackingGuard, RandomWindowsMatchReference) {
  std::map<std::tuple<std::int64_t, double, std::int32_t, std::int32_t, int, std::uint32_t, int,
                      std::int32_t, std::uint32_t, int>,
           std::unique_ptr<Sparsifier>>
      cache;
  Window window(kCaps);
  std::uint32_t guarded = 0, tracked = 0, culled = 0, promoted = 0, scoped = 0, newest_guarded = 0;
  for (std::uint64_t seed = 1; seed <= test::cases(300) && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(seed);
    test::random_policies(c, seed);
    test::random_guard(c, seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    const test::RefResult ref = test::reference_decide(c.frames, c.params);
    for (Start start : {Start::kClosedForm, Start::kZeroFlow}) {
      const auto key = std::make_tuple(c.params.pair_capacity, c.params.theta, c.params.box_width,
                                       c.params.box_height, static_cast<int>(c.params.scope),
                                       c.params.coverage_floor, static_cast<int>(c.params.cost_model),
                                       c.params.image_width, c.params.maturity_keyframes,
                                       static_cast<int>(start));
      auto& slot = cache[key];
      if (!slot) slot = std::make_unique<Sparsifier>(kCaps, c.params, SolveMode::kFromScratch, start);
      Sparsifier& s = *slot;
      ASSERT_EQ(s.run(window), Status::kOk) << "seed " << seed;
      ASSERT_TRUE(agrees(s, ref)) << "seed " << seed << " start " << static_cast<int>(start)
                                  << " A " << c.params.maturity_keyframes << " scope "
                                  << to_string(c.params.scope) << " floor " << c.params.coverage_floor;
      ASSERT_TRUE(protected_points_stay(window, s)) << "seed " << seed;
    }
    guarded += ref.guarded;
    tracked += ref.tracked;
    promoted += ref.floor_promoted;
    scoped += ref.out_of_scope;
    newest_guarded += c.params.scope == Scope::kNewest ? ref.guarded : 0;
    for (const auto& p : ref.points) culled += p.verdict == Verdict::kCull;
  }
  // The cases the check is for.
  EXPECT_GT(guarded, test::cases(500));
  EXPECT_GT(tracked, test::cases(100));
  EXPECT_GT(culled, test::cases(250));
  EXPECT_GT(promoted, test::cases(50));
  EXPECT_GT(scoped, test::cases(100));
  EXPECT_GT(newest_guarded, test::cases(100));
}

// update() on the incremental network (both starts) decides what run() does
// on a sliding window, and both what the reference does.
TEST(TrackingGuard, UpdateMatchesRunAndReference) {
  std::uint32_t windows = 0, guarded = 0, tracked = 0;
  for (std::uint64_t seed = 1; seed <= 50 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(9100 + seed, 16, 200);
    test::random_policies(c, 9100 + seed);
    test::random_guard(c, 9100 + seed);
    if (c.params.maturity_keyframes == 0) c.params.maturity_keyframes = 1 + seed % 3;
    if (seed % 4 == 0) c.params.coverage_floor = 20;
    const std::uint32_t size = 3 + static_cast<std::uint32_t>(seed % 6);
    const auto check = [&](const Window& window, const Sparsifier& run, const Sparsifier& closed,
                           const Sparsifier& zero, const test::RefKeyframe& f) {
      ASSERT_TRUE(same(run, closed)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(same(run, zero)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(agrees(run, test::reference_decide(test::ref_frames_of(window), c.params)))
          << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(protected_points_stay(window, run)) << "seed " << seed;
      ++windows;
      guarded += run.summary().guarded;
      tracked += run.summary().tracked;
    };
    test::slide_run_and_update(kCaps, c, size, seed % 3 == 0, check);
  }
  EXPECT_GT(windows, 400u);
  EXPECT_GT(guarded, 1000u);
  EXPECT_GT(tracked, 100u);
}

// Four keyframes; point 1 in slots 0-1, 2 in 1-2, 3 in 2-3, 4 in 0-3. With
// M = 1 on each pair the cheapest point per pair takes the unit; the rest is
// culled unless protected.
struct Hand {
  std::vector<test::RefKeyframe> frames;
  Hand() {
    frames.resize(4);
    for (std::uint64_t f = 0; f < 4; ++f) {
      frames[f].id = 10 + f;
      frames[f].centre[0] = static_cast<double>(f);
    }
    const auto see = [&](std::uint64_t point, std::size_t from, std::size_t to) {
      for (std::size_t f = from; f <= to; ++f) {
        frames[f].observations.push_back({point, 100.0 * static_cast<double>(point), 50.0 * static_cast<double>(f)});
      }
    };
    see(1, 0, 1);
    see(2, 1, 2);
    see(3, 2, 3);
    see(4, 0, 3);
    see(5, 0, 1);
    see(6, 2, 3);
  }
};

Verdict verdict_of(const Sparsifier& s, PointId id) {
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    if (s.decisions()[i].point == id) return s.decisions()[i].verdict;
  }
  return Verdict::kSkip;
}

TEST(TrackingGuard, GuardSkipsTheNewestAKeyframesPoints) {
  Hand h;
  Window w(kCaps);
  ASSERT_TRUE(test::load(w, h.frames));
  Params p;
  p.pair_capacity = 1;
  Sparsifier off(kCaps, p);
  ASSERT_EQ(off.run(w), Status::kOk);
  p.maturity_keyframes = 2;  // slots 2 and 3 are the newest two
  Sparsifier on(kCaps, p);
  ASSERT_EQ(on.run(w), Status::kOk);
  // First seen in slot 2 (points 3 and 6): skipped; first seen in 0 or 1: decided as without the guard.
  EXPECT_EQ(verdict_of(on, 3), Verdict::kSkip);
  EXPECT_EQ(verdict_of(on, 6), Verdict::kSkip);
  for (PointId id : {1, 2, 4, 5}) EXPECT_EQ(verdict_of(on, id), verdict_of(off, id)) << id;
  EXPECT_EQ(on.summary().guarded, 2u);
  EXPECT_EQ(on.summary().skipped, 2u);
  EXPECT_GT(off.summary().culled, 0u);
  // One more keyframe without new points: points 3 and 6 are now 2 keyframes old, and decided.
  test::RefKeyframe next;
  next.id = 99;
  next.observations.push_back({4, 400, 1});
  ASSERT_EQ(test::add_frame(w, next), Status::kOk);
  ASSERT_EQ(on.run(w), Status::kOk);
  EXPECT_NE(verdict_of(on, 3), Verdict::kSkip);
  EXPECT_NE(verdict_of(on, 6), Verdict::kSkip);
  EXPECT_EQ(on.summary().guarded, 0u);
}

TEST(TrackingGuard, NewestScopeDecidesTheKeyframeThatBecameOld) {
  Hand h;
  Window w(kCaps);
  ASSERT_TRUE(test::load(w, h.frames));
  Params p;
  p.pair_capacity = 1;
  p.scope = Scope::kNewest;
  p.maturity_keyframes = 1;  // decides slot 2's points: 2, 3, 4, 6; point 3 and 6 are first seen in 2
  Sparsifier s(kCaps, p);
  ASSERT_EQ(s.run(w), Status::kOk);
  EXPECT_EQ(verdict_of(s, 1), Verdict::kSkip);  // not seen by slot 2: out of scope
  EXPECT_EQ(verdict_of(s, 5), Verdict::kSkip);
  EXPECT_EQ(s.summary().out_of_scope, 2u);
  EXPECT_EQ(s.summary().guarded, 0u);  // nothing is first seen in slot 3 alone
  EXPECT_NE(verdict_of(s, 3), Verdict::kSkip);
  // The guard as large as the window: nothing is decided.
  p.maturity_keyframes = 4;
  Sparsifier all(kCaps, p);
  ASSERT_EQ(all.run(w), Status::kOk);
  EXPECT_EQ(all.summary().guarded, all.summary().evaluated);
  EXPECT_EQ(all.summary().culled + all.summary().kept, 0u);
}

TEST(TrackingGuard, NewestKeyframesTrackedFlagsProtect) {
  Hand h;
  Window w(kCaps);
  Params p;
  p.pair_capacity = 1;
  ASSERT_TRUE(test::load(w, h.frames));
  Sparsifier s(kCaps, p);
  ASSERT_EQ(s.run(w), Status::kOk);
  std::vector<PointId> culled_in_newest;
  for (const auto& o : h.frames[3].observations) {
    if (verdict_of(s, o.point) == Verdict::kCull) culled_in_newest.push_back(o.point);
  }
  ASSERT_FALSE(culled_in_newest.empty());
  const Verdict only_old = verdict_of(s, 1);  // point 1: slots 0-1
  // Flag every newest observation: none of them is culled, each counted once.
  h.frames[3].tracked.assign(h.frames[3].observations.size(), 1);
  // Flags on an older keyframe are history: ignored.
  h.frames[0].tracked.assign(h.frames[0].observations.size(), 1);
  ASSERT_TRUE(test::load(w, h.frames));
  ASSERT_EQ(s.run(w), Status::kOk);
  for (const auto& o : h.frames[3].observations) EXPECT_EQ(verdict_of(s, o.point), Verdict::kSkip);
  EXPECT_EQ(s.summary().tracked, h.frames[3].observations.size());
  EXPECT_EQ(verdict_of(s, 1), only_old);
  // The window's copy survives the removal of an older keyframe (the pool is compacted).
  ASSERT_EQ(w.remove_keyframe(10), Status::kOk);
  ASSERT_NE(w.keyframe(w.keyframe_count() - 1).tracked, nullptr);
  for (std::uint32_t i = 0; i < w.observation_count(w.keyframe_count() - 1); ++i) {
    EXPECT_EQ(w.keyframe(w.keyframe_count() - 1).tracked[i], 1);
  }
  EXPECT_EQ(w.keyframe(0).tracked, nullptr);
}

}  // namespace
}  // namespace keepless::core
