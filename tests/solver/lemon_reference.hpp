#pragma once
// Independent reference answers from LEMON (test-only dependency): the
// maximum flow value by Preflow, and the minimum cost of an s-t flow of a
// given value by NetworkSimplex.

#include <optional>

#include "random_networks.hpp"

namespace keepless::solver::test {

Flow lemon_max_flow(const TestNetwork& net);
// Minimum cost of sending exactly `value` from source to sink; nullopt when
// no such flow exists.
std::optional<Cost> lemon_min_cost(const TestNetwork& net, Flow value);

}  // namespace keepless::solver::test
