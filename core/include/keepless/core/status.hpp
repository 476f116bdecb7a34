#pragma once

#include <cstdint>

namespace keepless::core {

enum class [[nodiscard]] Status : std::uint8_t {
  kOk = 0,
  kCapacityExceeded,   // a fixed capacity would be exceeded; nothing held changed
                       // (a Sparsifier's call has no decisions: see run())
  kInvalidArgument,    // non-finite number, bad parameter
  kUnknownKeyframe,    // an observation names a keyframe not in the window
  kDuplicateKeyframe,  // keyframe id already in the window
  kDuplicateObservation,  // (keyframe, point) given twice
  kBudgetExhausted,    // solve stopped early; undecided points kept
};

const char* to_string(Status s);

}  // namespace keepless::core
