#include <algorithm>

#include "min_cost_flow_impl.hpp"

namespace keepless::solver {

using namespace detail;

// Path from `from` to `to` over residual arcs of zero reduced cost that
// are not fixed, avoiding nodes known not to reach `to`. A failed search
// proves every node it visited dead: augmentations only add arcs leaving
// nodes that reach `to`, and fixing arcs only removes some, so a dead node
// stays dead for the rest of the pass.
bool MinCostFlow::Impl::tie_path(NodeId from, NodeId to) {
  new_visit_epoch();
  touched_count = 0;
  visit[from] = visit_epoch;
  touched[touched_count++] = from;
  cur[from] = first_out[from];
  path_node[0] = from;
  std::int32_t depth = 0;
  for (;;) {
    const NodeId u = path_node[depth];
    if (u == to) {
      path_depth = depth;
      touched_count = 0;
      return true;
    }
    const Cost pu = pot[u];
    const std::int32_t fr = first_rev[u];
    const std::int32_t end = fr + nflow[u];
    std::int32_t p = cur[u];
    const std::int32_t start = p;
    std::int32_t found = -1;
    for (; p < end; ++p) {
      const std::int32_t i = p < fr ? p : flist[p];
      const Residual& a = res[i];
      if (a.cap == 0 || fixed[i] != 0) continue;
      const NodeId w = a.head;
      if (visit[w] == visit_epoch || dead[w] == dead_epoch) continue;
      if (a.cost + pu != pot[w]) continue;
      found = i;
      break;
    }
    stats.work_units += static_cast<std::uint64_t>(p - start + 1);
    cur[u] = p;
    if (found >= 0) {
      const NodeId w = res[found].head;
      path_arc[depth] = found;
      path_node[++depth] = w;
      visit[w] = visit_epoch;
      touched[touched_count++] = w;
      cur[w] = first_out[w];
      continue;
    }
    if (depth == 0) {
      for (std::int32_t k = 0; k < touched_count; ++k) dead[touched[k]] = dead_epoch;
      touched_count = 0;
      return false;
    }
    ++cur[path_node[--depth]];
  }
}

void MinCostFlow::Impl::new_dead_epoch() {
  if (++dead_epoch == 0) {
    std::fill(dead.begin(), dead.begin() + nodes, 0u);
    dead_epoch = 1;
  }
}

Status MinCostFlow::canonicalize(const ArcId* order, std::int32_t count, const Budget& budget) {
  Impl& m = *impl_;
  if (!m.optimal || count < 0 || (count > 0 && order == nullptr)) return Status::kInvalidInput;
  for (std::int32_t k = 0; k < count; ++k) {
    if (order[k] < 0 || order[k] >= m.arcs) return Status::kInvalidInput;
  }
  m.ensure_laid_out();
  const std::uint64_t swaps_before = m.stats.canonical_swaps;
  Meter meter(budget, m.stats);
  Status status = Status::kOptimal;
  NodeId target = -1;
  std::int32_t k = 0;
  for (; k < count && status == Status::kOptimal; ++k) {
    const std::int32_t f = m.arc_pos[order[k]];
    if (f < 0) continue;
    const NodeId u = m.res[m.rev[f]].head, v = m.res[f].head;  // internal numbers
    m.fixed[f] = 1;
    m.fixed[m.rev[f]] = 1;
    if (u != target) {  // dead marks are relative to the node a search must reach
      target = u;
      m.new_dead_epoch();
    }
    while (m.res[f].cap > 0 && m.res[f].cost + m.pot[u] == m.pot[v]) {
      if (meter.exhausted(0)) {
        status = Status::kBudgetExhausted;
        break;
      }
      if (!m.tie_path(v, u)) break;
      std::int32_t delta = m.res[f].cap;
      for (std::int32_t j = 0; j < m.path_depth; ++j) delta = std::min(delta, m.res[m.path_arc[j]].cap);
      m.push(f, delta);
      for (std::int32_t j = 0; j < m.path_depth; ++j) m.push(m.path_arc[j], delta);
      ++m.stats.canonical_swaps;
    }
  }
  for (std::int32_t j = 0; j < k; ++j) {
    const std::int32_t f = m.arc_pos[order[j]];
    if (f < 0) continue;
    m.fixed[f] = 0;
    m.fixed[m.rev[f]] = 0;
  }
  if (m.stats.canonical_swaps != swaps_before) m.finish();
  return status;
}

}  // namespace keepless::solver
