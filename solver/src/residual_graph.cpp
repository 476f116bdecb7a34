#include <algorithm>

#include "min_cost_flow_impl.hpp"

namespace keepless::solver {

using namespace detail;

// Storage, and the residual graph's layout (see min_cost_flow_impl.hpp).

MinCostFlow::Impl::Impl(const Capacity& c)
    : limits(c), heap(static_cast<std::size_t>(std::max(c.max_nodes, 0)) + 1) {
  const auto n = static_cast<std::size_t>(std::max(c.max_nodes, 0));
  const auto m = static_cast<std::size_t>(std::max(c.max_arcs, 0));
  arc.resize(m);
  layout_order.resize(m);
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
  int_of.resize(n);
  ext_of.resize(n);
  pot_ext.resize(n);
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
  return bytes(arc) + bytes(layout_order) + bytes(arc_flow) +
         bytes(arc_pos) + bytes(tie_order) + bytes(in_tie_order) + bytes(recosted) + bytes(is_recosted) + bytes(first_out) + bytes(first_rev) + bytes(block_end) + bytes(nflow) + bytes(res) + bytes(rev) +
         bytes(flist) + bytes(fpos) + bytes(fixed) + bytes(int_of) + bytes(ext_of) + bytes(pot_ext) + bytes(pot) + bytes(estimate) + bytes(key) +
         bytes(level) + bytes(cur) + bytes(fill) + bytes(path_arc) + bytes(path_node) +
         bytes(touched) + bytes(sources) + bytes(imbalanced) + bytes(excess) + bytes(origin) + bytes(served) + bytes(seen) +
         bytes(renewed) + bytes(visit) + bytes(dead) + bytes(tight_bits) + bytes(cand_bits) +
         bytes(pending) + bytes(spill) + heap.memory_bytes();
}

// Lists the arcs to lay out (layout_order: tie order first, then ids;
// inactive ones get no record and zero flow), counts degrees and the
// largest cost, and numbers the nodes in order of first appearance along
// that sequence, which is also the order of their blocks: the blocks the
// blocking flow visits in turn (the source's heads, in tie order) sit next
// to each other, and so do their per-node data, even when node ids are
// recycled.
Cost MinCostFlow::Impl::count_degrees() {
  std::fill(fill.begin(), fill.begin() + nodes, 0);  // out-degree
  std::fill(cur.begin(), cur.begin() + nodes, 0);   // in-degree
  new_visit_epoch();
  Cost max_cost = 0;
  std::int32_t placed = 0;
  layout_count = 0;
  for (std::int32_t k = 0; k < tie_count + arcs; ++k) {
    const ArcId a = k < tie_count ? tie_order[k] : k - tie_count;
    if (k >= tie_count && in_tie_order[a] != 0) continue;
    if (!active(a)) {
      arc_pos[a] = -1;
      arc_flow[a] = 0;
      continue;
    }
    layout_order[layout_count++] = a;
    const NodeId u = arc[a].tail, v = arc[a].head;
    ++fill[u];
    ++cur[v];
    max_cost = std::max<Cost>(max_cost, arc[a].cost);
    if (visit[u] != visit_epoch) {
      visit[u] = visit_epoch;
      touched[placed++] = u;
    }
    if (visit[v] != visit_epoch) {
      visit[v] = visit_epoch;
      touched[placed++] = v;
    }
  }
  // Labels count hops over nodes with arcs only (and the terminals, which
  // may have none): a network held in a larger solver (recycled ids) is
  // bounded by what it uses, not by its capacity.
  label_nodes = placed + 2;
  // Internal numbers in block order; nodes without arcs after the others.
  for (NodeId v = 0; v < nodes; ++v) {
    if (visit[v] != visit_epoch) touched[placed++] = v;
  }
  std::int32_t at = 0;
  for (NodeId i = 0; i < nodes; ++i) {
    const NodeId v = touched[i];
    int_of[v] = i;
    ext_of[i] = v;
    first_out[i] = at;
    first_rev[i] = at + fill[v];
    block_end[i] = first_rev[i] + cur[v];
    at = block_end[i];
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
    pot[v] = pot_ext[ext_of[v]];
  }
  // The tie order's arcs first at their tails, then the rest by id.
  for (std::int32_t k = 0; k < layout_count; ++k) {
    const ArcId a = layout_order[k];
    const NodeId u = int_of[arc[a].tail], v = int_of[arc[a].head];
    const std::int32_t cap = arc[a].capacity, cost = arc[a].cost;
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
    seen[ext_of[v]] = block_end[v] > first_out[v];
    renewed[ext_of[v]] = 0;
    if (v != src && v != snk && excess[v] != 0) imbalanced[imbalanced_count++] = v;
  }
  repair_pending = imbalanced_count > 0;
  laid_out = true;
}

}  // namespace keepless::solver
