#include "keepless/core/decision.hpp"

namespace keepless::core {

const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::kKeep: return "keep";
    case Verdict::kCull: return "cull";
    case Verdict::kSkip: return "skip";
  }
  return "unknown";
}

Verdict decide(std::int64_t flow, std::int64_t capacity, double theta) {
  if (capacity <= 0) return Verdict::kSkip;  // not a network node (n < 2)
  return static_cast<double>(flow) > theta * static_cast<double>(capacity) ? Verdict::kKeep
                                                                           : Verdict::kCull;
}

}  // namespace keepless::core
