#pragma once
// Seeded test networks for the min-cost-flow solver: general random digraphs
// (parallel arcs, self-loops, arcs into the source / out of the sink, zero and
// large capacities) and layered networks shaped like the paper's
// source -> points -> frame pairs -> sink graph.

#include <cstdint>
#include <string>
#include <vector>

#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::solver::test {

// splitmix64: tiny, portable and identical on every platform, unlike the
// std:: distributions whose output is implementation-defined.
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform-enough integer in [lo, hi] (modulo bias is irrelevant here).
  std::int64_t range(std::int64_t lo, std::int64_t hi) {
    return lo + static_cast<std::int64_t>(next() % static_cast<std::uint64_t>(hi - lo + 1));
  }
  // True with probability percent / 100.
  bool chance(int percent) { return static_cast<int>(next() % 100) < percent; }

 private:
  std::uint64_t state_;
};

struct TestArc {
  NodeId from;
  NodeId to;
  Flow capacity;
  Cost cost;
};

struct TestNetwork {
  std::string label;  // generator + seed, printed on failure to reproduce it
  std::int32_t node_count = 0;
  NodeId source = 0;
  NodeId sink = 1;
  std::vector<TestArc> arcs;
};

enum class CostShape { kSmall, kAllEqual, kLarge };

// General digraph: 2..60 nodes, up to 4 arcs per node.
TestNetwork random_general_network(std::uint64_t seed, CostShape shape);
// Paper-shaped: source -> points (capacity n(n-1)/2, connectivity cost) ->
// frame pairs (capacity 1, spatial cost) -> sink (capacity M, baseline cost).
TestNetwork random_layered_network(std::uint64_t seed);

// Largest sizes the generators produce, for sizing solvers.
inline constexpr std::int32_t kMaxTestNodes = 64;
inline constexpr std::int32_t kMaxTestArcs = 1024;

// reset + add_arc for every arc; returns the first non-optimal status.
Status load(MinCostFlow& solver, const TestNetwork& net);

}  // namespace keepless::solver::test
