#include "keepless/core/sparsifier.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "keepless/core/keep_thresholds.hpp"
#include "keepless/core/pairwise_start.hpp"
#include "solver_status.hpp"

namespace keepless::core {

namespace {

solver::Capacity larger(solver::Capacity a, solver::Capacity b) {
  return {std::max(a.max_nodes, b.max_nodes), std::max(a.max_arcs, b.max_arcs)};
}

// The shorter of the last two durations of a stage: one outlier cannot make
// every later call plan for it.
class RecentDuration {
 public:
  void add(std::uint64_t ns) {
    last_[1] = last_[0];
    last_[0] = ns;
  }
  std::uint64_t expected() const { return std::min(last_[0], last_[1]); }
  // A deferred call measures nothing: halving what is expected instead makes
  // an estimate from a slow spell (preemption) expire, so deferring cannot
  // become permanent; a stage that really is that slow is measured again.
  void decay() {
    last_[0] /= 2;
    last_[1] /= 2;
  }

 private:
  std::uint64_t last_[2] = {0, 0};
};

}  // namespace

struct Sparsifier::Impl {
  Capacities caps;
  Params params;
  SolveMode mode;
  Start start;
  // run()'s network: made at construction for kFromScratch, by the first
  // run() for kIncremental (update() never needs it, so a node that only
  // updates never holds it).
  std::unique_ptr<PaperNetwork> network;
  std::unique_ptr<IncrementalNetwork> incremental;  // kIncremental only
  solver::MinCostFlow solver;  // shared: run() resets it, update() keeps it
  PairwiseStart pairwise;      // Start::kClosedForm
  bool solver_incremental = false;  // the solver holds the incremental network
  bool resume = false;              // the last update stopped for budget: carry on from its state
  bool resumed = false;             // the last update was such a resumption
  bool deferred = false;            // the last update left the network for later
  // Scope::kNewest's turns: the id of the last keyframe a call decided, and
  // whether a turn was missed since (a call that decided nothing, or a
  // keyframe answered without a call, note_undecided()): then the next call
  // that decides takes the keyframes after that one too.
  KeyframeId last_decided = 0;
  bool has_decided = false;
  bool missed = false;
  // Scope::kAuto's smoothed counts: evaluated points, and those that came back.
  std::uint64_t evaluated_sum = 0, returned_sum = 0;
  // What update() expects its stages to take, on the budget's clock, to plan
  // against a deadline. A solve counts only when it finished: a stopped one
  // says nothing of what a whole one needs.
  RecentDuration network_time, solve_time, decide_time;
  // Back-off for a budget that stays below what a call takes: each tried
  // call that overruns its deadline doubles the deferrals before the next
  // decay (up to kMaxBackoff doublings), so such a budget costs one late
  // call in 2^k, not every other one; a call on time resets it. (The decay
  // alone made 40 % of calls late at 20 % of the median.)
  static constexpr std::uint32_t kMaxBackoff = 5;
  std::uint32_t backoff = 0;
  std::uint32_t deferrals = 0;  // since the last decay
  std::vector<PointDecision> decisions;  // [max_points]
  // The policies' scratch. Scope kNewest: which decisions the newest
  // keyframe observes. The floor: each point's window slots (flattened, see
  // PaperNetwork::point_slots); per window slot its evaluated points not
  // culled and its culled ones (indices into decisions, grouped by slot).
  std::vector<std::uint8_t> in_scope;      // [max_points]
  std::vector<std::uint8_t> tracked_now;   // [max_points] (Params::tracked_first)
  std::vector<std::uint32_t> slots_at;     // [max_points + 1]
  std::vector<std::uint32_t> slots;        // [max_observations]
  std::vector<std::uint32_t> covered;      // [max_keyframes]
  std::vector<std::uint32_t> culled_at;    // [max_keyframes + 1]
  std::vector<std::uint32_t> culled_list;  // [max_observations]
  std::vector<std::uint32_t> candidates;   // [max_observations]
  // Keep budgets (Params::budget, kind != kNone): the thresholds, each
  // decision's M* (0: skipped), the kept-count curve (curve[b + 1]: the
  // candidates with M* <= b, b <= curve_top; M* = kNever counts in none),
  // a counting sort's cursors and the candidates by (M*, id).
  std::unique_ptr<KeepThresholds> thresholds;
  std::unique_ptr<FractionBudget> fraction;  // kFraction: what earlier decisions kept
  std::vector<std::uint32_t> threshold_of;  // [max_points]
  std::vector<std::uint32_t> curve;         // [max_points + 4]
  std::vector<std::uint32_t> cursor;        // [max_points + 4]
  std::vector<std::uint32_t> ranked;        // [max_points]
  std::vector<std::int32_t> rank_of;        // [max_points] a decision's rank in canonical_order
  std::vector<std::uint32_t> views_of;      // [max_points] a decision's n
  std::vector<std::uint32_t> views_histogram;  // [max_keyframes + 1] a track share's (take_longest_tracks)
  std::uint32_t curve_top = 0;              // the curve's last bucket: the largest finite M*
  std::uint32_t max_points = 0;
  bool budgeted = false;
  std::uint32_t count = 0;
  Summary summary;
  const solver::Clock* clock = nullptr;
  StageTimes times;

