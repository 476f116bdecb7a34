// Keep budgets (Params::budget) and the keep thresholds behind them. On
// seeded random windows full of ties, with every scope, floor and cost
// model: the kept-count curve kept(M) equals, at every M of a sweep, what
// the closed-form oracle (ClosedForm), the closed-form start and the
// successive shortest paths from zero flow keep at that M; each point's
// threshold M* says exactly at which M it is kept; a budget of K points
// keeps exactly min(K, candidates), the set {M* <= M} wherever kept(M) == K;
// a fraction rounds as documented and, over a sequence of windows, holds its
// share of every point it evaluated; an observations budget never exceeds B;
// and update() decides what run() does.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "case_count.hpp"
#include "decision_checks.hpp"
#include "keepless/core/closed_form.hpp"
#include "keepless/core/keep_thresholds.hpp"
#include "keepless/core/network.hpp"
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"

namespace keepless::core {
namespace {

// Small capacities: the sweep builds four sparsifiers and an oracle per M,
// and their buffers (sized by the capacities, not the window) were most of
// its time under ASan. Every case here fits: run() would refuse one that
// did not, and the test would fail.
const Capacities kCaps{16, 1024, 4096, 8192, 1024};

// Evaluated points within the scope, by id (the budget's candidates).
std::set<PointId> candidates_of(const Window& w, const Params& p) {
  std::map<PointId, std::uint32_t> views;
  for (std::uint32_t k = 0; k < w.keyframe_count(); ++k) {
    for (std::uint32_t i = 0; i < w.observation_count(k); ++i) ++views[w.observations(k)[i].point];
  }
  std::set<PointId> newest;
  const std::uint32_t last = w.keyframe_count() - 1;
  for (std::uint32_t i = 0; i < w.observation_count(last); ++i) newest.insert(w.observations(last)[i].point);
  std::set<PointId> out;
  for (const auto& [id, n] : views) {
    if (n >= 2 && (p.scope == Scope::kWindow || newest.count(id) > 0)) out.insert(id);
  }
  return out;
}

std::map<PointId, std::uint32_t> views_of(const Window& w) {
  std::map<PointId, std::uint32_t> views;
  for (std::uint32_t k = 0; k < w.keyframe_count(); ++k) {
    for (std::uint32_t i = 0; i < w.observation_count(k); ++i) ++views[w.observations(k)[i].point];
  }
  return views;
}

// The points a sparsifier keeps, the floor's promotions aside: with the
// floor off, simply its kept points.
std::set<PointId> kept_of(const Sparsifier& s) {
  std::set<PointId> kept;
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    if (s.decisions()[i].verdict == Verdict::kKeep) kept.insert(s.decisions()[i].point);
  }
  return kept;
}

// The oracle at pair capacity M: ClosedForm's flows, decide(), the scope.
std::set<PointId> oracle_kept(const Window& w, Params p, std::int64_t m,
                              const std::set<PointId>& candidates) {
  p.pair_capacity = m;
  PaperNetwork net(kCaps);
  solver::MinCostFlow solver(PaperNetwork::solver_capacity(kCaps));
  EXPECT_EQ(net.build(w, p, solver), Status::kOk);
  ClosedForm form(kCaps);
  form.solve(net, p);
  std::set<PointId> kept;
  for (std::uint32_t i = 0; i < net.point_count(); ++i) {
    if (net.point_source_arc(i) < 0 || candidates.count(net.point_id(i)) == 0) continue;
    const std::int64_t n = net.point_views(i);
    if (decide(form.point_flow(i), n * (n - 1) / 2, p.theta) == Verdict::kKeep) kept.insert(net.point_id(i));
  }
  return kept;
}

TEST(KeepBudgets, CurveAndThresholdsMatchAnMSweep) {
  Window window(kCaps);
  std::uint64_t sweeps = 0, by_model[3] = {0, 0, 0}, newest = 0, never = 0;
  for (std::uint64_t seed = 1; seed <= test::cases(120) && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(seed);
    test::random_policies(c, seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    const std::set<PointId> candidates = candidates_of(window, c.params);
    Params b = c.params;
    b.coverage_floor = 0;
    b.budget = KeepBudget{BudgetKind::kFraction, 0, 1.0};
    Sparsifier budgeted(kCaps, b);
    ASSERT_EQ(budgeted.run(window), Status::kOk);
    std::map<PointId, std::uint32_t> threshold;
    std::uint32_t top = 0;
    for (std::uint32_t i = 0; i < budgeted.decision_count(); ++i) {
      const PointId id = budgeted.decisions()[i].point;
      if (candidates.count(id) == 0) continue;
      const std::uint32_t t = budgeted.keep_thresholds()[i];
      threshold[id] = t;
      if (t == KeepThresholds::kNever) {
        ++never;
      } else {
        top = std::max(top, t);
      }
    }
    ASSERT_EQ(threshold.size(), candidates.size()) << "seed " << seed;
    for (std::int64_t m = 1; m <= static_cast<std::int64_t>(top) + 1; ++m) {
      std::set<PointId> by_threshold;
      for (const auto& [id, t] : threshold) {
        if (t <= m) by_threshold.insert(id);
      }
      ASSERT_EQ(budgeted.kept_at(m), by_threshold.size()) << "seed " << seed << " M " << m;
      ASSERT_EQ(oracle_kept(window, c.params, m, candidates), by_threshold) << "seed " << seed << " M " << m;
      Params at = c.params;  // the floor's promotions are not the curve's
      at.pair_capacity = m;
      at.coverage_floor = 0;
      for (Start start : {Start::kClosedForm, Start::kZeroFlow}) {
        Sparsifier s(kCaps, at, SolveMode::kFromScratch, start);
        ASSERT_EQ(s.run(window), Status::kOk);
        ASSERT_EQ(kept_of(s), by_threshold) << "seed " << seed << " M " << m << " start "
                                            << static_cast<int>(start);
        // With the floor on, its promotions come on top of the same set.
        Params floored = at;
        floored.coverage_floor = c.params.coverage_floor;
        Sparsifier f(kCaps, floored, SolveMode::kFromScratch, start);
        ASSERT_EQ(f.run(window), Status::kOk);
        ASSERT_EQ(f.summary().kept - f.summary().floor_promoted, budgeted.kept_at(m));
      }
      ++sweeps;
    }
    ++by_model[static_cast<int>(c.params.cost_model)];
    newest += c.params.scope == Scope::kNewest;
  }
  EXPECT_GT(sweeps, test::cases(500));
  for (std::uint64_t n : by_model) EXPECT_GT(n, test::cases(30));
  EXPECT_GT(newest, test::cases(30));
  EXPECT_GT(never, 0u);  // theta = 1 cases
}

TEST(KeepBudgets, BudgetsKeepExactly) {
  Window window(kCaps);
  std::uint64_t exact_sets = 0, floor_bound = 0, limited = 0;
  for (std::uint64_t seed = 300; seed <= 300 + test::cases(50) && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(seed, 12, 120);
    test::random_policies(c, seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    const std::set<PointId> candidates = candidates_of(window, c.params);
    const auto views = views_of(window);
    const auto e = static_cast<std::uint32_t>(candidates.size());
    Params curve_params = c.params;
    curve_params.coverage_floor = 0;
    curve_params.budget = KeepBudget{BudgetKind::kPoints, 0, 0.0};
    Sparsifier curve(kCaps, curve_params);
    ASSERT_EQ(curve.run(window), Status::kOk);
    ASSERT_EQ(curve.summary().kept, 0u);
    ASSERT_EQ(curve.summary().culled, e) << "seed " << seed;
    // Every K from 0 to past the candidates.
    for (std::uint32_t k = 0; k <= e + 2; k += 1 + e / 12) {
      Params p = curve_params;
      p.budget = KeepBudget{BudgetKind::kPoints, k, 0.0};
      Sparsifier s(kCaps, p);
      ASSERT_EQ(s.run(window), Status::kOk);
      const std::set<PointId> kept = kept_of(s);
      ASSERT_EQ(kept.size(), std::min(k, e)) << "seed " << seed << " K " << k;
      for (PointId id : kept) ASSERT_EQ(candidates.count(id), 1u);
      // Where the curve hits K exactly, the set is the thresholds' at that M.
      for (std::int64_t m = 1; m <= 64; ++m) {
        if (curve.kept_at(m) != k) continue;
        std::set<PointId> at_m;
        for (std::uint32_t i = 0; i < curve.decision_count(); ++i) {
          const PointId id = curve.decisions()[i].point;
          if (candidates.count(id) > 0 && curve.keep_thresholds()[i] <= m) at_m.insert(id);
        }
        ASSERT_EQ(kept, at_m) << "seed " << seed << " K " << k << " M " << m;
        ++exact_sets;
        break;
      }
      // The budget's M: the largest threshold kept; flows are those at it.
      std::int64_t top = 0;
      for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
        if (s.decisions()[i].verdict == Verdict::kKeep) {
          top = std::max<std::int64_t>(top, s.keep_thresholds()[i]);
        }
      }
      if (top != KeepThresholds::kNever) {
        ASSERT_EQ(s.summary().budget_m, top) << "seed " << seed << " K " << k;
        if (top > 0) {
          Params at = c.params;
          at.pair_capacity = top;
          at.coverage_floor = 0;
          Sparsifier ref(kCaps, at);
          ASSERT_EQ(ref.run(window), Status::kOk);
          ASSERT_EQ(s.summary().max_flow, ref.summary().max_flow);
          ASSERT_EQ(s.summary().total_cost, ref.summary().total_cost);
          for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
            ASSERT_EQ(s.decisions()[i].flow, ref.decisions()[i].flow);
          }
        }
      }
      // With the floor: the budget's points, plus the floor's promotions.
      if (c.params.coverage_floor > 0) {
        Params f = p;
        f.coverage_floor = c.params.coverage_floor;
        Sparsifier floored(kCaps, f);
        ASSERT_EQ(floored.run(window), Status::kOk);
        ASSERT_EQ(floored.summary().kept - floored.summary().floor_promoted, std::min(k, e));
        const std::set<PointId> with_floor = kept_of(floored);
        ASSERT_TRUE(std::includes(with_floor.begin(), with_floor.end(), kept.begin(), kept.end()));
        floor_bound += floored.summary().floor_promoted > 0;
      }
    }
    // Fractions: K = floor(F * candidates + 0.5).
    for (double fraction : {0.0, 0.1, 0.25, 0.3, 0.5, 0.75, 1.0}) {
      Params p = curve_params;
      p.budget = KeepBudget{BudgetKind::kFraction, 0, fraction};
      Sparsifier s(kCaps, p);
      ASSERT_EQ(s.run(window), Status::kOk);
      ASSERT_EQ(s.summary().kept, static_cast<std::uint32_t>(std::floor(fraction * e + 0.5)))
          << "seed " << seed << " F " << fraction;
    }
    // Observations: never above B, and the next point in order would be.
    std::uint64_t total = 0;
    for (PointId id : candidates) total += views.at(id);
    for (std::uint64_t budget : {std::uint64_t{0}, std::uint64_t{5}, total / 3, total / 2, total, total + 9}) {
      Params p = curve_params;
      p.budget = KeepBudget{BudgetKind::kObservations, budget, 0.0};
      Sparsifier s(kCaps, p);
      ASSERT_EQ(s.run(window), Status::kOk);
      std::uint64_t used = 0;
      for (PointId id : kept_of(s)) used += views.at(id);
      ASSERT_LE(used, budget) << "seed " << seed;
      ASSERT_EQ(used, s.summary().budget_observations);
      // The same points as the points budget of that count: a prefix.
      Params q = curve_params;
      q.budget = KeepBudget{BudgetKind::kPoints, s.summary().kept, 0.0};
      Sparsifier same_count(kCaps, q);
      ASSERT_EQ(same_count.run(window), Status::kOk);
      ASSERT_EQ(kept_of(same_count), kept_of(s));
      if (s.summary().kept < e) {  // the next in order would exceed B
        Params r = curve_params;
        r.budget = KeepBudget{BudgetKind::kPoints, s.summary().kept + 1, 0.0};
        Sparsifier next(kCaps, r);
        ASSERT_EQ(next.run(window), Status::kOk);
        std::uint64_t more = 0;
        for (PointId id : kept_of(next)) more += views.at(id);
        ASSERT_GT(more, budget);
        ++limited;
      }
    }
  }
  EXPECT_GT(exact_sets, test::cases(150));
  EXPECT_GT(floor_bound, test::cases(10));
  EXPECT_GT(limited, test::cases(100));
}

// test::same_decisions, and the budget's: each point's M*, the budget's M
// and observations, and the kept-count curve.
::testing::AssertionResult same(const Sparsifier& a, const Sparsifier& b) {
  if (::testing::AssertionResult r = test::same_decisions(a, b); !r) return r;
  for (std::uint32_t i = 0; i < a.decision_count(); ++i) {
    if (a.keep_thresholds()[i] != b.keep_thresholds()[i]) {
      return ::testing::AssertionFailure() << "point " << a.decisions()[i].point << ": M* differs";
    }
  }
  const Summary& s = a.summary();
  const Summary& t = b.summary();
  if (s.budget_m != t.budget_m || s.budget_observations != t.budget_observations) {
    return ::testing::AssertionFailure() << "budgets differ";
  }
  for (std::int64_t m = 1; m <= 40; ++m) {
    if (a.kept_at(m) != b.kept_at(m)) return ::testing::AssertionFailure() << "curve at " << m;
  }
  return ::testing::AssertionSuccess();
}

TEST(KeepBudgets, UpdateMatchesRun) {
  std::uint32_t windows = 0;
  const KeepBudget budgets[] = {{BudgetKind::kPoints, 25, 0.0},
                                {BudgetKind::kFraction, 0, 0.3},
                                {BudgetKind::kObservations, 90, 0.0}};
  for (std::uint64_t seed = 1; seed <= 36 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(9000 + seed, 16, 200);
    test::random_policies(c, 9000 + seed);
    c.params.budget = budgets[seed % 3];
    const std::uint32_t size = 3 + static_cast<std::uint32_t>(seed % 6);
    const auto check = [&](const Window&, const Sparsifier& run, const Sparsifier& closed,
                           const Sparsifier& zero, const test::RefKeyframe& f) {
      ASSERT_TRUE(same(run, closed)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(same(run, zero)) << "seed " << seed << " keyframe " << f.id;
      ++windows;
    };
    test::slide_run_and_update(kCaps, c, size, seed % 3 == 0, check);
  }
  EXPECT_GT(windows, 200u);
}

// With the tracking guard (Params::maturity_keyframes) a budget is taken
// from what the guard and the scope leave: the guarded points stay skipped
// exactly as without a budget, the budget keeps min(K, those left) of them,
// the K with the smallest thresholds (ties to the smaller id), and update()
// decides what run() does.
TEST(KeepBudgets, TakenFromWhatTheGuardLeaves) {
  std::uint32_t windows = 0, guarded = 0;
  for (std::uint64_t seed = 1; seed <= 40 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(7000 + seed, 16, 160);
    test::random_policies(c, 7000 + seed);
    c.params.coverage_floor = 0;  // the floor's promotions come on top of the budget
    c.params.maturity_keyframes = 1 + static_cast<std::uint32_t>(seed % 3);
    Params budgeted = c.params;
    const std::uint32_t k_points = 5 + static_cast<std::uint32_t>(seed % 30);
    budgeted.budget = KeepBudget{BudgetKind::kPoints, k_points, 0.0};
    Window window(kCaps);
    Sparsifier plain(kCaps, c.params);
    Sparsifier run(kCaps, budgeted);
    Sparsifier update(kCaps, budgeted, SolveMode::kIncremental, Start::kClosedForm);
    const std::uint32_t size = 4 + static_cast<std::uint32_t>(seed % 5);
    for (const auto& f : c.frames) {
      if (window.keyframe_count() == size) {
        ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
      }
      ASSERT_EQ(test::add_frame(window, f), Status::kOk);
      ASSERT_EQ(plain.run(window), Status::kOk);
      ASSERT_EQ(run.run(window), Status::kOk);
      ASSERT_EQ(update.update(window), Status::kOk);
      ASSERT_TRUE(same(run, update)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_EQ(run.summary().guarded, plain.summary().guarded) << "seed " << seed;
      ASSERT_EQ(run.decision_count(), plain.decision_count());
      // The candidates: what the guard and the scope leave decided.
      std::vector<std::pair<std::uint32_t, PointId>> left;  // (threshold, id)
      for (std::uint32_t i = 0; i < plain.decision_count(); ++i) {
        const bool skipped = plain.decisions()[i].verdict == Verdict::kSkip;
        ASSERT_EQ(run.decisions()[i].verdict == Verdict::kSkip, skipped) << "seed " << seed;
        if (skipped) {
          EXPECT_EQ(run.keep_thresholds()[i], 0u) << "a skip's M* reads 0";
        } else {
          left.emplace_back(run.keep_thresholds()[i], run.decisions()[i].point);
        }
      }
      std::sort(left.begin(), left.end());
      std::set<PointId> expected;
      for (std::size_t j = 0; j < std::min<std::size_t>(k_points, left.size()); ++j) expected.insert(left[j].second);
      ASSERT_EQ(kept_of(run), expected) << "seed " << seed << " keyframe " << f.id;
      guarded += run.summary().guarded;
      ++windows;
    }
  }
  EXPECT_GT(windows, 200u);
  EXPECT_GT(guarded, 0u) << "the guard should have skipped points";
}

// Params::tracked_first: the points the newest keyframe flags tracked are
// candidates like the others (counted in Summary::tracked, not skipped), and
// a budget of K keeps them first: min(K, candidates) points, the tracked ones
// in the network's order (M*, id), then the others in that order; run() and
// update() agree. Without the option they are skipped (the guard's test).
TEST(KeepBudgets, TrackedFirstKeepsTheTrackedWithinTheBudget) {
  std::uint32_t windows = 0, short_of_tracked = 0, beyond_tracked = 0;
  for (std::uint64_t seed = 1; seed <= 40 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(9100 + seed, 16, 160);
    test::random_policies(c, 9100 + seed);
    test::random_guard(c, 9100 + seed);
    c.params.coverage_floor = 0;
    c.params.tracked_first = true;
    Params order_params = c.params;
    order_params.budget = KeepBudget{BudgetKind::kPoints, 0, 0.0};
    Params budgeted = c.params;
    const std::uint32_t k_points = 3 + static_cast<std::uint32_t>(seed % 25);
    budgeted.budget = KeepBudget{BudgetKind::kPoints, k_points, 0.0};
    Window window(kCaps);
    Sparsifier order_of(kCaps, order_params);
    Sparsifier run(kCaps, budgeted);
    Sparsifier update(kCaps, budgeted, SolveMode::kIncremental, Start::kClosedForm);
    const std::uint32_t size = 4 + static_cast<std::uint32_t>(seed % 5);
    for (const auto& f : c.frames) {
      if (window.keyframe_count() == size) {
        ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
      }
      ASSERT_EQ(test::add_frame(window, f), Status::kOk);
      ASSERT_EQ(order_of.run(window), Status::kOk);
      ASSERT_EQ(run.run(window), Status::kOk);
      ASSERT_EQ(update.update(window), Status::kOk);
      ASSERT_TRUE(same(run, update)) << "seed " << seed << " keyframe " << f.id;
      std::set<PointId> flagged;
      const std::uint32_t newest = window.keyframe_count() - 1;
      if (window.keyframe(newest).tracked != nullptr) {
        for (std::uint32_t i = 0; i < window.observation_count(newest); ++i) {
          if (window.keyframe(newest).tracked[i] != 0) flagged.insert(window.observations(newest)[i].point);
        }
      }
      // The candidates in the network's order, the tracked first.
      std::vector<std::tuple<bool, std::uint32_t, PointId>> order;  // (not tracked, M*, id)
      std::uint32_t tracked_candidates = 0;
      for (std::uint32_t i = 0; i < order_of.decision_count(); ++i) {
        if (order_of.decisions()[i].verdict == Verdict::kSkip) continue;
        const PointId id = order_of.decisions()[i].point;
        const bool tracked = flagged.count(id) > 0;
        tracked_candidates += tracked;
        order.emplace_back(!tracked, order_of.keep_thresholds()[i], id);
      }
      ASSERT_EQ(run.summary().tracked, tracked_candidates) << "seed " << seed;
      std::sort(order.begin(), order.end());
      std::set<PointId> expected;
      for (std::size_t j = 0; j < std::min<std::size_t>(k_points, order.size()); ++j) {
        expected.insert(std::get<2>(order[j]));
      }
      ASSERT_EQ(kept_of(run), expected) << "seed " << seed << " keyframe " << f.id;
      // An observations budget B: the longest prefix of that order within B.
      Params by_obs = c.params;
      by_obs.budget = KeepBudget{BudgetKind::kObservations, 3ull * k_points, 0.0};
      Sparsifier obs(kCaps, by_obs);
      ASSERT_EQ(obs.run(window), Status::kOk);
      const auto views = views_of(window);
      std::set<PointId> within;
      std::uint64_t sum = 0;
      for (const auto& [untracked, m, id] : order) {
        if (sum + views.at(id) > by_obs.budget.count) break;
        sum += views.at(id);
        within.insert(id);
      }
      ASSERT_EQ(kept_of(obs), within) << "seed " << seed << " keyframe " << f.id;
      short_of_tracked += k_points < tracked_candidates;
      beyond_tracked += tracked_candidates > 0 && k_points > tracked_candidates && order.size() > k_points;
      ++windows;
    }
  }
  EXPECT_GT(windows, 200u);
  EXPECT_GT(short_of_tracked, 10u) << "budgets below the tracked count";
  EXPECT_GT(beyond_tracked, 10u) << "budgets beyond it, the others by the order";
}

// The fraction budget over a sliding window whose culled points leave the
// map, as a SLAM's do: each decision keeps (the candidates it kept before)
// + the grant, the grants summing to floor(F x N + 0.5) over the N points
// evaluated so far (an independent model of that count checks the
// sparsifier's), those with the smallest thresholds; so the points the
// budget holds, in the window or gone from it, stay exactly that share of
// all it evaluated instead of F^k of those decided k times. update()
// decides what run() does.
TEST(KeepBudgets, FractionHoldsItsShareOverASequence) {
  std::uint32_t windows = 0, redecided = 0;
  for (std::uint64_t seed = 1; seed <= 45 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(11000 + seed, 16, 160);
    test::random_policies(c, 11000 + seed);
    test::random_guard(c, 11000 + seed);
    c.params.coverage_floor = 0;  // the floor's promotions come on top of the budget
    const double fractions[] = {0.1, 0.3, 0.45, 0.6};
    const double f = fractions[seed % 4];
    c.params.budget = KeepBudget{BudgetKind::kFraction, 0, f};
    Sparsifier run(kCaps, c.params);
    Sparsifier update(kCaps, c.params, SolveMode::kIncremental, Start::kClosedForm);
    const std::size_t size = 3 + seed % 6;
    std::vector<test::RefKeyframe> held;  // the window's frames, culled points removed
    std::set<PointId> culled;             // and those that left the window: no SLAM re-observes them here
    std::set<PointId> in_window;
    std::map<PointId, bool> remembered;   // the model: candidates before, and kept
    std::set<PointId> holding;            // the budget's points still in the map
    std::uint64_t evaluated = 0, granted = 0;
    const auto without_culled = [&](const test::RefKeyframe& k) {
      test::RefKeyframe out = k;
      out.observations.clear();
      out.tracked.clear();
      for (std::size_t i = 0; i < k.observations.size(); ++i) {
        if (culled.count(k.observations[i].point) > 0) continue;
        out.observations.push_back(k.observations[i]);
        if (!k.tracked.empty()) out.tracked.push_back(k.tracked[i]);
      }
      return out;
    };
    for (const auto& frame : c.frames) {
      held.push_back(frame);
      if (held.size() > size) held.erase(held.begin());
      for (auto& k : held) k = without_culled(k);
      Window window(kCaps);
      ASSERT_TRUE(test::load(window, held));
      std::set<PointId> now;
      for (const auto& k : held) {
        for (const auto& o : k.observations) now.insert(o.point);
      }
      for (PointId id : in_window) {
        if (now.count(id) == 0) culled.insert(id);
      }
      in_window.swap(now);
      ASSERT_EQ(run.run(window), Status::kOk);
      ASSERT_EQ(update.update(window), Status::kOk);
      ASSERT_TRUE(same(run, update)) << "seed " << seed << " keyframe " << frame.id;

      // The model's K.
      std::uint32_t kept_before = 0, fresh = 0, candidates = 0;
      std::vector<std::pair<std::uint32_t, PointId>> order;  // (M*, id) of the candidates
      for (std::uint32_t i = 0; i < run.decision_count(); ++i) {
        const PointDecision& d = run.decisions()[i];
        if (d.verdict == Verdict::kSkip) continue;
        ++candidates;
        const auto known = remembered.find(d.point);
        fresh += known == remembered.end() ? 1 : 0;
        kept_before += known != remembered.end() && known->second ? 1 : 0;
        redecided += known != remembered.end() ? 1 : 0;
        order.emplace_back(run.keep_thresholds()[i], d.point);
      }
      evaluated += fresh;
      const auto due = static_cast<std::uint64_t>(std::floor(f * static_cast<double>(evaluated) + 0.5));
      const std::uint64_t k = std::min<std::uint64_t>(kept_before + (due - granted), candidates);
      granted = due;
      ASSERT_EQ(run.summary().kept, k) << "seed " << seed << " keyframe " << frame.id;
      std::sort(order.begin(), order.end());
      std::set<PointId> expected;
      for (std::size_t j = 0; j < k; ++j) expected.insert(order[j].second);
      ASSERT_EQ(kept_of(run), expected) << "seed " << seed << " keyframe " << frame.id;

      // The model's memory, the map, and the share held.
      std::map<PointId, bool> next;
      for (std::uint32_t i = 0; i < run.decision_count(); ++i) {
        const PointDecision& d = run.decisions()[i];
        if (d.verdict != Verdict::kSkip) {
          next[d.point] = d.verdict == Verdict::kKeep;
          if (d.verdict == Verdict::kKeep) holding.insert(d.point);
          if (d.verdict == Verdict::kCull) culled.insert(d.point);
          if (d.verdict == Verdict::kCull) holding.erase(d.point);
        } else if (remembered.count(d.point) > 0) {
          next[d.point] = remembered[d.point];
        }
      }
      remembered.swap(next);
      ASSERT_EQ(holding.size(), granted) << "seed " << seed << " keyframe " << frame.id;
      ++windows;
    }
  }
  EXPECT_GT(windows, 300u);
  EXPECT_GT(redecided, 1000u) << "points should be decided again in later windows";
}

// A camera sweeping back and forth over 20 places (a window of 4 keyframes,
// each seeing its place's points and the next place's): points leave the
// window and come back. A point the budget kept stays known when it returns,
// so the map holds the share F of the distinct points evaluated on every
// sweep, not F of it again on each revisit (which left 3 % of them after
// three sweeps at F = 0.5).
TEST(KeepBudgets, AFractionHoldsItsShareWhenPointsComeBack) {
  const Capacities caps{4, 4000, 8000, 40000};
  std::uint32_t returned = 0;
  for (const double f : {0.2, 0.5, 0.7}) {
    for (const SolveMode mode : {SolveMode::kFromScratch, SolveMode::kIncremental}) {
      Params p;
      p.budget = KeepBudget{BudgetKind::kFraction, 0, f};
      Sparsifier s(caps, p, mode);
      std::uint64_t rng = 7;
      const auto pixel = [&rng](double step) {
        rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
        return step * static_cast<double>((rng >> 33) % 41);
      };
      struct Frame {
        Keyframe kf;
        std::vector<Observation> obs;
      };
      std::vector<Frame> window;
      std::set<PointId> deleted, evaluated, in_window;
      int place = 0, dir = 1;
      for (int step = 0; step < 160 && !HasFailure(); ++step) {
        if (window.size() == 4) window.erase(window.begin());
        Frame k;
        k.kf.id = static_cast<KeyframeId>(step + 1);
        k.kf.centre[0] = place;
        for (const int q : {place, place + 1}) {
          for (int i = 0; i < 60; ++i) {
            const PointId id = static_cast<PointId>(q * 100 + i);
            if (deleted.count(id) == 0) k.obs.push_back({id, pixel(8.0), pixel(6.0)});
          }
        }
        window.push_back(k);
        place += dir;
        if (place == 19 || place == 0) dir = -dir;
        Window w(caps);
        std::set<PointId> now;
        for (const Frame& x : window) {
          ASSERT_EQ(w.add_keyframe(x.kf, x.obs.data(), static_cast<std::uint32_t>(x.obs.size())), Status::kOk);
          for (const Observation& o : x.obs) now.insert(o.point);
        }
        for (const PointId id : now) returned += evaluated.count(id) > 0 && in_window.count(id) == 0;
        in_window = now;
        ASSERT_EQ(mode == SolveMode::kIncremental ? s.update(w) : s.run(w), Status::kOk);
        for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
          const PointDecision& d = s.decisions()[i];
          if (d.verdict != Verdict::kSkip) evaluated.insert(d.point);
          if (d.verdict == Verdict::kCull) deleted.insert(d.point);  // the VO deletes what is culled
        }
        for (Frame& x : window) {
          x.obs.erase(std::remove_if(x.obs.begin(), x.obs.end(),
                                     [&](const Observation& o) { return deleted.count(o.point) > 0; }),
                      x.obs.end());
        }
        const auto due = static_cast<std::size_t>(std::floor(f * static_cast<double>(evaluated.size()) + 0.5));
        ASSERT_EQ(evaluated.size() - deleted.size(), due) << "F " << f << " step " << step;
      }
    }
  }
  EXPECT_GT(returned, 1000u) << "points should come back to the window";
}

// What has left the window is remembered for the last max_points points to
// leave: one that comes back after more left is new again (evaluated anew).
TEST(KeepBudgets, AFractionForgetsWhatLeftLongestAgo) {
  FractionBudget b(8);
  const auto decide = [&b](std::vector<PointId> ids, double f) {
    std::vector<PointDecision> d;
    for (const PointId id : ids) d.push_back({id, Verdict::kKeep, 0, 0});
    const std::uint32_t k = b.take(f, d.data(), static_cast<std::uint32_t>(d.size()));
    b.record(d.data(), static_cast<std::uint32_t>(d.size()));
    return k;
  };
  EXPECT_EQ(decide({1, 2}, 1.0), 2u);
  EXPECT_EQ(b.evaluated(), 2u);
  EXPECT_EQ(decide({10, 11, 12, 13, 14, 15, 16}, 1.0), 7u);  // 1 and 2 left: remembered
  EXPECT_EQ(decide({1, 20}, 1.0), 2u);                       // 10..16 left; 1 came back, known
  EXPECT_EQ(b.evaluated(), 10u);
  // 2 left before 10..16 and 20's turn came: 8 departures since, so forgotten.
  EXPECT_EQ(decide({30}, 1.0), 1u);
  EXPECT_EQ(decide({2}, 1.0), 1u);
  EXPECT_EQ(b.evaluated(), 12u);
}

// A cleared window starts a new map whose point ids may repeat the old
// map's: after forget_history() a kept fraction decides as a new Sparsifier
// would; without it, what the old map kept still counts.
TEST(KeepBudgets, ForgetHistoryStartsAFractionAfresh) {
  std::uint32_t differed_without = 0;
  for (std::uint64_t seed = 1; seed <= 30 && !HasFailure(); ++seed) {
    test::RandomCase old_map = test::random_case(12000 + seed, 10, 120);
    test::RandomCase new_map = test::random_case(12500 + seed, 10, 120);
    Params params = old_map.params;
    params.budget = KeepBudget{BudgetKind::kFraction, 0, 0.3};
    Sparsifier reused(kCaps, params), kept_history(kCaps, params), fresh(kCaps, params);
    Window before(kCaps), after(kCaps);
    ASSERT_TRUE(test::load(before, old_map.frames));
    ASSERT_TRUE(test::load(after, new_map.frames));
    ASSERT_EQ(reused.run(before), Status::kOk);
    ASSERT_EQ(kept_history.run(before), Status::kOk);
    reused.forget_history();
    ASSERT_EQ(reused.run(after), Status::kOk);
    ASSERT_EQ(kept_history.run(after), Status::kOk);
    ASSERT_EQ(fresh.run(after), Status::kOk);
    EXPECT_TRUE(same(reused, fresh)) << "seed " << seed;
    differed_without += same(kept_history, fresh) ? 0 : 1;
  }
  EXPECT_GT(differed_without, 0u);  // the case has teeth: reused ids were remembered
}

// A track share S: of a count K, K - floor(S x K + 0.5) points by the
// network's order (M*, id), the rest the other candidates with the most
// window observations, ties in that order; S = 0 is the order alone.
TEST(KeepBudgets, TrackShareTakesTheLongestTracksAfterTheOrder) {
  Window window(kCaps);
  std::uint64_t differs = 0;
  for (std::uint64_t seed = 600; seed <= 600 + test::cases(30) && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(seed, 12, 120);
    test::random_policies(c, seed);
    c.params.coverage_floor = 0;
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    const std::set<PointId> candidates = candidates_of(window, c.params);
    const auto views = views_of(window);
    const auto e = static_cast<std::uint32_t>(candidates.size());
    Params order_params = c.params;
    order_params.budget = KeepBudget{BudgetKind::kPoints, 0, 0.0};
    Sparsifier order_of(kCaps, order_params);
    ASSERT_EQ(order_of.run(window), Status::kOk);
    std::vector<std::pair<std::uint32_t, PointId>> order;  // (M*, id): the network's order
    for (std::uint32_t i = 0; i < order_of.decision_count(); ++i) {
      const PointId id = order_of.decisions()[i].point;
      if (candidates.count(id) > 0) order.emplace_back(order_of.keep_thresholds()[i], id);
    }
    std::sort(order.begin(), order.end());
    for (double share : {0.0, 0.25, 0.5, 1.0}) {
      for (std::uint32_t k = 0; k <= e + 1; k += 1 + e / 9) {
        Params p = c.params;
        p.budget = KeepBudget{BudgetKind::kPoints, k, 0.0, share};
        ASSERT_EQ(Sparsifier::validate(p), Status::kOk);
        Sparsifier s(kCaps, p);
        ASSERT_EQ(s.run(window), Status::kOk);
        const std::uint32_t take = std::min(k, e);
        const auto by_track = static_cast<std::uint32_t>(std::floor(share * take + 0.5));
        std::set<PointId> expected;
        for (std::uint32_t j = 0; j < take - by_track; ++j) expected.insert(order[j].second);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> rest;  // (-views, position in the order)
        for (std::uint32_t j = take - by_track; j < e; ++j) rest.emplace_back(~views.at(order[j].second), j);
        std::sort(rest.begin(), rest.end());
        for (std::uint32_t j = 0; j < by_track; ++j) expected.insert(order[rest[j].second].second);
        const std::set<PointId> kept = kept_of(s);
        ASSERT_EQ(kept, expected) << "seed " << seed << " K " << k << " S " << share;
        Params plain = p;
        plain.budget.track_share = 0.0;
        Sparsifier ordered(kCaps, plain);
        ASSERT_EQ(ordered.run(window), Status::kOk);
        differs += kept_of(ordered) != kept;
        // From a share of the candidates on: the share where K >= 0.3 x candidates, the order below.
        Params from = p;
        from.budget.track_share_from = 0.3;
        Sparsifier gated(kCaps, from);
        ASSERT_EQ(gated.run(window), Status::kOk);
        ASSERT_EQ(kept_of(gated), take >= 0.3 * e ? kept : kept_of(ordered)) << "seed " << seed << " K " << k;
        // Up to a share: where K <= 0.3 x candidates; with both bounds, only at 0.3 exactly.
        Params to = p;
        to.budget.track_share_to = 0.3;
        Sparsifier capped(kCaps, to);
        ASSERT_EQ(capped.run(window), Status::kOk);
        ASSERT_EQ(kept_of(capped), take <= 0.3 * e ? kept : kept_of(ordered)) << "seed " << seed << " K " << k;
        to.budget.track_share_from = 0.3;
        Sparsifier both(kCaps, to);
        ASSERT_EQ(both.run(window), Status::kOk);
        ASSERT_EQ(kept_of(both), take == 0.3 * e ? kept : kept_of(ordered)) << "seed " << seed << " K " << k;
      }
    }
    // A fraction's count is unchanged by the share.
    Params f = c.params;
    f.budget = KeepBudget{BudgetKind::kFraction, 0, 0.3, 0.5};
    Sparsifier s(kCaps, f);
    ASSERT_EQ(s.run(window), Status::kOk);
    ASSERT_EQ(s.summary().kept, static_cast<std::uint32_t>(std::floor(0.3 * e + 0.5))) << "seed " << seed;
  }
  EXPECT_GT(differs, test::cases(50));  // the share changes what is kept, not only in theory
}

// Params::tracked_first with a track share: the tracked go ahead of the
// share's picks, and what is left of the count still goes to the longest
// tracks. S = 1 is longest-track-first: a point seen by every keyframe is
// kept before a two-view one the network's order puts ahead of it.
TEST(KeepBudgets, TrackedFirstWithAShareKeepsTheLongestTracks) {
  Window window(kCaps);
  // No costs: each pair orders its points by id. Point 1 (two views) and
  // point 5 (five) both have M* = 1, point 3 (two views, tracked) M* = 2.
  const std::uint8_t tracked[] = {1, 0, 0};
  for (KeyframeId id = 1; id <= 5; ++id) {
    std::vector<Observation> obs{{5, 10.0 * id, 10.0, 0.0}};
    if (id >= 4) {
      obs.push_back({1, 100.0, 100.0, 0.0});
      obs.push_back({3, 200.0, 200.0, 0.0});
    }
    Keyframe kf;
    kf.id = id;
    kf.centre[0] = static_cast<double>(id);
    if (id == 5) {  // the newest flags point 3 (listed first)
      std::swap(obs[0], obs[2]);
      kf.tracked = tracked;
    }
    ASSERT_EQ(window.add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size())), Status::kOk);
  }
  Params p;
  p.cost_terms = 0;
  p.tracked_first = true;
  p.budget = KeepBudget{BudgetKind::kPoints, 2, 0.0, 1.0};
  Sparsifier s(kCaps, p);
  ASSERT_EQ(s.run(window), Status::kOk);
  ASSERT_EQ(s.summary().tracked, 1u);
  EXPECT_EQ(kept_of(s), (std::set<PointId>{3, 5}));  // the tracked, then the longest track

