#pragma once
// Min-cost max-flow by successive shortest paths with node potentials
// (primal-dual): each phase runs one Dijkstra on reduced costs with a radix
// heap, then one Dinic blocking flow over the zero-reduced-cost arcs, so a
// phase carries every shortest path at once. The search runs forwards from
// the source, merging the source's arcs in lazily by reduced cost (in the
// paper's network the expensive part of a path is its source arc, so a phase
// touches only the points still worth it); once a phase has to scan more
// than a quarter of the residual graph, the rest of the solve searches from
// the sink instead, whose blocking flow then never meets a dead end. Either
// way the flows are the same.
//
// Generic: any directed network with integer capacities in [0, 2^31) and
// costs in [0, 2^30], accepted when B^2 (max cost + 1) <= 2^62, B the
// smallest power of two >= nodes + 4 (so B < 2 (nodes + 4)), nodes counting
// those with arcs (and the terminals), not node_count(): labels are 64-bit,
// distance x B + hops (see Status::kCapacityExceeded). The minimum cost of
// the maximum flow must fit int64 (a solve whose total cost would not
// returns kInvalidInput). All storage is sized by the constructor; nothing
// allocates afterwards. Deterministic: the result is a pure function of the
// calls made (adjacency is visited in a fixed order; no hashing, no floats).
// Tie-break: among equal-cost shortest paths, the blocking flow serves each
// node's arcs in insertion order (or the order given to set_tie_order), so
// earlier arcs win ties (the paper's network inserts points by ascending id;
// see core/network.hpp).
//
// Incremental use: after a solve, arcs may be edited in place (set_arc,
// replace_arc) and solve_warm() re-optimises from the previous flow and
// potentials: potentials absorb cost changes where they can, arcs whose
// reduced cost became negative are saturated, arcs carrying flow at a
// positive reduced cost are emptied, the resulting excesses and deficits are
// routed (first along short zero-cost paths, then along shortest paths),
// and the flow is then augmented to maximum. The result is a minimum-cost
// maximum flow, but among equal-cost optima it may differ from solve()'s;
// canonicalize() then selects one optimum by a rule that does not depend on
// the history.
//
// Known optimum: a caller that can write down an optimal flow and its
// potentials for its network (the paper's has a closed form) hands them to
// solve_from(), which certifies them in one pass over the arcs instead of
// solving; a start that fails the certificate is re-optimised as by
// solve_warm(), so a wrong guess costs time, never the result.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

#include "keepless/solver/status.hpp"

namespace keepless::solver {

using NodeId = std::int32_t;
using ArcId = std::int32_t;
using Flow = std::int64_t;
using Cost = std::int64_t;

struct Capacity {
  std::int32_t max_nodes = 0;
  std::int32_t max_arcs = 0;  // user arcs; the residual graph holds twice as many
};

// A monotonic clock for deadlines, injected so that tests can drive time.
// The solver reads no OS clock itself: keepless::platform::MonotonicClock
// is CLOCK_MONOTONIC.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::uint64_t now_ns() const = 0;
};

// How much a solve may do. Work units are deterministic (one per residual
// arc scanned), so a work budget reproduces exactly; the deadline is read
// from `clock` (absolute, in that clock's nanoseconds). Work is compared
// before every phase, after every augmentation and after every node a search
// scans; the clock is read before every phase, every 1024 work units inside
// a search, and after an augmentation once 64 units have passed since the
// last read (a read costs more than a short augmentation). A solve() whose
// deadline has passed returns at once. A stop leaves a valid state (see
// solve()).
struct Budget {
  std::uint64_t work_units = std::numeric_limits<std::uint64_t>::max();
  const Clock* clock = nullptr;  // no deadline when null
  std::uint64_t deadline_ns = std::numeric_limits<std::uint64_t>::max();
};

// An arc as added or last edited (capacity 0 retires it).
struct Arc {
  NodeId tail;
  NodeId head;
  std::int32_t capacity;
  std::int32_t cost;
};

struct SolveStats {
  std::uint64_t phases = 0;        // Dijkstra runs that reached a target
  std::uint64_t augmentations = 0; // augmenting paths pushed
  std::uint64_t work_units = 0;    // arcs scanned
  std::uint64_t repaired_arcs = 0; // solve_warm: arcs saturated or emptied by the repair
  std::uint64_t canonical_swaps = 0;  // canonicalize: zero-cost cycles pushed
  bool warm = false;               // solve_warm reused the previous state
  bool certified = false;          // solve_from: the given start was optimal as it stood
};

class MinCostFlow {
 public:
  explicit MinCostFlow(const Capacity& capacity);
  ~MinCostFlow();
  MinCostFlow(const MinCostFlow&) = delete;
  MinCostFlow& operator=(const MinCostFlow&) = delete;
  // A moved-from solver may only be destroyed or assigned to.
  MinCostFlow(MinCostFlow&&) noexcept;
  MinCostFlow& operator=(MinCostFlow&&) noexcept;

