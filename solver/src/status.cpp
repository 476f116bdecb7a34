#include "keepless/solver/status.hpp"

namespace keepless::solver {

const char* to_string(Status s) {
  switch (s) {
    case Status::kOptimal: return "optimal";
    case Status::kBudgetExhausted: return "budget_exhausted";
    case Status::kInvalidInput: return "invalid_input";
    case Status::kCapacityExceeded: return "capacity_exceeded";
  }
  return "unknown";
}

}  // namespace keepless::solver
