// The network and the sparsifier on hand-worked windows: node and arc order,
// costs, decisions, summary, tie-break, parameters, capacities, budget.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "flow_certificate.hpp"
#include "keepless/core/closed_form.hpp"
#include "keepless/core/costs.hpp"
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"

namespace keepless::core {
namespace {

Status add(Window& w, KeyframeId id, double x, double y, double z, const std::vector<Observation>& o) {
  Keyframe k;
  k.id = id;
  k.centre[0] = x;
  k.centre[1] = y;
  k.centre[2] = z;
  return w.add_keyframe(k, o.data(), static_cast<std::uint32_t>(o.size()));
}

const Capacities kCaps{8, 64, 256, 256};

// Three keyframes A (0,0,0), B (10,0,0), C (0,0,5); keypoints far apart, so
// every c_s = 0. Point 40 is seen by A, B, C (n = 3 = m, c_c = 1); 30 by A, B
// and 20 by B, C (n = 2, c_c = ceil(3/1 * 1) = 3); 10 by A only (skipped).
// c_b: AB d = 10 -> 5; AC d = 5 -> ceil(6.67) = 7; BC d = 11.18 -> ceil(4.72) = 5.
class HandWindow : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(add(window_, 100, 0, 0, 0, {{40, 100, 100}, {30, 300, 100}, {10, 500, 100}}), Status::kOk);
    ASSERT_EQ(add(window_, 200, 10, 0, 0, {{20, 100, 300}, {30, 300, 300}, {40, 500, 300}}), Status::kOk);
    ASSERT_EQ(add(window_, 300, 0, 0, 5, {{20, 100, 100}, {40, 300, 300}}), Status::kOk);
  }
  Window window_{kCaps};
};

TEST_F(HandWindow, NetworkLayout) {
  PaperNetwork net(kCaps);
  solver::MinCostFlow solver(PaperNetwork::solver_capacity(kCaps));
  ASSERT_EQ(net.build(window_, Params{}, solver), Status::kOk);
  ASSERT_EQ(net.point_count(), 4u);
  const PointId ids[] = {10, 20, 30, 40};
  const std::uint32_t views[] = {1, 2, 2, 3};
  const std::int32_t source_arcs[] = {-1, 0, 1, 2};
  for (std::uint32_t i = 0; i < 4; ++i) {
    EXPECT_EQ(net.point_id(i), ids[i]);
    EXPECT_EQ(net.point_views(i), views[i]);
    EXPECT_EQ(net.point_source_arc(i), source_arcs[i]);
  }
  EXPECT_EQ(net.evaluated_count(), 3u);
  EXPECT_EQ(net.max_views(), 3u);
  EXPECT_EQ(net.connectivity_cost(3), 1);
  EXPECT_EQ(net.connectivity_cost(2), 3);
  ASSERT_EQ(net.pair_count(), 3u);
  const std::uint32_t pj[] = {0, 0, 1}, pk[] = {1, 2, 2};
  const std::int64_t cb[] = {5, 7, 5};
  for (std::uint32_t q = 0; q < 3; ++q) {
    EXPECT_EQ(net.pair_slot_j(q), pj[q]);
    EXPECT_EQ(net.pair_slot_k(q), pk[q]);
    EXPECT_EQ(net.pair_baseline_cost(q), cb[q]);
  }
  // Arcs: point 20 -> BC; point 30 -> AB; point 40 -> AB, AC, BC.
  ASSERT_EQ(net.pair_arc_count(), 5u);
  const std::uint32_t ap[] = {1, 2, 3, 3, 3}, aq[] = {2, 0, 0, 1, 2};
  for (std::uint32_t a = 0; a < 5; ++a) {
    EXPECT_EQ(net.arc_point(a), ap[a]);
    EXPECT_EQ(net.arc_pair(a), aq[a]);
    EXPECT_EQ(net.arc_spatial_cost(a), 0);
    EXPECT_EQ(net.arc_solver_id(a), static_cast<solver::ArcId>(3 + a));
  }
  // Solver view: source 0, points 1..3, pairs 4..6, sink 7.
  EXPECT_EQ(net.source(), 0);
  EXPECT_EQ(net.sink(), 7);
  ASSERT_EQ(solver.node_count(), 8);
  ASSERT_EQ(solver.arc_count(), 3 + 5 + 3);
  const std::int64_t source_caps[] = {1, 1, 3}, source_costs[] = {3, 3, 1};
  for (solver::ArcId a = 0; a < 3; ++a) {
    EXPECT_EQ(solver.tail(a), 0);
    EXPECT_EQ(solver.head(a), 1 + a);
    EXPECT_EQ(solver.capacity(a), source_caps[a]);
    EXPECT_EQ(solver.cost(a), source_costs[a]);
  }
  for (std::uint32_t a = 0; a < 5; ++a) {
    const solver::ArcId id = net.arc_solver_id(a);
    EXPECT_EQ(solver.tail(id), static_cast<solver::NodeId>(1 + net.point_source_arc(ap[a])));
    EXPECT_EQ(solver.head(id), static_cast<solver::NodeId>(4 + aq[a]));
    EXPECT_EQ(solver.capacity(id), 1);
  }
  for (std::uint32_t q = 0; q < 3; ++q) {
    const solver::ArcId id = net.pair_sink_arc(q);
    EXPECT_EQ(id, static_cast<solver::ArcId>(8 + q));
    EXPECT_EQ(solver.tail(id), static_cast<solver::NodeId>(4 + q));
    EXPECT_EQ(solver.head(id), 7);
    EXPECT_EQ(solver.capacity(id), 100);
    EXPECT_EQ(solver.cost(id), cb[q]);
  }
  EXPECT_GT(net.memory_bytes(), 0u);
}

