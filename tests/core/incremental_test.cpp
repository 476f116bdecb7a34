// The incremental path (Sparsifier::update on an IncrementalNetwork, warm
// re-solve, canonical tie-break) against the from-scratch path (run) over
// long seeded keyframe streams: slides, culled points dropped from every
// keyframe, keyframes removed from the middle, window resets, parameter
// variants with heavy ties, and capacities at their limits. Every window's
// decisions, flows and summary must be identical; budgets that run out must
// keep every evaluated point and the next call must catch up.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <set>
#include <vector>

#include "keepless/core/closed_form.hpp"
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"

namespace keepless::core {
namespace {

struct Frame {
  Keyframe keyframe;
  std::vector<Observation> observations;
};

// A camera moving past clustered keypoints: points are tracked over runs of
// keyframes, keypoints sit on an 8 x 6 pixel lattice (box borders land
// exactly, N repeats), centres come from a small pool (c_b repeats), and a
// share of new points takes ids below existing ones.
class Stream {
 public:
  Stream(std::uint64_t seed, std::uint32_t per_frame) : rng_(seed), per_frame_(per_frame) {
    for (auto& c : centres_) {
      for (double& x : c) x = static_cast<double>(rng_.between(-20, 20));
    }
  }

  Frame next() {
    Frame f;
    f.keyframe.id = 10 + 3 * frame_++;
    const auto& c = centres_[rng_.between(0, 3)];
    std::copy(c, c + 3, f.keyframe.centre);
    if (rng_.chance(20)) f.keyframe.centre[0] += static_cast<double>(frame_) / 4.0;
    std::vector<Track> kept;
    for (Track& t : tracks_) {
      if (t.life-- <= 0 || rng_.chance(8)) continue;
      t.u = std::clamp<std::int64_t>(t.u + rng_.between(-1, 1), 0, 80);
      t.v = std::clamp<std::int64_t>(t.v + rng_.between(-1, 1), 0, 80);
      kept.push_back(t);
    }
    tracks_ = kept;
    const auto fresh = static_cast<std::uint32_t>(rng_.between(per_frame_ / 4, per_frame_ / 2));
    for (std::uint32_t i = 0; i < fresh; ++i) {
      Track t;
      t.id = rng_.chance(10) && next_id_ > 1000 ? next_id_ - static_cast<std::uint64_t>(rng_.between(1, 900))
                                                 : next_id_;
      if (used_.count(t.id) != 0) t.id = next_id_;
      ++next_id_;
      used_.insert(t.id);
      t.u = rng_.between(0, 80);
      t.v = rng_.between(0, 80);
      t.life = rng_.between(0, 8);
      tracks_.push_back(t);
    }
    for (const Track& t : tracks_) {
      Observation o;
      o.point = t.id;
      o.u = 8.0 * static_cast<double>(t.u) + (rng_.chance(10) ? 0.5 : 0.0);
      o.v = 6.0 * static_cast<double>(t.v);
      f.observations.push_back(o);
    }
    // Window order is not id order.
    for (std::size_t i = f.observations.size(); i > 1; --i) {
      std::swap(f.observations[i - 1], f.observations[static_cast<std::size_t>(rng_.between(0, static_cast<std::int64_t>(i) - 1))]);
    }
    return f;
  }

  test::Rng& rng() { return rng_; }

