#pragma once
// Keep thresholds of the paper's network, for keep budgets. A source arc's
// capacity never binds, so pair q carries its min(M, shared) cheapest units
// by (c_c + c_s, tie order), whatever M is: a point's position r_q in pair
// q's order does not depend on M, and its flow at M is the number of its
// pairs with r_q < M. It is kept iff that flow reaches t, the smallest flow
// above theta * n(n-1)/2 (decide()), so its threshold is
//   M*(p) = (the t-th smallest of its positions, from 0) + 1,
// and at any M the kept points are exactly those with M*(p) <= M. Read
// from the arcs held in the solver like PairwiseStart, so it serves
// PaperNetwork and IncrementalNetwork alike, whatever the cost model.
// O(arcs + nodes) but for a per-point selection over its own positions;
// allocation-free (storage sized by the solver's Capacity).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "keepless/core/decision.hpp"
#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::core {

class KeepThresholds {
 public:
  static constexpr std::uint32_t kNever = 0xffffffffu;  // no M keeps it (theta = 1)

  explicit KeepThresholds(const solver::Capacity& capacity);
  ~KeepThresholds();
  KeepThresholds(const KeepThresholds&) = delete;
  KeepThresholds& operator=(const KeepThresholds&) = delete;

  // `order` lists the source arcs in tie order, as for PairwiseStart.
  void compute(const solver::MinCostFlow& solver, solver::NodeId sink, const solver::ArcId* order,
               std::int32_t count, double theta);

  // M*(p) of the point whose source arc is order[k] (kNever for an arc of
  // capacity 0). By rank, not by node id: a decision reads every point's in
  // point order, which is this order, so it walks the array in order.
  std::uint32_t threshold(std::int32_t k) const;
  const std::uint32_t* threshold_data() const;  // threshold() of ranks 0 .. count - 1

  // The optimum at pair capacity `m` (m >= 0): flow_at(k) of each point (by
  // rank, as threshold()), and the maximum flow and total cost, as a solve
  // at M = m gives them.
  void evaluate_at(std::int64_t m);
  std::int64_t flow_at(std::int32_t k) const;
  const std::int64_t* flow_data() const;  // flow_at() of ranks 0 .. count - 1
  std::int64_t max_flow() const;
  std::int64_t total_cost() const;

  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The fraction budget (BudgetKind::kFraction) over a sequence of decisions.
// A point stays in a sliding window for several decisions; keeping the share
// F of every decision's candidates would keep F^k of the points decided k
// times. So F applies to the points evaluated for the first time: a decision
// keeps K = (its candidates the budget kept the last time they were
// candidates) + a grant, the grants summing to floor(F x N + 0.5) over the
// N points first evaluated so far. The budget's points are then the share F
// of every point it has evaluated (not culled by it since); the map holds F
// of what it would without culling. A point is remembered, by id, while it
// stays in the window and, once it has left, among the last max_points
// points to leave: one that comes back (a revisit, a covisibility window
// that changed) is known, kept or not, and not evaluated again; one that
// comes back after more than max_points others left counts as new.
// Allocation-free after construction.
class IdTable;

class FractionBudget {
 public:
  explicit FractionBudget(std::uint32_t max_points);
  ~FractionBudget();
  FractionBudget(FractionBudget&&) noexcept;
  FractionBudget& operator=(FractionBudget&&) noexcept;

  // K for a decision: `d` lists every window point (ascending ids, at most
  // max_points), its candidates with any verdict but kSkip. Counts the new
  // ones as evaluated; call record() with the same points after selecting.
  std::uint32_t take(double fraction, const PointDecision* d, std::uint32_t n);
  // After selecting: candidates with verdict kKeep were kept by the budget,
  // the other candidates were not; points skipped this time keep what was
  // remembered of them; points no longer in the window are forgotten.
  void record(const PointDecision* d, std::uint32_t n);
  void clear();

  std::uint64_t evaluated() const { return evaluated_; }  // points first evaluated so far
  std::uint64_t granted() const { return granted_; }      // floor(F x evaluated() + 0.5)
  std::size_t memory_bytes() const;

 private:
  struct Entry {
    PointId point;
    bool kept;
  };
  static constexpr std::uint8_t kFresh = 0, kKnown = 1, kKnownKept = 2, kReturned = 4;
  void depart(PointId point, bool kept);

  std::vector<Entry> held_, next_;    // [max_points] by ascending id
  std::vector<std::uint8_t> known_;   // [max_points] per decision of the last take()
  // Points that left the window: id -> (ring slot << 1 | kept), and the ring
  // of their ids in order of leaving (the oldest is overwritten first).
  std::unique_ptr<IdTable> departed_;
  std::vector<PointId> ring_;
  std::uint32_t ring_next_ = 0;
  std::uint32_t count_ = 0;
  std::uint64_t evaluated_ = 0;
  std::uint64_t granted_ = 0;
};

// A keep budget's track share (KeepBudget::track_share). `ranked` holds the
// `candidates` in the network's order (M*, id) and the budget keeps `take`
// of them; of those, floor(share x take + 0.5) are taken by track length:
// the first take minus that many stay, then come the other candidates with
// the most views (views[i]: candidate i's window observations n, counted up
// to max_views), most first, ties in the network's order, then the rest in
// that order. So ranked[0, take) is what the budget keeps, and any prefix of
// it (Params::tracked_first moves the tracked ahead) keeps the longest. `histogram` holds
// max_views + 1 entries and `scratch` `candidates`; no allocation.
std::uint32_t track_share_count(double share, std::uint32_t take);
// The share a decision keeping `take` of `candidates` applies: the budget's
// track_share, or 0 outside [track_share_from, track_share_to] (KeepBudget).
double track_share_at(const KeepBudget& budget, std::uint64_t take, std::uint64_t candidates);
void take_longest_tracks(std::uint32_t* ranked, std::uint32_t candidates, std::uint32_t take, double share,
                         const std::uint32_t* views, std::uint32_t max_views, std::uint32_t* histogram,
                         std::uint32_t* scratch);

}  // namespace keepless::core
