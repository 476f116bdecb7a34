#include "keepless/core/keep_thresholds.hpp"

#include <algorithm>
#include <vector>

namespace keepless::core {

struct KeepThresholds::Impl {
  struct Point {
    std::int32_t rank = -1;  // in the tie order; -1: not a point
    std::int32_t cost = 0;   // c_c
  };
  struct Unit {              // one point -> pair arc, grouped by point
    std::uint32_t cost;      // c_c + c_s
    solver::NodeId pair;
    std::uint32_t position;  // in its pair's order, from 0
  };
  struct Listed {            // the same in arc order
    std::uint32_t cost;
    std::int32_t rank;
    solver::NodeId pair;
  };
  static constexpr std::uint32_t kBins = 1024;

  std::vector<Point> point;            // [max_nodes] by node
  std::vector<std::uint32_t> thr;      // [max_nodes] M* by node
  std::vector<std::int64_t> flow;      // [max_nodes] by node, after evaluate_at
  std::vector<solver::ArcId> out;      // [max_nodes] a pair's sink arc
  std::vector<std::int32_t> at;        // [max_nodes + 1] a point's units (by rank)
  std::vector<std::int32_t> first;     // [max_nodes + 1] a pair's units (by node)
  std::vector<Listed> listed;          // [max_arcs]
  std::vector<Unit> units;             // [max_arcs] grouped by point rank
  std::vector<std::int32_t> by_pair;   // [max_arcs] indices into units, by pair, rank order
  std::vector<std::uint32_t> scratch;  // [max_arcs] one point's positions
  std::vector<std::uint32_t> bins;     // [kBins + 1]
  std::vector<solver::NodeId> node_of; // [max_nodes] a rank's node
  std::int32_t points = 0;
  std::int32_t nodes = 0;
  const solver::Arc* arc = nullptr;
  std::int64_t max_flow = 0;
  std::int64_t total_cost = 0;

  explicit Impl(const solver::Capacity& c) {
    const auto n = static_cast<std::size_t>(std::max(c.max_nodes, 0));
    const auto m = static_cast<std::size_t>(std::max(c.max_arcs, 0));
    point.resize(n);
    thr.resize(n);
    flow.resize(n);
    out.resize(n);
    at.resize(n + 1);
    first.resize(n + 1);
    listed.resize(m);
    units.resize(m);
    by_pair.resize(m);
    scratch.resize(m);
    bins.resize(kBins + 1);
    node_of.resize(n);
  }

  // The smallest flow f in [1, capacity] that decide() keeps, in the same
  // double comparison; capacity + 1 if none.
  static std::int64_t needed(std::int64_t capacity, double theta) {
    const double bar = theta * static_cast<double>(capacity);
    auto f = static_cast<std::int64_t>(bar) + 1;
    f = std::max<std::int64_t>(1, std::min(f, capacity + 1));
    while (f > 1 && static_cast<double>(f - 1) > bar) --f;
    while (f <= capacity && !(static_cast<double>(f) > bar)) ++f;
    return f;
  }

  // Each unit's position in its pair: units by rank, then grouped by pair
  // (stable, so rank order within a pair), then counted by cost.
  void positions(std::int32_t pair_nodes_end) {
    for (std::int32_t q = 0; q < pair_nodes_end; ++q) {
      const std::int32_t* begin = by_pair.data() + first[q];
      const std::int32_t* end = by_pair.data() + first[q + 1];
      if (begin == end) continue;
      std::uint32_t lo = ~0u, hi = 0;
      for (const std::int32_t* u = begin; u != end; ++u) {
        lo = std::min(lo, units[*u].cost);
        hi = std::max(hi, units[*u].cost);
      }
      if (hi - lo < kBins) {
        std::fill(bins.begin(), bins.begin() + (hi - lo + 2), 0u);
        for (const std::int32_t* u = begin; u != end; ++u) ++bins[units[*u].cost - lo + 1];
        for (std::uint32_t b = 0; b + 1 <= hi - lo; ++b) bins[b + 1] += bins[b];
        for (const std::int32_t* u = begin; u != end; ++u) {
          units[*u].position = bins[units[*u].cost - lo]++;
        }
      } else {  // costs too spread for bins: sort (indices ascend with rank)
        std::int32_t* b = by_pair.data() + first[q];
        std::int32_t* e = by_pair.data() + first[q + 1];
        std::sort(b, e, [this](std::int32_t x, std::int32_t y) {
          return units[x].cost != units[y].cost ? units[x].cost < units[y].cost : x < y;
        });
        for (std::int32_t* u = b; u != e; ++u) units[*u].position = static_cast<std::uint32_t>(u - b);
      }
    }
  }

