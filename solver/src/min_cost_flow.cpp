#include "keepless/solver/min_cost_flow.hpp"

#include <algorithm>
#include <vector>

#include "radix_heap.hpp"

namespace keepless::solver {
namespace {

constexpr Flow kMaxArcCapacity = std::numeric_limits<std::int32_t>::max();
constexpr Cost kMaxArcCost = (Cost{1} << 30);
constexpr std::uint64_t kUnlabelled = std::numeric_limits<std::uint64_t>::max();

}  // namespace

// Storage: user arcs in insertion order, and the residual graph in CSR order
// (LEMON's layout). A node's residual arcs are sorted by user arc id, which
// makes every scan, and so the result, a function of the insertion order.
// Each residual position also mirrors its partner's capacity, so the
// sink-side searches read one contiguous record per arc.
struct MinCostFlow::Impl {
  // 16 bytes, so a scan streams as little memory as possible.
  struct Residual {
    NodeId head;
    std::int32_t cap;      // residual capacity of this arc
    std::int32_t rev_cap;  // residual capacity of the partner (head -> tail)
    std::int32_t cost;     // the partner's cost is -cost
  };

  Capacity limits;
  std::int32_t nodes = 0;
  std::int32_t arcs = 0;

  // User arcs.
  std::vector<NodeId> arc_tail, arc_head;
  std::vector<Flow> arc_cap;
  std::vector<Cost> arc_cost;
  std::vector<std::int32_t> arc_pos;  // CSR position of the forward residual arc

  std::vector<std::int32_t> first_out;  // max_nodes + 1
  std::vector<Residual> res;            // 2 * max_arcs
  std::vector<std::int32_t> rev;        // partner position of each residual arc

  // Per-node workspace.
  std::vector<Cost> pot;
  std::vector<std::uint64_t> key;  // Dijkstra label: distance * key_base + hops
  std::vector<std::int32_t> level, cur, queue, path_arc;
  std::vector<NodeId> path_node;
  RadixHeap heap;

  bool solved = false;  // flows are read from the residual graph only after solve()
  Flow value = 0;
  Cost cost_total = 0;
  SolveStats stats;

  explicit Impl(const Capacity& c)
      : limits(c), heap(static_cast<std::size_t>(std::max(c.max_nodes, 0))) {
    const auto n = static_cast<std::size_t>(std::max(c.max_nodes, 0));
    const auto m = static_cast<std::size_t>(std::max(c.max_arcs, 0));
    arc_tail.resize(m);
    arc_head.resize(m);
    arc_cap.resize(m);
    arc_cost.resize(m);
    arc_pos.resize(m);
    first_out.resize(n + 1);
    res.resize(2 * m);
    rev.resize(2 * m);
    pot.resize(n);
    key.resize(n);
    level.resize(n);
    cur.resize(n);
    queue.resize(n);
    path_arc.resize(n);
    path_node.resize(n + 1);
  }

  std::size_t bytes() const {
    const auto n = static_cast<std::size_t>(std::max(limits.max_nodes, 0));
    const auto m = static_cast<std::size_t>(std::max(limits.max_arcs, 0));
    return m * (2 * sizeof(NodeId) + sizeof(Flow) + sizeof(Cost) + sizeof(std::int32_t)) +
           (n + 1) * sizeof(std::int32_t) + 2 * m * (sizeof(Residual) + sizeof(std::int32_t)) +
           n * (sizeof(Cost) + sizeof(std::uint64_t) + 5 * sizeof(std::int32_t)) + (n + 1) * sizeof(NodeId) +
           heap.memory_bytes();
  }

