#pragma once
// keepless_node's fixed memory for a --profile, predicted before allocating
// (estimate_node_bytes) and measured on a node built on memq://: its own
// count of what it holds and the process's resident-set growth while it was
// built; and the process's resident and peak resident set (/proc/self/status).

#include <cstdint>
#include <string>

#include "keepless/core/config.hpp"

namespace keepless::perf {

struct NodeMemory {
  core::Capacities caps{};
  double predicted_bytes = 0;
  std::uint64_t counted_bytes = 0;     // Node::memory_bytes()
  std::int64_t rss_growth_bytes = 0;   // VmRSS after building it minus before
};

// False with `error` for an unknown profile or a node that cannot be built.
bool measure_node_memory(const std::string& profile, NodeMemory* out, std::string* error);

// VmRSS / VmHWM of this process, bytes; 0 where /proc is not readable.
std::uint64_t resident_bytes();
std::uint64_t peak_resident_bytes();

}  // namespace keepless::perf