 private:
  struct Track {
    PointId id = 0;
    std::int64_t u = 0, v = 0, life = 0;
  };
  test::Rng rng_;
  std::uint32_t per_frame_;
  std::uint64_t frame_ = 0;
  std::uint64_t next_id_ = 1000;
  std::set<PointId> used_;
  std::vector<Track> tracks_;
  double centres_[4][3];
};

Status add(Window& w, const Frame& f) {
  return w.add_keyframe(f.keyframe, f.observations.data(),
                        static_cast<std::uint32_t>(f.observations.size()));
}

// Rebuilds the window without the given points (as the node does after a
// decision): every keyframe that saw one changes.
void drop_points(Window& w, const std::vector<PointId>& gone) {
  std::vector<Frame> frames;
  for (std::uint32_t s = 0; s < w.keyframe_count(); ++s) {
    Frame f;
    f.keyframe = w.keyframe(s);
    for (std::uint32_t i = 0; i < w.observation_count(s); ++i) {
      const Observation& o = w.observations(s)[i];
      if (!std::binary_search(gone.begin(), gone.end(), o.point)) f.observations.push_back(o);
    }
    frames.push_back(f);
  }
  w.clear();
  for (const Frame& f : frames) ASSERT_EQ(add(w, f), Status::kOk);
}

::testing::AssertionResult same_result(const Sparsifier& inc, const Sparsifier& ref) {
  if (inc.decision_count() != ref.decision_count()) {
    return ::testing::AssertionFailure() << "decision count " << inc.decision_count() << " vs "
                                         << ref.decision_count();
  }
  for (std::uint32_t i = 0; i < ref.decision_count(); ++i) {
    const PointDecision& a = inc.decisions()[i];
    const PointDecision& b = ref.decisions()[i];
    if (a.point != b.point || a.verdict != b.verdict || a.flow != b.flow || a.capacity != b.capacity) {
      return ::testing::AssertionFailure()
             << "point " << b.point << " (incremental " << a.point << "): flow " << a.flow << " vs "
             << b.flow << ", verdict " << to_string(a.verdict) << " vs " << to_string(b.verdict);
    }
  }
  const Summary& x = inc.summary();
  const Summary& y = ref.summary();
  if (x.keyframes != y.keyframes || x.points != y.points || x.evaluated != y.evaluated ||
      x.kept != y.kept || x.culled != y.culled || x.skipped != y.skipped || x.pairs != y.pairs ||
      x.arcs != y.arcs || x.max_flow != y.max_flow || x.total_cost != y.total_cost) {
    return ::testing::AssertionFailure()
           << "summary differs: pairs " << x.pairs << "/" << y.pairs << " arcs " << x.arcs << "/"
           << y.arcs << " flow " << x.max_flow << "/" << y.max_flow << " cost " << x.total_cost
           << "/" << y.total_cost;
  }
  return ::testing::AssertionSuccess();
}

struct StreamSpec {
  Capacities caps;
  Params params;
  std::uint32_t keyframes;  // window size K
  std::uint32_t per_frame;  // mean observations per keyframe
  std::uint32_t steps;
};

// Runs one stream through both paths; returns how many windows matched.
// `warm` is a second incremental sparsifier forced onto the resume path: on
// even steps a budget too small to finish; on odd steps, after the window
// has changed, a call that re-optimises from the flow and potentials left
// behind and restores the tie-break (canonicalize), whose swaps are counted.
std::uint32_t check_stream(std::uint64_t seed, const StreamSpec& spec, std::uint64_t* swaps,
                           std::uint32_t* capacity_errors) {
  Stream stream(seed, spec.per_frame);
  Window window(spec.caps);
  Sparsifier inc(spec.caps, spec.params, SolveMode::kIncremental);  // the closed-form start
  Sparsifier warm(spec.caps, spec.params, SolveMode::kIncremental, Start::kZeroFlow);
  Sparsifier ref(spec.caps, spec.params, SolveMode::kFromScratch, Start::kZeroFlow);
  std::uint32_t matched = 0;
  for (std::uint32_t step = 0; step < spec.steps; ++step) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed << " step " << step);
    test::Rng& rng = stream.rng();
    const auto event = rng.between(0, 99);
    if (event < 3) {
      window.clear();  // a reset
    } else if (event < 8 && window.keyframe_count() > 2) {
      const auto slot = static_cast<std::uint32_t>(rng.between(1, window.keyframe_count() - 2));
      EXPECT_EQ(window.remove_keyframe(window.keyframe(slot).id), Status::kOk);
    }
    while (window.keyframe_count() >= spec.keyframes) {
      EXPECT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
    }
    const Frame f = stream.next();
    if (add(window, f) != Status::kOk) {
      // Over the window's capacities: the keyframe is refused, the window
      // unchanged; decide the window as it is.
      ++*capacity_errors;
    }
    const Status a = inc.update(window);
    const Status b = ref.run(window);
    EXPECT_EQ(a, b);
    if (a != b) return matched;
    // Stop late (most of the flow in place), so the resume after the next
    // slide starts from a nearly optimal state plus the slide's edits.
    solver::Budget late;
    late.work_units = ref.solver().stats().work_units * (60 + step % 36) / 100;
    const Status w = warm.update(window, step % 2 == 0 ? late : solver::Budget{});
    if (w == Status::kBudgetExhausted) {
      EXPECT_EQ(warm.summary().culled, 0u);
    } else {
      EXPECT_EQ(w, b);
      if (step % 2 == 1) *swaps += warm.solver().stats().canonical_swaps;
    }
    if (b != Status::kOk) {
      ++*capacity_errors;
      continue;
    }
    EXPECT_TRUE(same_result(inc, ref));
    EXPECT_TRUE(inc.solver().stats().certified) << "the closed-form start should stand";
    if (w == Status::kOk) {
      EXPECT_TRUE(same_result(warm, ref)) << "resumed warm solve";
    }
    if (::testing::Test::HasFailure()) return matched;
    ++matched;
    // Sometimes the VO deletes what was culled, from every keyframe.
    if (rng.chance(25)) {
      std::vector<PointId> culled;
      for (std::uint32_t i = 0; i < ref.decision_count(); ++i) {
        if (ref.decisions()[i].verdict == Verdict::kCull && rng.chance(50)) {
          culled.push_back(ref.decisions()[i].point);
        }
      }
      drop_points(window, culled);
    }
  }
  return matched;
}