  std::uint64_t now() const { return clock != nullptr ? clock->now_ns() : 0; }

  Status run(const Window& window, const solver::Budget& budget);
  Status update(const Window& window, const solver::Budget& budget);

  // After every run()/update(): only a call that decided (kOk) takes the
  // keyframe's turn; a deferred, stopped or refused one leaves it (and the
  // ones before it not decided yet) to the next call that decides.
  void end_turn(const Window& window, Status r) {
    if (params.scope == Scope::kWindow) return;
    if (r != Status::kOk) {
      missed = true;
      return;
    }
    const std::uint32_t k = window.keyframe_count();
    if (k <= params.maturity_keyframes) return;  // nothing to decide yet
    last_decided = window.keyframe(k - 1 - params.maturity_keyframes).id;
    has_decided = true;
    missed = false;
  }

  Impl(const Capacities& c, const Params& p, SolveMode m, Start st)
      : caps(c),
        params(p),
        mode(m),
        start(st),
        network(m == SolveMode::kFromScratch ? std::make_unique<PaperNetwork>(c) : nullptr),
        incremental(m == SolveMode::kIncremental ? std::make_unique<IncrementalNetwork>(c) : nullptr),
        solver(m == SolveMode::kIncremental
                   ? larger(PaperNetwork::solver_capacity(c), IncrementalNetwork::solver_capacity(c))
                   : PaperNetwork::solver_capacity(c)),
        pairwise(st == Start::kClosedForm ? solver.capacity_limits() : solver::Capacity{}) {
    decisions.resize(c.max_points);
    max_points = c.max_points;
    budgeted = p.budget.kind != BudgetKind::kNone;
    if (budgeted) {
      thresholds = std::make_unique<KeepThresholds>(solver.capacity_limits());
      threshold_of.resize(c.max_points);
      curve.resize(std::size_t{c.max_points} + 4);
      cursor.resize(std::size_t{c.max_points} + 4);
      ranked.resize(c.max_points);
      rank_of.resize(c.max_points);
      views_of.resize(c.max_points);
      if (p.budget.track_share > 0.0) views_histogram.resize(std::size_t{c.max_keyframes} + 1);
    }
    if (p.budget.kind == BudgetKind::kFraction) fraction = std::make_unique<FractionBudget>(c.max_points);
    // The policies' scratch only where they are on (Params are fixed).
    if (p.scope != Scope::kWindow) in_scope.resize(c.max_points);
    if (budgeted && p.tracked_first) tracked_now.resize(c.max_points);
    if (p.coverage_floor > 0 || p.maturity_keyframes > 0 || p.scope == Scope::kAuto) {
      slots_at.resize(std::size_t{c.max_points} + 1);
      slots.resize(c.max_observations);
    }
    if (p.coverage_floor > 0) {
      covered.resize(c.max_keyframes);
      culled_at.resize(std::size_t{c.max_keyframes} + 1);
      culled_list.resize(c.max_observations);
      candidates.resize(c.max_observations);
    }
  }

  // Start::kClosedForm: the solver certifies the closed-form optimum. Should
  // it not (never for the paper's capacities), it re-optimised from there,
  // and canonicalize() moves its optimum to the tie-break's.
  Status solve_closed_form(solver::NodeId source, solver::NodeId sink, const solver::ArcId* order,
                           std::int32_t count, const solver::Budget& budget) {
    pairwise.compute(solver, sink, order, count);
    const Status r =
        from_solver(solver.solve_from(source, sink, pairwise.flow(), pairwise.potential(), budget));
    if (r != Status::kOk || solver.stats().certified) return r;
    return canonicalize(order, count, budget);
  }

  // canonicalize() on what the solve left of the work budget (the deadline
  // is absolute).
  Status canonicalize(const solver::ArcId* order, std::int32_t count, const solver::Budget& budget) {
    solver::Budget rest = budget;
    const std::uint64_t used = solver.stats().work_units;
    rest.work_units = budget.work_units > used ? budget.work_units - used : 0;
    return from_solver(solver.canonicalize(order, count, rest));
  }

  // f(i, id, views, source arc) for every point of the network, in order,
  // read in blocks (one call per block, not three per point; the blocks
  // live on the stack).
  template <typename Net, typename F>
  static void for_points(const Net& net, F&& f) {
    constexpr std::uint32_t kBlock = 256;
    PointId id[kBlock];
    std::uint32_t views[kBlock];
    solver::ArcId arc[kBlock];
    const std::uint32_t points = net.point_count();
    for (std::uint32_t b = 0; b < points; b += kBlock) {
      const std::uint32_t n = std::min(kBlock, points - b);
      net.read_points(b, n, id, views, arc);
      for (std::uint32_t j = 0; j < n; ++j) f(b + j, id[j], views[j], arc[j]);
    }
  }

