// Seeded random windows: the sparsifier (SSP solver on the built network), the
// closed form, and the independent naive reference (tests/support) agree
// exactly on every flow, verdict, max flow and total cost; the solver's
// optimality certificate holds; LEMON's network simplex finds the same cost.

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <memory>
#include <tuple>
#include <vector>

#include "case_count.hpp"
#include "decision_checks.hpp"
#include "flow_certificate.hpp"
#include "keepless/core/closed_form.hpp"
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"
#include "reference_sparsifier.hpp"

#include <lemon/list_graph.h>
#include <lemon/network_simplex.h>

namespace keepless::core {
namespace {

const Capacities kCaps{16, 2048, 8192, 32768};

::testing::AssertionResult agrees(const Sparsifier& s, const ClosedForm& closed,
                                  const test::RefResult& ref) {
  const Summary& sum = s.summary();
  const PaperNetwork& net = s.network();
  std::uint32_t verdicts[3];
  if (auto match = test::decisions_match(s, ref, verdicts); !match) return match;
  const std::uint32_t kept = verdicts[0], culled = verdicts[1], skipped = verdicts[2];
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    if (net.point_views(i) != ref.points[i].views) {
      return ::testing::AssertionFailure() << "point " << ref.points[i].id << ": views "
                                           << net.point_views(i) << " vs " << ref.points[i].views;
    }
    if (closed.point_flow(i) != s.decisions()[i].flow) {
      return ::testing::AssertionFailure() << "point " << ref.points[i].id << ": closed form flow "
                                           << closed.point_flow(i) << " vs " << s.decisions()[i].flow;
    }
  }
  // The solver's arc flows are the closed form's selection, arc by arc.
  for (std::uint32_t a = 0; a < net.pair_arc_count(); ++a) {
    if ((s.solver().flow(net.arc_solver_id(a)) == 1) != closed.arc_selected(a)) {
      return ::testing::AssertionFailure() << "pair arc " << a << " selection differs";
    }
  }
  if (sum.max_flow != ref.max_flow || sum.total_cost != ref.total_cost ||
      closed.max_flow() != ref.max_flow || closed.total_cost() != ref.total_cost) {
    return ::testing::AssertionFailure()
           << "max flow " << sum.max_flow << " / closed " << closed.max_flow() << " / ref "
           << ref.max_flow << "; cost " << sum.total_cost << " / closed " << closed.total_cost()
           << " / ref " << ref.total_cost;
  }
  if (sum.points != ref.points.size() || sum.evaluated != ref.evaluated || sum.pairs != ref.pairs ||
      net.pair_arc_count() != ref.pair_arcs || sum.arcs != ref.evaluated + ref.pair_arcs + ref.pairs ||
      sum.kept != kept || sum.culled != culled || sum.skipped != skipped ||
      sum.kept + sum.culled != sum.evaluated) {
    return ::testing::AssertionFailure() << "summary counts differ";
  }
  return ::testing::AssertionSuccess();
}

// Min-cost flow of the solver's value by LEMON's network simplex.
std::int64_t lemon_cost(const solver::MinCostFlow& s, solver::NodeId source, solver::NodeId sink) {
  using Graph = lemon::ListDigraph;
  Graph g;
  std::vector<Graph::Node> nodes;
  for (std::int32_t v = 0; v < s.node_count(); ++v) nodes.push_back(g.addNode());
  Graph::ArcMap<std::int64_t> cap(g), cost(g);
  for (solver::ArcId a = 0; a < s.arc_count(); ++a) {
    const auto arc = g.addArc(nodes[static_cast<std::size_t>(s.tail(a))],
                              nodes[static_cast<std::size_t>(s.head(a))]);
    cap[arc] = s.capacity(a);
    cost[arc] = s.cost(a);
  }
  lemon::NetworkSimplex<Graph, std::int64_t, std::int64_t> ns(g);
  ns.upperMap(cap).costMap(cost).stSupply(nodes[static_cast<std::size_t>(source)],
                                          nodes[static_cast<std::size_t>(sink)], s.flow_value());
  if (ns.run() != lemon::NetworkSimplex<Graph, std::int64_t, std::int64_t>::OPTIMAL) return -1;
  return ns.totalCost<std::int64_t>();
}

// Params are fixed per Sparsifier; building one per window would dominate the
// test's run time, so one is kept per distinct Params.
class SparsifierCache {
 public:
  Sparsifier& get(const Params& p, Start start) {
    const auto key = std::make_tuple(p.pair_capacity, p.theta, p.box_width, p.box_height, start);
    auto& slot = cache_[key];
    if (!slot) slot = std::make_unique<Sparsifier>(kCaps, p, SolveMode::kFromScratch, start);
    return *slot;
  }

