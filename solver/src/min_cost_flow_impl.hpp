#pragma once

// MinCostFlow's internals, shared by the solver's sources (not installed).

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "keepless/solver/min_cost_flow.hpp"
#include "radix_heap.hpp"

namespace keepless::solver {

namespace detail {

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

// What is left of `budget` once `used` work units are spent (a fallback
// continues under the caller's budget, it does not start a new one).
inline Budget remaining(const Budget& budget, std::uint64_t used) {
  Budget b = budget;
  b.work_units = used >= b.work_units ? 0 : b.work_units - used;
  return b;
}

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

}  // namespace detail

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

  // User arcs, one record each, so that a layout visiting arcs in tie
  // order (not id order) reads one cache line per arc.
  std::vector<Arc> arc;
  std::vector<std::int32_t> arc_flow;
  std::vector<std::int32_t> arc_pos;  // forward residual record, -1 when not laid out
  std::vector<ArcId> tie_order;          // set_tie_order
  std::vector<std::uint8_t> in_tie_order;
  std::int32_t tie_count = 0;
  std::vector<ArcId> layout_order;       // active arcs, tie order first then ids (count_degrees)
  std::int32_t layout_count = 0;
  std::int32_t label_nodes = 0;          // nodes with arcs at the last count_degrees, + 2 (terminals)
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

  // Nodes are numbered afresh at each layout, in block order (see
  // count_degrees), so that the phases' per-node arrays are read in the
  // order the blocks are: with recycled ids (an incrementally edited
  // network) the user's numbering scatters them. Everything below that is
  // per node, and the records' heads, use these internal numbers; the API,
  // the user arcs and the state kept between calls (pot_ext, seen, renewed)
  // use the user's.
  std::vector<NodeId> int_of;  // user id -> internal
  std::vector<NodeId> ext_of;  // internal -> user id
  std::vector<Cost> pot_ext;   // potentials by user id, between calls

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
  bool repair_pending = false;  // lay_out's imbalances not yet through local_repair (a resumed solve skips it)
  bool have_state = false;   // flows and potentials can seed solve_warm
  bool optimal = false;      // the last solve finished
  bool is_balanced = true;
  bool overflow = false;     // a label would have left 64 bits (never with checked input)
  bool cost_overflow = false;  // finish(): the flow's total cost left int64 (refused: kInvalidInput)
  NodeId src = -1, snk = -1;          // internal, during a call
  NodeId src_ext = -1, snk_ext = -1;  // the user's, of the last solve
  Mode mode = Mode::kMaxFlow;
  int shift = 1;  // labels are distance << shift | hops
  std::uint64_t hop_mask = 1;
  std::uint64_t rc_limit = 0;
  Flow value = 0;
  Cost cost_total = 0;
  SolveStats stats;

  // Storage (residual_graph.cpp).
  explicit Impl(const Capacity& c);

  std::size_t bytes() const;

  bool active(ArcId a) const { return arc[a].capacity > 0 && arc[a].tail != arc[a].head; }

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

  // --- layout (residual_graph.cpp) -------------------------------------------

  Cost count_degrees();
  void set_terminals(NodeId s, NodeId t) {  // after count_degrees
    src_ext = s;
    snk_ext = t;
    src = int_of[s];
    snk = int_of[t];
  }
  void lay_out(bool repair);
  // Arcs at user node v at the last count_degrees.
  std::int32_t degree(NodeId v) const { return block_end[int_of[v]] - first_out[int_of[v]]; }

  // --- phases (shortest_paths.cpp, blocking_flow.cpp) --------------------------

  bool is_target(NodeId v) const {
    switch (mode) {
      case Mode::kMaxFlow: return v == snk;
      case Mode::kExcess: return v == src || v == snk || excess[v] < 0;
      case Mode::kDeficit: return v != src && v != snk && excess[v] < 0;
    }
    return false;
  }
  std::int64_t supply_of(NodeId v) const {
    return mode == Mode::kExcess ? excess[v] : detail::kUnlimited;
  }
  std::int64_t need_of(NodeId v) const {
    if (mode == Mode::kMaxFlow || v == src || v == snk) return detail::kUnlimited;
    return -excess[v];
  }

  // Offers u the label kv + rc (reduced cost, clamped) + one hop, from `from`.
  // Inlined: it runs once per arc a search scans.
  [[gnu::always_inline]] void relax(NodeId u, std::uint64_t kv, Cost rc, NodeId from) {
    auto r = static_cast<std::uint64_t>(rc);
    if (r > rc_limit) {
      overflow = true;
      r = rc_limit;
    }
    const std::uint64_t nk = kv + (r << shift) + 1;
    if (nk < key[u]) {
      if (mode == Mode::kExcess) origin[u] = origin[from];
      if (key[u] == detail::kUnlabelled) {
        heap.push(u, nk);
        touched[touched_count++] = u;
      } else {
        heap.decrease(u, nk);
      }
      key[u] = nk;
    }
  }

  // --- the source's lazy arcs (shortest_paths.cpp) -----------------------------

  std::int32_t source_degree() const { return first_rev[src] - first_out[src]; }
  std::int32_t source_words() const { return source_degree() / 64 + 1; }
  static bool less(const Pending& a, const Pending& b) { return a.w != b.w ? a.w < b.w : a.pos < b.pos; }

  void lazy_begin();
  void lazy_queue(std::uint64_t frontier);
  void lazy_end_phase();

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

  Search shortest_paths(std::int32_t source_count, detail::Meter& meter);
  Search shortest_paths_to_sink(detail::Meter& meter);
  void clear_labels();
  std::uint64_t set_label_base();

  bool blocking_flow(std::int32_t source_count, detail::Meter& meter);
  Status run(Mode m, detail::Meter& meter);
  Status run_phases(Mode m, detail::Meter& meter);
  void finish();
  Status stop_before_start(NodeId s, NodeId t);
  Status solve_scratch(NodeId s, NodeId t, const Budget& budget);

  // --- local repair and warm starts (warm_start.cpp) ---------------------------

  static constexpr std::int32_t kLocalDepth = 3;

  bool can_absorb(NodeId v) const { return v == src || v == snk || excess[v] < 0; }
  bool can_supply(NodeId v) const { return v == src || v == snk || excess[v] > 0; }

  bool local_path(NodeId x, bool forward);
  bool local_repair(detail::Meter& meter);
  void clear_recosted();
  void shift_recosted_potentials();
  Status solve_warm(NodeId s, NodeId t, const Budget& budget);
  void estimate_potentials();

  // --- a caller's start (given_start.cpp) ---------------------------------------

  static constexpr Cost kPotentialBound = Cost{1} << 60;
  bool adopt(NodeId s, NodeId t, const Flow* flow, const Cost* potential);
  Status solve_from(NodeId s, NodeId t, const Flow* flow, const Cost* potential, const Budget& budget);
  // canonicalize() after an adopted start: the residual graph is laid out on demand.
  void ensure_laid_out();

  // --- canonicalize (canonicalize.cpp) -----------------------------------------

  bool tie_path(NodeId from, NodeId to);
  void new_dead_epoch();
  // A fresh mark for visit[] (searches and count_degrees mark nodes with it).
  void new_visit_epoch() {
    if (++visit_epoch == 0) {
      std::fill(visit.begin(), visit.begin() + nodes, 0u);
      visit_epoch = 1;
    }
  }

  bool valid_terminals(NodeId s, NodeId t) const {
    return s >= 0 && s < nodes && t >= 0 && t < nodes && s != t;
  }
};

}  // namespace keepless::solver
