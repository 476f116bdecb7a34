#pragma once
// The paper's network solved in closed form, with the potentials that prove
// it, as a start for MinCostFlow::solve_from. A source arc's capacity,
// n(n-1)/2, is the number of its point's pair arcs, so it never binds and
// the optimum decomposes by pair: pair q carries min(M, shared points)
// units on its cheapest points by c_c + c_s, ties to the point whose source
// arc comes first in the tie order (ascending point id). Its duals: the
// source 0, a point its c_c, a full pair its marginal unit cost, the sink
// above any path's cost (so no augmenting path is left) and a pair with room
// that much less its c_b. Read from the arcs held in the solver, so it
// serves PaperNetwork and IncrementalNetwork alike; O(arcs), allocation-free
// (storage sized by the solver's Capacity). Sparsifier uses it; ClosedForm
// is the independent, slower oracle the tests hold it to.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::core {

class PairwiseStart {
 public:
  explicit PairwiseStart(const solver::Capacity& capacity);
  ~PairwiseStart();
  PairwiseStart(const PairwiseStart&) = delete;
  PairwiseStart& operator=(const PairwiseStart&) = delete;

  // `order` lists the source arcs in tie order (the heads of these arcs are
  // the points; a pair is the head of a point's other arcs and the tail of
  // an arc into `sink`).
  void compute(const solver::MinCostFlow& solver, solver::NodeId sink, const solver::ArcId* order,
               std::int32_t count);

  // For MinCostFlow::solve_from: by arc id and by node id.
  const solver::Flow* flow() const;
  const solver::Cost* potential() const;
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
