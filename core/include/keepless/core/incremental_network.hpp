#pragma once
// The section III-B network of a sliding window, kept in a solver across
// window changes (PaperNetwork builds it from nothing each time).
//
// update() compares the window with the one it saw last and edits only what
// changed, in time proportional to the observations of the keyframes that
// came or went (not to the window). A keyframe is matched by id and content
// (bit for bit: Window::keyframe_stamp proves it without a comparison when it
// is the same Window); a new or changed keyframe gets its N(p, f) counted, an
// unchanged one keeps them. Only the points of the keyframes that came or
// went change: their pair arcs are diffed, kept or added or retired (a kept
// pair arc keeps its cost, since a kept keyframe keeps its N). Pairs appear
// with their first arc and go with their last. Nodes and arcs keep their
// solver ids while they live, so the solver can re-optimise from its
// previous flow and potentials (MinCostFlow::solve_warm). Node ids: source
// 0, sink 1; points and pairs take recycled ids, and so do arcs.
//
// The ids do not follow point order, so the solver's insertion-order
// tie-break does not apply by itself: canonical_order() lists the source
// arcs by ascending point id, the order PaperNetwork inserts them in. Given
// to MinCostFlow::set_tie_order, a solve finds PaperNetwork's optimum (ties
// to the smaller point id); given to canonicalize(), it moves any other
// optimum (e.g. after solve_warm) there.
//
// All storage is sized from Capacities at construction; update() allocates
// nothing.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/config.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"
#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::core {

class IncrementalNetwork {
 public:
  explicit IncrementalNetwork(const Capacities& capacities);
  ~IncrementalNetwork();
  IncrementalNetwork(const IncrementalNetwork&) = delete;
  IncrementalNetwork& operator=(const IncrementalNetwork&) = delete;

  // Brings the network held in `solver` (sized by solver_capacity) up to
  // date with `window`. The first update, the first after clear(), and any
  // update with different network parameters (M, box, cost terms, cost
  // model, image size; not the scope or the floor) reset the
  // solver and build from nothing. On an error the network is cleared, so
  // the next update rebuilds.
  [[nodiscard]] Status update(const Window& window, const Params& params,
                              solver::MinCostFlow& solver);
  void clear();

  static solver::Capacity solver_capacity(const Capacities& capacities);

  // What the last update did.
  struct Changes {
    bool rebuilt = false;
    std::uint32_t frames_added = 0;
    std::uint32_t frames_removed = 0;
    std::uint32_t points_added = 0;
    std::uint32_t points_removed = 0;
    std::uint32_t points_changed = 0;  // kept, with other keyframes or counts
    std::uint32_t arcs_added = 0;
    std::uint32_t arcs_retired = 0;
    std::uint32_t arcs_recosted = 0;  // pair arcs given a new c_s (none: N is per keyframe)
  };
  const Changes& changes() const;

  // The window's points by ascending id, like PaperNetwork's.
  std::uint32_t point_count() const;
  PointId point_id(std::uint32_t i) const;
  std::uint32_t point_views(std::uint32_t i) const;  // n
  // Source arc of an evaluated point (n >= 2); -1 for a skipped one.
  solver::ArcId point_source_arc(std::uint32_t i) const;
  // Points begin .. begin + count - 1 at once, as point_id, point_views and
  // point_source_arc give them (the decision passes read every point).
  void read_points(std::uint32_t begin, std::uint32_t count, PointId* id, std::uint32_t* views,
                   solver::ArcId* source_arc) const;
  // Every point's window slots, flattened in point order as
  // PaperNetwork::point_slots, each point's in no particular order.
  void point_slots(std::uint32_t* at, std::uint32_t* slots) const;

  // Source arcs of the evaluated points, ascending point id.
  const solver::ArcId* canonical_order() const;
  std::uint32_t evaluated_count() const;
  std::uint32_t pair_count() const;
  std::uint32_t pair_arc_count() const;  // point -> pair arcs
  std::uint32_t max_views() const;       // m

  solver::NodeId source() const;
  solver::NodeId sink() const;
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
