// After construction and one warm-up, the decision path allocates nothing:
// a counting global operator new (replaced for this binary only) sees zero
// calls across add_keyframe / remove_keyframe / run on random windows.

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "keepless/core/closed_form.hpp"
#include "counting_new.hpp"  // this binary's only inclusion
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"

namespace keepless::core {
namespace {

struct Prepared {
  Keyframe keyframe;
  std::vector<Observation> observations;
};

TEST(ZeroAllocation, CounterSeesAllocations) {
  test::AllocationCounter counter;
  auto* p = new std::vector<int>(10);
  const std::uint64_t allocations = counter.stop();
  delete p;
  EXPECT_EQ(allocations, 2u);  // the vector and its buffer
}

TEST(ZeroAllocation, DecisionPathAllocatesNothing) {
  const Capacities caps{12, 2048, 8192, 32768};
  // Every input is prepared before counting starts.
  std::vector<std::vector<Prepared>> windows;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const auto c = test::random_case(seed, 12, 150);
    std::vector<Prepared> frames;
    for (const auto& f : c.frames) {
      Prepared p;
      p.keyframe.id = f.id;
      std::copy(f.centre, f.centre + 3, p.keyframe.centre);
      for (const auto& o : f.observations) p.observations.push_back({o.point, o.u, o.v});
      frames.push_back(p);
    }
    windows.push_back(frames);
  }

  Window window(caps);
  Sparsifier sparsifier(caps, Params{});
  ClosedForm closed(caps);
  // Warm-up: one full pass, so lazily initialised library state (if any) exists.
  for (const auto& f : windows[0]) {
    ASSERT_EQ(window.add_keyframe(f.keyframe, f.observations.data(),
                                  static_cast<std::uint32_t>(f.observations.size())),
              Status::kOk);
  }
  ASSERT_EQ(sparsifier.run(window), Status::kOk);
  closed.solve(sparsifier.network(), sparsifier.params());
  window.clear();

  std::uint64_t runs = 0, kept = 0, removals = 0;
  std::uint32_t statuses_ok = 0;
  test::AllocationCounter counter;
  for (const auto& frames : windows) {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      // Slide: keep at most 6 keyframes, dropping the oldest.
      if (window.keyframe_count() == 6) {
        statuses_ok += window.remove_keyframe(window.keyframe(0).id) == Status::kOk;
        ++removals;
      }
      const auto& f = frames[i];
      statuses_ok += window.add_keyframe(f.keyframe, f.observations.data(),
                                         static_cast<std::uint32_t>(f.observations.size())) ==
                     Status::kOk;
      const Status s = sparsifier.run(window);
      statuses_ok += s == Status::kOk;
      closed.solve(sparsifier.network(), sparsifier.params());
      kept += sparsifier.summary().kept;
      ++runs;
    }
    // Failures allocate nothing either.
    const auto& last = frames.back();
    statuses_ok += window.add_keyframe(last.keyframe, last.observations.data(),
                                       static_cast<std::uint32_t>(last.observations.size())) ==
                   Status::kDuplicateKeyframe;
    solver::Budget tiny;
    tiny.work_units = 3;
    statuses_ok += sparsifier.run(window, tiny) != Status::kOk || sparsifier.summary().evaluated == 0;
    while (window.keyframe_count() > 0) {
      statuses_ok += window.remove_keyframe(window.keyframe(0).id) == Status::kOk;
      ++removals;
    }
  }
  EXPECT_EQ(counter.stop(), 0u);
  EXPECT_EQ(statuses_ok, 2 * runs + 2 * windows.size() + removals);
  EXPECT_GT(runs, 100u);
  EXPECT_GT(kept, 0u);
}

