#pragma once
// The per-pair closed form of the paper's network. With its capacities the
// source arcs never bind (capacity = out-degree), so the optimum decomposes:
// each pair carries min(M, shared points) units on its cheapest points by
// c_c + c_s, ties to the smaller point id. A test oracle, written
// independently and simply (it sorts each pair); the decision path's
// closed form is PairwiseStart, certified by the solver.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/config.hpp"
#include "keepless/core/network.hpp"

namespace keepless::core {

class ClosedForm {
 public:
  explicit ClosedForm(const Capacities& capacities);
  ~ClosedForm();
  ClosedForm(const ClosedForm&) = delete;
  ClosedForm& operator=(const ClosedForm&) = delete;

  // Solves a network built by PaperNetwork::build (the same params).
  void solve(const PaperNetwork& network, const Params& params);

  std::int64_t point_flow(std::uint32_t point_index) const;  // indexed like PaperNetwork points
  bool arc_selected(std::uint32_t pair_arc) const;
  std::int64_t max_flow() const;
  std::int64_t total_cost() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
