#pragma once

#include "keepless/core/status.hpp"
#include "keepless/solver/status.hpp"

namespace keepless::core {

// The solver's status in core's terms.
inline Status from_solver(solver::Status s) {
  switch (s) {
    case solver::Status::kOptimal: return Status::kOk;
    case solver::Status::kBudgetExhausted: return Status::kBudgetExhausted;
    case solver::Status::kInvalidInput: return Status::kInvalidArgument;
    case solver::Status::kCapacityExceeded: return Status::kCapacityExceeded;
  }
  return Status::kInvalidArgument;
}

}  // namespace keepless::core