  // On random windows: with S = 1 every untracked candidate kept has at
  // least the views of every untracked candidate culled.
  std::uint32_t checked = 0;
  for (std::uint64_t seed = 1; seed <= 40 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(9500 + seed, 12, 120);
    test::random_policies(c, 9500 + seed);
    test::random_guard(c, 9500 + seed);
    c.params.coverage_floor = 0;
    c.params.tracked_first = true;
    ASSERT_TRUE(test::load(window, c.frames));
    const auto views = views_of(window);
    std::set<PointId> flagged;
    const std::uint32_t newest = window.keyframe_count() - 1;
    if (window.keyframe(newest).tracked != nullptr) {
      for (std::uint32_t i = 0; i < window.observation_count(newest); ++i) {
        if (window.keyframe(newest).tracked[i] != 0) flagged.insert(window.observations(newest)[i].point);
      }
    }
    for (std::uint64_t k = 1; k <= 40; k += 3) {
      Params q = c.params;
      q.budget = KeepBudget{BudgetKind::kPoints, k, 0.0, 1.0};
      Sparsifier t(kCaps, q);
      ASSERT_EQ(t.run(window), Status::kOk);
      std::uint32_t fewest_kept = ~0u, most_culled = 0;
      for (std::uint32_t i = 0; i < t.decision_count(); ++i) {
        const PointDecision& d = t.decisions()[i];
        if (d.verdict == Verdict::kSkip || flagged.count(d.point) > 0) continue;
        if (d.verdict == Verdict::kKeep) fewest_kept = std::min(fewest_kept, views.at(d.point));
        if (d.verdict == Verdict::kCull) most_culled = std::max(most_culled, views.at(d.point));
      }
      ASSERT_TRUE(fewest_kept == ~0u || fewest_kept >= most_culled) << "seed " << seed << " K " << k;
      ++checked;
    }
  }
  EXPECT_GT(checked, 400u);
}