TEST_F(HandWindow, TightPairsKeepTheBestConnectedPoint) {
  Params p;
  p.pair_capacity = 1;
  Sparsifier s(kCaps, p);
  ASSERT_EQ(s.run(window_), Status::kOk);
  // Each pair takes point 40 (c_c 1): flow 3 of 3 -> keep; 20 and 30 get 0 -> cull.
  ASSERT_EQ(s.decision_count(), 4u);
  const PointDecision* d = s.decisions();
  EXPECT_EQ(d[0].point, 10u);
  EXPECT_EQ(d[0].verdict, Verdict::kSkip);
  EXPECT_EQ(d[0].capacity, 0);
  EXPECT_EQ(d[1].point, 20u);
  EXPECT_EQ(d[1].verdict, Verdict::kCull);
  EXPECT_EQ(d[1].flow, 0);
  EXPECT_EQ(d[1].capacity, 1);
  EXPECT_EQ(d[2].verdict, Verdict::kCull);
  EXPECT_EQ(d[3].point, 40u);
  EXPECT_EQ(d[3].flow, 3);
  EXPECT_EQ(d[3].capacity, 3);
  EXPECT_EQ(d[3].verdict, Verdict::kKeep);
  const Summary& sum = s.summary();
  EXPECT_EQ(sum.keyframes, 3u);
  EXPECT_EQ(sum.points, 4u);
  EXPECT_EQ(sum.evaluated, 3u);
  EXPECT_EQ(sum.kept, 1u);
  EXPECT_EQ(sum.culled, 2u);
  EXPECT_EQ(sum.skipped, 1u);
  EXPECT_EQ(sum.pairs, 3u);
  EXPECT_EQ(sum.arcs, 11u);
  EXPECT_EQ(sum.max_flow, 3);
  EXPECT_EQ(sum.total_cost, (1 + 5) + (1 + 7) + (1 + 5));
  EXPECT_TRUE(test::flow_certificate(s.solver(), s.network().source(), s.network().sink()));
}

