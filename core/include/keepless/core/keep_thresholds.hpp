#pragma once
// Keep thresholds of the paper's network, for keep budgets. A source arc's
// capacity never binds, so pair q carries its min(M, shared) cheapest units
// by (c_c + c_s, tie order), whatever M is: a point's position r_q in pair
// q's order does not depend on M, and its flow at M is the number of its
// pairs with r_q < M. It is kept iff that flow reaches t, the smallest flow
// above theta * n(n-1)/2 (decide()), so its threshold is
//   M*(p) = (the t-th smallest of its positions, from 0) + 1,
// and at any M the kept points are exactly those with M*(p) <= M. Read
// from the arcs held in the solver like PairwiseStart, so it serves
// PaperNetwork and IncrementalNetwork alike, whatever the cost model.
// O(arcs + nodes) but for a per-point selection over its own positions;
// allocation-free (storage sized by the solver's Capacity).

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::core {

class KeepThresholds {
 public:
  static constexpr std::uint32_t kNever = 0xffffffffu;  // no M keeps it (theta = 1)

  explicit KeepThresholds(const solver::Capacity& capacity);
  ~KeepThresholds();
  KeepThresholds(const KeepThresholds&) = delete;
  KeepThresholds& operator=(const KeepThresholds&) = delete;

  // `order` lists the source arcs in tie order, as for PairwiseStart.
  void compute(const solver::MinCostFlow& solver, solver::NodeId sink, const solver::ArcId* order,
               std::int32_t count, double theta);

  // M*(p) of the point node `node` (the head of a source arc in `order`).
  std::uint32_t threshold(solver::NodeId node) const;

  // The optimum at pair capacity `m` (m >= 0): flow_at(node) of each point,
  // and the maximum flow and total cost, as a solve at M = m gives them.
  void evaluate_at(std::int64_t m);
  std::int64_t flow_at(solver::NodeId node) const;
  std::int64_t max_flow() const;
  std::int64_t total_cost() const;

  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
