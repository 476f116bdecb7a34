#pragma once
// Optimality certificate of a min-cost max-flow, checked from the solver's
// public arrays only: feasibility, conservation, reported value and cost,
// complementary slackness under solver.potential(), and maximality (no
// augmenting path left in the residual graph).

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::test {

inline ::testing::AssertionResult flow_certificate(const solver::MinCostFlow& s,
                                                   solver::NodeId source, solver::NodeId sink) {
  const std::int32_t n = s.node_count();
  const std::int32_t m = s.arc_count();
  std::vector<std::int64_t> balance(static_cast<std::size_t>(n), 0);
  std::int64_t cost = 0;
  for (solver::ArcId a = 0; a < m; ++a) {
    const auto f = s.flow(a);
    if (f < 0 || f > s.capacity(a)) {
      return ::testing::AssertionFailure() << "arc " << a << " flow " << f << " outside [0, "
                                           << s.capacity(a) << "]";
    }
    balance[static_cast<std::size_t>(s.tail(a))] -= f;
    balance[static_cast<std::size_t>(s.head(a))] += f;
    cost += f * s.cost(a);
    const auto reduced = s.cost(a) + s.potential(s.tail(a)) - s.potential(s.head(a));
    if (f < s.capacity(a) && reduced < 0) {
      return ::testing::AssertionFailure() << "forward residual arc " << a << " reduced cost "
                                           << reduced;
    }
    if (f > 0 && reduced > 0) {
      return ::testing::AssertionFailure() << "backward residual arc " << a << " reduced cost "
                                           << -reduced;
    }
  }
  for (solver::NodeId v = 0; v < n; ++v) {
    const auto expected = v == source ? -s.flow_value() : v == sink ? s.flow_value() : 0;
    if (balance[static_cast<std::size_t>(v)] != expected) {
      return ::testing::AssertionFailure() << "node " << v << " imbalance "
                                           << balance[static_cast<std::size_t>(v)];
    }
  }
  if (cost != s.total_cost()) {
    return ::testing::AssertionFailure() << "cost " << cost << " != reported " << s.total_cost();
  }
  // Maximality: breadth-first search over residual arcs must not reach the sink.
  std::vector<std::vector<solver::NodeId>> residual(static_cast<std::size_t>(n));
  for (solver::ArcId a = 0; a < m; ++a) {
    if (s.flow(a) < s.capacity(a)) residual[static_cast<std::size_t>(s.tail(a))].push_back(s.head(a));
    if (s.flow(a) > 0) residual[static_cast<std::size_t>(s.head(a))].push_back(s.tail(a));
  }
  std::vector<char> seen(static_cast<std::size_t>(n), 0);
  std::vector<solver::NodeId> queue{source};
  seen[static_cast<std::size_t>(source)] = 1;
  for (std::size_t i = 0; i < queue.size(); ++i) {
    for (solver::NodeId w : residual[static_cast<std::size_t>(queue[i])]) {
      if (!seen[static_cast<std::size_t>(w)]) {
        seen[static_cast<std::size_t>(w)] = 1;
        queue.push_back(w);
      }
    }
  }
  if (seen[static_cast<std::size_t>(sink)]) {
    return ::testing::AssertionFailure() << "an augmenting path remains: flow is not maximum";
  }
  return ::testing::AssertionSuccess();
}

}  // namespace keepless::test
