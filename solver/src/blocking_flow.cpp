#include <algorithm>

#include "min_cost_flow_impl.hpp"

namespace keepless::solver {

using namespace detail;

// Dinic blocking flow on the level graph, from each source in turn. The
// DFS serves each node's forward arcs in arc id order, so earlier arcs win
// ties. Returns false if the budget ran out.
bool MinCostFlow::Impl::blocking_flow(std::int32_t source_count, Meter& meter) {
  for (std::int32_t k = 0; k < touched_count; ++k) {
    const NodeId v = touched[k];
    cur[v] = next_position(v, first_out[v]);
  }
  for (std::int32_t k = 0; k < source_count; ++k) {
    const NodeId x = sources[k];
    if (level[x] < 0) continue;
    std::int64_t supply = supply_of(x);
    std::int32_t depth = 0;
    path_node[0] = x;
    NodeId u = x;
    while (supply > 0) {
      if (depth > 0 && is_target(u)) {
        std::int64_t f = std::min(supply, need_of(u));
        for (std::int32_t j = 0; j < depth; ++j) f = std::min<std::int64_t>(f, res[path_arc[j]].cap);
        const auto f32 = static_cast<std::int32_t>(f);
        std::int32_t retreat = depth;
        for (std::int32_t j = 0; j < depth; ++j) {
          push(path_arc[j], f32);
          if (res[path_arc[j]].cap == 0 && retreat == depth) retreat = j;
        }
        if (mode != Mode::kMaxFlow) {
          if (x != src && x != snk) excess[x] -= f;
          if (u != src && u != snk) excess[u] += f;
        }
        if (supply != kUnlimited) supply -= f;
        ++stats.augmentations;
        if (meter.exhausted(kAugmentStride)) return false;
        depth = retreat;  // resume at the tail of the first saturated arc
        u = path_node[depth];
        continue;
      }
      const std::int32_t want = backward ? level[u] - 1 : level[u] + 1;
      const Cost pu = pot[u];
      const std::int32_t fr = first_rev[u];
      const std::int32_t end = fr + nflow[u];
      std::int32_t found = -1;
      std::int32_t p = cur[u];
      std::uint64_t scanned = 1;
      const auto admissible = [&](const Residual& a) {
        return a.cap > 0 && level[a.head] == want && a.cost + pu == pot[a.head];
      };
      if (u == src && (lazy || (backward && marked))) {
        for (; p < end; p = next_position(u, p + 1), ++scanned) {  // the listed source arcs only
          const std::int32_t i = record_at(u, p);
          if (admissible(res[i])) {
            found = i;
            break;
          }
        }
      } else {
        const std::int32_t start = p;
        for (; p < fr; ++p) {
          if (admissible(res[p])) {
            found = p;
            break;
          }
        }
        if (found < 0) {
          for (; p < end; ++p) {
            if (admissible(res[flist[p]])) {
              found = flist[p];
              break;
            }
          }
        }
        scanned += static_cast<std::uint64_t>(p - start);
      }
      stats.work_units += scanned;
      cur[u] = p;
      if (found >= 0) {
        path_arc[depth] = found;
        u = res[found].head;
        path_node[++depth] = u;
        continue;
      }
      level[u] = -1;  // dead end: prune it for the rest of this blocking flow
      if (depth == 0) break;
      u = path_node[--depth];
      cur[u] = next_position(u, cur[u] + 1);
    }
  }
  return true;
}

// Phases of one mode until nothing is left to route.
Status MinCostFlow::Impl::run(Mode m, Meter& meter) {
  mode = m;
  backward = false;
  marked = false;
  lazy_begin();
  const Status status = run_phases(m, meter);
  lazy = false;
  return status;
}

Status MinCostFlow::Impl::run_phases(Mode m, Meter& meter) {
  for (;;) {
    if (meter.exhausted(0)) return Status::kBudgetExhausted;
    std::int32_t count = 0;
    if (m == Mode::kExcess) {
      for (std::int32_t k = 0; k < imbalanced_count; ++k) {
        if (excess[imbalanced[k]] > 0) sources[count++] = imbalanced[k];
      }
    } else if (m == Mode::kDeficit) {
      bool any = false;
      for (std::int32_t k = 0; k < imbalanced_count && !any; ++k) any = excess[imbalanced[k]] < 0;
      if (any) {
        sources[count++] = std::min(src, snk);
        sources[count++] = std::max(src, snk);
      }
    } else {
      sources[count++] = src;
    }
    if (count == 0) return Status::kOptimal;
    const std::uint64_t before = stats.work_units;
    const Search found = backward ? shortest_paths_to_sink(meter) : shortest_paths(count, meter);
    // A forward search that had to scan more than a quarter of the
    // residual graph will keep doing so: the rest of the run searches
    // from the sink (only source-to-sink phases have a single target).
    const bool turn = m == Mode::kMaxFlow && !backward &&
                      stats.work_units - before > static_cast<std::uint64_t>(records) / 4;
    if (found != Search::kFound) {
      clear_labels();
      return found == Search::kExhausted ? Status::kBudgetExhausted : Status::kOptimal;
    }
    ++stats.phases;
    const bool done = blocking_flow(count, meter);
    clear_labels();
    if (!done) return Status::kBudgetExhausted;
    if (lazy) lazy_end_phase();
    if (turn) {
      backward = true;
      lazy = false;  // the source's lazy order is not kept up from here
    }
  }
}

// Reads flows, cost, value and potentials back from the residual graph.
void MinCostFlow::Impl::finish() {
  value = 0;
  cost_total = 0;
  cost_overflow = false;
  for (ArcId a = 0; a < arcs; ++a) {
    const std::int32_t f = arc_pos[a] >= 0 ? arc[a].capacity - res[arc_pos[a]].cap : 0;
    arc_flow[a] = f;
    cost_overflow |= __builtin_add_overflow(cost_total, Cost{f} * arc[a].cost, &cost_total);  // each term < 2^61
    if (arc[a].tail == src_ext) value += f;
    if (arc[a].head == src_ext) value -= f;
  }
  for (NodeId v = 0; v < nodes; ++v) pot_ext[ext_of[v]] = pot[v];
  std::int32_t kept = 0;
  for (std::int32_t k = 0; k < imbalanced_count; ++k) {
    if (excess[imbalanced[k]] != 0) imbalanced[kept++] = imbalanced[k];
  }
  imbalanced_count = kept;
  is_balanced = kept == 0;
}

// Too late to start: the zero flow, at zero potentials, is valid and
// certified (costs are >= 0), and a later solve_warm can start from it.
Status MinCostFlow::Impl::stop_before_start(NodeId s, NodeId t) {
  clear_recosted();
  src_ext = s;
  snk_ext = t;
  stats = {};
  std::fill(arc_flow.begin(), arc_flow.begin() + arcs, 0);
  std::fill(pot_ext.begin(), pot_ext.begin() + nodes, 0);
  value = 0;
  cost_total = 0;
  imbalanced_count = 0;
  is_balanced = true;
  laid_out = false;
  have_state = true;
  optimal = false;
  return Status::kBudgetExhausted;
}

Status MinCostFlow::Impl::solve_scratch(NodeId s, NodeId t, const Budget& budget) {
  if (budget.clock != nullptr && budget.clock->now_ns() >= budget.deadline_ns) {
    return stop_before_start(s, t);
  }
  clear_recosted();
  stats = {};
  overflow = false;
  const Cost max_cost = count_degrees();
  const std::uint64_t base = set_label_base();
  set_terminals(s, t);
  // Distances stay below nodes * max cost, and labels must hold them: a
  // network too large for its costs is beyond a capacity, not bad input.
  if (base > kLabelLimit / base / static_cast<std::uint64_t>(max_cost + 1)) {
    laid_out = false;
    have_state = false;
    return Status::kCapacityExceeded;
  }
  std::fill(pot_ext.begin(), pot_ext.begin() + nodes, 0);
  std::fill(arc_flow.begin(), arc_flow.begin() + arcs, 0);
  lay_out(false);
  Meter meter(budget, stats);
  const Status status = run(Mode::kMaxFlow, meter);
  finish();
  have_state = !cost_overflow;
  optimal = status == Status::kOptimal && !cost_overflow;
  return cost_overflow ? Status::kInvalidInput : status;
}

}  // namespace keepless::solver
