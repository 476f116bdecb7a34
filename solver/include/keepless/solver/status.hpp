#pragma once

#include <cstdint>

namespace keepless::solver {

enum class [[nodiscard]] Status : std::uint8_t {
  kOptimal = 0,
  kBudgetExhausted,   // stopped early; the flow is valid but not maximum
  kInvalidInput,      // node out of range, negative capacity or cost, source == sink
  kCapacityExceeded,  // more nodes or arcs than the constructor reserved, or a solve from zero
                      // flow whose labels would not fit: B^2 x (max cost + 1) > 2^62, B the
                      // smallest power of two >= nodes + 4, nodes: those with arcs, and the terminals
};

const char* to_string(Status s);

}  // namespace keepless::solver
