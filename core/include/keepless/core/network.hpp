#pragma once
// The section III-B flow network of a window:
//   source -> point p (seen by n >= 2 keyframes): cap n(n-1)/2, cost c_m(n)
//   point -> pair (f_j, f_k), both observing p:   cap 1,        cost c_s
//   pair -> sink:                                  cap M,        cost c_b
// Node order: source 0, points 1..P by ascending point id, pairs P+1..P+Q by
// (slot j, slot k), sink P+Q+1. Arc order: source arcs by point id, then each
// point's pair arcs by pair, then pair->sink arcs. That order is the solver's
// tie-break: equal-cost points are taken by ascending id.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/config.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"
#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::core {

class PaperNetwork {
 public:
  explicit PaperNetwork(const Capacities& capacities);
  ~PaperNetwork();
  PaperNetwork(const PaperNetwork&) = delete;
  PaperNetwork& operator=(const PaperNetwork&) = delete;

  // Builds the network of `window` into `solver` (which must have at least
  // solver_capacity(capacities) room). Allocates nothing.
  [[nodiscard]] Status build(const Window& window, const Params& params,
                             solver::MinCostFlow& solver);

  static solver::Capacity solver_capacity(const Capacities& capacities);

  // All distinct points of the window, ascending id; n = keyframes observing it.
  std::uint32_t point_count() const;
  PointId point_id(std::uint32_t i) const;
  std::uint32_t point_views(std::uint32_t i) const;  // n
  // Evaluated points (n >= 2) are network nodes; -1 for skipped points.
  std::int32_t point_source_arc(std::uint32_t i) const;
  // Points begin .. begin + count - 1 at once, as point_id, point_views and
  // point_source_arc give them (the decision passes read every point).
  void read_points(std::uint32_t begin, std::uint32_t count, PointId* id, std::uint32_t* views,
                   solver::ArcId* source_arc) const;
  // Every point's window slots (the keyframes observing it), flattened in
  // point order: point i's are slots[at[i] .. at[i + 1]), ascending. `at`
  // holds point_count() + 1 entries, `slots` the window's observations.
  void point_slots(std::uint32_t* at, std::uint32_t* slots) const;
  // Source arcs of the evaluated points, ascending point id (here simply
  // arcs 0 .. evaluated_count()-1), as IncrementalNetwork::canonical_order.
  const solver::ArcId* canonical_order() const;
  std::uint32_t evaluated_count() const;
  std::uint32_t pair_count() const;
  std::uint32_t pair_arc_count() const;  // point -> pair arcs
  std::uint32_t max_views() const;       // m
  std::int64_t connectivity_cost(std::uint32_t n) const;  // c_m(n), 2 <= n <= m

  // Pair q: window slots j < k, its sink arc, and c_b.
  std::uint32_t pair_slot_j(std::uint32_t q) const;
  std::uint32_t pair_slot_k(std::uint32_t q) const;
  solver::ArcId pair_sink_arc(std::uint32_t q) const;
  std::int64_t pair_baseline_cost(std::uint32_t q) const;

  // Point -> pair arc a (0 .. pair_arc_count-1): its point index, pair, c_s,
  // and the solver arc id.
  std::uint32_t arc_point(std::uint32_t a) const;
  std::uint32_t arc_pair(std::uint32_t a) const;
  std::int64_t arc_spatial_cost(std::uint32_t a) const;
  solver::ArcId arc_solver_id(std::uint32_t a) const;

  solver::NodeId source() const;
  solver::NodeId sink() const;
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
