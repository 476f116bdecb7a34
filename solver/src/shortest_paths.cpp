#include <algorithm>

#include "min_cost_flow_impl.hpp"

namespace keepless::solver {

using namespace detail;

// --- the source's lazy arcs -------------------------------------------------

// Splits the source's arcs into tight ones and pending ones sorted by
// cost - potential(head), ties by position (so the order is a function of
// the input). Saturated arcs are parked with the tight ones.
void MinCostFlow::Impl::lazy_begin() {
  const std::int32_t lo = first_out[src], hi = first_rev[src];
  lazy = hi - lo <= static_cast<std::int32_t>(pending.size());
  if (!lazy) return;  // more parallel source arcs than nodes: relax them all
  std::fill(tight_bits.begin(), tight_bits.begin() + source_words(), 0);
  std::fill(cand_bits.begin(), cand_bits.begin() + source_words(), 0);
  pend_begin = pend_end = pend_cursor = passed = 0;
  Cost lo_w = 0, hi_w = 0;
  for (std::int32_t i = lo; i < hi; ++i) {
    const Residual& a = res[i];
    const Cost w = a.cost - pot[a.head];
    if (a.cap == 0 || w + pot[src] == 0) {
      tight_bits[(i - lo) >> 6] |= std::uint64_t{1} << ((i - lo) & 63);
      continue;
    }
    lo_w = pend_end == 0 ? w : std::min(lo_w, w);
    hi_w = pend_end == 0 ? w : std::max(hi_w, w);
    pending[pend_end++] = Pending{w, i};
  }
  if (pend_end == 0) return;
  // Costs are small integers: a counting sort by w is stable in position.
  if (hi_w - lo_w + 1 < static_cast<Cost>(nodes)) {  // range + 1 counters fit in fill[]
    const auto range = static_cast<std::int32_t>(hi_w - lo_w) + 1;
    std::fill(fill.begin(), fill.begin() + range + 1, 0);
    for (std::int32_t j = 0; j < pend_end; ++j) ++fill[pending[j].w - lo_w + 1];
    for (std::int32_t r = 0; r < range; ++r) fill[r + 1] += fill[r];
    for (std::int32_t j = 0; j < pend_end; ++j) spill[fill[pending[j].w - lo_w]++] = pending[j];
    std::copy(spill.begin(), spill.begin() + pend_end, pending.begin());
  } else {
    std::sort(pending.begin(), pending.begin() + pend_end, less);
  }
}

// Queues the next pending arc: the virtual heap item's key is a lower
// bound of the key the arc gives its head, never below the frontier.
void MinCostFlow::Impl::lazy_queue(std::uint64_t frontier) {
  if (pend_cursor >= pend_end) return;
  const Cost rc = pending[pend_cursor].w + pot[src];
  std::uint64_t k = key[src] + 1;
  if (rc > 0) k += static_cast<std::uint64_t>(std::min<Cost>(rc, static_cast<Cost>(rc_limit))) << shift;
  heap.push(virtual_item, std::max(k, frontier));
}

// After a phase's potential update and blocking flow: relaxed pending arcs
// that became tight join the tight set, the others go back into the
// pending order with their new w (a merge: few move, the rest stay put).
// Unrelaxed entries keep their old w, a lower bound of the new one
// (a settled head's potential only drops), so the lazy order stays safe.
void MinCostFlow::Impl::lazy_end_phase() {
  const std::int32_t lo = first_out[src];
  std::int32_t k = 0;
  for (std::int32_t j = pend_begin; j < pend_begin + passed; ++j) {
    const std::int32_t i = pending[j].pos;
    const Residual& a = res[i];
    const Cost w = a.cost - pot[a.head];
    if (a.cap == 0 || w + pot[src] == 0) {
      tight_bits[(i - lo) >> 6] |= std::uint64_t{1} << ((i - lo) & 63);
    } else {
      spill[k++] = Pending{w, i};
    }
  }
  pend_begin += passed;
  passed = 0;
  if (k == 0) return;
  std::sort(spill.begin(), spill.begin() + k, less);
  std::int32_t out = pend_begin - k, s = pend_begin, r = 0;
  while (r < k) {
    if (s < pend_end && less(pending[s], spill[r])) {
      pending[out++] = pending[s++];
    } else {
      pending[out++] = spill[r++];
    }
  }
  pend_begin -= k;
}

// Dijkstra from the sources (distance 0) on reduced costs, with the hop
// count as the second key, until a target is settled at distance D. Every
// settled node's potential then rises by its distance and every other
// node's by D (implicitly: only differences matter, so the settled ones
// drop by D - distance instead), which keeps reduced costs >= 0 and makes
// the shortest source-target paths exactly the zero-reduced-cost ones. The
// hop counts of the settled nodes are the Dinic levels of those paths.
// Only what lies closer than the nearest target is explored: in the
// paper's network the expensive part of a path is its source arc, so the
// source's arcs are merged into the search lazily, in order of reduced
// cost, and most of them are never touched in a phase.
//
// Where it stops: at the sink when maximising flow; in the repair phases,
// once every source's tree has reached a target (excesses) or every
// target is reached (deficits). Any settled prefix keeps the certificate
// after the update, and the blocking flow may end at any settled target,
// so one phase routes every imbalance it can reach, not just the nearest.
MinCostFlow::Impl::Search MinCostFlow::Impl::shortest_paths(std::int32_t source_count, Meter& meter) {
  heap.clear();
  touched_count = 0;
  std::int32_t waiting = 1;
  if (mode == Mode::kExcess) {
    waiting = source_count;
  } else if (mode == Mode::kDeficit) {
    waiting = 0;
    for (std::int32_t k = 0; k < imbalanced_count; ++k) waiting += excess[imbalanced[k]] < 0;
  }
  for (std::int32_t k = 0; k < source_count; ++k) {
    const NodeId x = sources[k];
    key[x] = 0;
    origin[x] = x;
    served[x] = 0;
    touched[touched_count++] = x;
    heap.push(x, 0);
  }
  if (lazy) {
    pend_cursor = pend_begin;
    passed = 0;
  }
  NodeId found = -1;
  std::uint64_t last_key = 0;
  while (!heap.empty()) {
    const NodeId v = heap.pop_min();
    if (v == virtual_item) {  // the next pending source arc
      const std::uint64_t frontier = heap.key_of(v);
      const std::int32_t i = pending[pend_cursor++].pos;
      const std::int32_t b = i - first_out[src];
      cand_bits[b >> 6] |= std::uint64_t{1} << (b & 63);
      ++passed;
      const Residual& a = res[i];
      if (a.cap > 0 && level[a.head] < 0) relax(a.head, key[src], a.cost + pot[src] - pot[a.head], src);
      ++stats.work_units;
      lazy_queue(frontier);
      continue;
    }
    const std::uint64_t kv = key[v];
    level[v] = static_cast<std::int32_t>(kv & hop_mask);
    last_key = kv;
    if (is_target(v)) {
      found = v;
      if (mode == Mode::kExcess) {
        const NodeId x = origin[v];
        if (served[x] == 0) {
          served[x] = 1;
          --waiting;
        }
      } else {
        --waiting;
      }
      if (waiting <= 0) break;
    }
    const Cost pv = pot[v];
    const std::int32_t fr = first_rev[v];
    std::int32_t scanned = nflow[v];
    if (lazy && v == src) {
      const std::int32_t lo = first_out[v];
      const std::int32_t words = source_words();
      for (std::int32_t w = 0; w < words; ++w) {
        std::uint64_t m = tight_bits[w];
        cand_bits[w] = m;
        while (m != 0) {
          const std::int32_t i = lo + (w << 6) + __builtin_ctzll(m);
          m &= m - 1;
          const Residual& a = res[i];
          ++scanned;
          if (a.cap == 0 || level[a.head] >= 0) continue;
          relax(a.head, kv, a.cost + pv - pot[a.head], v);
        }
      }
      lazy_queue(kv);
    } else {
      for (std::int32_t i = first_out[v]; i < fr; ++i) {
        const Residual& a = res[i];
        if (a.cap == 0 || level[a.head] >= 0) continue;
        relax(a.head, kv, a.cost + pv - pot[a.head], v);
      }
      scanned += fr - first_out[v];
    }
    const std::int32_t end = fr + nflow[v];
    for (std::int32_t p = fr; p < end; ++p) {
      const Residual& a = res[flist[p]];
      if (level[a.head] >= 0) continue;
      relax(a.head, kv, a.cost + pv - pot[a.head], v);
    }
    stats.work_units += static_cast<std::uint64_t>(scanned);
    if (meter.exhausted(kScanStride)) return Search::kExhausted;
  }
  if (found < 0) return Search::kNone;
  const auto d = static_cast<Cost>(last_key >> shift);
  for (std::int32_t k = 0; k < touched_count; ++k) {
    const NodeId v = touched[k];
    if (level[v] >= 0) pot[v] += static_cast<Cost>(key[v] >> shift) - d;
  }
  return Search::kFound;
}

// The same search from the sink over reversed residual arcs (each record
// mirrors its partner's capacity, so a node's own block lists the arcs
// entering it), until the source is settled. Levels are then hops to the
// sink, and the blocking flow follows only arcs that lead there: when
// nearly every node lies closer to the source than the sink does (the
// whole window's points carry flow), this beats the forward search, whose
// blocking flow would walk into every dead end. The blocking flow serves
// the same paths in the same order either way, so the flows are the same.
MinCostFlow::Impl::Search MinCostFlow::Impl::shortest_paths_to_sink(Meter& meter) {
  heap.clear();
  touched_count = 0;
  offer_count = 0;
  // The source's admissible arcs are listed in cand_bits, which has room for
  // as many arcs as there are nodes; with more parallel source arcs than
  // that, the blocking flow scans them all.
  marked = source_degree() <= static_cast<std::int32_t>(pending.size());
  key[snk] = 0;
  touched[touched_count++] = snk;
  heap.push(snk, 0);
  std::uint64_t last_key = 0;
  bool reached = false;
  while (!heap.empty()) {
    const NodeId v = heap.pop_min();
    const std::uint64_t kv = key[v];
    level[v] = static_cast<std::int32_t>(kv & hop_mask);
    last_key = kv;
    if (v == src) {
      reached = true;
      break;
    }
    const Cost pv = pot[v];
    const std::int32_t end = block_end[v];
    for (std::int32_t i = first_out[v]; i < end; ++i) {
      const Residual& a = res[i];  // its partner a.head -> v is the arc searched
      if (a.rev_cap == 0 || level[a.head] >= 0) continue;
      relax(a.head, kv, pot[a.head] - a.cost - pv, v);
      if (a.head == src && rev[i] < first_rev[src] &&
          key[src] <= kv + (static_cast<std::uint64_t>(pot[src] - a.cost - pv) << shift) + 1) {
        // Remember the forward arcs that offer the source its best label so
        // far: at the end, those offering the final one are its admissible
        // arcs (cand_bits covers the forward block; the source's reverse
        // records, arcs into it with flow, are scanned from its flow list).
        if (offer_count < static_cast<std::int32_t>(pending.size())) {
          pending[offer_count++] = Pending{static_cast<Cost>(kv + (static_cast<std::uint64_t>(pot[src] - a.cost - pv) << shift) + 1), rev[i]};
        } else {
          marked = false;  // too many to list: the blocking flow scans them all
        }
      }
    }
    stats.work_units += static_cast<std::uint64_t>(end - first_out[v]);
    if (meter.exhausted(kScanStride)) return Search::kExhausted;
  }
  if (!reached) return Search::kNone;
  if (marked) {
    std::fill(cand_bits.begin(), cand_bits.begin() + source_words(), 0);
    const std::int32_t lo = first_out[src];
    for (std::int32_t k = 0; k < offer_count; ++k) {
      if (static_cast<std::uint64_t>(pending[k].w) != key[src]) continue;
      const std::int32_t b = pending[k].pos - lo;
      cand_bits[b >> 6] |= std::uint64_t{1} << (b & 63);
    }
  }
  const auto d = static_cast<Cost>(last_key >> shift);
  for (std::int32_t k = 0; k < touched_count; ++k) {
    const NodeId v = touched[k];
    if (level[v] >= 0) pot[v] += d - static_cast<Cost>(key[v] >> shift);
  }
  return Search::kFound;
}

void MinCostFlow::Impl::clear_labels() {
  for (std::int32_t k = 0; k < touched_count; ++k) {
    key[touched[k]] = kUnlabelled;
    level[touched[k]] = -1;
  }
  touched_count = 0;
}

// Labels are distance << shift | hops, hops < label_nodes (the nodes with
// arcs and the terminals, see count_degrees); a power of two keeps division
// out of the search.
std::uint64_t MinCostFlow::Impl::set_label_base() {
  shift = 1;
  while ((std::uint64_t{1} << shift) < static_cast<std::uint64_t>(label_nodes) + 2) ++shift;
  const std::uint64_t base = std::uint64_t{1} << shift;
  hop_mask = base - 1;
  rc_limit = kLabelLimit / base;
  return base;
}

}  // namespace keepless::solver
