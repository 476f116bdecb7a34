#include "flow_certificate.hpp"

#include <algorithm>
#include <cstddef>

namespace keepless::solver::test {

::testing::AssertionResult is_certified_min_cost_flow(const MinCostFlow& solver,
                                                      const TestNetwork& net) {
  const auto fail = [&net]() { return ::testing::AssertionFailure() << net.label << ": "; };
  if (solver.node_count() != net.node_count) {
    return fail() << "node_count " << solver.node_count() << " != " << net.node_count;
  }
  if (solver.arc_count() != static_cast<std::int32_t>(net.arcs.size())) {
    return fail() << "arc_count " << solver.arc_count() << " != " << net.arcs.size();
  }

  std::vector<Flow> excess(static_cast<std::size_t>(net.node_count), 0);
  Cost cost_sum = 0;
  for (std::size_t i = 0; i < net.arcs.size(); ++i) {
    const TestArc& arc = net.arcs[i];
    const auto a = static_cast<ArcId>(i);
    if (solver.tail(a) != arc.from || solver.head(a) != arc.to ||
        solver.capacity(a) != arc.capacity || solver.cost(a) != arc.cost) {
      return fail() << "arc " << a << " does not echo its input";
    }
    const Flow f = solver.flow(a);
    if (f < 0 || f > arc.capacity) {
      return fail() << "arc " << a << " flow " << f << " outside [0, " << arc.capacity << "]";
    }
    if (arc.from == arc.to && f != 0) {
      return fail() << "self-loop arc " << a << " carries flow " << f;
    }
    excess[static_cast<std::size_t>(arc.from)] -= f;
    excess[static_cast<std::size_t>(arc.to)] += f;
    Cost term = 0;
    if (__builtin_mul_overflow(f, arc.cost, &term) ||
        __builtin_add_overflow(cost_sum, term, &cost_sum)) {
      return fail() << "sum(flow * cost) overflows";
    }

    // Reduced cost cost + pi(tail) - pi(head), overflow-checked because a
    // solver may park unreachable nodes at a huge potential.
    Cost reduced = 0;
    if (__builtin_add_overflow(arc.cost, solver.potential(arc.from), &reduced) ||
        __builtin_sub_overflow(reduced, solver.potential(arc.to), &reduced)) {
      return fail() << "reduced cost of arc " << a << " overflows int64 (potentials "
                    << solver.potential(arc.from) << ", " << solver.potential(arc.to) << ")";
    }
    if (f < arc.capacity && reduced < 0) {
      return fail() << "arc " << a << " (" << arc.from << "->" << arc.to << ", flow " << f << "/"
                    << arc.capacity << ") has residual capacity but reduced cost " << reduced;
    }
    if (f > 0 && reduced > 0) {
      return fail() << "arc " << a << " (" << arc.from << "->" << arc.to << ", flow " << f << "/"
                    << arc.capacity << ") carries flow at reduced cost " << reduced;
    }
  }

  for (std::int32_t v = 0; v < net.node_count; ++v) {
    const Flow e = excess[static_cast<std::size_t>(v)];
    if (v == net.source) {
      if (-e != solver.flow_value()) {
        return fail() << "source net outflow " << -e << " != flow_value " << solver.flow_value();
      }
    } else if (v == net.sink) {
      if (e != solver.flow_value()) {
        return fail() << "sink net inflow " << e << " != flow_value " << solver.flow_value();
      }
    } else if (e != 0) {
      return fail() << "node " << v << " violates conservation by " << e;
    }
  }
  if (solver.flow_value() < 0) return fail() << "negative flow_value " << solver.flow_value();
  if (cost_sum != solver.total_cost()) {
    return fail() << "total_cost " << solver.total_cost() << " != sum(flow * cost) " << cost_sum;
  }
  return ::testing::AssertionSuccess();
}

std::vector<char> residual_reach(const TestNetwork& net, const std::vector<Flow>& flows) {
  std::vector<char> reached(static_cast<std::size_t>(net.node_count), 0);
  std::vector<NodeId> queue{net.source};
  reached[static_cast<std::size_t>(net.source)] = 1;
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const NodeId v = queue[q];
    for (std::size_t i = 0; i < net.arcs.size(); ++i) {
      const TestArc& arc = net.arcs[i];
      const Flow f = flows[i];
      NodeId next = -1;
      if (arc.from == v && f < arc.capacity) next = arc.to;
      if (arc.to == v && f > 0) next = arc.from;
      if (next >= 0 && !reached[static_cast<std::size_t>(next)]) {
        reached[static_cast<std::size_t>(next)] = 1;
        queue.push_back(next);
      }
    }
  }
  return reached;
}

::testing::AssertionResult is_maximum_flow(const MinCostFlow& solver, const TestNetwork& net) {
  if (residual_reach(net, arc_flows(solver))[static_cast<std::size_t>(net.sink)]) {
    return ::testing::AssertionFailure() << net.label << ": residual graph still has an s-t path";
  }
  return ::testing::AssertionSuccess();
}

::testing::AssertionResult is_fresh_optimum(const MinCostFlow& solver, const TestNetwork& net) {
  if (auto certified = is_certified_min_cost_flow(solver, net); !certified) return certified;
  if (auto maximum = is_maximum_flow(solver, net); !maximum) return maximum;
  MinCostFlow fresh(Capacity{std::max(net.node_count, 1), std::max<std::int32_t>(static_cast<std::int32_t>(net.arcs.size()), 1)});
  if (load(fresh, net) != Status::kOptimal || fresh.solve(net.source, net.sink) != Status::kOptimal) {
    return ::testing::AssertionFailure() << net.label << ": the fresh solve failed";
  }
  if (solver.flow_value() != fresh.flow_value() || solver.total_cost() != fresh.total_cost()) {
    return ::testing::AssertionFailure()
           << net.label << ": value " << solver.flow_value() << " cost " << solver.total_cost()
           << ", a fresh solve " << fresh.flow_value() << " / " << fresh.total_cost();
  }
  return ::testing::AssertionSuccess();
}

std::vector<Flow> arc_flows(const MinCostFlow& solver) {
  std::vector<Flow> flows;
  for (ArcId a = 0; a < solver.arc_count(); ++a) flows.push_back(solver.flow(a));
  return flows;
}

}  // namespace keepless::solver::test