TEST_F(HandWindow, LoosePairsKeepEverything) {
  Params p;
  p.pair_capacity = 2;
  Sparsifier s(kCaps, p);
  ASSERT_EQ(s.run(window_), Status::kOk);
  const PointDecision* d = s.decisions();
  EXPECT_EQ(d[1].flow, 1);
  EXPECT_EQ(d[2].flow, 1);
  EXPECT_EQ(d[3].flow, 3);
  EXPECT_EQ(s.summary().kept, 3u);
  EXPECT_EQ(s.summary().max_flow, 5);
  // AB: 40 (1+5), 30 (3+5); AC: 40 (1+7); BC: 40 (1+5), 20 (3+5).
  EXPECT_EQ(s.summary().total_cost, 6 + 8 + 8 + 6 + 8);
}

TEST_F(HandWindow, ThetaIsAStrictThreshold) {
  Params p;
  p.pair_capacity = 1;
  p.theta = 1.0;  // flow 3 of 3 is not > 3
  Sparsifier s(kCaps, p);
  ASSERT_EQ(s.run(window_), Status::kOk);
  EXPECT_EQ(s.decisions()[3].verdict, Verdict::kCull);
  EXPECT_EQ(s.summary().kept, 0u);
  EXPECT_EQ(decide(3, 3, 0.999), Verdict::kKeep);
  EXPECT_EQ(decide(1, 2, 0.5), Verdict::kCull);
  EXPECT_EQ(decide(2, 3, 0.5), Verdict::kKeep);
  EXPECT_EQ(decide(0, 1, 0.0), Verdict::kCull);
  EXPECT_EQ(decide(0, 0, 0.5), Verdict::kSkip);
}

// Equal costs everywhere: the pair takes the smallest ids, whatever the
// insertion order of the observations.
TEST(Sparsifier, TiesGoToTheSmallerPointId) {
  Window w(kCaps);
  ASSERT_EQ(add(w, 1, 0, 0, 0, {{9, 100, 100}, {5, 300, 100}, {3, 500, 100}, {7, 700, 100}}), Status::kOk);
  ASSERT_EQ(add(w, 2, 1, 0, 0, {{3, 100, 100}, {7, 300, 100}, {9, 500, 100}, {5, 700, 100}}), Status::kOk);
  for (std::int64_t m = 1; m <= 4; ++m) {
    Params p;
    p.pair_capacity = m;
    Sparsifier s(kCaps, p);
    ASSERT_EQ(s.run(w), Status::kOk);
    const PointId order[] = {3, 5, 7, 9};
    for (std::uint32_t i = 0; i < 4; ++i) {
      EXPECT_EQ(s.decisions()[i].point, order[i]);
      EXPECT_EQ(s.decisions()[i].flow, i < m ? 1 : 0) << "M=" << m << " point " << order[i];
    }
  }
}

TEST(Sparsifier, EmptyAndSingleKeyframeWindows) {
  Window w(kCaps);
  Sparsifier s(kCaps, Params{});
  ASSERT_EQ(s.run(w), Status::kOk);
  EXPECT_EQ(s.decision_count(), 0u);
  EXPECT_EQ(s.summary().max_flow, 0);
  EXPECT_EQ(s.summary().arcs, 0u);
  ASSERT_EQ(add(w, 1, 0, 0, 0, {{1, 1, 1}, {2, 2, 2}}), Status::kOk);
  ASSERT_EQ(s.run(w), Status::kOk);
  EXPECT_EQ(s.decision_count(), 2u);
  EXPECT_EQ(s.summary().skipped, 2u);
  EXPECT_EQ(s.summary().evaluated, 0u);
  EXPECT_EQ(s.decisions()[1].verdict, Verdict::kSkip);
}