  // Decisions from the source arcs' flows; an unfinished solve culls nothing.
  template <typename Net>
  void decide_all(const Net& net, bool finished) {
    Summary& sum = summary;
    for_points(net, [&](std::uint32_t i, PointId id, std::uint32_t views, solver::ArcId arc) {
      PointDecision& d = decisions[i];
      d.point = id;
      if (arc < 0) {
        d.verdict = Verdict::kSkip;
        d.flow = 0;
        d.capacity = 0;
        ++sum.skipped;
        return;
      }
      const std::int64_t n = views;
      d.capacity = n * (n - 1) / 2;
      d.flow = solver.flow(arc);
      d.verdict = finished ? decide(d.flow, d.capacity, params.theta) : Verdict::kKeep;
      if (d.verdict == Verdict::kKeep) {
        ++sum.kept;
      } else {
        ++sum.culled;
      }
    });
    count = net.point_count();
    sum.points = net.point_count();
    sum.evaluated = net.evaluated_count();
    sum.pairs = net.pair_count();
    sum.arcs = net.evaluated_count() + net.pair_arc_count() + net.pair_count();
    sum.max_flow = solver.flow_value();
    sum.total_cost = solver.total_cost();
  }

  // Keep budgets: every evaluated point's threshold M*, the scope, then the
  // budget keeps the candidates (evaluated, in scope) with the smallest M*,
  // ties to the smaller point id; flows are reported at the budget's M (the
  // largest M* kept), so a point tied at that M beyond the budget is culled
  // with a flow that M would keep. A track share swaps the last of the
  // budget's points for the longest tracks (take_longest_tracks).
  template <typename Net>
  void decide_budget(const Window& window, const Net& net) {
    Summary& sum = summary;
    thresholds->compute(solver, net.sink(), net.canonical_order(),
                        static_cast<std::int32_t>(net.evaluated_count()), params.theta);
    count = net.point_count();
    std::uint32_t top = 0;  // the largest finite M*
    // The evaluated points in point order are canonical_order's: the k-th
    // has rank k there (KeepThresholds' arrays are by rank).
    const std::uint32_t* threshold_by_rank = thresholds->threshold_data();
    std::int32_t rank = 0;
    for_points(net, [&](std::uint32_t i, PointId id, std::uint32_t views, solver::ArcId a) {
      PointDecision& d = decisions[i];
      d.point = id;
      d.flow = 0;
      views_of[i] = views;
      if (a < 0) {
        d.verdict = Verdict::kSkip;
        d.capacity = 0;
        threshold_of[i] = 0;
        ++sum.skipped;
        return;
      }
      const std::int64_t n = views;
      d.capacity = n * (n - 1) / 2;
      d.verdict = Verdict::kCull;
      rank_of[i] = rank;
      threshold_of[i] = threshold_by_rank[rank++];
      if (threshold_of[i] != KeepThresholds::kNever) top = std::max(top, threshold_of[i]);
      ++sum.culled;
    });
    sum.points = count;
    sum.evaluated = net.evaluated_count();
    sum.pairs = net.pair_count();
    sum.arcs = net.evaluated_count() + net.pair_arc_count() + net.pair_count();
    // The budget is taken from what the tracking guard and the scope leave.
    protect_and_scope(window, net, window.keyframe_count());

    // Candidates by (M*, id): a stable counting sort (decisions ascend by id)
    // over buckets 0 .. top, `never` (M* = kNever) and, last, the skipped
    // (no branch on the verdict: they sort after every candidate).
    curve_top = top;
    const std::uint32_t never = top + 1;
    const auto bucket = [&](std::uint32_t i) {
      return decisions[i].verdict == Verdict::kCull ? std::min(threshold_of[i], never) : never + 1;
    };
    std::fill(curve.begin(), curve.begin() + never + 3, 0u);
    for (std::uint32_t i = 0; i < count; ++i) ++curve[bucket(i) + 1];
    for (std::uint32_t b = 0; b <= never; ++b) curve[b + 1] += curve[b];
    const std::uint32_t candidates = curve[never + 1];
    std::copy(curve.begin(), curve.begin() + never + 2, cursor.begin());
    for (std::uint32_t i = 0; i < count; ++i) ranked[cursor[bucket(i)]++] = i;

    const KeepBudget& b = params.budget;
    // Params::tracked_first: the budget's order with the tracked first. A
    // count's share swaps by the network's order first; B's prefix is taken
    // from the tracked-first order.
    if (b.kind == BudgetKind::kObservations) tracked_to_front(candidates);
    std::uint32_t take = 0;
    std::uint64_t observations = 0;
    if (b.kind == BudgetKind::kPoints) {
      take = static_cast<std::uint32_t>(std::min<std::uint64_t>(b.count, candidates));
    } else if (b.kind == BudgetKind::kFraction) {  // F of the points new to the budget (FractionBudget)
      take = fraction->take(b.fraction, decisions.data(), count);
    } else {  // kObservations: the longest prefix within B
      while (take < candidates && observations + views_of[ranked[take]] <= b.count) {
        observations += views_of[ranked[take++]];
      }
    }
    if (!views_histogram.empty()) {  // cursor is free again: the scratch
      take_longest_tracks(ranked.data(), candidates, take, track_share_at(b, take, candidates), views_of.data(),
                          caps.max_keyframes, views_histogram.data(), cursor.data());
    }
    if (b.kind != BudgetKind::kObservations) tracked_to_front(candidates);
    observations = 0;
    std::uint32_t kept_top = 0;
    for (std::uint32_t j = 0; j < take; ++j) {
      const std::uint32_t i = ranked[j];
      decisions[i].verdict = Verdict::kKeep;
      observations += views_of[i];
      kept_top = std::max(kept_top, std::min(threshold_of[i], never));
    }
    if (fraction) fraction->record(decisions.data(), count);
    sum.kept += take;
    sum.culled -= take;
    sum.budget_observations = observations;
    // M = kNever's bucket reports as max_points + 1, as before the buckets were bounded.
    sum.budget_m = kept_top == never ? static_cast<std::int64_t>(max_points) + 1 : kept_top;
    thresholds->evaluate_at(sum.budget_m);
    const std::int64_t* flow_by_rank = thresholds->flow_data();
    for (std::uint32_t i = 0; i < count; ++i) {
      if (decisions[i].verdict == Verdict::kSkip) continue;
      decisions[i].flow = flow_by_rank[rank_of[i]];
    }
    sum.max_flow = thresholds->max_flow();
    sum.total_cost = thresholds->total_cost();
  }