// Without a budget the option changes nothing: the tracked are skipped.
TEST(KeepBudgets, TrackedFirstWithoutABudgetSkipsAsBefore) {
  Window window(kCaps);
  for (std::uint64_t seed = 1; seed <= 10 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(9300 + seed, 12, 120);
    test::random_policies(c, 9300 + seed);
    test::random_guard(c, 9300 + seed);
    ASSERT_TRUE(test::load(window, c.frames));
    Params first = c.params;
    first.tracked_first = true;
    ASSERT_EQ(Sparsifier::validate(first), Status::kOk);
    Sparsifier a(kCaps, c.params), b(kCaps, first);
    ASSERT_EQ(a.run(window), Status::kOk);
    ASSERT_EQ(b.run(window), Status::kOk);
    ASSERT_EQ(a.decision_count(), b.decision_count());
    for (std::uint32_t i = 0; i < a.decision_count(); ++i) {
      const PointDecision &x = a.decisions()[i], &y = b.decisions()[i];
      ASSERT_TRUE(x.point == y.point && x.verdict == y.verdict && x.flow == y.flow) << "seed " << seed;
    }
    ASSERT_EQ(a.summary().tracked, b.summary().tracked);
    ASSERT_EQ(a.summary().skipped, b.summary().skipped);
  }
}