TEST(Sparsifier, ValidateParams) {
  EXPECT_EQ(Sparsifier::validate(Params{}), Status::kOk);
  const auto with = [](auto edit) {
    Params p;
    edit(p);
    return Sparsifier::validate(p);
  };
  EXPECT_EQ(with([](Params& p) { p.pair_capacity = 1; }), Status::kOk);
  EXPECT_EQ(with([](Params& p) { p.pair_capacity = 0; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) { p.pair_capacity = -3; }), Status::kInvalidArgument);
  // The solver's arc capacities are 32-bit: M up to INT32_MAX, with a budget too.
  EXPECT_EQ(with([](Params& p) { p.pair_capacity = INT32_MAX; }), Status::kOk);
  EXPECT_EQ(with([](Params& p) { p.pair_capacity = std::int64_t{INT32_MAX} + 1; }), Status::kInvalidArgument);
  // Undefined term bits would be ignored silently.
  EXPECT_EQ(with([](Params& p) { p.cost_terms = kSpatialCost; }), Status::kOk);
  EXPECT_EQ(with([](Params& p) { p.cost_terms = 0xff; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) { p.track_terms = kTrackAngle; }), Status::kOk);
  EXPECT_EQ(with([](Params& p) { p.track_terms = 0xf0; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) {
              p.pair_capacity = std::int64_t{1} << 40;
              p.budget = {BudgetKind::kPoints, 1, 0.0};
            }),
            Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) { p.theta = 0; }), Status::kOk);
  EXPECT_EQ(with([](Params& p) { p.theta = 1; }), Status::kOk);
  EXPECT_EQ(with([](Params& p) { p.theta = -0.01; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) { p.theta = 1.01; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) { p.theta = std::nan(""); }), Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) { p.theta = std::numeric_limits<double>::infinity(); }),
            Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) { p.box_width = 0; p.box_height = 0; }), Status::kOk);
  EXPECT_EQ(with([](Params& p) { p.box_width = -1; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](Params& p) { p.box_height = -1; }), Status::kInvalidArgument);

  Window w(kCaps);
  ASSERT_EQ(add(w, 1, 0, 0, 0, {{1, 1, 1}}), Status::kOk);
  Params bad;
  bad.theta = 2;
  Sparsifier s(kCaps, bad);
  EXPECT_EQ(s.run(w), Status::kInvalidArgument);
  EXPECT_EQ(s.decision_count(), 0u);
}

TEST(Sparsifier, PairArcCapacityIsCheckedAtBuild) {
  // One point seen by 4 keyframes needs 6 pair arcs.
  Window w(kCaps);
  for (KeyframeId k = 0; k < 4; ++k) {
    ASSERT_EQ(add(w, k, static_cast<double>(k), 0, 0, {{1, 10, 10}, {2, 50, 50}}), Status::kOk);
  }
  Capacities tight = kCaps;
  tight.max_pair_arcs = 11;  // 12 needed
  Sparsifier s(tight, Params{});
  EXPECT_EQ(s.run(w), Status::kCapacityExceeded);
  EXPECT_EQ(s.decision_count(), 0u);
  EXPECT_EQ(s.summary().points, 0u);
  EXPECT_EQ(s.network().pair_arc_count(), 0u);
  tight.max_pair_arcs = 12;
  Sparsifier ok(tight, Params{});
  EXPECT_EQ(ok.run(w), Status::kOk);
  EXPECT_EQ(ok.summary().kept, 2u);
  // A window larger than the sparsifier's capacities is refused, not overrun.
  Capacities few = kCaps;
  few.max_keyframes = 3;
  Sparsifier small(few, Params{});
  EXPECT_EQ(small.run(w), Status::kCapacityExceeded);
  few = kCaps;
  few.max_points = 1;
  Sparsifier narrow(few, Params{});
  EXPECT_EQ(narrow.run(w), Status::kCapacityExceeded);
}

