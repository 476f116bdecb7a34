#pragma once
// Min-cost max-flow by successive shortest paths with node potentials
// (primal-dual): each round runs one Dijkstra on reduced costs, from the sink
// backwards with a radix heap, then one Dinic blocking flow over the
// zero-reduced-cost arcs, so a round carries every shortest path at once.
//
// Generic: any directed network with integer capacities in [0, 2^31) and
// costs in [0, 2^30], with (nodes + 1)^2 * (max cost + 1) <= 2^62 (labels are
// 64-bit). All storage is sized by the constructor; nothing allocates
// afterwards. Deterministic: the result is a pure function of the arc
// sequence (adjacency is visited in insertion order; no hashing, no floats).
// Tie-break: among equal-cost shortest paths, the blocking flow serves each
// node's arcs in insertion order, so earlier arcs win ties (the paper's
// network inserts points by ascending id; see core/network.hpp).

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

#include "keepless/solver/status.hpp"

namespace keepless::solver {

using NodeId = std::int32_t;
using ArcId = std::int32_t;
using Flow = std::int64_t;
using Cost = std::int64_t;

struct Capacity {
  std::int32_t max_nodes = 0;
  std::int32_t max_arcs = 0;  // user arcs; the residual graph holds twice as many
};

// Deterministic work limit: one unit per arc scanned, checked after every
// augmentation and every round.
struct Budget {
  std::uint64_t work_units = std::numeric_limits<std::uint64_t>::max();
};

struct SolveStats {
  std::uint64_t phases = 0;        // Dijkstra runs that reached the sink
  std::uint64_t augmentations = 0; // augmenting paths pushed
  std::uint64_t work_units = 0;    // arcs scanned
};

class MinCostFlow {
 public:
  explicit MinCostFlow(const Capacity& capacity);
  ~MinCostFlow();
  MinCostFlow(const MinCostFlow&) = delete;
  MinCostFlow& operator=(const MinCostFlow&) = delete;
  MinCostFlow(MinCostFlow&&) noexcept;
  MinCostFlow& operator=(MinCostFlow&&) noexcept;

  // Starts a new network of `node_count` nodes (0 .. node_count-1), no arcs.
  [[nodiscard]] Status reset(std::int32_t node_count);
  // Appends an arc; its id is the number of arcs added before it.
  [[nodiscard]] Status add_arc(NodeId from, NodeId to, Flow capacity, Cost cost);

  // Maximum flow from source to sink at minimum cost. kBudgetExhausted leaves
  // a valid (feasible, cost-optimal for its value) but not maximum flow.
  [[nodiscard]] Status solve(NodeId source, NodeId sink, const Budget& budget = {});

  std::int32_t node_count() const;
  std::int32_t arc_count() const;
  NodeId tail(ArcId a) const;
  NodeId head(ArcId a) const;
  Flow capacity(ArcId a) const;
  Cost cost(ArcId a) const;
  Flow flow(ArcId a) const;  // 0 until solve() has run on the current arcs
  Flow flow_value() const;
  Cost total_cost() const;
  // Dual certificate: every arc with residual capacity has
  // cost + potential(tail) - potential(head) >= 0.
  Cost potential(NodeId v) const;
  const SolveStats& stats() const;

  const Capacity& capacity_limits() const;
  // Bytes held by the preallocated workspace.
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::solver
