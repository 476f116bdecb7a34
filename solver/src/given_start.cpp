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
  // Locals, not members, in the node loops: a store through a byte pointer
  // would make the compiler reload every member on every iteration. (The
  // arc pass keeps reading members: written with locals, it spilled.)
  const NodeId n = nodes;
  Cost* pot = pot_ext.data();
  std::int64_t* ex = excess.data();
  std::uint8_t* seen_at = seen.data();
  std::uint8_t* renewed_at = renewed.data();
  bool ok = true;
  for (NodeId v = 0; v < n; ++v) {
    ok &= potential[v] >= -kPotentialBound && potential[v] <= kPotentialBound;
    pot[v] = std::clamp(potential[v], -kPotentialBound, kPotentialBound);
    ex[v] = 0;  // user numbering here
    seen_at[v] = 1;  // the given potentials stand (see estimate_potentials)
    renewed_at[v] = 0;
  }
  Cost max_cost = 0;
  Cost total = 0;
  bool wrapped = false;  // the total left int64: no certificate (the re-optimisation refuses it)
  const ArcId m = arcs;
  // No branches (`&`, `|`): an edited network scatters retired arcs over
  // the ids. A retired arc's flow must be 0, and is taken as 0.
  for (ArcId a = 0; a < m; ++a) {
    const Flow f = flow[a];
    const Arc& e = arc[a];
    const bool live = (e.capacity > 0) & (e.tail != e.head);  // active(a)
    const std::int32_t cap = live ? e.capacity : 0;
    const Cost rc = e.cost + pot_ext[e.tail] - pot_ext[e.head];
    ok &= (f >= 0) & (f <= cap) & ((f == cap) | (rc >= 0)) & ((f == 0) | (rc <= 0));
    const auto fl = static_cast<std::int32_t>(std::clamp<Flow>(f, 0, cap));
    arc_flow[a] = fl;
    excess[e.tail] -= fl;
    excess[e.head] += fl;
    max_cost = std::max<Cost>(max_cost, live ? e.cost : 0);
    wrapped |= __builtin_add_overflow(total, Cost{fl} * e.cost, &total);
  }
  cost_total = total;
  // Conservation but at the terminals: an OR over the excesses with theirs
  // set aside (no branch per node, and it vectorises).
  const std::int64_t at_s = ex[s], at_t = ex[t];
  ex[s] = ex[t] = 0;
  std::int64_t unbalanced = 0;
  for (NodeId v = 0; v < n; ++v) unbalanced |= ex[v];
  ex[s] = at_s;
  ex[t] = at_t;
  value = -at_s;
  return ok && !wrapped && unbalanced == 0 && pot[t] - pot[s] > Cost{n - 1} * max_cost;
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
  if (!certified) return solve_warm(s, t, remaining(budget, static_cast<std::uint64_t>(arcs)));  // after the pass
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