// The same with every policy on: the newest keyframe's scope, a floor that
// binds, and each cost model reading depths, intrinsics and unmapped
// keypoints, without and with each keep budget; from-scratch and
// incremental, both starts.
TEST(ZeroAllocation, PoliciesAndCostModelsAllocateNothing) {
  const Capacities caps{12, 2048, 8192, 32768, 2048};
  struct Frame {
    Keyframe keyframe;
    std::vector<Observation> observations;
    std::vector<Keypoint> unmapped;
    std::vector<PointQuality> quality;
  };
  std::vector<std::vector<Frame>> windows;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    auto c = test::random_case(seed, 12, 150);
    test::random_policies(c, seed);
    test::random_quality(c, seed);  // point quality for kTrack (the others ignore it)
    std::vector<Frame> frames(c.frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      frames[i].keyframe = test::keyframe_of(c.frames[i], frames[i].unmapped);
      frames[i].observations = test::observations_of(c.frames[i]);
      frames[i].quality = c.frames[i].quality;
      frames[i].keyframe.quality = frames[i].quality.empty() ? nullptr : frames[i].quality.data();
    }
    windows.push_back(std::move(frames));
  }
  std::vector<std::unique_ptr<Sparsifier>> sparsifiers;
  // Each with no budget and with each kind of keep budget.
  const KeepBudget budgets[] = {{}, {BudgetKind::kPoints, 40, 0.0}, {BudgetKind::kFraction, 0, 0.3},
                                {BudgetKind::kObservations, 150, 0.0}};
  for (CostModel model : {CostModel::kPaper, CostModel::kAuthors, CostModel::kInformation, CostModel::kTrack}) {
    for (const KeepBudget& budget : budgets) {
      Params p;
      p.pair_capacity = 2;
      p.scope = Scope::kNewest;
      p.coverage_floor = 10;
      p.cost_model = model;
      p.budget = budget;
      for (Start start : {Start::kClosedForm, Start::kZeroFlow}) {
        sparsifiers.push_back(std::make_unique<Sparsifier>(caps, p, SolveMode::kIncremental, start));
      }
    }
  }
  Window window(caps);
  const auto run_all = [&](std::uint64_t* promoted) {
    std::uint32_t ok = 0;
    for (auto& s : sparsifiers) {
      ok += s->run(window) == Status::kOk;
      *promoted += s->summary().floor_promoted;
      ok += s->update(window) == Status::kOk;
    }
    return ok;
  };
  std::uint64_t promoted = 0;
  for (const auto& f : windows[0]) {
    ASSERT_EQ(window.add_keyframe(f.keyframe, f.observations.data(),
                                  static_cast<std::uint32_t>(f.observations.size())),
              Status::kOk);
  }
  ASSERT_EQ(run_all(&promoted), 2 * sparsifiers.size());  // warm-up
  window.clear();

  std::uint64_t calls = 0, ok = 0;
  promoted = 0;
  test::AllocationCounter counter;
  for (const auto& frames : windows) {
    for (const auto& f : frames) {
      if (window.keyframe_count() == 6) (void)window.remove_keyframe(window.keyframe(0).id);
      (void)window.add_keyframe(f.keyframe, f.observations.data(),
                                static_cast<std::uint32_t>(f.observations.size()));
      ok += run_all(&promoted);
      calls += 2 * sparsifiers.size();
    }
    window.clear();
  }
  EXPECT_EQ(counter.stop(), 0u);
  EXPECT_EQ(ok, calls);
  EXPECT_GT(calls, 200u);
  EXPECT_GT(promoted, 0u);
}

// Tracking-safe culling on: a maturity guard with each scope and a floor,
// and tracked flags on the keyframes; from-scratch and incremental.
TEST(ZeroAllocation, TrackingGuardAllocatesNothing) {
  const Capacities caps{12, 2048, 8192, 32768, 2048};
  struct Frame {
    Keyframe keyframe;
    std::vector<Observation> observations;
    std::vector<Keypoint> unmapped;
    std::vector<std::uint8_t> tracked;
  };
  std::vector<std::vector<Frame>> windows;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    auto c = test::random_case(seed, 12, 150);
    test::random_policies(c, seed);
    test::random_guard(c, seed);
    std::vector<Frame> frames(c.frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      frames[i].tracked = c.frames[i].tracked;
      frames[i].keyframe = test::keyframe_of(c.frames[i], frames[i].unmapped);
      frames[i].keyframe.tracked = frames[i].tracked.empty() ? nullptr : frames[i].tracked.data();
      frames[i].observations = test::observations_of(c.frames[i]);
    }
    windows.push_back(std::move(frames));
  }
  std::vector<std::unique_ptr<Sparsifier>> sparsifiers;
  for (Scope scope : {Scope::kWindow, Scope::kNewest}) {
    Params p;
    p.pair_capacity = 2;
    p.scope = scope;
    p.coverage_floor = 10;
    p.maturity_keyframes = 2;
    for (Start start : {Start::kClosedForm, Start::kZeroFlow}) {
      sparsifiers.push_back(std::make_unique<Sparsifier>(caps, p, SolveMode::kIncremental, start));
    }
  }
  Window window(caps);
  const auto run_all = [&](std::uint64_t* guarded) {
    std::uint32_t ok = 0;
    for (auto& s : sparsifiers) {
      ok += s->run(window) == Status::kOk;
      *guarded += s->summary().guarded + s->summary().tracked;
      ok += s->update(window) == Status::kOk;
    }
    return ok;
  };
  std::uint64_t guarded = 0;
  for (const auto& f : windows[0]) {
    ASSERT_EQ(window.add_keyframe(f.keyframe, f.observations.data(),
                                  static_cast<std::uint32_t>(f.observations.size())),
              Status::kOk);
  }
  ASSERT_EQ(run_all(&guarded), 2 * sparsifiers.size());  // warm-up
  window.clear();

  std::uint64_t calls = 0, ok = 0;
  guarded = 0;
  test::AllocationCounter counter;
  for (const auto& frames : windows) {
    for (const auto& f : frames) {
      if (window.keyframe_count() == 6) (void)window.remove_keyframe(window.keyframe(0).id);
      (void)window.add_keyframe(f.keyframe, f.observations.data(),
                                static_cast<std::uint32_t>(f.observations.size()));
      ok += run_all(&guarded);
      calls += 2 * sparsifiers.size();
    }
    window.clear();
  }
  EXPECT_EQ(counter.stop(), 0u);
  EXPECT_EQ(ok, calls);
  EXPECT_GT(calls, 200u);
  EXPECT_GT(guarded, 0u);
}

}  // namespace
}  // namespace keepless::core
