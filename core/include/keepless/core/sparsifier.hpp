#pragma once
// The decision path: window -> network -> solve -> decisions, in storage
// sized once from Capacities. run() and update() allocate nothing (but an
// incremental Sparsifier's first run(), see SolveMode).
//
// run() builds the network and solves it from nothing. update() (with
// SolveMode::kIncremental) keeps the network between calls and edits only
// what changed since the previous window (IncrementalNetwork), then solves it
// from the closed-form start (or, with Start::kZeroFlow, in the canonical
// tie-break order; then after a stop for budget the next call resumes from
// the flow and potentials left behind (solve_warm) and restores the
// tie-break (canonicalize)). Its decisions, flows and cost equal run()'s on
// the same window.
//
// The decision policies act on the exact optimum's verdicts, the same way in
// run() and update(): first tracking-safe culling skips the points younger
// than Params::maturity_keyframes (Summary::guarded) and those the newest
// keyframe flags tracked (Keyframe::tracked, Summary::tracked); then
// Params::scope = kNewest (deciding the keyframe maturity_keyframes before
// the newest; kAuto when it decides as kNewest) turns every evaluated point the
// decided keyframe does not observe into a skip (flow and capacity reported
// as 0, Summary::out_of_scope); after a missed turn (a call that did not
// return kOk, or note_undecided()) the next call that decides also decides
// the keyframes between the last one decided (by id) and that one, or all
// before it if the last one decided left the window (Summary::caught_up).
// Params::coverage_floor = L then promotes
// culled points back to keep, keyframe by keyframe from the oldest, until
// each keyframe has L evaluated points not culled or none of its evaluated
// points is culled (Summary::floor_*). A promoted point keeps its flow, so
// it is the only kept point whose flow is not above theta * capacity.
//
// Keep budgets (Params::budget): with the paper's capacities each evaluated
// point p has a keep threshold M*(p) (keepless/core/keep_thresholds.hpp):
// at pair capacity M the kept points are exactly those with M*(p) <= M. A
// budget needs no solve: the thresholds are computed from the network's
// arcs, the scope leaves its candidates, and the budget keeps those with the
// smallest M*, ties to the smaller point id (KeepBudget). Each decision's
// flow is then its flow at the budget's M (Summary::budget_m, the largest M*
// kept); the floor promotes on top, smallest M* first. kept_at(M) gives the
// whole kept-count curve of the window from the same pass.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/incremental_network.hpp"
#include "keepless/core/network.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"
#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::core {

enum class SolveMode : std::uint8_t {
  kFromScratch,  // run() only; update() behaves as run()
  // update() on the incremental network (about the size of the window again)
  // instead of run()'s, which is made by the first run() only: a caller that
  // only updates never holds it, and one that also runs allocates it once.
  kIncremental,
};

// How a solve starts. kClosedForm: from the optimum of the paper's network
// in closed form (per pair, see keepless/core/pairwise_start.hpp) with the
// potentials that prove it, which the solver certifies in one pass over the
// arcs (MinCostFlow::solve_from); a start that failed the certificate would
// be re-optimised, then put in the canonical tie-break. kZeroFlow: successive
// shortest paths from the zero flow, as a general network would need. Both
// give the same flows, but kZeroFlow's labels bound the network: B^2 x
// (largest arc cost + 1) <= 2^62, B the smallest power of two >= nodes + 6
// (the window's points and pairs), beyond it kCapacityExceeded (c_c grows
// as m^3 / 10: e.g. 724 keyframes that all see one point, which the closed
// form decides).
enum class Start : std::uint8_t { kClosedForm, kZeroFlow };

// Where a run() or update() spent its time, when a clock is set.
struct StageTimes {
  std::uint64_t network_ns = 0;  // build (run) or in-place update (update)
  std::uint64_t solve_ns = 0;    // solve; for update, warm re-solve and tie-break restoration
  std::uint64_t decide_ns = 0;   // verdicts and summary
};

class Sparsifier {
 public:
  Sparsifier(const Capacities& capacities, const Params& params,
             SolveMode mode = SolveMode::kFromScratch, Start start = Start::kClosedForm);
  ~Sparsifier();
  Sparsifier(const Sparsifier&) = delete;
  Sparsifier& operator=(const Sparsifier&) = delete;

  // kInvalidArgument for bad Params (M outside 1 .. INT32_MAX, the solver's
  // arc capacities, also with a budget; theta outside [0,1], box < 0,
  // an unknown scope or cost model, kAuthors with an image side <= 0).
  [[nodiscard]] static Status validate(const Params& params);

  // Decides every point of `window` (within Params::scope). On
  // kBudgetExhausted the decisions keep every evaluated point (nothing is
  // culled on an unfinished solve, so the floor has nothing to do). Any other
  // status but kOk (kCapacityExceeded, also for a point seen by more than
  // kMaxPointViews window keyframes while c_c is on; kInvalidArgument) leaves no decisions
  // (decision_count() 0, kept_at() 0), and update()'s next call rebuilds its
  // network from the window it is given.
  [[nodiscard]] Status run(const Window& window, const solver::Budget& budget = {});

  // The same decisions as run(window), incrementally: the network is edited
  // in place. The budget's work units cover the solve (from the closed
  // form: its certificate, one unit per arc slot; from zero flow: the solve
  // and the tie-break restoration, and a call after one that ran out of
  // budget carries on from its state, once: if that runs out too, the next
  // call starts afresh, so sustained overload cannot lock it into slow
  // repairs). Its deadline is when the decisions must be ready: the solver
  // stops early enough to leave deciding its usual time, and when less time
  // is left than updating the network, a finished solve and deciding
  // usually take (the shorter of each one's last two durations), the call is
  // deferred: it returns kBudgetExhausted at once, with no per-point
  // decisions and every window point counted as kept (summary().kept ==
  // summary().points), and the next call brings the network up to date with
  // everything since. On any kBudgetExhausted nothing is culled. A call to
  // run() in between makes the next update() start from nothing.
  [[nodiscard]] Status update(const Window& window, const solver::Budget& budget = {});
  // The last update() was deferred (see above).
  bool deferred() const;
  // Scope::kNewest: the caller answered a keyframe without calling run() or
  // update() (e.g. a drain superseded it): its turn is missed, like a call
  // that did not return kOk, so the next call that decides also decides the
  // keyframes after the last one decided. Without it, only calls are seen.
  void note_undecided();
  // A new map (the caller cleared its window): a kept fraction counts its
  // points from nothing again, so reused point ids are not taken for points
  // an earlier map kept; Scope::kNewest forgets its last decided keyframe.
  void forget_history();

  // Times the stages of each run()/update() on `clock` (null: not timed).
  void set_clock(const solver::Clock* clock);
  const StageTimes& stage_times() const;

  const Summary& summary() const;
  // One per distinct window point, ascending point id.
  std::uint32_t decision_count() const;
  const PointDecision* decisions() const;

  // With a budget: the candidates (evaluated, in scope) the window keeps at
  // pair capacity m, before the floor (0 without a budget), and each
  // decision's M* (0: skipped; KeepThresholds::kNever: no M keeps it;
  // null without a budget), indexed like decisions().
  std::uint32_t kept_at(std::int64_t m) const;
  const std::uint32_t* keep_thresholds() const;

  const Params& params() const;
  // After run(); before an incremental Sparsifier's first run(), an empty network.
  const PaperNetwork& network() const;
  const IncrementalNetwork* incremental_network() const;  // after update(); null without kIncremental
  SolveMode mode() const;
  Start start() const;
  const solver::MinCostFlow& solver() const;
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
