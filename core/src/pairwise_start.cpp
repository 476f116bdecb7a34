#include "keepless/core/pairwise_start.hpp"

#include <algorithm>
#include <vector>

namespace keepless::core {

struct PairwiseStart::Impl {
  // 12 bytes: the units are the start's largest array (one per pair arc).
  // Ordered by (cost, rank); a pair's units have distinct ranks.
  struct Unit {
    std::uint32_t cost;  // unit cost, c_c + c_s (each at most 2^30)
    std::uint32_t rank;  // the point's rank in the tie order
    solver::ArcId arc;
  };
  struct Point {  // read together for every pair arc
    std::int32_t rank = -1;  // in the tie order; -1: not a point (source, pairs)
    std::int32_t cost = 0;   // its source arc's, c_c
  };
  std::vector<solver::Flow> flow;       // [max_arcs]
  std::vector<solver::Cost> potential;  // [max_nodes]
  std::vector<Point> point;             // [max_nodes]
  std::vector<solver::ArcId> out;       // [max_nodes] a pair's sink arc
  std::vector<std::int32_t> next;       // [max_nodes] counts a pair's units, then its cursor in `units`
  std::vector<solver::NodeId> pairs;    // [max_nodes] the nodes with a way out, in arc order
  std::vector<Unit> units;              // [max_arcs + 1] grouped by pair, arc order within one
  std::vector<Unit> ties;               // [max_nodes] one pair's units at the cut
  static constexpr std::uint64_t kBins = 1024;
  std::vector<std::uint32_t> bins;      // [kBins] unit costs of a pair, from its cheapest