  // Counting sort of residual arcs by tail, stable in user arc id.
  void build_residual() {
    std::fill(first_out.begin(), first_out.begin() + nodes + 1, 0);
    for (std::int32_t a = 0; a < arcs; ++a) {
      ++first_out[arc_tail[a] + 1];
      ++first_out[arc_head[a] + 1];
    }
    for (std::int32_t v = 0; v < nodes; ++v) first_out[v + 1] += first_out[v];
    std::copy(first_out.begin(), first_out.begin() + nodes, cur.begin());
    for (std::int32_t a = 0; a < arcs; ++a) {
      const std::int32_t f = cur[arc_tail[a]]++;
      const std::int32_t r = cur[arc_head[a]]++;
      const auto cap = static_cast<std::int32_t>(arc_cap[a]);
      const auto cost = static_cast<std::int32_t>(arc_cost[a]);
      res[f] = Residual{arc_head[a], cap, 0, cost};
      res[r] = Residual{arc_tail[a], 0, cap, -cost};
      rev[f] = r;
      rev[r] = f;
      arc_pos[a] = f;
    }
  }

  void push(std::int32_t i, std::int32_t f) {
    Residual& a = res[i];
    Residual& b = res[rev[i]];
    a.cap -= f;
    b.rev_cap -= f;
    b.cap += f;
    a.rev_cap += f;
  }

  // Dijkstra towards the sink over reversed residual arcs, on reduced costs,
  // with hop count as the second key; it stops when the source is settled.
  // Every potential then drops by min(distance, D = distance of the source),
  // which keeps reduced costs >= 0 and makes the shortest s-t paths exactly
  // the zero-reduced-cost ones; the hop counts of the settled nodes are the
  // Dinic levels of those paths, so no separate BFS is needed. Only what can
  // still reach the sink cheaply is explored: as pairs fill up, a round
  // touches less of the network.
  bool shortest_paths(NodeId s, NodeId t) {
    const auto base = static_cast<std::uint64_t>(nodes) + 1;
    std::fill(key.begin(), key.begin() + nodes, kUnlabelled);
    std::fill(level.begin(), level.begin() + nodes, -1);
    heap.clear();
    key[t] = 0;
    heap.push(t, 0);
    bool reached = false;
    while (!heap.empty()) {
      const NodeId v = heap.pop_min();
      const std::uint64_t kv = key[v];
      level[v] = static_cast<std::int32_t>(kv % base);
      if (v == s) {
        reached = true;
        break;
      }
      const Cost pv = pot[v];
      const std::int32_t end = first_out[v + 1];
      stats.work_units += static_cast<std::uint64_t>(end - first_out[v]);
      for (std::int32_t i = first_out[v]; i < end; ++i) {
        const Residual& a = res[i];  // its partner u -> v is the arc searched
        if (a.rev_cap == 0) continue;
        const NodeId u = a.head;
        if (level[u] >= 0) continue;  // settled
        const auto rc = static_cast<std::uint64_t>(pot[u] - a.cost - pv);
        const std::uint64_t nk = kv + rc * base + 1;
        if (nk < key[u]) {
          if (key[u] == kUnlabelled) {
            heap.push(u, nk);
          } else {
            heap.decrease(u, nk);
          }
          key[u] = nk;
        }
      }
    }
    if (!reached) return false;
    const auto ds = static_cast<Cost>(key[s] / base);
    if (ds > 0) {
      for (std::int32_t v = 0; v < nodes; ++v) {
        const Cost dv = key[v] == kUnlabelled ? ds : static_cast<Cost>(key[v] / base);
        pot[v] -= std::min(dv, ds);
      }
    }
    return true;
  }