  void compute(const solver::MinCostFlow& solver, solver::NodeId sink, const solver::ArcId* order,
               std::int32_t count, double theta) {
    nodes = solver.node_count();
    const std::int32_t arcs = solver.arc_count();
    arc = solver.arc_data();
    std::fill(point.begin(), point.begin() + nodes, Point{});
    std::fill(thr.begin(), thr.begin() + nodes, kNever);
    std::fill(out.begin(), out.begin() + nodes, -1);
    std::fill(first.begin(), first.begin() + nodes + 1, 0);
    points = count;
    std::fill(at.begin(), at.begin() + count + 1, 0);
    for (std::int32_t k = 0; k < count; ++k) {
      const solver::Arc& e = arc[order[k]];
      node_of[k] = e.capacity != 0 ? e.head : -1;
      if (e.capacity == 0) continue;
      point[e.head] = Point{k, e.cost};
    }
    std::int32_t listed_count = 0;
    for (solver::ArcId a = 0; a < arcs; ++a) {
      const solver::Arc e = arc[a];
      if (e.capacity == 0) continue;
      if (e.head == sink) {
        out[e.tail] = a;
        continue;
      }
      const Point p = point[e.tail];
      if (p.rank < 0) continue;  // a source arc
      listed[listed_count++] = Listed{static_cast<std::uint32_t>(p.cost) + static_cast<std::uint32_t>(e.cost),
                                      p.rank, e.head};
      ++at[p.rank + 1];
      ++first[e.head + 1];
    }
    for (std::int32_t k = 0; k < count; ++k) at[k + 1] += at[k];
    for (std::int32_t v = 0; v < nodes; ++v) first[v + 1] += first[v];
    // Group by rank (at[] advances to each group's end, then is restored).
    for (std::int32_t u = 0; u < listed_count; ++u) {
      const Listed& l = listed[u];
      units[at[l.rank]++] = Unit{l.cost, l.pair, 0};
    }
    for (std::int32_t k = count; k > 0; --k) at[k] = at[k - 1];
    at[0] = 0;
    // Then by pair, keeping rank order.
    for (std::int32_t u = 0; u < listed_count; ++u) by_pair[first[units[u].pair]++] = u;
    for (std::int32_t v = nodes; v > 0; --v) first[v] = first[v - 1];
    first[0] = 0;
    positions(nodes);
    // Each point's threshold: the t-th smallest of its positions, plus one.
    for (std::int32_t k = 0; k < count; ++k) {
      const solver::NodeId node = node_of[k];
      if (node < 0) continue;
      const std::int64_t capacity = arc[order[k]].capacity;
      const std::int64_t t = needed(capacity, theta);
      const std::int32_t n = at[k + 1] - at[k];
      if (t > n) continue;  // kNever
      std::uint32_t* s = scratch.data();
      for (std::int32_t u = 0; u < n; ++u) s[u] = units[at[k] + u].position;
      std::nth_element(s, s + (t - 1), s + n);
      thr[node] = s[t - 1] + 1;
    }
  }

  void evaluate_at(std::int64_t m) {
    max_flow = 0;
    total_cost = 0;
    for (std::int32_t k = 0; k < points; ++k) {
      const solver::NodeId node = node_of[k];
      if (node < 0) continue;
      std::int64_t f = 0;
      for (std::int32_t u = at[k]; u < at[k + 1]; ++u) {
        const Unit& unit = units[u];
        if (static_cast<std::int64_t>(unit.position) >= m) continue;
        ++f;
        const solver::ArcId way_out = out[unit.pair];
        total_cost += static_cast<std::int64_t>(unit.cost) + (way_out >= 0 ? arc[way_out].cost : 0);
      }
      flow[node] = f;
      max_flow += f;
    }
  }
};

KeepThresholds::KeepThresholds(const solver::Capacity& c) : impl_(std::make_unique<Impl>(c)) {}
KeepThresholds::~KeepThresholds() = default;

void KeepThresholds::compute(const solver::MinCostFlow& solver, solver::NodeId sink,
                             const solver::ArcId* order, std::int32_t count, double theta) {
  impl_->compute(solver, sink, order, count, theta);
}
std::uint32_t KeepThresholds::threshold(solver::NodeId node) const { return impl_->thr[node]; }
void KeepThresholds::evaluate_at(std::int64_t m) { impl_->evaluate_at(m); }
std::int64_t KeepThresholds::flow_at(solver::NodeId node) const { return impl_->flow[node]; }
std::int64_t KeepThresholds::max_flow() const { return impl_->max_flow; }
std::int64_t KeepThresholds::total_cost() const { return impl_->total_cost; }

std::size_t KeepThresholds::memory_bytes() const {
  const Impl& s = *impl_;
  return sizeof(Impl) + s.point.capacity() * sizeof(Impl::Point) +
         s.thr.capacity() * sizeof(std::uint32_t) + s.flow.capacity() * sizeof(std::int64_t) +
         s.out.capacity() * sizeof(solver::ArcId) +
         (s.at.capacity() + s.first.capacity()) * sizeof(std::int32_t) +
         s.listed.capacity() * sizeof(Impl::Listed) + s.units.capacity() * sizeof(Impl::Unit) +
         s.by_pair.capacity() * sizeof(std::int32_t) + s.scratch.capacity() * sizeof(std::uint32_t) +
         s.bins.capacity() * sizeof(std::uint32_t) + s.node_of.capacity() * sizeof(solver::NodeId);
}

}  // namespace keepless::core
