#include "keepless/core/pairwise_start.hpp"

#include <algorithm>
#include <vector>

namespace keepless::core {

struct PairwiseStart::Impl {
  struct Unit {
    std::uint64_t key;  // unit cost << 32 | the point's rank in the tie order
    solver::ArcId arc;
    solver::NodeId pair;
  };
  struct Point {  // read together for every pair arc
    std::int32_t rank = -1;  // in the tie order; -1: not a point (source, pairs)
    std::int32_t cost = 0;   // its source arc's, c_c
  };
  std::vector<solver::Flow> flow;       // [max_arcs]
  std::vector<solver::Cost> potential;  // [max_nodes]
  std::vector<Point> point;             // [max_nodes]
  std::vector<solver::ArcId> out;       // [max_nodes] a pair's sink arc
  std::vector<std::int32_t> first;      // [max_nodes + 1] a pair's first unit in `units`
  std::vector<Unit> listed;             // [max_arcs] units in arc order; later, ties at a cut
  std::vector<Unit> units;              // [max_arcs] the same, grouped by pair
  static constexpr std::uint64_t kBins = 1024;
  std::vector<std::uint32_t> bins;      // [kBins] unit costs of a pair, from its cheapest

  explicit Impl(const solver::Capacity& c) {
    const auto n = static_cast<std::size_t>(std::max(c.max_nodes, 0));
    const auto m = static_cast<std::size_t>(std::max(c.max_arcs, 0));
    flow.resize(m);
    potential.resize(n);
    point.resize(n);
    out.resize(n);
    first.resize(n + 1);
    listed.resize(m);
    units.resize(m);
    bins.resize(kBins);
  }
  void take_cheapest(Unit* begin, Unit* end, std::int64_t take);
  void compute(const solver::MinCostFlow& solver, solver::NodeId sink, const solver::ArcId* order,
               std::int32_t count);
};

PairwiseStart::PairwiseStart(const solver::Capacity& c) : impl_(std::make_unique<Impl>(c)) {}
PairwiseStart::~PairwiseStart() = default;

void PairwiseStart::compute(const solver::MinCostFlow& solver, solver::NodeId sink,
                            const solver::ArcId* order, std::int32_t count) {
  impl_->compute(solver, sink, order, count);
}
const solver::Flow* PairwiseStart::flow() const { return impl_->flow.data(); }
const solver::Cost* PairwiseStart::potential() const { return impl_->potential.data(); }

std::size_t PairwiseStart::memory_bytes() const {
  const Impl& s = *impl_;
  return sizeof(Impl) + s.flow.capacity() * sizeof(solver::Flow) +
         s.potential.capacity() * sizeof(solver::Cost) + s.point.capacity() * sizeof(Impl::Point) +
         s.out.capacity() * sizeof(solver::ArcId) + s.first.capacity() * sizeof(std::int32_t) +
         (s.listed.capacity() + s.units.capacity()) * sizeof(Impl::Unit) +
         s.bins.capacity() * sizeof(std::uint32_t);
}

// Moves the `take` smallest keys of [begin, end) to its front, in any
// order. Unit costs are small integers here (c_c + c_s), so a histogram
// finds the cost at the cut in two passes, and only the units at that cost
// need ordering by key (rank); a pair whose costs span more bins than there
// are takes nth_element.
void PairwiseStart::Impl::take_cheapest(Unit* begin, Unit* end, std::int64_t take) {
  const auto by_key = [](const Unit& a, const Unit& b) { return a.key < b.key; };
  std::uint64_t lo = ~std::uint64_t{0}, hi = 0;
  for (const Unit* u = begin; u != end; ++u) {
    lo = std::min(lo, u->key >> 32);
    hi = std::max(hi, u->key >> 32);
  }
  if (hi - lo >= kBins) {
    std::nth_element(begin, begin + take, end, by_key);
    return;
  }
  std::fill(bins.begin(), bins.begin() + static_cast<std::ptrdiff_t>(hi - lo + 1), 0u);
  for (const Unit* u = begin; u != end; ++u) ++bins[(u->key >> 32) - lo];
  std::uint64_t cut = 0;
  std::int64_t below = 0;
  while (below + bins[cut] < take) below += bins[cut++];
  cut += lo;
  // Below the cut to the front (in place: never ahead of the reader), those
  // at it aside; then the cheapest ranks among those at it.
  Unit* front = begin;
  Unit* ties = listed.data();
  std::int64_t tied = 0;
  for (const Unit* u = begin; u != end; ++u) {
    const std::uint64_t c = u->key >> 32;
    const Unit unit = *u;
    *front = unit;
    front += c < cut ? 1 : 0;
    ties[tied] = unit;
    tied += c == cut ? 1 : 0;
  }
  const std::int64_t need = take - below;
  if (need < tied) std::nth_element(ties, ties + need, ties + tied, by_key);
  std::copy(ties, ties + need, front);
}

void PairwiseStart::Impl::compute(const solver::MinCostFlow& solver, solver::NodeId sink,
                                  const solver::ArcId* order, std::int32_t count) {
  const std::int32_t nodes = solver.node_count();
  const std::int32_t arcs = solver.arc_count();
  const solver::Arc* arc = solver.arc_data();
  std::fill(flow.begin(), flow.begin() + arcs, 0);
  std::fill(potential.begin(), potential.begin() + nodes, 0);
  std::fill(point.begin(), point.begin() + nodes, Point{});
  std::fill(out.begin(), out.begin() + nodes, -1);
  std::fill(first.begin(), first.begin() + nodes + 1, 0);

  for (std::int32_t k = 0; k < count; ++k) {
    const solver::Arc& e = arc[order[k]];
    if (e.capacity == 0) continue;
    point[e.head] = Point{k, e.cost};
    potential[e.head] = e.cost;
  }
  // One pass over the arcs: a pair's sink arc is its way out, a point's
  // pair arc becomes a unit, and the largest cost bounds every path's. No
  // branches on an arc's kind (an incrementally edited network scatters the
  // kinds over the ids): every arc is written out, units advance the list.
  // Then a counting sort groups the units by pair.
  solver::Cost max_cost = 0;
  std::int32_t listed_count = 0;
  for (solver::ArcId a = 0; a < arcs; ++a) {
    const solver::Arc e = arc[a];
    const bool live = e.capacity != 0;
    const bool way_out = live && e.head == sink;
    if (way_out) out[e.tail] = a;  // one per pair: predictable
    max_cost = std::max<solver::Cost>(max_cost, live ? e.cost : 0);
    const Point p = point[e.tail];
    const bool unit = live && !way_out && p.rank >= 0;
    const auto unit_cost = static_cast<std::uint64_t>(p.cost) + static_cast<std::uint64_t>(e.cost);
    listed[listed_count] = Unit{unit_cost << 32 | static_cast<std::uint32_t>(p.rank), a, e.head};
    listed_count += unit ? 1 : 0;
    first[e.head + 1] += unit ? 1 : 0;
  }
  for (std::int32_t v = 0; v < nodes; ++v) first[v + 1] += first[v];
  for (std::int32_t u = 0; u < listed_count; ++u) units[first[listed[u].pair]++] = listed[u];
  for (std::int32_t v = nodes; v > 0; --v) first[v] = first[v - 1];
  first[0] = 0;

  // Each pair takes its cheapest units, as many as its sink arc carries.
  const solver::Cost top = solver::Cost{nodes} * max_cost + 1;  // the sink: beyond any path
  for (std::int32_t q = 0; q < nodes; ++q) {
    Unit* begin = units.data() + first[q];
    Unit* end = units.data() + first[q + 1];
    if (begin == end) continue;
    const solver::ArcId way_out = out[q];
    const std::int64_t room = way_out >= 0 ? arc[way_out].capacity : 0;
    const std::int64_t take = std::min<std::int64_t>(room, end - begin);
    if (take < end - begin) take_cheapest(begin, end, take);
    std::uint64_t marginal = 0;
    for (const Unit* u = begin; u != begin + take; ++u) {
      flow[u->arc] = 1;
      ++flow[order[static_cast<std::uint32_t>(u->key)]];  // the point's source arc
      marginal = std::max(marginal, u->key >> 32);
    }
    if (way_out < 0) continue;  // nothing carried: potential 0 <= every unit's cost
    flow[way_out] = take;
    potential[q] = take == room ? static_cast<solver::Cost>(marginal) : top - arc[way_out].cost;
  }
  potential[sink] = top;
}

}  // namespace keepless::core
