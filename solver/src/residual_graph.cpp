#include <algorithm>

#include "min_cost_flow_impl.hpp"

namespace keepless::solver {

using namespace detail;

// Storage, and the residual graph's layout (see min_cost_flow_impl.hpp).

MinCostFlow::Impl::Impl(const Capacity& c)
    : limits(c), heap(static_cast<std::size_t>(std::max(c.max_nodes, 0)) + 1) {
  const auto n = static_cast<std::size_t>(std::max(c.max_nodes, 0));
  const auto m = static_cast<std::size_t>(std::max(c.max_arcs, 0));
  arc_tail.resize(m);
  arc_head.resize(m);
  arc_cap.resize(m);
  arc_cost.resize(m);
  arc_flow.resize(m);
  arc_pos.resize(m);
  tie_order.resize(m);
  in_tie_order.resize(m);
  recosted.resize(m);
  is_recosted.resize(m);
  first_out.resize(n + 1);
  first_rev.resize(n);
  block_end.resize(n);
  nflow.resize(n);
  res.resize(2 * m);
  rev.resize(2 * m);
  flist.resize(2 * m);
  fpos.resize(2 * m);
  fixed.resize(2 * m);
  pot.resize(n);
  estimate.resize(n);
  key.assign(n, kUnlabelled);
  level.assign(n, -1);
  cur.resize(n);
  fill.resize(n);
  path_arc.resize(n);
  path_node.resize(n + 1);
  touched.resize(n);
  sources.resize(n);
  imbalanced.resize(n);
  excess.resize(n);
  origin.resize(n);
  served.resize(n);
  seen.resize(n);
  renewed.resize(n);
  visit.resize(n);
  dead.resize(n);
  tight_bits.resize(n / 64 + 1);
  cand_bits.resize(n / 64 + 1);
  pending.resize(n);
  spill.resize(n);
  virtual_item = static_cast<NodeId>(n);
}

std::size_t MinCostFlow::Impl::bytes() const {
  const auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return bytes(arc_tail) + bytes(arc_head) + bytes(arc_cap) + bytes(arc_cost) + bytes(arc_flow) +
         bytes(arc_pos) + bytes(tie_order) + bytes(in_tie_order) + bytes(recosted) + bytes(is_recosted) + bytes(first_out) + bytes(first_rev) + bytes(block_end) + bytes(nflow) + bytes(res) + bytes(rev) +
         bytes(flist) + bytes(fpos) + bytes(fixed) + bytes(pot) + bytes(estimate) + bytes(key) +
         bytes(level) + bytes(cur) + bytes(fill) + bytes(path_arc) + bytes(path_node) +
         bytes(touched) + bytes(sources) + bytes(imbalanced) + bytes(excess) + bytes(origin) + bytes(served) + bytes(seen) +
         bytes(renewed) + bytes(visit) + bytes(dead) + bytes(tight_bits) + bytes(cand_bits) +
         bytes(pending) + bytes(spill) + heap.memory_bytes();
}

// Counts degrees and the largest cost of the arcs to lay out, and places
// the node blocks in order of first appearance along the layout's arc
// sequence (tie order first, then ids): the blocks the blocking flow visits
// in turn (the source's heads, in tie order) sit next to each other even
// when node ids are recycled.
Cost MinCostFlow::Impl::count_degrees() {
  std::fill(fill.begin(), fill.begin() + nodes, 0);  // out-degree
  std::fill(cur.begin(), cur.begin() + nodes, 0);   // in-degree
  if (++visit_epoch == 0) {
    std::fill(visit.begin(), visit.begin() + nodes, 0u);
    visit_epoch = 1;
  }
  Cost max_cost = 0;
  std::int32_t placed = 0;
  for (std::int32_t k = 0; k < tie_count + arcs; ++k) {
    const ArcId a = k < tie_count ? tie_order[k] : k - tie_count;
    if ((k >= tie_count && in_tie_order[a] != 0) || !active(a)) continue;
    const NodeId u = arc_tail[a], v = arc_head[a];
    ++fill[u];
    ++cur[v];
    max_cost = std::max<Cost>(max_cost, arc_cost[a]);
    if (visit[u] != visit_epoch) {
      visit[u] = visit_epoch;
      touched[placed++] = u;
    }
    if (visit[v] != visit_epoch) {
      visit[v] = visit_epoch;
      touched[placed++] = v;
    }
  }
  for (NodeId v = 0; v < nodes; ++v) first_out[v] = first_rev[v] = block_end[v] = 0;
  std::int32_t at = 0;
  for (std::int32_t k = 0; k < placed; ++k) {
    const NodeId v = touched[k];
    first_out[v] = at;
    first_rev[v] = at + fill[v];
    block_end[v] = first_rev[v] + cur[v];
    at = block_end[v];
  }
  records = at;
  return max_cost;
}

// Lays out the residual graph of the arcs and their flows. With `repair`,
// first restores the certificate: an arc with residual capacity and a
// negative reduced cost is saturated, an arc with flow and a positive
// reduced cost emptied. Excesses are recomputed either way.
void MinCostFlow::Impl::lay_out(bool repair) {
  for (NodeId v = 0; v < nodes; ++v) {
    fill[v] = first_out[v];
    cur[v] = first_rev[v];
    nflow[v] = 0;
    excess[v] = 0;
  }
  // The tie order's arcs first at their tails, then the rest by id.
  for (std::int32_t k = 0; k < tie_count + arcs; ++k) {
    const ArcId a = k < tie_count ? tie_order[k] : k - tie_count;
    if (k >= tie_count && in_tie_order[a] != 0) continue;
    if (!active(a)) {
      arc_pos[a] = -1;
      arc_flow[a] = 0;
      continue;
    }
    const NodeId u = arc_tail[a], v = arc_head[a];
    const std::int32_t cap = arc_cap[a], cost = arc_cost[a];
    std::int32_t fl = std::min(std::max(arc_flow[a], 0), cap);
    if (repair) {
      const Cost rc = cost + pot[u] - pot[v];
      if (rc < 0 && fl < cap) {
        fl = cap;
        ++stats.repaired_arcs;
      } else if (rc > 0 && fl > 0) {
        fl = 0;
        ++stats.repaired_arcs;
      }
    }
    const std::int32_t f = fill[u]++;
    const std::int32_t r = cur[v]++;
    res[f] = Residual{v, cap - fl, fl, cost};
    res[r] = Residual{u, fl, cap - fl, -cost};
    rev[f] = r;
    rev[r] = f;
    arc_pos[a] = f;
    arc_flow[a] = fl;
    if (fl > 0) {
      list_add(v, r);
      excess[u] -= fl;
      excess[v] += fl;
    }
  }
  imbalanced_count = 0;
  for (NodeId v = 0; v < nodes; ++v) {
    seen[v] = block_end[v] > first_out[v];
    renewed[v] = 0;
    if (v != src && v != snk && excess[v] != 0) imbalanced[imbalanced_count++] = v;
  }
  laid_out = true;
}

}  // namespace keepless::solver
