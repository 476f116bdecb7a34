#include "keepless/solver/min_cost_flow.hpp"

#include <algorithm>
#include <chrono>
#include <vector>

#include "radix_heap.hpp"

namespace keepless::solver {

std::uint64_t SteadyClock::now_ns() const {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

namespace {

constexpr Flow kMaxArcCapacity = std::numeric_limits<std::int32_t>::max();
constexpr Cost kMaxArcCost = (Cost{1} << 30);
constexpr std::uint64_t kUnlabelled = std::numeric_limits<std::uint64_t>::max();
constexpr std::int64_t kUnlimited = std::numeric_limits<std::int64_t>::max();
constexpr std::uint64_t kLabelLimit = std::uint64_t{1} << 62;

// Clock reads are rationed by work: a read costs tens of nanoseconds, an arc
// scan a few. Inside a search the clock is read every kScanStride units;
// after an augmentation once kAugmentStride units have passed since the last
// read (an augmentation of the paper's network scans ~10 arcs, and reading
// the clock after each would cost more than the augmentation). Work units
// themselves are compared at every check.
constexpr std::uint64_t kScanStride = 1024;
constexpr std::uint64_t kAugmentStride = 64;

class Meter {
 public:
  Meter(const Budget& budget, const SolveStats& stats)
      : budget_(budget), stats_(stats), start_(stats.work_units), last_read_(stats.work_units) {}

  // Work, then the clock once `stride` units have passed since the last read.
  bool exhausted(std::uint64_t stride = 0) {
    const std::uint64_t used = stats_.work_units - start_;
    if (used > budget_.work_units) return true;
    if (budget_.clock == nullptr || stats_.work_units - last_read_ < stride) return false;
    last_read_ = stats_.work_units;
    return budget_.clock->now_ns() >= budget_.deadline_ns;
  }

 private:
  const Budget& budget_;
  const SolveStats& stats_;
  std::uint64_t start_;
  std::uint64_t last_read_;
};

}  // namespace

// Storage: user arcs in insertion order, and the residual graph in CSR form
// (LEMON's layout) rebuilt from them by each solve. A node's block holds its
// forward arcs in arc id order (the blocking flow's tie-break), then one
// reverse record per arc entering it. Reverse records with capacity (arcs
// carrying flow) are also kept in a per-node list, so a search skips the
// many empty ones: in the paper's network a pair node has hundreds of
// entering arcs but at most M carry flow.
struct MinCostFlow::Impl {
  // 16 bytes, so a scan streams as little memory as possible. The
  // partner's capacity is mirrored so that a sink-side search reads the
  // arcs entering a node from that node's own block.
  struct Residual {
    NodeId head;
    std::int32_t cap;      // residual capacity
    std::int32_t rev_cap;  // residual capacity of the partner (head -> this node)
    std::int32_t cost;     // the arc's cost; -cost on reverse records
  };
  // What the phases route: excesses of a repair (to deficits, source or
  // sink), deficits (from source or sink), or source-to-sink flow.
  enum class Mode : std::uint8_t { kExcess, kDeficit, kMaxFlow };
  enum class Search : std::uint8_t { kFound, kNone, kExhausted };

  Capacity limits;
  std::int32_t nodes = 0;
  std::int32_t arcs = 0;

  // User arcs.
  std::vector<NodeId> arc_tail, arc_head;
  std::vector<std::int32_t> arc_cap, arc_cost, arc_flow;
  std::vector<std::int32_t> arc_pos;  // forward residual record, -1 when not laid out
  std::vector<ArcId> tie_order;          // set_tie_order
  std::vector<std::uint8_t> in_tie_order;
  std::int32_t tie_count = 0;
  std::vector<std::int32_t> recosted;    // arcs whose cost set_arc changed since the last layout
  std::vector<std::uint8_t> is_recosted;
  std::int32_t recosted_count = 0;

  // Residual graph.
  std::vector<std::int32_t> first_out;  // [max_nodes + 1]
  std::vector<std::int32_t> first_rev;  // [max_nodes] start of a node's reverse records
  std::vector<std::int32_t> block_end;  // [max_nodes] end of a node's block (blocks are not in id order)
  std::int32_t records = 0;
  std::vector<std::int32_t> nflow;      // [max_nodes] length of a node's flow list
  std::vector<Residual> res;            // [2 * max_arcs]
  std::vector<std::int32_t> rev;        // [2 * max_arcs] position of each record's partner
  std::vector<std::int32_t> flist;      // [2 * max_arcs] flow lists, in the reverse blocks
  std::vector<std::int32_t> fpos;       // [2 * max_arcs] a reverse record's place in flist

  // Per-node workspace.
  std::vector<Cost> pot;
  std::vector<Cost> estimate;       // solve_warm: potentials of renewed nodes
  std::vector<std::uint64_t> key;   // Dijkstra label: distance * (nodes + 1) + hops
  std::vector<std::int32_t> level;  // hops from a source of settled nodes, else -1
  std::vector<std::int32_t> cur, fill, path_arc;
  std::vector<NodeId> path_node, touched, sources, imbalanced;
  std::vector<std::int64_t> excess;  // inflow - outflow
  std::vector<NodeId> origin;        // search source whose tree holds a node (excess phases)
  std::vector<std::uint8_t> served;  // a source whose tree reached a target
  std::vector<std::uint8_t> seen;    // had arcs at the last layout
  std::vector<std::uint8_t> renewed;
  std::vector<std::uint8_t> fixed;   // [2 * max_arcs] canonicalize
  std::vector<std::uint32_t> visit, dead;
  std::uint32_t visit_epoch = 0, dead_epoch = 0;
  std::int32_t touched_count = 0, imbalanced_count = 0, path_depth = 0;
  RadixHeap heap;  // max_nodes + 1 items: the last stands for the source's pending arcs

  // The source's arcs, relaxed lazily (see shortest_paths). Tight arcs (zero
  // reduced cost) are relaxed every phase; the others wait in `pending`,
  // sorted by a lower bound of cost - potential(head), and are relaxed only
  // when the search's frontier reaches them.
  struct Pending {
    Cost w;
    std::int32_t pos;
  };
  std::vector<std::uint64_t> tight_bits, cand_bits;  // over the source's forward records
  std::vector<Pending> pending, spill;               // [max_nodes]
  std::int32_t pend_begin = 0, pend_end = 0, pend_cursor = 0;
  std::int32_t passed = 0;  // pending entries relaxed this phase: [pend_begin, pend_begin + passed)
  bool lazy = false;        // the source is a search source and its arcs are lazy
  bool backward = false;    // this run's source-to-sink phases search from the sink
  bool marked = false;      // cand_bits lists the source's admissible arcs (sink-side search)
  std::int32_t offer_count = 0;  // sink-side search: the source's arcs that offered its best label
  NodeId virtual_item = 0;

  // State between calls.
  bool laid_out = false;     // the residual graph reflects the arcs
  bool have_state = false;   // flows and potentials can seed solve_warm
  bool optimal = false;      // the last solve finished
  bool is_balanced = true;
  bool overflow = false;     // a label would have left 64 bits (never with checked input)
  NodeId src = -1, snk = -1;
  Mode mode = Mode::kMaxFlow;
  int shift = 1;  // labels are distance << shift | hops
  std::uint64_t hop_mask = 1;
  std::uint64_t rc_limit = 0;
  Flow value = 0;
  Cost cost_total = 0;
  SolveStats stats;

  explicit Impl(const Capacity& c)
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

  std::size_t bytes() const {
    const auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
    return bytes(arc_tail) + bytes(arc_head) + bytes(arc_cap) + bytes(arc_cost) + bytes(arc_flow) +
           bytes(arc_pos) + bytes(tie_order) + bytes(in_tie_order) + bytes(recosted) + bytes(is_recosted) + bytes(first_out) + bytes(first_rev) + bytes(block_end) + bytes(nflow) + bytes(res) + bytes(rev) +
           bytes(flist) + bytes(fpos) + bytes(fixed) + bytes(pot) + bytes(estimate) + bytes(key) +
           bytes(level) + bytes(cur) + bytes(fill) + bytes(path_arc) + bytes(path_node) +
           bytes(touched) + bytes(sources) + bytes(imbalanced) + bytes(excess) + bytes(origin) + bytes(served) + bytes(seen) +
           bytes(renewed) + bytes(visit) + bytes(dead) + bytes(tight_bits) + bytes(cand_bits) +
           bytes(pending) + bytes(spill) + heap.memory_bytes();
  }

  bool active(ArcId a) const { return arc_cap[a] > 0 && arc_tail[a] != arc_head[a]; }

  // --- flow lists -----------------------------------------------------------

  void list_add(NodeId v, std::int32_t r) {
    const std::int32_t p = first_rev[v] + nflow[v]++;
    flist[p] = r;
    fpos[r] = p;
  }
  void list_remove(NodeId v, std::int32_t r) {
    const std::int32_t p = fpos[r];
    const std::int32_t last = first_rev[v] + --nflow[v];
    const std::int32_t moved = flist[last];
    flist[p] = moved;
    fpos[moved] = p;
  }

  void push(std::int32_t i, std::int32_t f) {
    Residual& a = res[i];
    const std::int32_t j = rev[i];
    Residual& b = res[j];
    const NodeId u = b.head;  // tail of record i
    const NodeId v = a.head;
    a.cap -= f;
    b.rev_cap -= f;
    if (a.cap == 0 && i >= first_rev[u]) list_remove(u, i);
    if (b.cap == 0 && j >= first_rev[v]) list_add(v, j);
    b.cap += f;
    a.rev_cap += f;
  }

  // Record at position p of node u's scan order: forward arcs, then its flow list.
  std::int32_t record_at(NodeId u, std::int32_t p) const { return p < first_rev[u] ? p : flist[p]; }
  std::int32_t scan_end(NodeId u) const { return first_rev[u] + nflow[u]; }

  // --- layout -----------------------------------------------------------------

  // Counts degrees and the largest cost of the arcs to lay out, and places
  // the node blocks in order of first appearance along the layout's arc
  // sequence (tie order first, then ids): the blocks the blocking flow visits
  // in turn (the source's heads, in tie order) sit next to each other even
  // when node ids are recycled.
  Cost count_degrees() {
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
  void lay_out(bool repair) {
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

  // --- phases -------------------------------------------------------------------

  bool is_target(NodeId v) const {
    switch (mode) {
      case Mode::kMaxFlow: return v == snk;
      case Mode::kExcess: return v == src || v == snk || excess[v] < 0;
      case Mode::kDeficit: return v != src && v != snk && excess[v] < 0;
    }
    return false;
  }
  std::int64_t supply_of(NodeId v) const {
    return mode == Mode::kExcess ? excess[v] : kUnlimited;
  }
  std::int64_t need_of(NodeId v) const {
    if (mode == Mode::kMaxFlow || v == src || v == snk) return kUnlimited;
    return -excess[v];
  }

  void relax(NodeId u, std::uint64_t kv, Cost rc, NodeId from) {
    auto r = static_cast<std::uint64_t>(rc);
    if (r > rc_limit) {
      overflow = true;
      r = rc_limit;
    }
    const std::uint64_t nk = kv + (r << shift) + 1;
    if (nk < key[u]) {
      origin[u] = origin[from];
      if (key[u] == kUnlabelled) {
        heap.push(u, nk);
        touched[touched_count++] = u;
      } else {
        heap.decrease(u, nk);
      }
      key[u] = nk;
    }
  }

  // --- the source's lazy arcs -------------------------------------------------

  std::int32_t source_degree() const { return first_rev[src] - first_out[src]; }
  std::int32_t source_words() const { return source_degree() / 64 + 1; }
  static bool less(const Pending& a, const Pending& b) { return a.w != b.w ? a.w < b.w : a.pos < b.pos; }

  // Splits the source's arcs into tight ones and pending ones sorted by
  // cost - potential(head), ties by position (so the order is a function of
  // the input). Saturated arcs are parked with the tight ones.
  void lazy_begin() {
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
    if (hi_w - lo_w < static_cast<Cost>(nodes)) {
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
  void lazy_queue(std::uint64_t frontier) {
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
  void lazy_end_phase() {
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

  // First scan position >= p of node u: the source visits only its tight
  // and relaxed arcs (the others cannot be admissible, see lazy_queue).
  std::int32_t next_position(NodeId u, std::int32_t p) const {
    if (!(lazy || (backward && marked)) || u != src || p >= first_rev[u]) return p;
    const std::int32_t lo = first_out[u];
    const std::int32_t b = p - lo;
    std::int32_t w = b >> 6;
    std::uint64_t m = cand_bits[w] & (~std::uint64_t{0} << (b & 63));
    const std::int32_t words = source_words();
    while (m == 0) {
      if (++w >= words) return first_rev[u];
      m = cand_bits[w];
    }
    return std::min(first_rev[u], lo + (w << 6) + __builtin_ctzll(m));
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
  Search shortest_paths(std::int32_t source_count, Meter& meter) {
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
  Search shortest_paths_to_sink(Meter& meter) {
    heap.clear();
    touched_count = 0;
    offer_count = 0;
    marked = true;
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
        if (a.head == src && key[src] <= kv + (static_cast<std::uint64_t>(pot[src] - a.cost - pv) << shift) + 1) {
          // Remember the arcs that offer the source its best label so far:
          // at the end, those offering the final one are its admissible arcs.
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

  void clear_labels() {
    for (std::int32_t k = 0; k < touched_count; ++k) {
      key[touched[k]] = kUnlabelled;
      level[touched[k]] = -1;
    }
    touched_count = 0;
  }

  // Dinic blocking flow on the level graph, from each source in turn. The
  // DFS serves each node's forward arcs in arc id order, so earlier arcs win
  // ties. Returns false if the budget ran out.
  bool blocking_flow(std::int32_t source_count, Meter& meter) {
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
        for (; p < end; p = next_position(u, p + 1), ++scanned) {
          const std::int32_t i = p < fr ? p : flist[p];
          const Residual& a = res[i];
          if (a.cap > 0 && level[a.head] == want && a.cost + pu == pot[a.head]) {
            found = i;
            break;
          }
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

  // --- local repair -------------------------------------------------------------

  static constexpr std::int32_t kLocalDepth = 3;

  bool can_absorb(NodeId v) const { return v == src || v == snk || excess[v] < 0; }
  bool can_supply(NodeId v) const { return v == src || v == snk || excess[v] > 0; }

  // A path of at most kLocalDepth zero-reduced-cost residual arcs from x
  // (forwards) or into x (backwards) to a node that can take (or give) flow,
  // by depth-first search; the records of the path, from x, are left in
  // path_arc[0 .. path_depth). Forwards scans a node's residual arcs;
  // backwards scans its whole block, every record's partner being an arc
  // into it.
  bool local_path(NodeId x, bool forward) {
    if (++visit_epoch == 0) {
      std::fill(visit.begin(), visit.begin() + nodes, 0u);
      visit_epoch = 1;
    }
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
          const std::int32_t arc = forward ? i : rev[i];
          if (res[arc].cap == 0) continue;
          if (forward ? a.cost + pu != pot[w] : res[arc].cost + pot[w] != pu) continue;
          found = arc;
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
  bool local_repair(Meter& meter) {
    for (int pass = 0; pass < 2; ++pass) {
      const bool forward = pass == 0;  // excesses first, then deficits
      for (std::int32_t k = 0; k < imbalanced_count; ++k) {
        const NodeId x = imbalanced[k];
        while (forward ? excess[x] > 0 : excess[x] < 0) {
          if (!local_path(x, forward)) break;
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

  // Phases of one mode until nothing is left to route.
  Status run(Mode m, Meter& meter) {
    mode = m;
    backward = false;
    marked = false;
    lazy_begin();
    const Status status = run_phases(m, meter);
    lazy = false;
    return status;
  }

  Status run_phases(Mode m, Meter& meter) {
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

  // Reads flows, cost and value back from the residual graph.
  void finish() {
    value = 0;
    cost_total = 0;
    for (ArcId a = 0; a < arcs; ++a) {
      const std::int32_t f = arc_pos[a] >= 0 ? arc_cap[a] - res[arc_pos[a]].cap : 0;
      arc_flow[a] = f;
      cost_total += Cost{f} * arc_cost[a];
      if (arc_tail[a] == src) value += f;
      if (arc_head[a] == src) value -= f;
    }
    std::int32_t kept = 0;
    for (std::int32_t k = 0; k < imbalanced_count; ++k) {
      if (excess[imbalanced[k]] != 0) imbalanced[kept++] = imbalanced[k];
    }
    imbalanced_count = kept;
    is_balanced = kept == 0;
  }

  // Path from `from` to `to` over residual arcs of zero reduced cost that
  // are not fixed, avoiding nodes known not to reach `to`. A failed search
  // proves every node it visited dead: augmentations only add arcs leaving
  // nodes that reach `to`, and fixing arcs only removes some, so a dead node
  // stays dead for the rest of the pass.
  bool tie_path(NodeId from, NodeId to) {
    if (++visit_epoch == 0) {
      std::fill(visit.begin(), visit.begin() + nodes, 0u);
      visit_epoch = 1;
    }
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

  void new_dead_epoch() {
    if (++dead_epoch == 0) {
      std::fill(dead.begin(), dead.begin() + nodes, 0u);
      dead_epoch = 1;
    }
  }

  bool valid_terminals(NodeId s, NodeId t) const {
    return s >= 0 && s < nodes && t >= 0 && t < nodes && s != t;
  }

  // Labels are distance << shift | hops, hops <= nodes; a power of two
  // keeps division out of the search.
  std::uint64_t set_label_base() {
    shift = 1;
    while ((std::uint64_t{1} << shift) < static_cast<std::uint64_t>(nodes) + 2) ++shift;
    const std::uint64_t base = std::uint64_t{1} << shift;
    hop_mask = base - 1;
    rc_limit = kLabelLimit / base;
    return base;
  }

  void clear_recosted() {
    for (std::int32_t k = 0; k < recosted_count; ++k) is_recosted[recosted[k]] = 0;
    recosted_count = 0;
  }

  // An arc that carried flow and changed cost usually still belongs in the
  // optimum: rather than let the repair saturate or empty it (up to its
  // capacity in new excess), move its new reduced cost onto the potential
  // of its end with fewer arcs. In the paper's network that is a point whose
  // view count changed: its source arc stays tight and only the pair arcs
  // at the margin of its new cost get repaired, one unit each.
  void shift_recosted_potentials() {
    for (std::int32_t k = 0; k < recosted_count; ++k) {
      const ArcId a = recosted[k];
      is_recosted[a] = 0;
      if (!active(a)) continue;
      const NodeId u = arc_tail[a], v = arc_head[a];
      const std::int32_t fl = std::min(arc_flow[a], arc_cap[a]);
      const Cost rc = arc_cost[a] + pot[u] - pot[v];
      if (!((rc < 0 && fl < arc_cap[a]) || (rc > 0 && fl > 0))) continue;
      const std::int32_t deg_u = block_end[u] - first_out[u];
      const std::int32_t deg_v = block_end[v] - first_out[v];
      if (deg_v <= deg_u) {
        pot[v] += rc;
      } else {
        pot[u] -= rc;
      }
    }
    recosted_count = 0;
  }

  Status solve_scratch(NodeId s, NodeId t, const Budget& budget) {
    clear_recosted();
    if (budget.clock != nullptr && budget.clock->now_ns() >= budget.deadline_ns) {
      // Too late to start: the zero flow, at zero potentials, is valid and
      // certified (costs are >= 0), and a later solve_warm can start from it.
      src = s;
      snk = t;
      stats = {};
      std::fill(arc_flow.begin(), arc_flow.begin() + arcs, 0);
      std::fill(pot.begin(), pot.begin() + nodes, 0);
      value = 0;
      cost_total = 0;
      imbalanced_count = 0;
      is_balanced = true;
      laid_out = false;
      have_state = true;
      optimal = false;
      return Status::kBudgetExhausted;
    }
    const std::uint64_t base = set_label_base();
    src = s;
    snk = t;
    stats = {};
    overflow = false;
    const Cost max_cost = count_degrees();
    // Distances stay below nodes * max cost.
    if (base > kLabelLimit / base / static_cast<std::uint64_t>(max_cost + 1)) {
      laid_out = false;
      have_state = false;
      return Status::kInvalidInput;
    }
    std::fill(pot.begin(), pot.begin() + nodes, 0);
    std::fill(arc_flow.begin(), arc_flow.begin() + arcs, 0);
    lay_out(false);
    Meter meter(budget, stats);
    const Status status = run(Mode::kMaxFlow, meter);
    finish();
    have_state = true;
    optimal = status == Status::kOptimal;
    return status;
  }

  Status solve_warm(NodeId s, NodeId t, const Budget& budget) {
    if (!have_state || s != src || t != snk || overflow) return solve_scratch(s, t, budget);
    stats = {};
    stats.warm = true;
    const std::uint64_t base = set_label_base();
    if (!laid_out) {
      const Cost max_cost = count_degrees();
      estimate_potentials();
      shift_recosted_potentials();
      // The reduced cost of any arc stays below max cost + potential spread.
      Cost lo = 0, hi = 0;
      bool first = true;
      for (NodeId v = 0; v < nodes; ++v) {
        if (block_end[v] == first_out[v]) continue;
        lo = first ? pot[v] : std::min(lo, pot[v]);
        hi = first ? pot[v] : std::max(hi, pot[v]);
        first = false;
      }
      const auto span = static_cast<std::uint64_t>(max_cost) + static_cast<std::uint64_t>(hi - lo) + 1;
      if (hi - lo > Cost{1} << 60 || base > kLabelLimit / base / span) {
        return solve_scratch(s, t, budget);
      }
      lay_out(true);
    }
    Meter meter(budget, stats);
    Status status = local_repair(meter) ? Status::kOptimal : Status::kBudgetExhausted;
    if (status == Status::kOptimal) status = run(Mode::kExcess, meter);
    if (status == Status::kOptimal) status = run(Mode::kDeficit, meter);
    if (status == Status::kOptimal) status = run(Mode::kMaxFlow, meter);
    finish();
    if (overflow) {
      laid_out = false;
      return solve_scratch(s, t, budget);
    }
    optimal = status == Status::kOptimal && is_balanced;
    return status;
  }

  // Potentials for nodes that are new since the last layout (or renewed):
  // the cheapest arrival over an arc from a known node, else the latest
  // departure over an arc to one, else unchanged. Any value is correct (the
  // repair restores the certificate); a good one leaves little to repair.
  // Runs between count_degrees and lay_out, whose scratch it borrows.
  void estimate_potentials() {
    std::int32_t fresh_count = 0;
    for (NodeId v = 0; v < nodes; ++v) {
      const bool fresh = (!seen[v] || renewed[v]) && block_end[v] > first_out[v];
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
      const NodeId u = arc_tail[a], v = arc_head[a];
      if (fill[v] != 0 && fill[u] == 0) arrival[v] = std::min(arrival[v], pot[u] + arc_cost[a]);
      if (fill[u] != 0 && fill[v] == 0) departure[u] = std::max(departure[u], pot[v] - arc_cost[a]);
    }
    for (NodeId v = 0; v < nodes; ++v) {
      if (fill[v] == 0) continue;
      if (arrival[v] != kNoArrival) {
        pot[v] = arrival[v];
      } else if (departure[v] != kNoDeparture) {
        pot[v] = departure[v];
      }
    }
  }
};

MinCostFlow::MinCostFlow(const Capacity& capacity) : impl_(std::make_unique<Impl>(capacity)) {}
MinCostFlow::~MinCostFlow() = default;
MinCostFlow::MinCostFlow(MinCostFlow&&) noexcept = default;
MinCostFlow& MinCostFlow::operator=(MinCostFlow&&) noexcept = default;

Status MinCostFlow::reset(std::int32_t node_count) {
  Impl& m = *impl_;
  if (node_count < 0) return Status::kInvalidInput;
  if (node_count > m.limits.max_nodes) return Status::kCapacityExceeded;
  m.nodes = node_count;
  m.arcs = 0;
  m.laid_out = false;
  m.have_state = false;
  m.optimal = false;
  m.is_balanced = true;
  m.imbalanced_count = 0;
  m.clear_recosted();
  for (std::int32_t k = 0; k < m.tie_count; ++k) m.in_tie_order[m.tie_order[k]] = 0;
  m.tie_count = 0;
  m.value = 0;
  m.cost_total = 0;
  m.stats = {};
  std::fill(m.seen.begin(), m.seen.begin() + node_count, 0);
  std::fill(m.renewed.begin(), m.renewed.begin() + node_count, 0);
  std::fill(m.pot.begin(), m.pot.begin() + node_count, 0);
  return Status::kOptimal;
}

Status MinCostFlow::add_arc(NodeId from, NodeId to, Flow capacity, Cost cost) {
  Impl& m = *impl_;
  if (from < 0 || from >= m.nodes || to < 0 || to >= m.nodes) return Status::kInvalidInput;
  if (capacity < 0 || capacity > kMaxArcCapacity || cost < 0 || cost > kMaxArcCost) {
    return Status::kInvalidInput;
  }
  if (m.arcs >= m.limits.max_arcs) return Status::kCapacityExceeded;
  m.arc_tail[m.arcs] = from;
  m.arc_head[m.arcs] = to;
  m.arc_cap[m.arcs] = static_cast<std::int32_t>(capacity);
  m.arc_cost[m.arcs] = static_cast<std::int32_t>(cost);
  m.arc_flow[m.arcs] = 0;
  m.arc_pos[m.arcs] = -1;
  ++m.arcs;
  m.laid_out = false;
  m.optimal = false;
  return Status::kOptimal;
}

Status MinCostFlow::set_arc(ArcId a, Flow capacity, Cost cost) {
  Impl& m = *impl_;
  if (a < 0 || a >= m.arcs) return Status::kInvalidInput;
  if (capacity < 0 || capacity > kMaxArcCapacity || cost < 0 || cost > kMaxArcCost) {
    return Status::kInvalidInput;
  }
  if (m.arc_cap[a] == capacity && m.arc_cost[a] == cost) return Status::kOptimal;
  if (m.arc_cost[a] != cost && m.is_recosted[a] == 0) {
    m.is_recosted[a] = 1;
    m.recosted[m.recosted_count++] = a;
  }
  m.arc_cap[a] = static_cast<std::int32_t>(capacity);
  m.arc_cost[a] = static_cast<std::int32_t>(cost);
  m.laid_out = false;
  m.optimal = false;
  return Status::kOptimal;
}

Status MinCostFlow::replace_arc(ArcId a, NodeId from, NodeId to, Flow capacity, Cost cost) {
  Impl& m = *impl_;
  if (a < 0 || a >= m.arcs) return Status::kInvalidInput;
  if (from < 0 || from >= m.nodes || to < 0 || to >= m.nodes) return Status::kInvalidInput;
  if (capacity < 0 || capacity > kMaxArcCapacity || cost < 0 || cost > kMaxArcCost) {
    return Status::kInvalidInput;
  }
  m.arc_tail[a] = from;
  m.arc_head[a] = to;
  m.arc_cap[a] = static_cast<std::int32_t>(capacity);
  m.arc_cost[a] = static_cast<std::int32_t>(cost);
  m.arc_flow[a] = 0;
  m.laid_out = false;
  m.optimal = false;
  return Status::kOptimal;
}

Status MinCostFlow::renew_node(NodeId v) {
  Impl& m = *impl_;
  if (v < 0 || v >= m.nodes) return Status::kInvalidInput;
  m.renewed[v] = 1;
  m.laid_out = false;
  m.optimal = false;
  return Status::kOptimal;
}

Status MinCostFlow::set_tie_order(const ArcId* order, std::int32_t count) {
  Impl& m = *impl_;
  if (count < 0 || count > m.arcs || (count > 0 && order == nullptr)) return Status::kInvalidInput;
  for (std::int32_t k = 0; k < m.tie_count; ++k) m.in_tie_order[m.tie_order[k]] = 0;
  m.tie_count = 0;
  for (std::int32_t k = 0; k < count; ++k) {
    const ArcId a = order[k];
    if (a < 0 || a >= m.arcs || m.in_tie_order[a] != 0) {
      for (std::int32_t j = 0; j < k; ++j) m.in_tie_order[order[j]] = 0;
      return Status::kInvalidInput;
    }
    m.in_tie_order[a] = 1;
    m.tie_order[k] = a;
  }
  m.tie_count = count;
  m.laid_out = false;
  m.optimal = false;
  return Status::kOptimal;
}

Status MinCostFlow::solve(NodeId source, NodeId sink, const Budget& budget) {
  Impl& m = *impl_;
  if (!m.valid_terminals(source, sink)) return Status::kInvalidInput;
  return m.solve_scratch(source, sink, budget);
}

Status MinCostFlow::solve_warm(NodeId source, NodeId sink, const Budget& budget) {
  Impl& m = *impl_;
  if (!m.valid_terminals(source, sink)) return Status::kInvalidInput;
  return m.solve_warm(source, sink, budget);
}

Status MinCostFlow::canonicalize(const ArcId* order, std::int32_t count, const Budget& budget) {
  Impl& m = *impl_;
  if (!m.optimal || !m.laid_out || count < 0 || (count > 0 && order == nullptr)) {
    return Status::kInvalidInput;
  }
  for (std::int32_t k = 0; k < count; ++k) {
    if (order[k] < 0 || order[k] >= m.arcs) return Status::kInvalidInput;
  }
  const std::uint64_t swaps_before = m.stats.canonical_swaps;
  Meter meter(budget, m.stats);
  Status status = Status::kOptimal;
  NodeId target = -1;
  std::int32_t k = 0;
  for (; k < count && status == Status::kOptimal; ++k) {
    const std::int32_t f = m.arc_pos[order[k]];
    if (f < 0) continue;
    const NodeId u = m.arc_tail[order[k]], v = m.arc_head[order[k]];
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

std::int32_t MinCostFlow::node_count() const { return impl_->nodes; }
std::int32_t MinCostFlow::arc_count() const { return impl_->arcs; }
NodeId MinCostFlow::tail(ArcId a) const { return impl_->arc_tail[a]; }
NodeId MinCostFlow::head(ArcId a) const { return impl_->arc_head[a]; }
Flow MinCostFlow::capacity(ArcId a) const { return impl_->arc_cap[a]; }
Cost MinCostFlow::cost(ArcId a) const { return impl_->arc_cost[a]; }
Flow MinCostFlow::flow(ArcId a) const { return impl_->arc_flow[a]; }
Flow MinCostFlow::flow_value() const { return impl_->value; }
Cost MinCostFlow::total_cost() const { return impl_->cost_total; }
bool MinCostFlow::balanced() const { return impl_->is_balanced; }
Cost MinCostFlow::potential(NodeId v) const { return impl_->pot[v]; }
const SolveStats& MinCostFlow::stats() const { return impl_->stats; }
const Capacity& MinCostFlow::capacity_limits() const { return impl_->limits; }
std::size_t MinCostFlow::memory_bytes() const { return impl_->bytes(); }

}  // namespace keepless::solver
