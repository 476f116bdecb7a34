#include <algorithm>
#include <limits>

#include "min_cost_flow_impl.hpp"

namespace keepless::solver {

using namespace detail;

// A path of at most kLocalDepth zero-reduced-cost residual arcs from x
// (forwards) or into x (backwards) to a node that can take (or give) flow,
// by depth-first search; the records of the path, from x, are left in
// path_arc[0 .. path_depth). Forwards scans a node's residual arcs;
// backwards scans its whole block, every record's partner being an arc
// into it.
bool MinCostFlow::Impl::local_path(NodeId x, bool forward) {
  new_visit_epoch();
  visit[x] = visit_epoch;
  path_node[0] = x;
  cur[x] = first_out[x];
  std::int32_t depth = 0;
  for (;;) {
    const NodeId u = path_node[depth];
    if (depth > 0 && (forward ? can_absorb(u) : can_supply(u))) {
      path_depth = depth;
      return true;
    }
    std::int32_t found = -1;
    if (depth < kLocalDepth) {
      const Cost pu = pot[u];
      const std::int32_t end = forward ? first_rev[u] + nflow[u] : block_end[u];
      std::int32_t p = cur[u];
      const std::int32_t start = p;
      for (; p < end; ++p) {
        const std::int32_t i = forward ? record_at(u, p) : p;
        const Residual& a = res[i];
        const NodeId w = a.head;
        if (visit[w] == visit_epoch) continue;
        // Forwards: the arc u -> w is record i. Backwards: w -> u is its partner.
        const std::int32_t record = forward ? i : rev[i];
        if (res[record].cap == 0) continue;
        if (forward ? a.cost + pu != pot[w] : res[record].cost + pot[w] != pu) continue;
        found = record;
        break;
      }
      stats.work_units += static_cast<std::uint64_t>(p - start + 1);
      cur[u] = p + 1;
    }
    if (found >= 0) {
      const NodeId w = forward ? res[found].head : res[rev[found]].head;
      path_arc[depth] = found;
      path_node[++depth] = w;
      visit[w] = visit_epoch;
      cur[w] = first_out[w];
      continue;
    }
    if (depth == 0) return false;
    --depth;
  }
}

// Routes what it can of every imbalance along such short paths: most
// repairs of a window slide end one or two arcs away (an excess unit back
// to the source, a pair's marginal point evicted, a deficit filled by the
// next tied candidate). Zero reduced cost keeps the certificate, and no
// search is needed. Returns false if the budget ran out.
bool MinCostFlow::Impl::local_repair(Meter& meter) {
  for (int pass = 0; pass < 2; ++pass) {
    const bool forward = pass == 0;  // excesses first, then deficits
    for (std::int32_t k = 0; k < imbalanced_count; ++k) {
      const NodeId x = imbalanced[k];
      while (forward ? excess[x] > 0 : excess[x] < 0) {
        if (!local_path(x, forward)) {
          if (meter.exhausted(kAugmentStride)) return false;  // failed scans cost work too
          break;
        }
        const NodeId end = path_node[path_depth];
        std::int64_t f = forward ? excess[x] : -excess[x];
        if (end != src && end != snk) f = std::min(f, forward ? -excess[end] : excess[end]);
        for (std::int32_t j = 0; j < path_depth; ++j) f = std::min<std::int64_t>(f, res[path_arc[j]].cap);
        for (std::int32_t j = 0; j < path_depth; ++j) push(path_arc[j], static_cast<std::int32_t>(f));
        if (forward) {
          excess[x] -= f;
          if (end != src && end != snk) excess[end] += f;
        } else {
          excess[x] += f;
          if (end != src && end != snk) excess[end] -= f;
        }
        ++stats.augmentations;
        if (meter.exhausted(kAugmentStride)) return false;
      }
    }
  }
  return true;
}

void MinCostFlow::Impl::clear_recosted() {
  for (std::int32_t k = 0; k < recosted_count; ++k) is_recosted[recosted[k]] = 0;
  recosted_count = 0;
}

// An arc that carried flow and changed cost usually still belongs in the
// optimum: rather than let the repair saturate or empty it (up to its
// capacity in new excess), move its new reduced cost onto the potential
// of its end with fewer arcs. In the paper's network that is a point whose
// view count changed: its source arc stays tight and only the pair arcs
// at the margin of its new cost get repaired, one unit each.
void MinCostFlow::Impl::shift_recosted_potentials() {
  for (std::int32_t k = 0; k < recosted_count; ++k) {
    const ArcId a = recosted[k];
    is_recosted[a] = 0;
    if (!active(a)) continue;
    const NodeId u = arc[a].tail, v = arc[a].head;
    const std::int32_t fl = std::min(arc_flow[a], arc[a].capacity);
    const Cost rc = arc[a].cost + pot_ext[u] - pot_ext[v];
    if (!((rc < 0 && fl < arc[a].capacity) || (rc > 0 && fl > 0))) continue;
    if (degree(v) <= degree(u)) {
      pot_ext[v] += rc;
    } else {
      pot_ext[u] -= rc;
    }
  }
  recosted_count = 0;
}

Status MinCostFlow::Impl::solve_warm(NodeId s, NodeId t, const Budget& budget) {
  if (!have_state || s != src_ext || t != snk_ext || overflow) return solve_scratch(s, t, budget);
  stats = {};
  stats.warm = true;
  if (!laid_out) {
    const Cost max_cost = count_degrees();
    const std::uint64_t base = set_label_base();
    set_terminals(s, t);
    estimate_potentials();
    shift_recosted_potentials();
    // The reduced cost of any arc stays below max cost + potential spread.
    Cost lo = 0, hi = 0;
    bool first = true;
    for (NodeId v = 0; v < nodes; ++v) {
      if (degree(v) == 0) continue;
      lo = first ? pot_ext[v] : std::min(lo, pot_ext[v]);
      hi = first ? pot_ext[v] : std::max(hi, pot_ext[v]);
      first = false;
    }
    const auto span = static_cast<std::uint64_t>(max_cost) + static_cast<std::uint64_t>(hi - lo) + 1;
    if (hi - lo > Cost{1} << 60 || base > kLabelLimit / base / span) {
      return solve_scratch(s, t, budget);
    }
    lay_out(true);
  } else {
    set_label_base();  // as at the layout (label_nodes is the layout's)
  }
  Meter meter(budget, stats);
  // Once per layout: a resumed call goes on with the searches.
  Status status = !repair_pending || local_repair(meter) ? Status::kOptimal : Status::kBudgetExhausted;
  if (status == Status::kOptimal) repair_pending = false;
  if (status == Status::kOptimal) status = run(Mode::kExcess, meter);
  if (status == Status::kOptimal) status = run(Mode::kDeficit, meter);
  if (status == Status::kOptimal) status = run(Mode::kMaxFlow, meter);
  finish();
  if (overflow) {
    laid_out = false;
    return solve_scratch(s, t, remaining(budget, stats.work_units));
  }
  if (cost_overflow) {
    have_state = optimal = false;
    return Status::kInvalidInput;
  }
  optimal = status == Status::kOptimal && is_balanced;
  return status;
}

// Potentials for nodes that are new since the last layout (or renewed):
// the cheapest arrival over an arc from a known node, else the latest
// departure over an arc to one, else unchanged. Any value is correct (the
// repair restores the certificate); a good one leaves little to repair.
// Runs between count_degrees and lay_out, whose scratch it borrows; in
// user numbers, like the potentials kept between calls.
void MinCostFlow::Impl::estimate_potentials() {
  std::int32_t fresh_count = 0;
  for (NodeId v = 0; v < nodes; ++v) {
    const bool fresh = (!seen[v] || renewed[v]) && degree(v) > 0;
    fill[v] = fresh ? 1 : 0;
    fresh_count += fresh ? 1 : 0;
  }
  if (fresh_count == 0) return;
  constexpr Cost kNoArrival = std::numeric_limits<Cost>::max();
  constexpr Cost kNoDeparture = std::numeric_limits<Cost>::min();
  Cost* arrival = estimate.data();
  std::int64_t* departure = excess.data();  // recomputed by lay_out
  for (NodeId v = 0; v < nodes; ++v) {
    arrival[v] = kNoArrival;
    departure[v] = kNoDeparture;
  }
  for (ArcId a = 0; a < arcs; ++a) {
    if (!active(a)) continue;
    const NodeId u = arc[a].tail, v = arc[a].head;
    if (fill[v] != 0 && fill[u] == 0) arrival[v] = std::min(arrival[v], pot_ext[u] + arc[a].cost);
    if (fill[u] != 0 && fill[v] == 0) departure[u] = std::max(departure[u], pot_ext[v] - arc[a].cost);
  }
  for (NodeId v = 0; v < nodes; ++v) {
    if (fill[v] == 0) continue;
    if (arrival[v] != kNoArrival) {
      pot_ext[v] = arrival[v];
    } else if (departure[v] != kNoDeparture) {
      pot_ext[v] = departure[v];
    }
  }
}

}  // namespace keepless::solver
