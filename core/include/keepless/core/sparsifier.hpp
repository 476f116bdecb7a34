#pragma once
// The decision path: window -> network -> solve -> decisions, in storage
// sized once from Capacities. run() allocates nothing.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/network.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"
#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::core {

class Sparsifier {
 public:
  Sparsifier(const Capacities& capacities, const Params& params);
  ~Sparsifier();
  Sparsifier(const Sparsifier&) = delete;
  Sparsifier& operator=(const Sparsifier&) = delete;

  // kInvalidArgument for bad Params (M < 1, theta outside [0,1], box < 0).
  [[nodiscard]] static Status validate(const Params& params);

  // Decides every point of `window`. On kBudgetExhausted the decisions keep
  // every evaluated point (nothing is culled on an unfinished solve).
  [[nodiscard]] Status run(const Window& window, const solver::Budget& budget = {});

  const Summary& summary() const;
  // One per distinct window point, ascending point id.
  std::uint32_t decision_count() const;
  const PointDecision* decisions() const;

  const Params& params() const;
  const PaperNetwork& network() const;
  const solver::MinCostFlow& solver() const;
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