  // Params::tracked_first: the tracked candidates ahead of the others in
  // ranked[0, candidates), each part in its order (a stable partition;
  // cursor is the scratch), counted in Summary::tracked.
  void tracked_to_front(std::uint32_t candidates) {
    if (tracked_now.empty()) return;
    std::uint32_t front = 0, rest = 0;
    for (std::uint32_t j = 0; j < candidates; ++j) {
      const std::uint32_t i = ranked[j];
      if (tracked_now[i]) {
        ranked[front++] = i;
      } else {
        cursor[rest++] = i;
      }
    }
    std::copy(cursor.begin(), cursor.begin() + rest, ranked.begin() + front);
    summary.tracked = front;
  }

  // Every call starts with no decisions and an empty curve: a call that
  // fails or is deferred leaves nothing of the previous window's answer.
  void begin_call() {
    count = 0;
    summary = Summary{};
    deferred = false;
    curve_top = 0;
    if (budgeted) curve[0] = curve[1] = 0;
  }

  std::uint32_t kept_at(std::int64_t m) const {
    if (!budgeted || m < 1) return 0;
    const std::uint32_t b = static_cast<std::uint32_t>(std::min<std::int64_t>(m, curve_top));
    return curve[b + 1];
  }

  // The decision policies, on the verdicts of the exact optimum (see
  // Params::scope and Params::coverage_floor).
  template <typename Net>
  void apply_policies(const Window& window, const Net& net, bool finished) {
    const std::uint32_t k = window.keyframe_count();
    if (params.cost_model == CostModel::kTrack) {
      for (std::uint32_t s = 0; s < k; ++s) summary.track_fallback += window.keyframe(s).quality == nullptr;
    }
    if (params.coverage_floor > 0 && finished) net.point_slots(slots_at.data(), slots.data());
    // A budget chose among what the guard and the scope left (decide_budget).
    if (!budgeted) protect_and_scope(window, net, k);
    if (params.coverage_floor > 0 && finished) apply_floor(k);
  }

  // The tracking guard, then the scope: with the guard the scope decides the
  // keyframe that just became A old (while the window holds A keyframes or
  // fewer, the guard skipped all). After a missed turn it also decides the
  // keyframes between the last one decided and that one (all before it if
  // the last one decided left the window): the turn is kept by keyframe id,
  // not by slot, as a slot passes on when the window slides. Without a
  // missed turn the scope is that keyframe alone, whatever the window did.
  template <typename Net>
  void protect_and_scope(const Window& window, const Net& net, std::uint32_t k) {
    const std::uint32_t maturity = params.maturity_keyframes;
    const bool automatic = params.scope == Scope::kAuto;
    if (maturity > 0 || automatic) net.point_slots(slots_at.data(), slots.data());
    if (automatic) measure_returning();
    protect_tracking(window, k);
    const bool newest = params.scope == Scope::kNewest || summary.decided_newest;
    if (!newest || k <= maturity) return;
    const std::uint32_t decided = k - 1 - maturity;
    std::uint32_t from = decided;
    if (missed) {
      const std::int32_t last = has_decided ? window.find_keyframe(last_decided) : -1;
      from = last < 0 ? 0 : std::min(static_cast<std::uint32_t>(last) + 1, decided);
    }
    restrict_to_slots(window, from, decided);
  }