TEST(Incremental, LongStreamsEqualTheFromScratchPath) {
  // M = 8 fills most pairs, so thresholds (and ties at them) matter.
  StreamSpec spec{{12, 600, 1500, 8000}, Params{}, 8, 40, 80};
  spec.params.pair_capacity = 8;
  std::uint64_t swaps = 0;
  std::uint32_t errors = 0, matched = 0;
  for (std::uint64_t seed = 1; seed <= 25 && !HasFailure(); ++seed) {
    matched += check_stream(seed, spec, &swaps, &errors);
  }
  EXPECT_GT(matched, 1500u);
  // The resumed warm solves really landed on other optima and were moved.
  EXPECT_GT(swaps, 0u);
}

TEST(Incremental, TiesEverywhere) {
  // M of 1..3 makes almost every pair full with ties at its threshold;
  // the cost-term ablations make whole pairs tie.
  std::uint64_t swaps = 0;
  std::uint32_t errors = 0, matched = 0;
  for (std::uint64_t seed = 1; seed <= 24 && !HasFailure(); ++seed) {
    StreamSpec spec{{10, 600, 1500, 8000}, Params{}, 6, 30, 50};
    spec.params.pair_capacity = 1 + static_cast<std::int64_t>(seed % 3);
    spec.params.cost_terms = static_cast<std::uint8_t>(seed % 8);
    spec.params.theta = seed % 4 == 0 ? 0.0 : 0.5;
    spec.params.box_width = seed % 5 == 0 ? 0 : 64;
    spec.params.spatial_weight = seed % 3 == 1 ? 1000 : 1;  // c_s outranking c_c
    matched += check_stream(seed * 7, spec, &swaps, &errors);
  }
  EXPECT_GT(matched, 1000u);
  EXPECT_GT(swaps, 0u);
}

TEST(Incremental, CapacityLimitsAreHitAndRecoveredFrom) {
  // Tight capacities: keyframes get refused by the window, and the pair-arc
  // limit is crossed by windows the window itself accepts. Both paths must
  // report the same status and recover on the next window.
  std::uint64_t swaps = 0;
  std::uint32_t errors = 0, matched = 0;
  for (std::uint64_t seed = 1; seed <= 20 && !HasFailure(); ++seed) {
    StreamSpec spec{{8, 140, 260, 260 + 40 * static_cast<std::uint32_t>(seed % 5)}, Params{}, 8, 40, 60};
    matched += check_stream(seed * 13, spec, &swaps, &errors);
  }
  EXPECT_GT(errors, 20u) << "the limits were never reached";
  EXPECT_GT(matched, 200u);
}

TEST(Incremental, UnfinishedUpdatesKeepEverythingAndCatchUp) {
  const StreamSpec spec{{10, 600, 1500, 8000}, Params{}, 8, 40, 0};
  std::uint32_t stopped = 0;
  for (std::uint64_t seed = 1; seed <= 10 && !HasFailure(); ++seed) {
    Stream stream(seed, spec.per_frame);
    Window window(spec.caps);
    Sparsifier inc(spec.caps, spec.params, SolveMode::kIncremental);
    Sparsifier ref(spec.caps, spec.params);
    for (std::uint32_t step = 0; step < 40; ++step) {
      if (window.keyframe_count() >= spec.keyframes) {
        ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
      }
      ASSERT_EQ(add(window, stream.next()), Status::kOk);
      ASSERT_EQ(ref.run(window), Status::kOk);
      // A budget far below what the slide needs, now and then.
      solver::Budget budget;
      if (step % 3 == 1) budget.work_units = static_cast<std::uint64_t>(step % 7);
      const Status s = inc.update(window, budget);
      if (s == Status::kBudgetExhausted) {
        ++stopped;
        ASSERT_EQ(inc.decision_count(), ref.decision_count());
        for (std::uint32_t i = 0; i < ref.decision_count(); ++i) {
          const PointDecision& d = inc.decisions()[i];
          ASSERT_EQ(d.point, ref.decisions()[i].point);
          ASSERT_NE(d.verdict, Verdict::kCull) << "culled on an unfinished solve";
          if (ref.decisions()[i].verdict == Verdict::kSkip) {
            ASSERT_EQ(d.verdict, Verdict::kSkip);
          }
        }
        ASSERT_EQ(inc.summary().culled, 0u);
        // The same window again, with no limit: caught up exactly.
        ASSERT_EQ(inc.update(window), Status::kOk);
      } else {
        ASSERT_EQ(s, Status::kOk);
      }
      ASSERT_TRUE(same_result(inc, ref)) << "seed " << seed << " step " << step;
    }
  }
  EXPECT_GT(stopped, 20u);
}