// From zero flow the labels need B^2 x (largest arc cost + 1) <= 2^62, B the
// smallest power of two >= nodes + 6 (nodes: the window's points and pairs).
// 723 keyframes that all see one point (c_c(2) = 38.4e6; 261,726 nodes:
// B = 2^18) are decided; 724 (262,450 nodes: B = 2^19) are refused, though
// (nodes + 2)^2 x (c_c(2) + 1) < 2^62 there too. Beyond the bound the window
// is a capacity (kCapacityExceeded), not bad input: the closed form decides it.
TEST(Sparsifier, ZeroFlowLabelBoundIsAPowerOfTwo) {
  for (const std::uint32_t k : {723u, 724u}) {
    Capacities caps;
    caps.max_keyframes = k;
    caps.max_points = 2 * k;
    caps.max_observations = 4 * k;
    caps.max_pair_arcs = k * (k - 1) / 2 + 2 * k;
    Window w(caps);
    for (std::uint32_t i = 0; i < k; ++i) {
      Keyframe kf;
      kf.id = 1000 + i;
      kf.centre[0] = i;
      std::vector<Observation> obs{{1, 10, 10}, {100 + i, 300, 300}};
      if (i > 0) obs.push_back({100 + i - 1, 500, 400});
      ASSERT_EQ(w.add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size())), Status::kOk);
    }
    Sparsifier closed(caps, Params{}, SolveMode::kFromScratch, Start::kClosedForm);
    ASSERT_EQ(closed.run(w), Status::kOk);
    EXPECT_GT(closed.summary().kept, 0u);
    const std::uint64_t nodes = closed.network().evaluated_count() + closed.network().pair_count();
    std::vector<std::int64_t> table(k + 1);
    connectivity_costs(k, table.data());
    const long double stated = static_cast<long double>(nodes + 2) * (nodes + 2) * (table[2] + 1);
    EXPECT_LT(stated, static_cast<long double>(std::uint64_t{1} << 62)) << k;
    std::uint64_t base = 1;
    while (base < nodes + 6) base <<= 1;
    const bool fits = static_cast<long double>(base) * base * (table[2] + 1) <=
                      static_cast<long double>(std::uint64_t{1} << 62);
    EXPECT_EQ(fits, k == 723u) << k;
    Sparsifier zero(caps, Params{}, SolveMode::kFromScratch, Start::kZeroFlow);
    EXPECT_EQ(zero.run(w), fits ? Status::kOk : Status::kCapacityExceeded) << k << " keyframes, " << nodes << " nodes";
  }
}

// A keyframe beyond the per-keyframe scratch (max_keyframe_observations) of
// either network is refused before it is scored, never overrun; within it the
// decisions are those of a sparsifier without the limit.
TEST(Sparsifier, KeyframeObservationCapacityIsChecked) {
  Window w(kCaps);
  for (KeyframeId k = 0; k < 4; ++k) {
    ASSERT_EQ(add(w, k, static_cast<double>(k), 0, 0, {{1, 10, 10}, {2, 50, 50}, {3, 90, 90}}), Status::kOk);
  }
  Capacities tight = kCaps;
  tight.max_keyframe_observations = 2;
  for (const SolveMode mode : {SolveMode::kFromScratch, SolveMode::kIncremental}) {
    Sparsifier refused(tight, Params{}, mode);
    EXPECT_EQ(mode == SolveMode::kIncremental ? refused.update(w) : refused.run(w), Status::kCapacityExceeded);
    EXPECT_EQ(refused.decision_count(), 0u);
  }
  tight.max_keyframe_observations = 3;
  Sparsifier limited(tight, Params{}, SolveMode::kIncremental);
  Sparsifier unlimited(kCaps, Params{}, SolveMode::kIncremental);
  ASSERT_EQ(limited.update(w), Status::kOk);
  ASSERT_EQ(unlimited.update(w), Status::kOk);
  ASSERT_EQ(limited.decision_count(), unlimited.decision_count());
  for (std::uint32_t i = 0; i < limited.decision_count(); ++i) {
    EXPECT_EQ(limited.decisions()[i].point, unlimited.decisions()[i].point);
    EXPECT_EQ(limited.decisions()[i].verdict, unlimited.decisions()[i].verdict);
    EXPECT_EQ(limited.decisions()[i].flow, unlimited.decisions()[i].flow);
  }
}