  // Scope::kAuto: adds this window's evaluated points, and those a keyframe
  // saw again after kReturnGap or more window keyframes without them, to the
  // decaying sums, and decides as kNewest while the smoothed share is at
  // least kReturningForNewestPermille. Sorts each point's slots in place
  // (the other passes read them in any order).
  void measure_returning() {
    const auto came_back = [](std::uint32_t a, std::uint32_t b) { return b - a > kReturnGap; };
    std::uint64_t evaluated = 0, returned = 0;
    for (std::uint32_t i = 0; i < count; ++i) {
      std::uint32_t* first = slots.data() + slots_at[i];
      std::uint32_t* last = slots.data() + slots_at[i + 1];
      if (last - first < 2) continue;
      std::sort(first, last);
      ++evaluated;
      returned += std::adjacent_find(first, last, came_back) != last ? 1 : 0;
    }
    evaluated_sum = evaluated_sum - (evaluated_sum >> kReturnDecayShift) + evaluated;
    returned_sum = returned_sum - (returned_sum >> kReturnDecayShift) + returned;
    summary.returning_permille =
        evaluated_sum == 0 ? 0 : static_cast<std::uint32_t>(returned_sum * 1000 / evaluated_sum);
    // The per mille is floored, so this is share >= kReturningForNewestPermille / 1000 exactly.
    summary.decided_newest = summary.returning_permille >= kReturningForNewestPermille;
  }

  // Turns a decided point into a skip, as the policies report skips (with a
  // budget its M* reads 0, as every skip's does).
  void skip(PointDecision& d) {
    --(d.verdict == Verdict::kKeep ? summary.kept : summary.culled);
    ++summary.skipped;
    d = PointDecision{d.point, Verdict::kSkip, 0, 0};
    if (!threshold_of.empty()) threshold_of[static_cast<std::size_t>(&d - decisions.data())] = 0;
  }

  // Tracking-safe culling, before the scope and the floor: points first seen
  // in the newest A window keyframes (Params::maturity_keyframes; first seen =
  // the smallest window slot observing the point) are skipped as guarded;
  // then the points the newest keyframe flags tracked (Keyframe::tracked)
  // are skipped as tracked. The network is untouched: they still compete
  // for the pairs' M, so the step is a pass over the exact optimum.
  void protect_tracking(const Window& window, std::uint32_t k) {
    const std::uint32_t maturity = params.maturity_keyframes;
    if (maturity > 0) {
      const std::uint32_t young_from = k > maturity ? k - maturity : 0;
      for (std::uint32_t i = 0; i < count; ++i) {
        PointDecision& d = decisions[i];
        if (d.verdict == Verdict::kSkip) continue;
        std::uint32_t first = k;
        for (std::uint32_t x = slots_at[i]; x < slots_at[i + 1]; ++x) first = std::min(first, slots[x]);
        if (first < young_from) continue;
        skip(d);
        ++summary.guarded;
      }
    }
    const bool first_in_budget = !tracked_now.empty();
    if (first_in_budget) std::fill(tracked_now.begin(), tracked_now.begin() + count, std::uint8_t{0});
    if (k == 0 || window.keyframe(k - 1).tracked == nullptr) return;
    const std::uint8_t* tracked = window.keyframe(k - 1).tracked;
    const Observation* obs = window.observations(k - 1);
    const PointDecision* first = decisions.data();
    for (std::uint32_t o = 0; o < window.observation_count(k - 1); ++o) {
      if (tracked[o] == 0) continue;
      PointDecision* d = std::lower_bound(
          decisions.data(), decisions.data() + count, obs[o].point,
          [](const PointDecision& x, PointId id) { return x.point < id; });
      if (d == first + count || d->point != obs[o].point || d->verdict == Verdict::kSkip) continue;
      if (first_in_budget) {  // counted among the candidates (decide_budget)
        tracked_now[static_cast<std::size_t>(d - first)] = 1;
        continue;
      }
      skip(*d);
      ++summary.tracked;
    }
  }

  // The decided keyframes' (slots from .. to) points are found by id among
  // the decisions (ascending id): their observations, not every point's
  // keyframes, are read.
  void restrict_to_slots(const Window& window, std::uint32_t from, std::uint32_t to) {
    std::uint8_t* seen = in_scope.data();
    std::fill(seen, seen + count, std::uint8_t{0});
    const PointDecision* first = decisions.data();
    for (std::uint32_t s = from; s <= to; ++s) {
      const Observation* obs = window.observations(s);
      for (std::uint32_t o = 0; o < window.observation_count(s); ++o) {
        const PointDecision* at = std::lower_bound(
            first, first + count, obs[o].point,
            [](const PointDecision& d, PointId id) { return d.point < id; });
        seen[at - first] = 1;  // every window point has a decision
      }
    }
    summary.caught_up = to - from;
    for (std::uint32_t i = 0; i < count; ++i) {
      PointDecision& d = decisions[i];
      if (d.verdict == Verdict::kSkip || seen[i]) continue;
      skip(d);
      ++summary.out_of_scope;
    }
  }