TEST(Incremental, RunInBetweenRestartsTheIncrementalPath) {
  const Capacities caps{10, 600, 1500, 8000};
  Stream stream(99, 40);
  Window window(caps);
  Sparsifier s(caps, Params{}, SolveMode::kIncremental);
  Sparsifier ref(caps, Params{});
  for (std::uint32_t step = 0; step < 30; ++step) {
    if (window.keyframe_count() >= 6) {
      ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
    }
    ASSERT_EQ(add(window, stream.next()), Status::kOk);
    ASSERT_EQ(ref.run(window), Status::kOk);
    if (step % 4 == 2) {
      ASSERT_EQ(s.run(window), Status::kOk);
    } else {
      ASSERT_EQ(s.update(window), Status::kOk);
      ASSERT_NE(s.incremental_network(), nullptr);
      EXPECT_EQ(s.incremental_network()->changes().rebuilt, step == 0 || step % 4 == 3);
    }
    ASSERT_TRUE(same_result(s, ref)) << "step " << step;
  }
}

// An incremental Sparsifier does not hold run()'s network until a run()
// needs it: updates never make it, the first run() does, and decides as a
// from-scratch Sparsifier does.
TEST(Incremental, RunsNetworkIsMadeOnlyByTheFirstRun) {
  const Capacities caps{10, 600, 1500, 8000};
  Stream stream(7, 40);
  Window window(caps);
  Sparsifier s(caps, Params{}, SolveMode::kIncremental);
  Sparsifier ref(caps, Params{});
  const std::size_t held = s.memory_bytes();
  EXPECT_EQ(s.network().point_count(), 0u);
  for (std::uint32_t step = 0; step < 8; ++step) {
    if (window.keyframe_count() >= 6) {
      ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
    }
    ASSERT_EQ(add(window, stream.next()), Status::kOk);
    ASSERT_EQ(s.update(window), Status::kOk);
    EXPECT_EQ(s.memory_bytes(), held) << "step " << step;
  }
  ASSERT_EQ(s.run(window), Status::kOk);
  ASSERT_EQ(ref.run(window), Status::kOk);
  EXPECT_TRUE(same_result(s, ref));
  EXPECT_EQ(s.memory_bytes(), held + s.network().memory_bytes());
  EXPECT_EQ(s.network().point_count(), ref.network().point_count());
  ASSERT_EQ(s.update(window), Status::kOk);  // and updates carry on beside it
  EXPECT_TRUE(same_result(s, ref));
}

TEST(Incremental, ASlideEditsOnlyWhatChanged) {
  const Capacities caps{10, 600, 1500, 8000};
  Stream stream(5, 40);
  Window window(caps);
  Sparsifier s(caps, Params{}, SolveMode::kIncremental);
  std::vector<Frame> frames;
  for (int i = 0; i < 12; ++i) frames.push_back(stream.next());
  for (int i = 0; i < 6; ++i) ASSERT_EQ(add(window, frames[i]), Status::kOk);
  ASSERT_EQ(s.update(window), Status::kOk);
  const IncrementalNetwork& net = *s.incremental_network();
  EXPECT_TRUE(net.changes().rebuilt);
  EXPECT_EQ(net.changes().frames_added, 6u);
  // The same window again: no network edit at all.
  ASSERT_EQ(s.update(window), Status::kOk);
  EXPECT_FALSE(net.changes().rebuilt);
  EXPECT_EQ(net.changes().frames_added, 0u);
  EXPECT_EQ(net.changes().arcs_added + net.changes().arcs_retired + net.changes().arcs_recosted, 0u);
  // One slide: one keyframe in, one out; only points they touch change.
  ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
  ASSERT_EQ(add(window, frames[6]), Status::kOk);
  ASSERT_EQ(s.update(window), Status::kOk);
  EXPECT_FALSE(net.changes().rebuilt);
  EXPECT_EQ(net.changes().frames_added, 1u);
  EXPECT_EQ(net.changes().frames_removed, 1u);
  EXPECT_LE(net.changes().points_changed + net.changes().points_added,
            frames[0].observations.size() + frames[6].observations.size());
  EXPECT_GT(s.memory_bytes(), Sparsifier(caps, Params{}).memory_bytes());
}

