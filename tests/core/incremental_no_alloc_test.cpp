// The incremental decision path allocates nothing after construction: a
// counting global operator new (replaced for this binary only) sees zero
// calls across sliding windows, point drops, resets, budget stops and
// capacity errors handled by Sparsifier::update.

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "keepless/core/closed_form.hpp"
#include "counting_new.hpp"  // this binary's only inclusion
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"

namespace keepless::core {
namespace {

// Every read is past the deadline it is given (0): the stop path, not time.
class PastDeadlineClock final : public solver::Clock {
 public:
  std::uint64_t now_ns() const override { return 1; }
};

struct Prepared {
  Keyframe keyframe;
  std::vector<Observation> observations;
};

TEST(IncrementalZeroAllocation, UpdateAllocatesNothing) {
  const Capacities caps{8, 1024, 4096, 16384};
  // Every keyframe of every stream is prepared before counting starts.
  std::vector<std::vector<Prepared>> streams;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    test::Rng rng(seed);
    std::vector<Prepared> frames;
    std::uint64_t next_id = 100;
    std::vector<std::pair<PointId, std::pair<double, double>>> tracks;
    for (std::uint32_t k = 0; k < 40; ++k) {
      Prepared p;
      p.keyframe.id = 1 + k;
      p.keyframe.centre[0] = static_cast<double>(rng.between(-5, 5));
      std::vector<std::pair<PointId, std::pair<double, double>>> kept;
      for (const auto& t : tracks) {
        if (rng.chance(80)) kept.push_back(t);
      }
      tracks = kept;
      const auto fresh = rng.between(10, 40);
      for (std::int64_t i = 0; i < fresh; ++i) {
        tracks.push_back({next_id++, {8.0 * static_cast<double>(rng.between(0, 80)),
                                      6.0 * static_cast<double>(rng.between(0, 80))}});
      }
      for (const auto& t : tracks) p.observations.push_back({t.first, t.second.first, t.second.second});
      frames.push_back(p);
    }
    streams.push_back(frames);
  }
  const auto add = [](Window& w, const Prepared& p) {
    return w.add_keyframe(p.keyframe, p.observations.data(),
                          static_cast<std::uint32_t>(p.observations.size()));
  };

  Window window(caps);
  Sparsifier sparsifier(caps, Params{}, SolveMode::kIncremental);
  // A keep budget of each kind decides without a solve (its thresholds).
  const KeepBudget budgets[] = {{BudgetKind::kPoints, 40, 0.0}, {BudgetKind::kFraction, 0, 0.3},
                                {BudgetKind::kObservations, 150, 0.0}};
  std::vector<std::unique_ptr<Sparsifier>> budgeted;
  for (const KeepBudget& b : budgets) {
    Params p;
    p.budget = b;
    budgeted.push_back(std::make_unique<Sparsifier>(caps, p, SolveMode::kIncremental));
  }
  // Scope::kNewest, whose missed turns (deferred calls, note_undecided())
  // the next call that decides catches up.
  Params newest_params;
  newest_params.scope = Scope::kNewest;
  newest_params.maturity_keyframes = 2;
  Sparsifier newest(caps, newest_params, SolveMode::kIncremental);
  // Room for too few pair arcs: most windows are answered kCapacityExceeded.
  Capacities tight_caps = caps;
  tight_caps.max_pair_arcs = 64;
  Sparsifier tight(tight_caps, Params{}, SolveMode::kIncremental);
  // Warm-up: one stream's first window.
  for (std::size_t i = 0; i < 4; ++i) ASSERT_EQ(add(window, streams[0][i]), Status::kOk);
  ASSERT_EQ(sparsifier.update(window), Status::kOk);
  ASSERT_EQ(newest.update(window), Status::kOk);
  for (auto& b : budgeted) ASSERT_EQ(b->update(window), Status::kOk);
  (void)tight.update(window);
  window.clear();

  std::uint64_t updates = 0, ok = 0, stopped = 0, budget_ok = 0, caught_up = 0, beyond = 0, tight_ok = 0;
  PastDeadlineClock clock;
  test::AllocationCounter counter;
  for (const auto& frames : streams) {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (window.keyframe_count() == 6) (void)window.remove_keyframe(window.keyframe(0).id);
      (void)add(window, frames[i]);
      solver::Budget budget;
      if (i % 5 == 3) budget.work_units = 10;  // stops, then the next call resumes
      if (i % 7 == 4) {
        budget.clock = &clock;
        budget.deadline_ns = 0;
      }
      const Status s = sparsifier.update(window, budget);
      for (auto& b : budgeted) budget_ok += b->update(window, budget) == Status::kOk;
      if (i % 11 == 5) {
        newest.note_undecided();
      } else {
        (void)newest.update(window, budget);
        caught_up += newest.summary().caught_up;
      }
      const Status t = tight.update(window, budget);
      beyond += t == Status::kCapacityExceeded;
      tight_ok += t == Status::kOk;
      ok += s == Status::kOk;
      stopped += s == Status::kBudgetExhausted;
      ++updates;
    }
    window.clear();
    (void)sparsifier.update(window);
    for (auto& b : budgeted) (void)b->update(window);
    (void)newest.update(window);
    (void)tight.update(window);
    newest.forget_history();
  }
  EXPECT_EQ(counter.stop(), 0u);
  EXPECT_GT(updates, 200u);
  EXPECT_GT(ok, 100u);
  EXPECT_GT(stopped, 20u);
  EXPECT_GT(budget_ok, 300u);
  EXPECT_GT(caught_up, 20u);
  EXPECT_GT(beyond, 100u) << "the tight sparsifier should have met its pair-arc capacity";
  EXPECT_GT(tight_ok, 0u) << "and decided the windows within it";
}

}  // namespace
}  // namespace keepless::core
