#include "keepless/core/status.hpp"

namespace keepless::core {

const char* to_string(Status s) {
  switch (s) {
    case Status::kOk: return "ok";
    case Status::kCapacityExceeded: return "capacity_exceeded";
    case Status::kInvalidArgument: return "invalid_argument";
    case Status::kUnknownKeyframe: return "unknown_keyframe";
    case Status::kDuplicateKeyframe: return "duplicate_keyframe";
    case Status::kDuplicateObservation: return "duplicate_observation";
    case Status::kBudgetExhausted: return "budget_exhausted";
  }
  return "unknown";
}

}  // namespace keepless::core