 private:
  std::map<std::tuple<std::int64_t, double, std::int32_t, std::int32_t, Start>,
           std::unique_ptr<Sparsifier>>
      cache_;
};

TEST(ReferenceCrossCheck, RandomWindows) {
  SparsifierCache sparsifiers;
  Window window(kCaps);
  ClosedForm closed(kCaps);
  std::uint32_t windows = 0, culled = 0, kept = 0, bound = 0;
  for (std::uint64_t seed = 1; seed <= test::cases(1500); ++seed) {
    const test::RandomCase c = test::random_case(seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    // The product's closed-form start, and successive shortest paths from
    // zero flow: both must be the reference's canonical optimum.
    Sparsifier& zero = sparsifiers.get(c.params, Start::kZeroFlow);
    ASSERT_EQ(zero.run(window), Status::kOk) << "seed " << seed;
    Sparsifier& s = sparsifiers.get(c.params, Start::kClosedForm);
    ASSERT_EQ(s.run(window), Status::kOk) << "seed " << seed;
    ASSERT_TRUE(s.solver().stats().certified) << "seed " << seed;
    closed.solve(s.network(), c.params);
    const test::RefResult ref = test::reference_sparsify(c.frames, c.params);
    ASSERT_TRUE(agrees(s, closed, ref)) << "seed " << seed;
    ASSERT_TRUE(agrees(zero, closed, ref)) << "seed " << seed << " (zero-flow start)";
    if (seed % 5 == 0) {
      ASSERT_TRUE(test::flow_certificate(s.solver(), s.network().source(), s.network().sink()))
          << "seed " << seed;
    }
    if (seed % 25 == 0) {
      ASSERT_EQ(lemon_cost(s.solver(), s.network().source(), s.network().sink()),
                s.summary().total_cost)
          << "seed " << seed;
    }
    ++windows;
    culled += s.summary().culled;
    kept += s.summary().kept;
    for (std::uint32_t q = 0; q < s.network().pair_count(); ++q) {
      bound += s.solver().flow(s.network().pair_sink_arc(q)) == c.params.pair_capacity;
    }
  }
  // The generator must produce the cases the check is for.
  EXPECT_EQ(windows, test::cases(1500));
  EXPECT_GT(culled, test::cases(1000));
  EXPECT_GT(kept, test::cases(1000));
  EXPECT_GT(bound, test::cases(1000));
}

// Windows of 24 to 40 keyframes with a few points seen by all of them:
// c_m(2) passes 1,024 (1,470 at m = 24), so the closed-form start's
// histogram cannot span the unit costs of the pairs that hold both those
// points and two-view ones, and it selects with nth_element instead. Both
// starts must still be the reference's optimum.
TEST(ReferenceCrossCheck, WideCostRanges) {
  const Capacities caps{40, 4096, 16384, 65536};
  Window window(caps);
  ClosedForm closed(caps);
  std::uint32_t wide = 0;
  for (std::uint64_t seed = 1; seed <= 200 && wide < 60 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(50000 + seed, 40, 150);
    if (c.frames.size() < 24) continue;
    for (std::uint64_t j = 0; j < 3; ++j) {  // ids the generator never draws
      for (std::size_t f = 0; f < c.frames.size(); ++f) {
        c.frames[f].observations.push_back({(std::uint64_t{1} << 62) + j, 8.0 * static_cast<double>(f + j),
                                            6.0 * static_cast<double>(f)});
      }
    }
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    Sparsifier s(caps, c.params);
    Sparsifier zero(caps, c.params, SolveMode::kFromScratch, Start::kZeroFlow);
    ASSERT_EQ(s.run(window), Status::kOk) << "seed " << seed;
    ASSERT_EQ(zero.run(window), Status::kOk) << "seed " << seed;
    ASSERT_TRUE(s.solver().stats().certified) << "seed " << seed;
    ASSERT_GE(s.network().max_views(), 24u);
    closed.solve(s.network(), c.params);
    const test::RefResult ref = test::reference_sparsify(c.frames, c.params);
    ASSERT_TRUE(agrees(s, closed, ref)) << "seed " << seed;
    ASSERT_TRUE(agrees(zero, closed, ref)) << "seed " << seed << " (zero-flow start)";
    ++wide;
  }
  EXPECT_EQ(wide, 60u);
}

// Keypoints far outside any image (cell indices clamp), at huge magnitudes
// where the box test's subtraction rounds, and next to clamped cell borders:
// the grid still counts exactly what the all-pairs reference counts.
TEST(ReferenceCrossCheck, ExtremeCoordinates) {
  const double bases[] = {0.0,    -1e300, 1e300,  1.7e308, -1.7e308, 1e15 + 0.5, -3e12,
                          68719476736.0 /* 2^30 * 64 */, -51539607552.0 /* -2^30 * 48 */};
  const double offsets[] = {0, 0.25, 16, 24, 31.999, 32, 32.5, -32, -24, -1};
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    test::Rng rng(seed);
    test::RandomCase c = test::random_case(seed, 6, 40);
    for (auto& f : c.frames) {
      for (auto& o : f.observations) {
        o.u = bases[rng.between(0, 8)] + offsets[rng.between(0, 9)];
        o.v = rng.chance(50) ? o.u : bases[rng.between(0, 8)] + offsets[rng.between(0, 9)];
      }
    }
    Window window(kCaps);
    ASSERT_TRUE(test::load(window, c.frames));
    Sparsifier s(kCaps, c.params);
    ClosedForm closed(kCaps);
    ASSERT_EQ(s.run(window), Status::kOk);
    closed.solve(s.network(), c.params);
    ASSERT_TRUE(agrees(s, closed, test::reference_sparsify(c.frames, c.params))) << "seed " << seed;
  }
}

// A window sliding over a long sequence: the removal and compaction path
// feeds the same answers as a fresh reference of the current content.
TEST(ReferenceCrossCheck, SlidingWindow) {
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    const test::RandomCase c = test::random_case(1000 + seed, 16, 200);
    const std::uint32_t size = 4 + static_cast<std::uint32_t>(seed % 5);
    Window window(kCaps);
    Sparsifier s(kCaps, c.params);
    ClosedForm closed(kCaps);
    for (const auto& f : c.frames) {
      if (window.keyframe_count() == size) {
        ASSERT_EQ(window.remove_keyframe(window.keyframe(seed % 2 ? 0 : 1).id), Status::kOk);
      }
      Keyframe kf;
      kf.id = f.id;
      std::copy(f.centre, f.centre + 3, kf.centre);
      std::vector<Observation> obs;
      for (const auto& o : f.observations) obs.push_back({o.point, o.u, o.v});
      ASSERT_EQ(window.add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size())),
                Status::kOk);
      ASSERT_EQ(s.run(window), Status::kOk);
      closed.solve(s.network(), c.params);
      const auto ref = test::reference_sparsify(test::ref_frames_of(window), c.params);
      ASSERT_TRUE(agrees(s, closed, ref)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(test::flow_certificate(s.solver(), s.network().source(), s.network().sink()));
    }
  }
}

}  // namespace
}  // namespace keepless::core
