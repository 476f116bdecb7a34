// The paper's ablation switches cost terms off: a switched-off term costs 0 on
// its arcs, the solver's optimum still equals the per-pair closed form, and
// c_b alone never changes which points are kept (it is constant per pair).
// Params::spatial_weight multiplies c_s, and the optimum stays exact.

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "case_count.hpp"
#include "keepless/core/closed_form.hpp"
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"

namespace keepless::core {
namespace {

const Capacities kCaps{16, 2048, 8192, 32768};

std::vector<PointDecision> decisions_of(const Sparsifier& s) {
  return {s.decisions(), s.decisions() + s.decision_count()};
}

bool same_verdicts(const std::vector<PointDecision>& a, const std::vector<PointDecision>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].point != b[i].point || a[i].verdict != b[i].verdict || a[i].flow != b[i].flow) return false;
  }
  return true;
}

TEST(CostTerms, SwitchedOffTermsCostNothingAndTheOptimumStaysCanonical) {
  Window window(kCaps);
  ClosedForm closed(kCaps);
  std::uint32_t nonzero_cs = 0;
  for (std::uint64_t seed = 1; seed <= test::cases(200); ++seed) {
    const test::RandomCase c = test::random_case(seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    std::vector<PointDecision> by_mask[8];
    for (std::uint8_t mask = 0; mask < 8; ++mask) {
      Params p = c.params;
      p.cost_terms = mask;
      Sparsifier s(kCaps, p);
      ASSERT_EQ(s.run(window), Status::kOk) << "seed " << seed;
      const PaperNetwork& net = s.network();
      for (std::uint32_t a = 0; a < net.pair_arc_count(); ++a) {
        if (!(mask & kSpatialCost)) {
          ASSERT_EQ(net.arc_spatial_cost(a), 0);
        }
        if (mask == 7) nonzero_cs += net.arc_spatial_cost(a) > 0;
      }
      for (std::uint32_t q = 0; q < net.pair_count(); ++q) {
        if (mask & kBaselineCost) {
          ASSERT_GE(net.pair_baseline_cost(q), 1);
        } else {
          ASSERT_EQ(net.pair_baseline_cost(q), 0);
        }
      }
      for (std::uint32_t n = 2; n <= net.max_views(); ++n) {
        if (mask & kConnectivityCost) {
          ASSERT_GE(net.connectivity_cost(n), 1);
        } else {
          ASSERT_EQ(net.connectivity_cost(n), 0);
        }
      }
      closed.solve(net, p);
      ASSERT_EQ(closed.total_cost(), s.summary().total_cost) << "seed " << seed << " mask " << int(mask);
      ASSERT_EQ(closed.max_flow(), s.summary().max_flow) << "seed " << seed << " mask " << int(mask);
      for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
        ASSERT_EQ(closed.point_flow(i), s.decisions()[i].flow) << "seed " << seed << " mask " << int(mask);
      }
      by_mask[mask] = decisions_of(s);
    }
    // c_b is constant per pair, so adding it keeps the same points.
    for (std::uint8_t mask = 0; mask < 4; ++mask) {
      EXPECT_TRUE(same_verdicts(by_mask[mask], by_mask[mask | kBaselineCost]))
          << "seed " << seed << " mask " << int(mask);
    }
  }
  EXPECT_GT(nonzero_cs, test::cases(100));  // the windows exercise c_s
}

TEST(CostTerms, TermNames) {
  std::uint8_t terms = 0;
  EXPECT_TRUE(parse_cost_terms("c_s", &terms));
  EXPECT_EQ(terms, kSpatialCost);
  EXPECT_TRUE(parse_cost_terms("c_b,c_s,c_c", &terms));
  EXPECT_EQ(terms, Params{}.cost_terms);
  EXPECT_TRUE(parse_cost_terms("c_s,c_b", &terms));
  for (const char* bad : {"", "c_s,", ",c_b", "c_s,c_s", "c_d", "C_s", "c_s c_b"}) {
    EXPECT_FALSE(parse_cost_terms(bad, &terms)) << bad;
    EXPECT_EQ(terms, kSpatialCost | kBaselineCost);
  }
}

TEST(CostTerms, TheSpatialWeightMultipliesCsAndTheOptimumStaysCanonical) {
  Window window(kCaps);
  ClosedForm closed(kCaps);
  std::uint32_t changed = 0;
  for (std::uint64_t seed = 1; seed <= test::cases(100); ++seed) {
    const test::RandomCase c = test::random_case(seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    Sparsifier paper(kCaps, c.params);
    ASSERT_EQ(paper.run(window), Status::kOk) << "seed " << seed;
    for (const std::int32_t w : {7, 1000, kMaxSpatialWeight}) {
      Params p = c.params;
      p.spatial_weight = w;
      Sparsifier s(kCaps, p);
      ASSERT_EQ(s.run(window), Status::kOk) << "seed " << seed << " weight " << w;
      ASSERT_EQ(s.network().pair_arc_count(), paper.network().pair_arc_count());
      for (std::uint32_t a = 0; a < s.network().pair_arc_count(); ++a) {
        ASSERT_EQ(s.network().arc_spatial_cost(a), w * paper.network().arc_spatial_cost(a)) << "seed " << seed;
      }
      closed.solve(s.network(), p);
      ASSERT_EQ(closed.total_cost(), s.summary().total_cost) << "seed " << seed << " weight " << w;
      for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
        ASSERT_EQ(closed.point_flow(i), s.decisions()[i].flow) << "seed " << seed << " weight " << w;
      }
      changed += !same_verdicts(decisions_of(paper), decisions_of(s));
    }
  }
  EXPECT_GT(changed, test::cases(10));  // a weight that outranks c_c keeps other points
  for (const std::int32_t bad : {0, -1, kMaxSpatialWeight + 1}) {
    Params p;
    p.spatial_weight = bad;
    Sparsifier s(kCaps, p);
    EXPECT_EQ(s.run(Window(kCaps)), Status::kInvalidArgument) << bad;
  }
}

}  // namespace
}  // namespace keepless::core
