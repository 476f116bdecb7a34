#include <algorithm>

#include "min_cost_flow_impl.hpp"

namespace keepless::solver {

using namespace detail;

// Takes the caller's start as the state (flows clipped to the capacities,
// potentials to +-2^60) and checks it in the same pass: capacities,
// reduced costs, conservation, and the potential gap between the
// terminals. Any residual source-to-sink path P has potential(sink) -
// potential(source) <= cost(P) <= (nodes - 1) x max cost when every
// residual arc's reduced cost is >= 0, so a larger gap proves the flow
// maximum while the reduced costs prove it cheapest for its value.
bool MinCostFlow::Impl::adopt(NodeId s, NodeId t, const Flow* flow, const Cost* potential) {
  // Locals, not members, in the loops: the compiler cannot keep a member
  // in a register across stores through other pointers (one pass is most
  // of a decision's certificate).
  const NodeId n = nodes;
  const ArcId m = arcs;
  Cost* pot = pot_ext.data();
  std::int64_t* ex = excess.data();
  std::int32_t* carried = arc_flow.data();
  const Arc* arc_at = arc.data();
  bool ok = true;
  for (NodeId v = 0; v < n; ++v) {
    ok &= potential[v] >= -kPotentialBound && potential[v] <= kPotentialBound;
    pot[v] = std::clamp(potential[v], -kPotentialBound, kPotentialBound);
  }
  std::fill(ex, ex + n, 0);  // user numbering here
  std::fill(seen.begin(), seen.begin() + n, std::uint8_t{1});  // the given potentials stand (see estimate_potentials)
  std::fill(renewed.begin(), renewed.begin() + n, std::uint8_t{0});
  Cost max_cost = 0;
  Cost total = 0;
  // No branches (`&`, `|`): an edited network scatters retired arcs over
  // the ids. A retired arc's flow must be 0, and is taken as 0.
  for (ArcId a = 0; a < m; ++a) {
    const Flow f = flow[a];
    const Arc e = arc_at[a];
    const bool live = (e.capacity > 0) & (e.tail != e.head);  // active(a)
    const std::int32_t mask = -static_cast<std::int32_t>(live);  // masks, not selects: no jumps
    const std::int32_t cap = e.capacity & mask;
    const Cost rc = e.cost + pot[e.tail] - pot[e.head];
    ok &= (f >= 0) & (f <= cap) & ((f == cap) | (rc >= 0)) & ((f == 0) | (rc <= 0));
    const auto fl = static_cast<std::int32_t>(std::min<Flow>(std::max<Flow>(f, 0), cap));
    carried[a] = fl;
    ex[e.tail] -= fl;
    ex[e.head] += fl;
    max_cost = std::max<Cost>(max_cost, e.cost & mask);
    total += Cost{fl} * e.cost;
  }
  cost_total = total;
  for (NodeId v = 0; v < n; ++v) ok &= (v == s) | (v == t) | (ex[v] == 0);
  value = -ex[s];
  return ok && pot[t] - pot[s] > Cost{n - 1} * max_cost;
}

Status MinCostFlow::Impl::solve_from(NodeId s, NodeId t, const Flow* flow, const Cost* potential,
                                     const Budget& budget) {
  if ((budget.clock != nullptr && budget.clock->now_ns() >= budget.deadline_ns) ||
      budget.work_units < static_cast<std::uint64_t>(arcs)) {
    return stop_before_start(s, t);  // no time for the check
  }
  clear_recosted();
  stats = {};
  overflow = false;
  const bool certified = adopt(s, t, flow, potential);
  src_ext = s;
  snk_ext = t;
  have_state = true;
  laid_out = false;
  if (!certified) return solve_warm(s, t, budget);
  stats.work_units = static_cast<std::uint64_t>(arcs);
  stats.certified = true;
  imbalanced_count = 0;
  is_balanced = true;
  optimal = true;
  return Status::kOptimal;
}

void MinCostFlow::Impl::ensure_laid_out() {
  if (laid_out) return;
  count_degrees();
  set_terminals(src_ext, snk_ext);
  lay_out(false);
}

Status MinCostFlow::solve_from(NodeId source, NodeId sink, const Flow* flow, const Cost* potential,
                               const Budget& budget) {
  Impl& m = *impl_;
  if (!m.valid_terminals(source, sink) || (flow == nullptr && m.arcs > 0) || potential == nullptr) {
    return Status::kInvalidInput;
  }
  return m.solve_from(source, sink, flow, potential, budget);
}

}  // namespace keepless::solver