  explicit Impl(const solver::Capacity& c) {
    const auto n = static_cast<std::size_t>(std::max(c.max_nodes, 0));
    const auto m = static_cast<std::size_t>(std::max(c.max_arcs, 0));
    flow.resize(m);
    potential.resize(n);
    point.resize(n);
    out.resize(n);
    next.resize(n);
    pairs.resize(n);
    units.resize(m + 1);  // + the dump slot (compute)
    ties.resize(n);
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
         (s.out.capacity() + s.pairs.capacity()) * sizeof(solver::NodeId) +
         s.next.capacity() * sizeof(std::int32_t) +
         (s.units.capacity() + s.ties.capacity()) * sizeof(Impl::Unit) +
         s.bins.capacity() * sizeof(std::uint32_t);
}

// Moves the `take` smallest units of [begin, end) (by cost, then rank) to
// its front, in any order. Unit costs are small integers here (c_c + c_s),
// so a histogram finds the cost at the cut in two passes, and only the units
// at that cost need ordering by rank; a pair whose costs span more bins than
// there are, or with more units than `ties` holds, takes nth_element. The
// set taken is the same either way: a pair's units have distinct ranks.
void PairwiseStart::Impl::take_cheapest(Unit* begin, Unit* end, std::int64_t take) {
  const auto by_key = [](const Unit& a, const Unit& b) {
    return a.cost != b.cost ? a.cost < b.cost : a.rank < b.rank;
  };
  std::uint32_t lo = ~std::uint32_t{0}, hi = 0;
  for (const Unit* u = begin; u != end; ++u) {
    lo = std::min(lo, u->cost);
    hi = std::max(hi, u->cost);
  }
  if (hi - lo >= kBins || end - begin > static_cast<std::ptrdiff_t>(ties.size())) {
    std::nth_element(begin, begin + take, end, by_key);
    return;
  }
  std::fill(bins.begin(), bins.begin() + static_cast<std::ptrdiff_t>(hi - lo + 1), 0u);
  for (const Unit* u = begin; u != end; ++u) ++bins[u->cost - lo];
  std::uint32_t cut = 0;
  std::int64_t below = 0;
  while (below + bins[cut] < take) below += bins[cut++];
  cut += lo;
  // Below the cut to the front (in place: never ahead of the reader), those
  // at it aside; then the cheapest ranks among those at it.
  Unit* front = begin;
  Unit* at_cut = ties.data();
  std::int64_t tied = 0;
  for (const Unit* u = begin; u != end; ++u) {
    const std::uint32_t c = u->cost;
    const Unit unit = *u;
    *front = unit;
    front += static_cast<std::ptrdiff_t>(c < cut);
    at_cut[tied] = unit;
    tied += static_cast<std::int64_t>(c == cut);
  }
  const std::int64_t need = take - below;
  if (need < tied) std::nth_element(at_cut, at_cut + need, at_cut + tied, by_key);
  std::copy(at_cut, at_cut + need, front);
}

void PairwiseStart::Impl::compute(const solver::MinCostFlow& solver, solver::NodeId sink,
                                  const solver::ArcId* order, std::int32_t count) {
  const std::int32_t nodes = solver.node_count();
  const std::int32_t arcs = solver.arc_count();
  const solver::Arc* arc = solver.arc_data();
  std::fill(potential.begin(), potential.begin() + nodes, 0);
  std::fill(point.begin(), point.begin() + nodes, Point{});
  std::fill(out.begin(), out.begin() + nodes, -1);
  std::fill(next.begin(), next.begin() + nodes, 0);

  for (std::int32_t k = 0; k < count; ++k) {
    const solver::Arc& e = arc[order[k]];
    if (e.capacity == 0) continue;
    point[e.head] = Point{k, e.cost};
    potential[e.head] = e.cost;
  }
  // Two passes over the arcs: the first finds each pair's sink arc (its way
  // out; the pairs are listed, so nothing later scans every node) and how
  // many units (a point's pair arcs) it has, and the largest cost, which
  // bounds every path's; the second writes each unit into its pair's group
  // (a counting sort, arc order within a pair) and clears every arc's flow.
  // No branches on an arc's kind (an incrementally edited network scatters
  // the kinds over the ids): a non-unit is written to the dump slot past
  // the end, as is a unit of a node without a way out (it carries nothing).
  solver::Cost max_cost = 0;
  std::int32_t pair_count = 0;
  for (solver::ArcId a = 0; a < arcs; ++a) {
    const solver::Arc e = arc[a];
    const bool live = e.capacity != 0;
    const bool way_out = live && e.head == sink;
    if (way_out) {  // one per pair: predictable (listed once, the last one kept, as before)
      if (out[e.tail] < 0) pairs[pair_count++] = e.tail;
      out[e.tail] = a;
    }
    max_cost = std::max<solver::Cost>(max_cost, live ? e.cost : 0);
    next[e.head] += live && !way_out && point[e.tail].rank >= 0 ? 1 : 0;
  }
  std::int32_t grouped = 0;
  for (std::int32_t i = 0; i < pair_count; ++i) {
    std::int32_t& at = next[pairs[i]];
    const std::int32_t n = at;
    at = grouped;
    grouped += n;
  }
  const auto dump = static_cast<std::int32_t>(units.size() - 1);
  for (solver::ArcId a = 0; a < arcs; ++a) {
    const solver::Arc e = arc[a];
    const Point p = point[e.tail];
    // In arithmetic, not `&&`: the compiler branched on each term, and the
    // kinds' scatter mispredicted about one arc in three. The rank and the
    // way out are both >= 0 iff the sign bit of their OR is clear.
    const auto signs = static_cast<std::uint32_t>(p.rank | out[e.head]);
    const std::int32_t unit = static_cast<std::int32_t>((e.capacity != 0) & (e.head != sink)) &
                              static_cast<std::int32_t>(~signs >> 31);
    std::int32_t& at = next[e.head];
    const auto cost = static_cast<std::uint32_t>(p.cost) + static_cast<std::uint32_t>(e.cost);
    // at if a unit, else dump, by a mask (`unit ? at : dump` became a branch).
    units[dump ^ ((at ^ dump) & -unit)] = Unit{cost, static_cast<std::uint32_t>(p.rank), a};
    at += unit;
    flow[a] = 0;
  }

  // Each pair takes its cheapest units, as many as its sink arc carries
  // (next[q] is now the end of its group, which starts where the previous
  // listed pair's ends).
  const solver::Cost top = solver::Cost{nodes} * max_cost + 1;  // the sink: beyond any path
  Unit* begin = units.data();
  for (std::int32_t i = 0; i < pair_count; ++i) {
    const solver::NodeId q = pairs[i];
    Unit* end = units.data() + next[q];
    const solver::ArcId way_out = out[q];
    const std::int64_t room = arc[way_out].capacity;
    const std::int64_t take = std::min<std::int64_t>(room, end - begin);
    if (take < end - begin) take_cheapest(begin, end, take);
    std::uint32_t marginal = 0;
    for (const Unit* u = begin; u != begin + take; ++u) {
      flow[u->arc] = 1;
      ++flow[order[u->rank]];  // the point's source arc
      marginal = std::max(marginal, u->cost);
    }
    flow[way_out] = take;
    potential[q] = take == room ? static_cast<solver::Cost>(marginal) : top - arc[way_out].cost;
    begin = end;
  }
  potential[sink] = top;
}

}  // namespace keepless::core