  // Keyframes in slot order (oldest first): one below the floor promotes its
  // culled points back to keep, those whose flow is the largest fraction
  // of their capacity first (nearest to being kept), ties to the smaller
  // point id, until it holds or none is left. A promotion only raises
  // counts, so every earlier keyframe still holds when the pass ends.
  void apply_floor(std::uint32_t k) {
    std::fill(covered.begin(), covered.begin() + k, 0u);
    std::fill(culled_at.begin(), culled_at.begin() + k + 1, 0u);
    const auto for_slots = [this](std::uint32_t i, auto&& f) {
      for (std::uint32_t x = slots_at[i]; x < slots_at[i + 1]; ++x) f(slots[x]);
    };
    // Evaluated: seen by >= 2 keyframes (a scope's skips included).
    const auto evaluated = [this](std::uint32_t i) { return slots_at[i + 1] - slots_at[i] >= 2; };
    for (std::uint32_t i = 0; i < count; ++i) {
      if (!evaluated(i)) continue;
      if (decisions[i].verdict == Verdict::kCull) {
        for_slots(i, [&](std::uint32_t s) { ++culled_at[s + 1]; });
      } else {
        for_slots(i, [&](std::uint32_t s) { ++covered[s]; });
      }
    }
    const std::uint32_t floor = params.coverage_floor;
    // Most windows hold the floor already: then the culled lists are not needed.
    if (std::all_of(covered.begin(), covered.begin() + k, [floor](std::uint32_t c) { return c >= floor; })) return;
    for (std::uint32_t s = 0; s < k; ++s) culled_at[s + 1] += culled_at[s];
    for (std::uint32_t i = 0; i < count; ++i) {
      if (!evaluated(i) || decisions[i].verdict != Verdict::kCull) continue;
      for_slots(i, [&](std::uint32_t s) { culled_list[culled_at[s]++] = i; });
    }
    for (std::uint32_t s = k; s > 0; --s) culled_at[s] = culled_at[s - 1];
    culled_at[0] = 0;

    const auto nearer = [this](std::uint32_t a, std::uint32_t b) {
      if (budgeted) {  // smaller threshold first
        return threshold_of[a] != threshold_of[b] ? threshold_of[a] < threshold_of[b] : a < b;
      }
      const PointDecision& x = decisions[a];
      const PointDecision& y = decisions[b];
      const std::int64_t l = x.flow * y.capacity, r = y.flow * x.capacity;
      return l != r ? l > r : a < b;
    };
    for (std::uint32_t s = 0; s < k; ++s) {
      if (covered[s] >= floor) continue;
      ++summary.floor_keyframes;
      std::uint32_t n = 0;
      for (std::uint32_t c = culled_at[s]; c < culled_at[s + 1]; ++c) {
        if (decisions[culled_list[c]].verdict == Verdict::kCull) candidates[n++] = culled_list[c];
      }
      const std::uint32_t take = std::min(floor - covered[s], n);
      std::uint32_t* first = candidates.data();
      std::partial_sort(first, first + take, first + n, nearer);
      for (std::uint32_t c = 0; c < take; ++c) {
        decisions[first[c]].verdict = Verdict::kKeep;
        for_slots(first[c], [&](std::uint32_t t) { ++covered[t]; });
      }
      summary.kept += take;
      summary.culled -= take;
      summary.floor_promoted += take;
      summary.floor_short += covered[s] < floor ? 1 : 0;
    }
  }
};

Sparsifier::Sparsifier(const Capacities& capacities, const Params& params, SolveMode mode,
                       Start start)
    : impl_(std::make_unique<Impl>(capacities, params, mode, start)) {}
Sparsifier::~Sparsifier() = default;

Status Sparsifier::validate(const Params& p) {
  // M is an arc capacity, which the solver holds in 32 bits (with a budget too:
  // the thresholds' solves run at M* up to it).
  if (p.pair_capacity < 1 || p.pair_capacity > INT32_MAX) return Status::kInvalidArgument;
  if (!std::isfinite(p.theta) || p.theta < 0.0 || p.theta > 1.0) return Status::kInvalidArgument;
  if (p.box_width < 0 || p.box_height < 0) return Status::kInvalidArgument;
  if (p.spatial_weight < 1 || p.spatial_weight > kMaxSpatialWeight) return Status::kInvalidArgument;
  if (p.scope != Scope::kWindow && p.scope != Scope::kNewest && p.scope != Scope::kAuto) {
    return Status::kInvalidArgument;
  }
  // Bits beyond the defined terms would be ignored silently.
  if ((p.cost_terms & ~(kConnectivityCost | kSpatialCost | kBaselineCost)) != 0) return Status::kInvalidArgument;
  if ((p.track_terms & ~(kTrackLength | kTrackAge | kTrackError | kTrackAngle)) != 0) return Status::kInvalidArgument;
  switch (p.budget.kind) {
    case BudgetKind::kNone:
    case BudgetKind::kPoints:
    case BudgetKind::kObservations: break;
    case BudgetKind::kFraction:
      if (!std::isfinite(p.budget.fraction) || p.budget.fraction < 0.0 || p.budget.fraction > 1.0) {
        return Status::kInvalidArgument;
      }
      break;
    default: return Status::kInvalidArgument;
  }
  // A track share takes part of a count (kPoints, kFraction) by track length.
  const double share = p.budget.track_share;
  if (!std::isfinite(share) || share < 0.0 || share > 1.0) return Status::kInvalidArgument;
  const double from = p.budget.track_share_from, to = p.budget.track_share_to;
  if (!std::isfinite(from) || !std::isfinite(to) || from < 0.0 || from > to || to > 1.0) {
    return Status::kInvalidArgument;
  }
  if (share_needs_a_count(p.budget) && !keeps_a_count(p.budget.kind)) return Status::kInvalidArgument;
  switch (p.cost_model) {
    case CostModel::kPaper:
    case CostModel::kInformation:
    case CostModel::kTrack: return Status::kOk;
    case CostModel::kAuthors:
      return p.image_width > 0 && p.image_height > 0 ? Status::kOk : Status::kInvalidArgument;
  }
  return Status::kInvalidArgument;
}

Status Sparsifier::run(const Window& window, const solver::Budget& budget) {
  const Status r = impl_->run(window, budget);
  impl_->end_turn(window, r);
  return r;
}

Status Sparsifier::update(const Window& window, const solver::Budget& budget) {
  Impl& s = *impl_;
  const Status r = s.incremental ? s.update(window, budget) : s.run(window, budget);
  s.end_turn(window, r);
  return r;
}

void Sparsifier::note_undecided() {
  if (impl_->params.scope != Scope::kWindow) impl_->missed = true;
}

Status Sparsifier::Impl::run(const Window& window, const solver::Budget& budget) {
  Impl& s = *this;
  s.begin_call();
  if (Status v = validate(s.params); v != Status::kOk) return v;
  if (!s.network) s.network = std::make_unique<PaperNetwork>(s.caps);  // kIncremental's first run()
  PaperNetwork& net = *s.network;
  s.solver_incremental = false;  // build() resets the solver
  const std::uint64_t t0 = s.now();
  if (Status b = net.build(window, s.params, s.solver); b != Status::kOk) return b;
  const std::uint64_t t1 = s.now();
  const solver::NodeId source = net.source(), sink = net.sink();
  if (s.budgeted) {  // no solve: the thresholds decide
    s.summary.keyframes = window.keyframe_count();
    s.decide_budget(window, net);
    const std::uint64_t t2 = s.now();
    s.apply_policies(window, net, true);
    s.times = StageTimes{t1 - t0, t2 - t1, s.now() - t2};
    return Status::kOk;
  }
  const Status result =
      s.start == Start::kClosedForm
          ? s.solve_closed_form(source, sink, net.canonical_order(),
                                static_cast<std::int32_t>(net.evaluated_count()), budget)
          : from_solver(s.solver.solve(source, sink, budget));
  const std::uint64_t t2 = s.now();
  if (result != Status::kOk && result != Status::kBudgetExhausted) return result;
  s.summary.keyframes = window.keyframe_count();
  s.decide_all(net, result == Status::kOk);
  s.apply_policies(window, net, result == Status::kOk);
  s.times = StageTimes{t1 - t0, t2 - t1, s.now() - t2};
  return result;
}

Status Sparsifier::Impl::update(const Window& window, const solver::Budget& budget) {
  Impl& s = *this;
  s.begin_call();
  if (Status v = validate(s.params); v != Status::kOk) return v;
  IncrementalNetwork& net = *s.incremental;
  if (!s.solver_incremental) {  // run() used the solver since
    net.clear();
    s.resume = s.resumed = false;
  }
  s.solver_incremental = true;
  const std::uint64_t t0 = s.now();
  // Planning against the deadline: deciding needs its usual time after the
  // solve, so the solver's deadline is that much earlier; and if there is
  // not time to update the network, solve and decide as usual, the call
  // answers at once, keeping every point, and leaves the network as it is
  // (the next call catches up with everything since: the diff is against
  // the network, not against the previous window).
  const solver::Clock* deadline_clock = budget.clock;
  const std::uint64_t u0 = deadline_clock != nullptr ? deadline_clock->now_ns() : 0;
  const std::uint64_t decide_ns = s.decide_time.expected();
  s.deferred = deadline_clock != nullptr &&
               (u0 >= budget.deadline_ns ||
                budget.deadline_ns - u0 <
                    s.network_time.expected() + s.solve_time.expected() + decide_ns);
  if (s.deferred) {
    // Deferred on the estimate, not because the call came late: the estimate decays (with the back-off).
    if (u0 < budget.deadline_ns && ++s.deferrals >= (1u << s.backoff)) {
      s.deferrals = 0;
      s.network_time.decay();
      s.solve_time.decay();
      s.decide_time.decay();
    }
    s.summary.keyframes = window.keyframe_count();
    s.summary.points = window.distinct_points();
    s.summary.kept = s.summary.points;
    s.times = StageTimes{0, 0, s.now() - t0};
    return Status::kBudgetExhausted;
  }
  if (Status u = net.update(window, s.params, s.solver); u != Status::kOk) {
    net.clear();
    return u;
  }
  const std::uint64_t t1 = s.now();
  solver::Budget solve_budget = budget;
  const std::uint64_t u1 = deadline_clock != nullptr ? deadline_clock->now_ns() : 0;
  if (deadline_clock != nullptr) {
    s.network_time.add(u1 - u0);
    solve_budget.deadline_ns = budget.deadline_ns > decide_ns ? budget.deadline_ns - decide_ns : 0;
  }
  // The network's arc ids are recycled, so the tie-break is given as an
  // order: source arcs by ascending point id, as PaperNetwork inserts them.
  // The closed-form start breaks its ties by that order directly. From zero
  // flow, the solver is told it and a solve finds run()'s optimum; only
  // after a stop for budget does the next call re-optimise from the flow
  // and potentials left behind (keeping the progress made), which can land
  // on another optimum among ties, so canonicalize() then moves to the one
  // run() finds. A slide's repair from that state costs more than a fresh
  // solve, so if the resumption runs out too, the next call starts afresh:
  // sustained overload cannot lock the path into it.
  const auto evaluated = static_cast<std::int32_t>(net.evaluated_count());
  const solver::ArcId* order = net.canonical_order();
  Status result = Status::kOk;
  bool warm = false;
  if (s.budgeted) {  // no solve: the thresholds decide (in the decide stage)
  } else if (s.start == Start::kClosedForm) {
    result = s.solve_closed_form(net.source(), net.sink(), order, evaluated, solve_budget);
  } else {
    result = from_solver(s.solver.set_tie_order(order, evaluated));
    warm = s.resume && !s.resumed;
    if (result == Status::kOk && !warm) {
      result = from_solver(s.solver.solve(net.source(), net.sink(), solve_budget));
    } else if (result == Status::kOk) {
      result = from_solver(s.solver.solve_warm(net.source(), net.sink(), solve_budget));
      if (result == Status::kOk) result = s.canonicalize(order, evaluated, solve_budget);
    }
  }
  s.resume = result == Status::kBudgetExhausted;
  s.resumed = warm;
  if (deadline_clock != nullptr && result == Status::kOk) {
    s.solve_time.add(deadline_clock->now_ns() - u1);
  }
  const std::uint64_t t2 = s.now();
  if (result != Status::kOk && result != Status::kBudgetExhausted) {
    net.clear();
    return result;
  }
  const std::uint64_t d0 = deadline_clock != nullptr ? deadline_clock->now_ns() : 0;
  s.summary.keyframes = window.keyframe_count();
  if (s.budgeted) {
    s.decide_budget(window, net);
  } else {
    s.decide_all(net, result == Status::kOk);
  }
  s.apply_policies(window, net, result == Status::kOk);
  if (deadline_clock != nullptr) {
    const std::uint64_t done = deadline_clock->now_ns();
    s.decide_time.add(done - d0);
    s.backoff = done > budget.deadline_ns ? std::min(s.backoff + 1, Impl::kMaxBackoff) : 0;
    s.deferrals = 0;
  }
  s.times = StageTimes{t1 - t0, t2 - t1, s.now() - t2};
  return result;
}

void Sparsifier::set_clock(const solver::Clock* clock) { impl_->clock = clock; }
const StageTimes& Sparsifier::stage_times() const { return impl_->times; }
bool Sparsifier::deferred() const { return impl_->deferred; }
const Summary& Sparsifier::summary() const { return impl_->summary; }
std::uint32_t Sparsifier::decision_count() const { return impl_->count; }
const PointDecision* Sparsifier::decisions() const { return impl_->decisions.data(); }
std::uint32_t Sparsifier::kept_at(std::int64_t m) const { return impl_->kept_at(m); }
const std::uint32_t* Sparsifier::keep_thresholds() const {
  return impl_->budgeted ? impl_->threshold_of.data() : nullptr;
}
void Sparsifier::forget_history() {
  if (impl_->fraction) impl_->fraction->clear();
  impl_->has_decided = impl_->missed = false;
  impl_->evaluated_sum = impl_->returned_sum = 0;
}
const Params& Sparsifier::params() const { return impl_->params; }
const PaperNetwork& Sparsifier::network() const {
  if (impl_->network) return *impl_->network;
  static const PaperNetwork none(Capacities{0, 0, 0, 0, 0});  // an incremental Sparsifier before any run()
  return none;
}
const IncrementalNetwork* Sparsifier::incremental_network() const {
  return impl_->incremental.get();
}
SolveMode Sparsifier::mode() const { return impl_->mode; }
Start Sparsifier::start() const { return impl_->start; }
const solver::MinCostFlow& Sparsifier::solver() const { return impl_->solver; }

std::size_t Sparsifier::memory_bytes() const {
  const Impl& s = *impl_;
  return sizeof(Sparsifier) + sizeof(Impl) + (s.network ? s.network->memory_bytes() : 0) +
         (s.incremental ? s.incremental->memory_bytes() : 0) + s.solver.memory_bytes() +
         s.pairwise.memory_bytes() +
         (s.thresholds ? sizeof(KeepThresholds) + s.thresholds->memory_bytes() : 0) +
         (s.fraction ? s.fraction->memory_bytes() : 0) +
         (s.threshold_of.capacity() + s.curve.capacity() + s.cursor.capacity() +
          s.ranked.capacity() + s.views_of.capacity() + s.views_histogram.capacity()) *
             sizeof(std::uint32_t) +
         s.rank_of.capacity() * sizeof(std::int32_t) +
         s.decisions.capacity() * sizeof(PointDecision) +
         s.in_scope.capacity() + s.tracked_now.capacity() +
         (s.slots_at.capacity() + s.slots.capacity() + s.covered.capacity() +
          s.culled_at.capacity() + s.culled_list.capacity() + s.candidates.capacity()) *
             sizeof(std::uint32_t);
}

}  // namespace keepless::core
