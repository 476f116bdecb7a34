#include "compare.hpp"

// LEMON's SmartDigraph pushes default-constructed PODs with uninitialised
// fields; GCC 12 reports that where it is inlined (here), not in the header.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <lemon/cost_scaling.h>
#include <lemon/network_simplex.h>
#include <lemon/preflow.h>
#include <lemon/smart_graph.h>

#include <limits>

namespace keepless::perf {

void network_arcs(const core::Sparsifier& scratch, ArcList* out) {
  const solver::MinCostFlow& m = scratch.solver();
  out->nodes = m.node_count();
  out->source = scratch.network().source();
  out->sink = scratch.network().sink();
  out->evaluated = static_cast<std::int32_t>(scratch.network().evaluated_count());
  out->arcs.clear();
  for (solver::ArcId a = 0; a < m.arc_count(); ++a) {
    out->arcs.push_back({m.tail(a), m.head(a), m.capacity(a), m.cost(a)});
  }
  const solver::ArcId* order = scratch.network().canonical_order();
  out->source_arcs.assign(order, order + out->evaluated);
}

namespace {

bool load(const ArcList& net, solver::MinCostFlow& mcf) {
  bool ok = mcf.reset(net.nodes) == solver::Status::kOptimal;
  for (const ArcList::Arc& a : net.arcs) {
    ok = ok && mcf.add_arc(a.from, a.to, a.capacity, a.cost) == solver::Status::kOptimal;
  }
  return ok;
}

}  // namespace

std::uint64_t time_ours(const ArcList& net, const solver::Clock& clock, solver::MinCostFlow& mcf,
                        core::PairwiseStart& start, solver::Flow* value, solver::Cost* cost,
                        std::uint64_t* solve_ns) {
  const std::uint64_t t0 = clock.now_ns();
  bool ok = load(net, mcf);
  const std::uint64_t loaded = clock.now_ns();
  start.compute(mcf, net.sink, net.source_arcs.data(), net.evaluated);
  ok = ok && mcf.solve_from(net.source, net.sink, start.flow(), start.potential()) ==
                 solver::Status::kOptimal;
  const std::uint64_t t1 = clock.now_ns();
  *solve_ns = t1 - loaded;
  ok = ok && mcf.stats().certified;
  *value = ok ? mcf.flow_value() : -1;
  *cost = ok ? mcf.total_cost() : -1;
  return t1 - t0;
}

std::uint64_t time_ours_zero_flow(const ArcList& net, const solver::Clock& clock,
                                  solver::MinCostFlow& mcf, solver::Flow* value, solver::Cost* cost) {
  const std::uint64_t t0 = clock.now_ns();
  const bool ok = load(net, mcf) && mcf.solve(net.source, net.sink) == solver::Status::kOptimal;
  const std::uint64_t t1 = clock.now_ns();
  *value = ok ? mcf.flow_value() : -1;
  *cost = ok ? mcf.total_cost() : -1;
  return t1 - t0;
}

namespace {

using Graph = lemon::SmartDigraph;
using ArcMap = Graph::ArcMap<std::int64_t>;

// Graph construction is part of what a LEMON user pays, so it is timed.
struct LemonNetwork {
  Graph graph;
  ArcMap capacity{graph};
  ArcMap cost{graph};

  explicit LemonNetwork(const ArcList& net) {
    graph.reserveNode(net.nodes);
    graph.reserveArc(static_cast<int>(net.arcs.size()));
    for (std::int32_t v = 0; v < net.nodes; ++v) graph.addNode();
    for (const ArcList::Arc& a : net.arcs) {
      const Graph::Arc arc = graph.addArc(graph.nodeFromId(a.from), graph.nodeFromId(a.to));
      capacity[arc] = a.capacity;
      cost[arc] = a.cost;
    }
  }
  std::int64_t max_flow(const ArcList& net) {
    lemon::Preflow<Graph, ArcMap> preflow(graph, capacity, graph.nodeFromId(net.source),
                                          graph.nodeFromId(net.sink));
    preflow.runMinCut();
    return preflow.flowValue();
  }
};

template <typename Solver>
std::uint64_t time_lemon(const ArcList& net, const solver::Clock& clock, solver::Flow* value,
                         solver::Cost* cost) {
  const std::uint64_t t0 = clock.now_ns();
  LemonNetwork g(net);
  const std::int64_t flow = g.max_flow(net);
  Solver s(g.graph);
  s.upperMap(g.capacity).costMap(g.cost).stSupply(g.graph.nodeFromId(net.source),
                                                   g.graph.nodeFromId(net.sink), flow);
  const bool ok = s.run() == Solver::OPTIMAL;
  const std::uint64_t t1 = clock.now_ns();
  *value = ok ? flow : -1;
  *cost = ok ? s.template totalCost<std::int64_t>() : -1;
  return t1 - t0;
}

}  // namespace

std::uint64_t time_lemon_network_simplex(const ArcList& net, const solver::Clock& clock,
                                         solver::Flow* value, solver::Cost* cost) {
  return time_lemon<lemon::NetworkSimplex<Graph, std::int64_t, std::int64_t>>(net, clock, value, cost);
}

std::uint64_t time_lemon_cost_scaling(const ArcList& net, const solver::Clock& clock,
                                      solver::Flow* value, solver::Cost* cost) {
  return time_lemon<lemon::CostScaling<Graph, std::int64_t, std::int64_t>>(net, clock, value, cost);
}

bool lemon_canonical_flows(const ArcList& net, solver::Flow max_flow,
                           std::vector<solver::Flow>* source_flows) {
  // Two maximum flows differ in the ranks they select by less than W.
  const std::int64_t w = max_flow * static_cast<std::int64_t>(net.evaluated) + 1;
  std::int64_t max_cost = 0;
  for (const ArcList::Arc& a : net.arcs) max_cost = std::max(max_cost, a.cost);
  const double bound = static_cast<double>(w) * static_cast<double>(max_cost + 1) *
                       static_cast<double>(max_flow + 1) * 4.0;
  if (bound > static_cast<double>(std::numeric_limits<std::int64_t>::max() / 2)) return false;
  LemonNetwork g(net);
  for (std::size_t i = 0; i < net.arcs.size(); ++i) {
    const ArcList::Arc& a = net.arcs[i];
    const bool pair_arc = a.from != net.source && a.from <= net.evaluated;
    g.cost[g.graph.arcFromId(static_cast<int>(i))] = a.cost * w + (pair_arc ? a.from - 1 : 0);
  }
  lemon::NetworkSimplex<Graph, std::int64_t, std::int64_t> simplex(g.graph);
  simplex.upperMap(g.capacity).costMap(g.cost).stSupply(g.graph.nodeFromId(net.source),
                                                        g.graph.nodeFromId(net.sink), max_flow);
  if (simplex.run() != decltype(simplex)::OPTIMAL) return false;
  source_flows->assign(static_cast<std::size_t>(net.evaluated), 0);
  for (std::size_t i = 0; i < net.arcs.size(); ++i) {
    const ArcList::Arc& a = net.arcs[i];
    if (a.from == net.source && a.to >= 1 && a.to <= net.evaluated) {
      (*source_flows)[static_cast<std::size_t>(a.to - 1)] +=
          simplex.flow(g.graph.arcFromId(static_cast<int>(i)));
    }
  }
  return true;
}

}  // namespace keepless::perf
