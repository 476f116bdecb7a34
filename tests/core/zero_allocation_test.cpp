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

// A keyframe of a random case with its arrays (what Keyframe points into).
struct Frame {
  Keyframe keyframe;
  std::vector<Observation> observations;
  std::vector<Keypoint> unmapped;
  std::vector<std::uint8_t> tracked;
  std::vector<PointQuality> quality;
};

// Seeds 1..12 with random policies, point quality for kTrack (the other
// cost models ignore it) and, with `guard`, the tracking guard's flags; every
// input is prepared before counting starts.
std::vector<std::vector<Frame>> policy_windows(bool guard) {
  std::vector<std::vector<Frame>> windows;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    auto c = test::random_case(seed, 12, 150);
    test::random_policies(c, seed);
    test::random_quality(c, seed);
    if (guard) test::random_guard(c, seed);
    std::vector<Frame> frames(c.frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      frames[i].tracked = c.frames[i].tracked;
      frames[i].keyframe = test::keyframe_of(c.frames[i], frames[i].unmapped);
      frames[i].keyframe.tracked = frames[i].tracked.empty() ? nullptr : frames[i].tracked.data();
      frames[i].quality = c.frames[i].quality;
      frames[i].keyframe.quality = frames[i].quality.empty() ? nullptr : frames[i].quality.data();
      frames[i].observations = test::observations_of(c.frames[i]);
    }
    windows.push_back(std::move(frames));
  }
  return windows;
}

struct Counted {
  std::uint64_t allocations = 0, calls = 0, ok = 0, tally = 0;
};

// After a warm-up pass on the first window, slides a window of at most 6
// keyframes over every window's frames and calls run() then update() on each
// sparsifier per keyframe, counting allocations; `tally` sums what `count`
// reads from each run()'s summary.
Counted slide_counted(const Capacities& caps, const std::vector<std::unique_ptr<Sparsifier>>& sparsifiers,
                      const std::vector<std::vector<Frame>>& windows, std::uint64_t (*count)(const Summary&)) {
  Window window(caps);
  Counted out;
  const auto run_all = [&]() {
    for (const auto& s : sparsifiers) {
      out.ok += s->run(window) == Status::kOk;
      out.tally += count(s->summary());
      out.ok += s->update(window) == Status::kOk;
    }
    out.calls += 2 * sparsifiers.size();
  };
  for (const auto& f : windows[0]) {
    EXPECT_EQ(window.add_keyframe(f.keyframe, f.observations.data(),
                                  static_cast<std::uint32_t>(f.observations.size())),
              Status::kOk);
  }
  run_all();
  EXPECT_EQ(out.ok, out.calls);  // warm-up
  window.clear();

  out = Counted{};
  test::AllocationCounter counter;
  for (const auto& frames : windows) {
    for (const auto& f : frames) {
      if (window.keyframe_count() == 6) (void)window.remove_keyframe(window.keyframe(0).id);
      (void)window.add_keyframe(f.keyframe, f.observations.data(),
                                static_cast<std::uint32_t>(f.observations.size()));
      run_all();
    }
    window.clear();
  }
  out.allocations = counter.stop();
  return out;
}

// The same with every policy on: the newest keyframe's scope, a floor that
// binds, and each cost model reading depths, intrinsics and unmapped
// keypoints, without and with each keep budget (and a track share);
// from-scratch and incremental, both starts.
TEST(ZeroAllocation, PoliciesAndCostModelsAllocateNothing) {
  const Capacities caps{12, 2048, 8192, 32768, 2048};
  std::vector<std::unique_ptr<Sparsifier>> sparsifiers;
  // Each with no budget and with each kind of keep budget.
  const KeepBudget budgets[] = {{}, {BudgetKind::kPoints, 40, 0.0}, {BudgetKind::kFraction, 0, 0.3},
                                {BudgetKind::kObservations, 150, 0.0}, {BudgetKind::kPoints, 40, 0.0, 0.5}};
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
  const Counted c = slide_counted(caps, sparsifiers, policy_windows(false),
                                  [](const Summary& s) -> std::uint64_t { return s.floor_promoted; });
  EXPECT_EQ(c.allocations, 0u);
  EXPECT_EQ(c.ok, c.calls);
  EXPECT_GT(c.calls, 200u);
  EXPECT_GT(c.tally, 0u) << "the floor should have promoted points";
}

