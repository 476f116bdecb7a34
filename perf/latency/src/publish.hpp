#pragma once
// The publish stage of the decision path: the decision message encoded into
// a buffer sized at start (LCM's decision_t when LCM is built; a plain byte
// layout otherwise). Sending is the bus's business and is not timed here.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"

namespace keepless::perf {

class DecisionEncoder {
 public:
  explicit DecisionEncoder(const core::Capacities& capacities);
  ~DecisionEncoder();
  // Encodes the decision for keyframe `sequence`; returns the encoded size.
  std::size_t encode(std::int64_t sequence, const core::Window& window, const core::Sparsifier& s,
                     core::Status status);
  std::size_t memory_bytes() const;
  static const char* format();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::perf