// A clock that moves only when told to.
class ManualClock final : public solver::Clock {
 public:
  std::uint64_t now_ns() const override { return now; }
  std::uint64_t now = 1000;
};

// A clock that moves `step` on every read, so a network update or a
// decide stage (one read before, one after) lasts exactly `step`.
class SteppingClock final : public solver::Clock {
 public:
  explicit SteppingClock(std::uint64_t step) : step_(step) {}
  std::uint64_t now_ns() const override { return now_ += step_; }
  void set_step(std::uint64_t step) { step_ = step; }

 private:
  std::uint64_t step_;
  mutable std::uint64_t now_ = 0;
};

// The deadline tests' window: at most 6 keyframes slid along a stream, with
// run()'s decisions on each slide as the reference.
struct SlidingWindow {
  SlidingWindow(std::uint64_t seed, std::uint32_t per_frame) : stream(seed, per_frame) {}
  void slide() {
    if (window.keyframe_count() >= 6) {
      ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
    }
    ASSERT_EQ(add(window, stream.next()), Status::kOk);
    ASSERT_EQ(ref.run(window), Status::kOk);
  }
  const Capacities caps{10, 600, 1500, 8000};
  Stream stream;
  Window window{caps};
  Sparsifier ref{caps, Params{}};
};

// A deadline `left` after a read of `clock` (a SteppingClock moves on that
// read: deadline = next read + left - step).
solver::Budget budget_after(const solver::Clock& clock, std::uint64_t left) {
  solver::Budget b;
  b.clock = &clock;
  b.deadline_ns = clock.now_ns() + left;
  return b;
}

TEST(Incremental, NoTimeForTheNetworkDefersAndKeepsEverything) {
  SlidingWindow w(17, 40);
  const Window& window = w.window;
  Sparsifier s(w.caps, Params{}, SolveMode::kIncremental);
  ManualClock clock;
  solver::Budget past;
  past.clock = &clock;
  past.deadline_ns = clock.now;  // already due
  for (std::uint32_t step = 0; step < 24; ++step) {
    SCOPED_TRACE(::testing::Message() << "step " << step);
    ASSERT_NO_FATAL_FAILURE(w.slide());
    // Runs of deferred keyframes between full updates: the update after a
    // run catches up with several slides at once, exactly.
    if (step % 5 != 0) {
      ASSERT_EQ(s.update(window, past), Status::kBudgetExhausted);
      EXPECT_TRUE(s.deferred());
      EXPECT_EQ(s.decision_count(), 0u);
      EXPECT_EQ(s.summary().points, window.distinct_points());
      EXPECT_EQ(s.summary().kept, window.distinct_points());
      EXPECT_EQ(s.summary().culled, 0u);
    } else {
      ASSERT_EQ(s.update(window), Status::kOk);
      EXPECT_FALSE(s.deferred());
      ASSERT_TRUE(same_result(s, w.ref));
    }
  }
}

TEST(Incremental, DefersOnlyWhenLessTimeIsLeftThanTheNetworkAndDecidingTake) {
  SlidingWindow w(23, 40);
  const Window& window = w.window;
  Sparsifier s(w.caps, Params{}, SolveMode::kIncremental);
  SteppingClock clock(100);  // network updates and deciding take 100 ns each
  const auto budget = [&clock](std::uint64_t left) { return budget_after(clock, left); };
  // No estimate yet: a deadline in the future is tried however close (the
  // network is updated; the solver then finds the deadline passed).
  ASSERT_NO_FATAL_FAILURE(w.slide());
  EXPECT_EQ(s.update(window, budget(150)), Status::kBudgetExhausted);
  EXPECT_FALSE(s.deferred());
  EXPECT_EQ(s.decision_count(), window.distinct_points());
  ASSERT_NO_FATAL_FAILURE(w.slide());
  EXPECT_EQ(s.update(window, budget(150)), Status::kBudgetExhausted);
  EXPECT_FALSE(s.deferred());
  // Both stages measured twice at 100 ns: 50 ns left is too little (200 ns
  // expected), 10 ms enough.
  ASSERT_NO_FATAL_FAILURE(w.slide());
  EXPECT_EQ(s.update(window, budget(150)), Status::kBudgetExhausted);
  EXPECT_TRUE(s.deferred());
  ASSERT_NO_FATAL_FAILURE(w.slide());
  ASSERT_EQ(s.update(window, budget(10000000)), Status::kOk);
  EXPECT_FALSE(s.deferred());
  EXPECT_TRUE(same_result(s, w.ref));
}