TEST(Sparsifier, ExhaustedBudgetKeepsEveryEvaluatedPoint) {
  const auto c = test::random_case(7, 10, 60);
  Window w(Capacities{});
  ASSERT_TRUE(test::load(w, c.frames));
  Params p = c.params;
  p.pair_capacity = 1;
  p.theta = 1.0;  // would cull every point on a finished solve
  Sparsifier s(Capacities{}, p);
  ASSERT_EQ(s.run(w), Status::kOk);
  ASSERT_GT(s.summary().evaluated, 0u);
  ASSERT_EQ(s.summary().kept, 0u);
  solver::Budget budget;
  budget.work_units = 1;
  ASSERT_EQ(s.run(w, budget), Status::kBudgetExhausted);
  EXPECT_EQ(s.summary().kept, s.summary().evaluated);
  EXPECT_EQ(s.summary().culled, 0u);
  EXPECT_EQ(s.decision_count(), s.summary().points);
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    EXPECT_NE(s.decisions()[i].verdict, Verdict::kCull);
  }
}

// Same keyframes reached by different histories (observation order, a removed
// keyframe in between) give identical decisions.
TEST(Sparsifier, DecisionsDependOnTheWindowContentOnly) {
  const Capacities kRandomCaps{16, 2048, 8192, 32768};
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    auto c = test::random_case(seed);
    Window a(kRandomCaps);
    ASSERT_TRUE(test::load(a, c.frames));
    Sparsifier sa(kRandomCaps, c.params);
    ASSERT_EQ(sa.run(a), Status::kOk);

    Window b(kRandomCaps);
    auto reversed = c.frames;
    for (auto& f : reversed) std::reverse(f.observations.begin(), f.observations.end());
    test::RefKeyframe extra;
    extra.id = 1u << 30;
    extra.observations = {{c.frames[0].observations.empty() ? 1 : c.frames[0].observations[0].point, 1, 1},
                          {12345678, 2, 2}};
    reversed.insert(reversed.begin(), extra);
    ASSERT_TRUE(test::load(b, reversed));
    ASSERT_EQ(b.remove_keyframe(extra.id), Status::kOk);
    Sparsifier sb(kRandomCaps, c.params);
    ASSERT_EQ(sb.run(b), Status::kOk);

    ASSERT_EQ(sa.decision_count(), sb.decision_count());
    for (std::uint32_t i = 0; i < sa.decision_count(); ++i) {
      EXPECT_EQ(sa.decisions()[i].point, sb.decisions()[i].point);
      EXPECT_EQ(sa.decisions()[i].flow, sb.decisions()[i].flow);
      EXPECT_EQ(sa.decisions()[i].verdict, sb.decisions()[i].verdict);
    }
    EXPECT_EQ(sa.summary().total_cost, sb.summary().total_cost);
  }
}

TEST(Sparsifier, MemoryIsReportedAndFixed) {
  Sparsifier s(Capacities{}, Params{});
  const std::size_t bytes = s.memory_bytes();
  EXPECT_GT(bytes, s.network().memory_bytes());
  EXPECT_GT(bytes, s.solver().memory_bytes());
  const auto c = test::random_case(3);
  Window w(Capacities{});
  ASSERT_TRUE(test::load(w, c.frames));
  ASSERT_EQ(s.run(w), Status::kOk);
  EXPECT_EQ(s.memory_bytes(), bytes);
}

TEST(Sparsifier, ToStrings) {
  EXPECT_STREQ(to_string(Verdict::kKeep), "keep");
  EXPECT_STREQ(to_string(Verdict::kCull), "cull");
  EXPECT_STREQ(to_string(Verdict::kSkip), "skip");
  EXPECT_STREQ(to_string(Status::kOk), "ok");
  EXPECT_STREQ(to_string(Status::kCapacityExceeded), "capacity_exceeded");
  EXPECT_STREQ(to_string(Status::kBudgetExhausted), "budget_exhausted");
}

}  // namespace
}  // namespace keepless::core