// memory_bytes() is what a Sparsifier holds: every byte its construction
// allocates, for each solve mode, start and policy (the node sizes and
// reports its memory from it).
TEST(ZeroAllocation, MemoryBytesCountsWhatConstructionAllocates) {
  const Capacities caps{12, 2048, 8192, 32768, 2048};
  const KeepBudget budgets[] = {{}, {BudgetKind::kPoints, 40, 0.0}, {BudgetKind::kFraction, 0, 0.3},
                                {BudgetKind::kObservations, 150, 0.0}, {BudgetKind::kFraction, 0, 0.3, 0.5}};
  std::uint32_t checked = 0;
  for (const KeepBudget& budget : budgets) {
    for (Scope scope : {Scope::kWindow, Scope::kNewest, Scope::kAuto}) {
      for (SolveMode mode : {SolveMode::kFromScratch, SolveMode::kIncremental}) {
        for (Start start : {Start::kClosedForm, Start::kZeroFlow}) {
          Params p;
          p.scope = scope;
          p.budget = budget;
          p.coverage_floor = scope == Scope::kNewest ? 10 : 0;
          p.tracked_first = budget.kind == BudgetKind::kFraction && scope == Scope::kNewest;  // its scratch too
          test::AllocationCounter counter;
          auto s = std::make_unique<Sparsifier>(caps, p, mode, start);
          const std::uint64_t allocated = counter.stop();
          EXPECT_EQ(s->memory_bytes(), counter.bytes())
              << "budget " << static_cast<int>(budget.kind) << " share " << budget.track_share << " scope "
              << static_cast<int>(scope) << " mode " << static_cast<int>(mode) << " start "
              << static_cast<int>(start) << " (" << allocated << " allocations)";
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 60u);
}

// Tracking-safe culling on: a maturity guard with each scope (auto's
// measurement too) and a floor,
// and tracked flags on the keyframes; incremental, and from scratch with a
// fraction that keeps the tracked first.
TEST(ZeroAllocation, TrackingGuardAllocatesNothing) {
  const Capacities caps{12, 2048, 8192, 32768, 2048};
  std::vector<std::unique_ptr<Sparsifier>> sparsifiers;
  for (Scope scope : {Scope::kWindow, Scope::kNewest, Scope::kAuto}) {
    Params p;
    p.pair_capacity = 2;
    p.scope = scope;
    p.coverage_floor = 10;
    p.maturity_keyframes = 2;
    for (Start start : {Start::kClosedForm, Start::kZeroFlow}) {
      sparsifiers.push_back(std::make_unique<Sparsifier>(caps, p, SolveMode::kIncremental, start));
    }
    // And a kept fraction that keeps the tracked first (Params::tracked_first).
    p.budget = KeepBudget{BudgetKind::kFraction, 0, 0.3};
    p.tracked_first = true;
    sparsifiers.push_back(std::make_unique<Sparsifier>(caps, p));
  }
  const Counted c = slide_counted(caps, sparsifiers, policy_windows(true),
                                  [](const Summary& s) -> std::uint64_t { return s.guarded + s.tracked; });
  EXPECT_EQ(c.allocations, 0u);
  EXPECT_EQ(c.ok, c.calls);
  EXPECT_GT(c.calls, 200u);
  EXPECT_GT(c.tally, 0u) << "the guard should have skipped points";
}

}  // namespace
}  // namespace keepless::core
