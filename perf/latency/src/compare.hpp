#pragma once
// The from-scratch solvers keepless_latency compares on a window's network:
// ours as the decision path runs it (reset + arcs + the closed-form start +
// solve_from, which certifies it), ours from zero flow (reset + arcs +
// solve: successive shortest paths, as any other network would need),
// LEMON's NetworkSimplex and CostScaling (each
// after Preflow for the maximum flow value, as a LEMON user would), and
// LEMON's simplex on costs with an exact tie-break, whose optimum is unique,
// to derive decisions independently of our solver.

#include <cstdint>
#include <vector>

#include "keepless/core/pairwise_start.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::perf {

// A PaperNetwork as built into a solver by Sparsifier::run: source 0, points
// 1..evaluated by ascending id, then pairs, sink last.
struct ArcList {
  struct Arc {
    solver::NodeId from, to;
    solver::Flow capacity;
    solver::Cost cost;
  };
  std::int32_t nodes = 0;
  solver::NodeId source = 0, sink = 1;
  std::int32_t evaluated = 0;
  std::vector<Arc> arcs;
  std::vector<solver::ArcId> source_arcs;  // PaperNetwork::canonical_order(): the tie order
};

// Copies the network of the last run() (allocates: not on the decision path).
void network_arcs(const core::Sparsifier& scratch, ArcList* out);

// Each returns the elapsed nanoseconds on `clock`, and the answer (-1 when
// the solve failed or, for ours, its start was not certified). time_ours
// counts loading the network, as LEMON's graph construction is counted;
// `solve_ns` gets the start and the solve alone, what update() times.
std::uint64_t time_ours(const ArcList& net, const solver::Clock& clock, solver::MinCostFlow& mcf,
                        core::PairwiseStart& start, solver::Flow* value, solver::Cost* cost,
                        std::uint64_t* solve_ns);
std::uint64_t time_ours_zero_flow(const ArcList& net, const solver::Clock& clock,
                                  solver::MinCostFlow& mcf, solver::Flow* value, solver::Cost* cost);

std::uint64_t time_lemon_network_simplex(const ArcList& net, const solver::Clock& clock,
                                         solver::Flow* value, solver::Cost* cost);
std::uint64_t time_lemon_cost_scaling(const ArcList& net, const solver::Clock& clock,
                                      solver::Flow* value, solver::Cost* cost);

// LEMON's network simplex with each point -> pair arc's cost raised to
// cost * W + (point rank), W above any sum of ranks: the optimum becomes
// unique and is the canonical one (ties to the smaller point id). Writes the
// source-arc flows, ascending point id. False when W would overflow.
bool lemon_canonical_flows(const ArcList& net, solver::Flow max_flow,
                           std::vector<solver::Flow>* source_flows);

}  // namespace keepless::perf