  // Dinic blocking flow on the level graph. The DFS serves each node's arcs
  // in CSR order, so earlier arcs win ties. Returns false if the budget ran out.
  bool blocking_flow(NodeId s, NodeId t, const Budget& budget) {
    std::copy(first_out.begin(), first_out.begin() + nodes, cur.begin());
    std::int32_t depth = 0;
    path_node[0] = s;
    NodeId u = s;
    for (;;) {
      if (u == t) {
        std::int32_t f = res[path_arc[0]].cap;
        for (std::int32_t k = 1; k < depth; ++k) f = std::min(f, res[path_arc[k]].cap);
        std::int32_t retreat = depth;
        for (std::int32_t k = 0; k < depth; ++k) {
          push(path_arc[k], f);
          if (res[path_arc[k]].cap == 0 && retreat == depth) retreat = k;
        }
        value += f;
        ++stats.augmentations;
        if (stats.work_units > budget.work_units) return false;
        depth = retreat;  // resume at the tail of the first saturated arc
        u = path_node[depth];
        continue;
      }
      const std::int32_t want = level[u] - 1;
      const Cost pu = pot[u];
      const std::int32_t end = first_out[u + 1];
      std::int32_t i = cur[u];
      for (; i < end; ++i) {
        ++stats.work_units;
        const Residual& a = res[i];
        if (a.cap > 0 && level[a.head] == want && a.cost + pu == pot[a.head]) break;
      }
      cur[u] = i;
      if (i < end) {
        path_arc[depth] = i;
        u = res[i].head;
        path_node[++depth] = u;
        continue;
      }
      level[u] = -1;  // dead end: prune it for the rest of this blocking flow
      if (depth == 0) return true;
      u = path_node[--depth];
      ++cur[u];
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
  m.solved = false;
  m.value = 0;
  m.cost_total = 0;
  m.stats = {};
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
  m.arc_cap[m.arcs] = capacity;
  m.arc_cost[m.arcs] = cost;
  ++m.arcs;
  m.solved = false;
  return Status::kOptimal;
}

Status MinCostFlow::solve(NodeId source, NodeId sink, const Budget& budget) {
  Impl& m = *impl_;
  if (source < 0 || source >= m.nodes || sink < 0 || sink >= m.nodes || source == sink) {
    return Status::kInvalidInput;
  }
  // Labels are distance * (nodes + 1) + hops, distance <= (nodes - 1) * max cost.
  Cost max_cost = 0;
  for (std::int32_t a = 0; a < m.arcs; ++a) max_cost = std::max(max_cost, m.arc_cost[a]);
  const auto base = static_cast<std::uint64_t>(m.nodes) + 1;
  if (base > (std::uint64_t{1} << 62) / base / static_cast<std::uint64_t>(max_cost + 1)) {
    return Status::kInvalidInput;
  }
  m.build_residual();
  m.solved = true;
  std::fill(m.pot.begin(), m.pot.begin() + m.nodes, 0);
  m.value = 0;
  m.stats = {};
  Status status = Status::kOptimal;
  // Each round finds the shortest s-t distance, then one blocking flow over
  // the zero-reduced-cost paths. The distance never decreases and each
  // blocking flow saturates an arc, so rounds are finite; the budget bounds
  // them in work too.
  for (;;) {
    if (m.stats.work_units > budget.work_units) {
      status = Status::kBudgetExhausted;
      break;
    }
    if (!m.shortest_paths(source, sink)) break;
    ++m.stats.phases;
    if (!m.blocking_flow(source, sink, budget)) {
      status = Status::kBudgetExhausted;
      break;
    }
  }
  m.cost_total = 0;
  for (std::int32_t a = 0; a < m.arcs; ++a) m.cost_total += flow(a) * m.arc_cost[a];
  return status;
}

std::int32_t MinCostFlow::node_count() const { return impl_->nodes; }
std::int32_t MinCostFlow::arc_count() const { return impl_->arcs; }
NodeId MinCostFlow::tail(ArcId a) const { return impl_->arc_tail[a]; }
NodeId MinCostFlow::head(ArcId a) const { return impl_->arc_head[a]; }
Flow MinCostFlow::capacity(ArcId a) const { return impl_->arc_cap[a]; }
Cost MinCostFlow::cost(ArcId a) const { return impl_->arc_cost[a]; }
Flow MinCostFlow::flow(ArcId a) const {
  return impl_->solved ? impl_->arc_cap[a] - impl_->res[impl_->arc_pos[a]].cap : 0;
}
Flow MinCostFlow::flow_value() const { return impl_->value; }
Cost MinCostFlow::total_cost() const { return impl_->cost_total; }
Cost MinCostFlow::potential(NodeId v) const { return impl_->solved ? impl_->pot[v] : 0; }
const SolveStats& MinCostFlow::stats() const { return impl_->stats; }
const Capacity& MinCostFlow::capacity_limits() const { return impl_->limits; }
std::size_t MinCostFlow::memory_bytes() const { return impl_->bytes(); }

}  // namespace keepless::solver