// Two slides preempted (every stage 3 ms) must not make the path defer every
// later keyframe once the machine is fast again: a deferral measures
// nothing, so the slow estimate has to expire on its own.
TEST(Incremental, ASlowSpellDoesNotDeferForever) {
  SlidingWindow w(29, 60);
  const Window& window = w.window;
  Sparsifier s(w.caps, Params{}, SolveMode::kIncremental);
  SteppingClock clock(3'000'000);
  const auto budget = [&clock](std::uint64_t left) { return budget_after(clock, left); };
  for (int i = 0; i < 2; ++i) {  // the slow spell: measured, answered in an ample budget
    ASSERT_NO_FATAL_FAILURE(w.slide());
    ASSERT_EQ(s.update(window, budget(1'000'000'000'000)), Status::kOk);
  }
  clock.set_step(100);  // fast again; 10 ms is far more than a slide now needs
  int deferred = 0, first_ok = -1;
  for (int i = 0; i < 40; ++i) {
    SCOPED_TRACE(::testing::Message() << "slide " << i);
    ASSERT_NO_FATAL_FAILURE(w.slide());
    const Status st = s.update(window, budget(10'000'000));
    if (first_ok < 0 && st == Status::kOk) first_ok = i;
    if (first_ok < 0) {
      EXPECT_TRUE(s.deferred());
      ++deferred;
      continue;
    }
    ASSERT_EQ(st, Status::kOk);  // once measured fast, never deferred again
    EXPECT_FALSE(s.deferred());
    EXPECT_TRUE(same_result(s, w.ref));
  }
  EXPECT_GE(first_ok, 0) << "every keyframe after the slow spell was deferred";
  EXPECT_LT(deferred, 40);
}

// A budget that stays below what a call takes (every stage 100 ns, 150 ns
// given): the decayed estimate brings a retry now and then, never every
// other keyframe (each late retry doubles the deferrals before the next
// decay), and never stops: once the budget is ample the path decides again.
TEST(Incremental, ABudgetAlwaysTooSmallRetriesRarely) {
  SlidingWindow w(31, 40);
  const Window& window = w.window;
  Sparsifier s(w.caps, Params{}, SolveMode::kIncremental);
  SteppingClock clock(100);
  const auto budget = [&clock](std::uint64_t left) { return budget_after(clock, left); };
  int tried = 0;
  for (int i = 0; i < 400; ++i) {
    ASSERT_NO_FATAL_FAILURE(w.slide());
    EXPECT_EQ(s.update(window, budget(150)), Status::kBudgetExhausted);
    if (!s.deferred()) ++tried;
  }
  // Back-off up to 32 deferrals: about 400 / 33 + log2(32) retries, not 200.
  EXPECT_GE(tried, 5);
  EXPECT_LE(tried, 30);
  ASSERT_NO_FATAL_FAILURE(w.slide());
  ASSERT_EQ(s.update(window, budget(10'000'000)), Status::kOk);
  EXPECT_TRUE(same_result(s, w.ref));
}

TEST(Incremental, FromScratchModeFallsBackToRun) {
  const Capacities caps{10, 600, 1500, 8000};
  Stream stream(3, 40);
  Window window(caps);
  for (int i = 0; i < 5; ++i) ASSERT_EQ(add(window, stream.next()), Status::kOk);
  Sparsifier plain(caps, Params{});
  Sparsifier ref(caps, Params{});
  ASSERT_EQ(plain.update(window), Status::kOk);
  ASSERT_EQ(ref.run(window), Status::kOk);
  EXPECT_EQ(plain.incremental_network(), nullptr);
  EXPECT_TRUE(same_result(plain, ref));
}

}  // namespace
}  // namespace keepless::core