  // Starts a new network of `node_count` nodes (0 .. node_count-1), no arcs.
  [[nodiscard]] Status reset(std::int32_t node_count);
  // Appends an arc; its id is the number of arcs added before it.
  [[nodiscard]] Status add_arc(NodeId from, NodeId to, Flow capacity, Cost cost);

  // Edits for solve_warm. set_arc changes an arc's data and keeps its flow
  // (clipped to the new capacity by the next solve); replace_arc gives slot
  // `a` new end points and data and zero flow (capacity 0 retires an arc).
  [[nodiscard]] Status set_arc(ArcId a, Flow capacity, Cost cost);
  [[nodiscard]] Status replace_arc(ArcId a, NodeId from, NodeId to, Flow capacity, Cost cost);
  // Tells solve_warm that node v now stands for something new, so its old
  // potential is no guide: it is re-estimated from its neighbours.
  [[nodiscard]] Status renew_node(NodeId v);

  // The tie-break order: the blocking flow serves these arcs first at their
  // tails, in this order, and every other arc after them in id order (by
  // default, id order alone). A network whose arc ids do not follow its
  // preferred order (e.g. recycled ids) states it here. Copied; takes effect
  // at the next solve. kInvalidInput for an id out of range or a repeat, the
  // order in force left as it was.
  [[nodiscard]] Status set_tie_order(const ArcId* order, std::int32_t count);

  // Maximum flow from source to sink at minimum cost, from zero flow.
  // kBudgetExhausted leaves a valid (feasible, cost-optimal for its value)
  // but not maximum flow, from which solve_warm() can resume.
  [[nodiscard]] Status solve(NodeId source, NodeId sink, const Budget& budget = {});

  // The same optimum, re-optimised from the state of the previous solve
  // (same source and sink) after the edits made since; falls back to solve()
  // when there is no usable state. kBudgetExhausted may stop while excesses
  // from the repair are still being routed: then balanced() is false (the
  // flow respects capacities and the potential certificate but not
  // conservation at some nodes); the next solve_warm() continues. A stop
  // within a phase's search discards that search, so a resumed solve makes
  // progress once its budget covers one search (up to the residual graph's
  // record count in work units).
  [[nodiscard]] Status solve_warm(NodeId source, NodeId sink, const Budget& budget = {});

  // Starts from the caller's flow[arc] and potential[node] (arrays of
  // arc_count() and node_count()). They are adopted at the cost of one pass
  // over the arcs (arc_count() work units) when they certify a minimum-cost
  // maximum flow: every flow within its arc's capacity (zero on retired
  // arcs), conservation at every node but source and sink, every arc with
  // residual capacity at reduced cost >= 0 and every arc with flow at <= 0,
  // potentials within +-2^60, and potential(sink) - potential(source) above
  // (node_count() - 1) x the largest cost, which no residual source-to-sink
  // path can exceed, so none is left. Then stats().certified is set. Any
  // other start is clipped to the capacities and re-optimised like
  // solve_warm()'s previous state, to the same kind of result. A budget
  // that cannot cover the pass (work units below arc_count(), or a deadline
  // already passed) stops before it, as solve() past its deadline does:
  // kBudgetExhausted at the zero flow.
  [[nodiscard]] Status solve_from(NodeId source, NodeId sink, const Flow* flow,
                                  const Cost* potential, const Budget& budget = {});

  // After an optimal solve: among all minimum-cost maximum flows, moves to
  // the one whose flows on `order` are lexicographically greatest (first
  // arc's flow as large as possible, then the second's, ...), by pushing
  // flow around zero-reduced-cost cycles. Cost and value are unchanged.
  // Listing the source's arcs makes the result a function of the network
  // alone, whatever path solve or solve_warm took (for networks whose
  // optimum is determined by the source arcs' flows, like the paper's).
  // kBudgetExhausted leaves an optimal but possibly non-canonical flow;
  // kInvalidInput if the last solve did not finish or an id is out of range.
  [[nodiscard]] Status canonicalize(const ArcId* order, std::int32_t count,
                                    const Budget& budget = {});

  // The accessors below take ids in range (0 .. arc_count() - 1, 0 ..
  // node_count() - 1) unchecked, as a container's operator[] does: they sit
  // in callers' per-arc loops. The calls above check what they are given.
  std::int32_t node_count() const;
  std::int32_t arc_count() const;
  NodeId tail(ArcId a) const;
  NodeId head(ArcId a) const;
  Flow capacity(ArcId a) const;
  Cost cost(ArcId a) const;
  const Arc* arc_data() const;  // arcs 0 .. arc_count() - 1, for bulk reads
  Flow flow(ArcId a) const;  // as of the last solve; 0 for arcs added or replaced since
  Flow flow_value() const;   // net flow out of the source
  Cost total_cost() const;
  bool balanced() const;     // conservation holds at every node but source and sink
  // Dual certificate: every arc with residual capacity has
  // cost + potential(tail) - potential(head) >= 0.
  Cost potential(NodeId v) const;
  const SolveStats& stats() const;

  const Capacity& capacity_limits() const;
  // Bytes held on the heap: the preallocated workspace and its bookkeeping.
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::solver
