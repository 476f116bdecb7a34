#pragma once
// Optimality certificate of the min-cost max-flow inside a core Sparsifier,
// by the solver tests' checks (keepless_solver_test_support): feasibility,
// conservation, reported value and cost, complementary slackness under
// solver.potential(), and maximality. The core network has no TestNetwork,
// so one is read back from the solver's public arrays.

#include <gtest/gtest.h>

#include <string>

#include "keepless/solver/min_cost_flow.hpp"
// By path: tests/core's own name would shadow the solver's header.
#include "../solver/flow_certificate.hpp"

namespace keepless::test {

inline ::testing::AssertionResult flow_certificate(const solver::MinCostFlow& s,
                                                   solver::NodeId source, solver::NodeId sink) {
  solver::test::TestNetwork net;
  net.label = "core network";
  net.node_count = s.node_count();
  net.source = source;
  net.sink = sink;
  net.arcs.reserve(static_cast<std::size_t>(s.arc_count()));
  for (solver::ArcId a = 0; a < s.arc_count(); ++a) {
    net.arcs.push_back({s.tail(a), s.head(a), s.capacity(a), s.cost(a)});
  }
  if (auto certified = solver::test::is_certified_min_cost_flow(s, net); !certified) return certified;
  return solver::test::is_maximum_flow(s, net);
}

}  // namespace keepless::test
