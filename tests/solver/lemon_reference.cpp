#include "lemon_reference.hpp"

// LEMON's SmartDigraph pushes default-constructed PODs with uninitialised
// fields; GCC 12 reports that where it is inlined (here), not in the header.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include <lemon/network_simplex.h>
#include <lemon/preflow.h>
#include <lemon/smart_graph.h>

#include <vector>

namespace keepless::solver::test {
namespace {

struct LemonGraph {
  lemon::SmartDigraph graph;
  lemon::SmartDigraph::ArcMap<Flow> capacity{graph};
  lemon::SmartDigraph::ArcMap<Cost> cost{graph};
  std::vector<lemon::SmartDigraph::Node> nodes;

  explicit LemonGraph(const TestNetwork& net) {
    for (std::int32_t v = 0; v < net.node_count; ++v) nodes.push_back(graph.addNode());
    for (const TestArc& arc : net.arcs) {
      // A self-loop can never be part of an optimal s-t flow's useful part
      // (costs are >= 0), so the reference simply omits it.
      if (arc.from == arc.to) continue;
      const auto a = graph.addArc(nodes[static_cast<std::size_t>(arc.from)],
                                  nodes[static_cast<std::size_t>(arc.to)]);
      capacity[a] = arc.capacity;
      cost[a] = arc.cost;
    }
  }
};

}  // namespace

Flow lemon_max_flow(const TestNetwork& net) {
  LemonGraph g(net);
  lemon::Preflow<lemon::SmartDigraph, lemon::SmartDigraph::ArcMap<Flow>> preflow(
      g.graph, g.capacity, g.nodes[static_cast<std::size_t>(net.source)],
      g.nodes[static_cast<std::size_t>(net.sink)]);
  preflow.runMinCut();
  return preflow.flowValue();
}

std::optional<Cost> lemon_min_cost(const TestNetwork& net, Flow value) {
  LemonGraph g(net);
  lemon::NetworkSimplex<lemon::SmartDigraph, Flow, Cost> simplex(g.graph);
  simplex.upperMap(g.capacity)
      .costMap(g.cost)
      .stSupply(g.nodes[static_cast<std::size_t>(net.source)],
                g.nodes[static_cast<std::size_t>(net.sink)], value);
  if (simplex.run() != decltype(simplex)::OPTIMAL) return std::nullopt;
  return simplex.totalCost();
}

}  // namespace keepless::solver::test