TEST(KeepBudgets, InvalidBudgets) {
  Params p;
  p.budget = KeepBudget{BudgetKind::kFraction, 0, 1.5};
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
  p.budget.fraction = -0.1;
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
  p.budget.fraction = std::nan("");
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
  p.budget.fraction = 0.4;
  EXPECT_EQ(Sparsifier::validate(p), Status::kOk);
  p.budget = KeepBudget{static_cast<BudgetKind>(9), 0, 0.0};
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
  for (double share : {-0.1, 1.5, std::nan("")}) {
    p.budget = KeepBudget{BudgetKind::kPoints, 10, 0.0, share};
    EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument) << share;
  }
  p.budget = KeepBudget{BudgetKind::kObservations, 10, 0.0, 0.5};  // a share of a count only
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
  p.budget = KeepBudget{BudgetKind::kNone, 0, 0.0, 0.5};
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
  p.budget = KeepBudget{BudgetKind::kFraction, 0, 0.2, 1.0};
  EXPECT_EQ(Sparsifier::validate(p), Status::kOk);
  for (double from : {-0.1, 1.5, std::nan("")}) {
    p.budget = KeepBudget{BudgetKind::kFraction, 0, 0.2, 0.5, from};
    EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument) << from;
  }
  for (double to : {-0.1, 0.2, 1.5, std::nan("")}) {  // 0.2: below its from
    p.budget = KeepBudget{BudgetKind::kFraction, 0, 0.2, 0.5, 0.3, to};
    EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument) << to;
  }
  // A share bounded to a range of budgets needs no count: without one it never applies.
  for (BudgetKind kind : {BudgetKind::kNone, BudgetKind::kObservations}) {
    for (const auto& [from, to] : {std::pair{0.3, 1.0}, std::pair{0.0, 0.1}}) {
      p.budget = KeepBudget{kind, 10, 0.0, 0.5, from, to};
      EXPECT_EQ(Sparsifier::validate(p), Status::kOk);
      EXPECT_EQ(track_share_at(p.budget, 1, 10), 0.0);
    }
  }
  p.budget = KeepBudget{BudgetKind::kFraction, 0, 0.1, 0.5, 0.0, 0.1};
  EXPECT_EQ(track_share_at(p.budget, 100, 100), 0.5);  // F decides, not the decision's take
  p.budget.fraction = 0.11;
  EXPECT_EQ(track_share_at(p.budget, 0, 100), 0.0);
  p.budget = KeepBudget{BudgetKind::kFraction, 0, 0.3, 0.5, 0.3};
  EXPECT_EQ(track_share_at(p.budget, 0, 100), 0.5);  // F itself decides, not the decision's take
  p.budget.fraction = 0.29;
  EXPECT_EQ(track_share_at(p.budget, 100, 100), 0.0);
  EXPECT_STREQ(to_string(BudgetKind::kObservations), "observations");
}

}  // namespace
}  // namespace keepless::core
