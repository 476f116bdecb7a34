#include "keepless/core/keep_thresholds.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "id_table.hpp"

namespace keepless::core {

struct KeepThresholds::Impl {
  struct Point {
    std::int32_t rank = -1;  // in the tie order; -1: not a point
    std::int32_t cost = 0;   // c_c
  };
  struct Unit {              // one point -> pair arc
    std::uint32_t cost;      // c_c + c_s
    solver::NodeId pair;
  };
  struct Listed {            // the same in arc order
    std::uint32_t cost;
    std::int32_t rank;
    solver::NodeId pair;
  };
  static constexpr std::uint32_t kBins = 1024;
  static constexpr std::int32_t kSmall = 32;  // a point's positions selected without nth_element
  static constexpr std::int64_t kNeeded = 64;
  std::int64_t need[kNeeded] = {};             // needed(c, theta) for c < kNeeded

  // By rank (position in `order`), not by node: the decision reads them in
  // point order, which is rank order, so it walks these arrays in order.
  std::vector<Point> point;            // [max_nodes] by node
  std::vector<std::uint32_t> thr;      // [max_nodes] M* by rank
  std::vector<std::int64_t> flow;      // [max_nodes] by rank, after evaluate_at
  std::vector<std::int32_t> way_cost;  // [max_nodes] a pair's sink arc's cost (0: none)
  std::vector<std::int32_t> at;        // [max_nodes + 1] a point's units (by rank)
  std::vector<std::int32_t> first;     // [max_nodes + 1] a pair's units (by node); its cells
  std::vector<std::uint32_t> lo, hi;   // [max_nodes] a pair's unit costs
  std::vector<Listed> listed;          // [max_arcs]
  std::vector<Unit> units;             // [max_arcs] grouped by point rank
  std::vector<std::uint32_t> pos;      // [max_arcs + 2] each unit's position in its pair, from 0
  std::vector<std::int32_t> by_pair;   // [max_arcs] units by pair (rank order); or (pair, cost) cells
  std::vector<std::uint32_t> scratch;  // [max_arcs + 1] one point's positions, for nth_element
  std::vector<std::uint32_t> bins;     // [kBins + 1]
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
    way_cost.resize(n);
    at.resize(n + 1);
    first.resize(n + 1);
    lo.resize(n);
    hi.resize(n);
    listed.resize(m);
    units.resize(m);
    pos.resize(m + 2);  // select_of_three() reads up to two past a point's last position
    by_pair.resize(m);
    scratch.resize(m + 1);
    bins.resize(kBins + 1);
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

  // Each unit's position in its pair, by (cost, rank). Pairs are few and
  // their costs narrow, so one counter per (pair, cost) fits in the cache:
  // counted, then handed out to the units in rank order (ties by rank),
  // all in passes over the units in order. Returns false if the cells
  // would not fit in by_pair (costs too spread).
  bool positions_by_cells(std::int32_t listed_count) {
    std::int64_t cells = 0;
    for (std::int32_t v = 0; v < nodes; ++v) {
      const std::int32_t units_of = first[v + 1];   // counted, not yet summed
      first[v] = static_cast<std::int32_t>(cells);  // the pair's first cell
      cells += units_of > 0 ? std::int64_t{hi[v]} - lo[v] + 1 : 0;
    }
    if (cells > static_cast<std::int64_t>(by_pair.size())) return false;
    std::int32_t* cell = by_pair.data();
    std::fill(cell, cell + cells, 0);
    for (std::int32_t u = 0; u < listed_count; ++u) {  // pos[] holds the unit's cell until handed out
      const Unit& unit = units[u];
      const auto c = static_cast<std::uint32_t>(first[unit.pair]) + (unit.cost - lo[unit.pair]);
      pos[u] = c;
      ++cell[c];
    }
    for (std::int32_t v = 0; v < nodes; ++v) {  // exclusive prefix within each pair
      const std::int32_t b = first[v];
      const std::int32_t e = v + 1 < nodes ? first[v + 1] : static_cast<std::int32_t>(cells);
      std::int32_t sum = 0;
      for (std::int32_t c = b; c < e; ++c) {
        const std::int32_t n = cell[c];
        cell[c] = sum;
        sum += n;
      }
    }
    for (std::int32_t u = 0; u < listed_count; ++u) pos[u] = static_cast<std::uint32_t>(cell[pos[u]]++);
    return true;
  }

  // The same where costs are spread: units grouped by pair (stable, so in
  // rank order), then counted by cost, or sorted where even one pair's
  // costs span more than kBins.
  void positions_by_pair(std::int32_t listed_count) {
    for (std::int32_t v = 0; v < nodes; ++v) first[v + 1] += first[v];
    for (std::int32_t u = 0; u < listed_count; ++u) by_pair[first[units[u].pair]++] = u;
    for (std::int32_t v = nodes; v > 0; --v) first[v] = first[v - 1];
    first[0] = 0;
    for (std::int32_t q = 0; q < nodes; ++q) {
      std::int32_t* b = by_pair.data() + first[q];
      std::int32_t* e = by_pair.data() + first[q + 1];
      if (b == e) continue;
      const std::uint32_t low = lo[q], span = hi[q] - lo[q];
      if (span < kBins) {
        std::fill(bins.begin(), bins.begin() + (span + 2), 0u);
        for (const std::int32_t* u = b; u != e; ++u) ++bins[units[*u].cost - low + 1];
        for (std::uint32_t c = 0; c + 1 <= span; ++c) bins[c + 1] += bins[c];
        for (const std::int32_t* u = b; u != e; ++u) pos[*u] = bins[units[*u].cost - low]++;
      } else {  // indices ascend with rank
        std::sort(b, e, [this](std::int32_t x, std::int32_t y) {
          return units[x].cost != units[y].cost ? units[x].cost < units[y].cost : x < y;
        });
        for (std::int32_t* u = b; u != e; ++u) pos[*u] = static_cast<std::uint32_t>(u - b);
      }
    }
  }

  // select() for n <= 3, where most points are (two or three views: n = 1
  // or 3), inlined and without branches on n or t (they mispredicted often,
  // n varying from point to point): the minimum, median or maximum of
  // s[0..2], the entries past n taken as +inf (an OR with an all-ones mask).
  // s[1] and s[2] are always readable: pos has two words of padding.
  static std::uint32_t select_of_three(const std::uint32_t* s, std::int32_t n, std::uint32_t t) {
    const std::uint32_t a = s[0];
    const std::uint32_t b = s[1] | (0u - static_cast<std::uint32_t>(n < 2));
    const std::uint32_t c = s[2] | (0u - static_cast<std::uint32_t>(n < 3));
    const std::uint32_t low = std::min(a, b), high = std::max(a, b);
    const std::uint32_t median = std::max(low, std::min(high, c));
    return t == 1 ? std::min(low, c) : t == 2 ? median : std::max(high, c);
  }

  // The t-th smallest (t >= 1) of n positions. Points have few pairs, so
  // for n <= kSmall each position's rank among them is counted, without
  // branches (keys position * 32 + index are distinct, and int32 compares
  // vectorise on any x86-64 or NEON); nth_element on a copy otherwise.
  std::uint32_t select(const std::uint32_t* s, std::int32_t n, std::int64_t t) {
    if (n <= kSmall) {
      std::int32_t key[kSmall];
      std::uint32_t any = 0;
      for (std::int32_t i = 0; i < n; ++i) {
        key[i] = static_cast<std::int32_t>(s[i] << 5 | static_cast<std::uint32_t>(i));
        any |= s[i];
      }
      if (any < (1u << 26)) {
        std::int32_t found = 0;
        for (std::int32_t i = 0; i < n; ++i) {
          std::int32_t below = 0;
          for (std::int32_t j = 0; j < n; ++j) below += key[j] < key[i] ? 1 : 0;
          found = below == t - 1 ? key[i] : found;
        }
        return static_cast<std::uint32_t>(found) >> 5;
      }
    }
    std::uint32_t* c = scratch.data();
    std::copy(s, s + n, c);
    std::nth_element(c, c + (t - 1), c + n);
    return c[t - 1];
  }

  void compute(const solver::MinCostFlow& solver, solver::NodeId sink, const solver::ArcId* order,
               std::int32_t count, double theta) {
    nodes = solver.node_count();
    const std::int32_t arcs = solver.arc_count();
    arc = solver.arc_data();
    std::fill(point.begin(), point.begin() + nodes, Point{});
    std::fill(way_cost.begin(), way_cost.begin() + nodes, 0);
    std::fill(first.begin(), first.begin() + nodes + 1, 0);
    std::fill(lo.begin(), lo.begin() + nodes, ~0u);
    std::fill(hi.begin(), hi.begin() + nodes, 0u);
    points = count;
    std::fill(at.begin(), at.begin() + count + 1, 0);
    // thr[k] holds the flow t the point needs (decide()) until its threshold
    // replaces it: read here with its source arc, not looked up again.
    for (std::int64_t c = 0; c < kNeeded; ++c) need[c] = needed(c, theta);
    for (std::int32_t k = 0; k < count; ++k) {
      const solver::Arc& e = arc[order[k]];
      if (e.capacity == 0) {
        thr[k] = kNever;
        continue;
      }
      point[e.head] = Point{k, e.cost};
      const std::int64_t capacity = e.capacity;
      thr[k] = static_cast<std::uint32_t>(capacity < kNeeded ? need[capacity] : needed(capacity, theta));
    }
    // One pass over the arcs, without branches on an arc's kind (an
    // incrementally edited network scatters the kinds over the ids, as in
    // PairwiseStart): a pair's sink arc is its way out, a point's pair arc
    // becomes a unit; per pair its unit count and cost range. `unit` is an
    // integer used in arithmetic, not in conditionals: with `unit ? x : y`
    // the compiler branched on the rank's sign, which mispredicted about one
    // arc in three.
    std::int32_t listed_count = 0;
    for (solver::ArcId a = 0; a < arcs; ++a) {
      const solver::Arc e = arc[a];
      const bool live = e.capacity != 0;
      const bool way_out = live && e.head == sink;
      if (way_out) way_cost[e.tail] = e.cost;  // one per pair: predictable
      const Point p = point[e.tail];
      const std::int32_t unit = static_cast<std::int32_t>(live & !way_out) &
                                static_cast<std::int32_t>(~static_cast<std::uint32_t>(p.rank) >> 31);
      const std::uint32_t cost = static_cast<std::uint32_t>(p.cost) + static_cast<std::uint32_t>(e.cost);
      listed[listed_count] = Listed{cost, p.rank, e.head};
      listed_count += unit;
      const solver::NodeId q = sink + (e.head - sink) * unit;  // the sink collects what is not a unit
      at[(p.rank + 1) * unit] += unit;
      first[q + 1] += unit;
      lo[q] = std::min(lo[q], cost);
      hi[q] = std::max(hi[q], cost);
    }
    for (std::int32_t k = 0; k < count; ++k) at[k + 1] += at[k];
    // Group by rank (at[] advances to each group's end, then is restored).
    for (std::int32_t u = 0; u < listed_count; ++u) {
      const Listed& l = listed[u];
      units[at[l.rank]++] = Unit{l.cost, l.pair};
    }
    for (std::int32_t k = count; k > 0; --k) at[k] = at[k - 1];
    at[0] = 0;
    if (!positions_by_cells(listed_count)) {
      // first[] now holds cell offsets: recount the pairs' units.
      std::fill(first.begin(), first.begin() + nodes + 1, 0);
      for (std::int32_t u = 0; u < listed_count; ++u) ++first[units[u].pair + 1];
      positions_by_pair(listed_count);
    }
    // Each point's threshold: the t-th smallest of its positions, plus one.
    for (std::int32_t k = 0; k < count; ++k) {
      const std::uint32_t t = thr[k];
      const std::int32_t n = at[k + 1] - at[k];
      const std::uint32_t* s = pos.data() + at[k];
      if (t > static_cast<std::uint32_t>(n)) {  // no M keeps it (or not a point: t = kNever)
        thr[k] = kNever;
      } else {
        thr[k] = (n <= 3 ? select_of_three(s, n, t) : select(s, n, t)) + 1;
      }
    }
  }

  // One pass over the units (grouped by rank) counting those carried, then
  // each point's flow as a difference of the running count: no loop per
  // point, whose varying lengths mispredicted, and no branch on the cut.
  void evaluate_at(std::int64_t m) {
    std::uint32_t* carried_before = scratch.data();  // [u]: units carried before unit u
    const std::int32_t unit_count = at[points];
    std::uint32_t carried_count = 0;
    std::int64_t cost_sum = 0;
    for (std::int32_t u = 0; u < unit_count; ++u) {  // masks, not `carried ? :` (it branched)
      carried_before[u] = carried_count;
      const auto carried = static_cast<std::uint32_t>(static_cast<std::int64_t>(pos[u]) < m);
      const Unit& unit = units[u];
      const std::int64_t cost = static_cast<std::int64_t>(unit.cost) + way_cost[unit.pair];
      carried_count += carried;
      cost_sum += cost & -static_cast<std::int64_t>(carried);
    }
    carried_before[unit_count] = carried_count;
    for (std::int32_t k = 0; k < points; ++k) flow[k] = carried_before[at[k + 1]] - carried_before[at[k]];
    max_flow = carried_count;
    total_cost = cost_sum;
  }
};

KeepThresholds::KeepThresholds(const solver::Capacity& c) : impl_(std::make_unique<Impl>(c)) {}
KeepThresholds::~KeepThresholds() = default;

void KeepThresholds::compute(const solver::MinCostFlow& solver, solver::NodeId sink,
                             const solver::ArcId* order, std::int32_t count, double theta) {
  impl_->compute(solver, sink, order, count, theta);
}
std::uint32_t KeepThresholds::threshold(std::int32_t k) const { return impl_->thr[k]; }
const std::uint32_t* KeepThresholds::threshold_data() const { return impl_->thr.data(); }
const std::int64_t* KeepThresholds::flow_data() const { return impl_->flow.data(); }
void KeepThresholds::evaluate_at(std::int64_t m) { impl_->evaluate_at(m); }
std::int64_t KeepThresholds::flow_at(std::int32_t k) const { return impl_->flow[k]; }
std::int64_t KeepThresholds::max_flow() const { return impl_->max_flow; }
std::int64_t KeepThresholds::total_cost() const { return impl_->total_cost; }

std::size_t KeepThresholds::memory_bytes() const {
  const Impl& s = *impl_;
  return sizeof(Impl) + s.point.capacity() * sizeof(Impl::Point) +
         s.thr.capacity() * sizeof(std::uint32_t) + s.flow.capacity() * sizeof(std::int64_t) +
         s.way_cost.capacity() * sizeof(std::int32_t) +
         (s.at.capacity() + s.first.capacity()) * sizeof(std::int32_t) +
         (s.lo.capacity() + s.hi.capacity() + s.pos.capacity()) * sizeof(std::uint32_t) +
         s.listed.capacity() * sizeof(Impl::Listed) + s.units.capacity() * sizeof(Impl::Unit) +
         s.by_pair.capacity() * sizeof(std::int32_t) + s.scratch.capacity() * sizeof(std::uint32_t) +
         s.bins.capacity() * sizeof(std::uint32_t);
}

FractionBudget::FractionBudget(std::uint32_t max_points)
    : held_(max_points), next_(max_points), known_(max_points),
      departed_(std::make_unique<IdTable>(std::max<std::uint32_t>(max_points, 1))),
      ring_(std::max<std::uint32_t>(max_points, 1), 0) {}

FractionBudget::~FractionBudget() = default;
FractionBudget::FractionBudget(FractionBudget&&) noexcept = default;
FractionBudget& FractionBudget::operator=(FractionBudget&&) noexcept = default;

std::size_t FractionBudget::memory_bytes() const {
  return sizeof(FractionBudget) + (held_.capacity() + next_.capacity()) * sizeof(Entry) + known_.capacity() +
         sizeof(IdTable) + departed_->memory_bytes() + ring_.capacity() * sizeof(PointId);
}

void FractionBudget::clear() {
  count_ = 0;
  evaluated_ = granted_ = 0;
  departed_->clear();
  ring_next_ = 0;
}

// Remembers a point that left the window, in the ring slot of the oldest
// departure, whose record goes (unless that point came back or left again
// since, when its record names another slot).
void FractionBudget::depart(PointId point, bool kept) {
  const std::uint32_t slot = ring_next_;
  ring_next_ = ring_next_ + 1 == ring_.size() ? 0 : ring_next_ + 1;
  const std::uint32_t* old = departed_->find(ring_[slot]);
  if (old != nullptr && (*old >> 1) == slot) departed_->erase(ring_[slot]);
  ring_[slot] = point;
  departed_->erase(point);
  departed_->insert(point, slot << 1 | (kept ? 1u : 0u));  // never full: one record per ring slot
}

// One merge of the decisions with what is remembered (both by ascending id);
// what it finds is kept per decision for record().
std::uint32_t FractionBudget::take(double fraction, const PointDecision* d, std::uint32_t n) {
  n = std::min(n, static_cast<std::uint32_t>(known_.size()));
  std::uint32_t candidates = 0, kept_before = 0, fresh = 0;
  std::uint32_t h = 0;
  // Locals: a byte store (known) would make every member reload per point.
  const Entry* held = held_.data();
  const std::uint32_t held_count = count_;
  std::uint8_t* known_at = known_.data();
  const IdTable& departed = *departed_;
  const bool any_departed = departed.size() > 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    while (h < held_count && held[h].point < d[i].point) ++h;
    std::uint8_t k = kFresh;
    if (h < held_count && held[h].point == d[i].point) {
      k = held[h].kept ? kKnownKept : kKnown;
    } else if (any_departed) {
      if (const std::uint32_t* v = departed.find(d[i].point)) k = kReturned | ((*v & 1) ? kKnownKept : kKnown);
    }
    known_at[i] = k;
    const bool candidate = d[i].verdict != Verdict::kSkip;
    candidates += candidate ? 1 : 0;
    kept_before += candidate && (k & kKnownKept) ? 1 : 0;
    fresh += candidate && k == kFresh ? 1 : 0;
  }
  evaluated_ += fresh;
  const auto due = static_cast<std::uint64_t>(std::floor(fraction * static_cast<double>(evaluated_) + 0.5));
  const std::uint64_t grant = due > granted_ ? due - granted_ : 0;
  granted_ += grant;
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(kept_before + grant, candidates));
}

void FractionBudget::record(const PointDecision* d, std::uint32_t n) {
  n = std::min(n, static_cast<std::uint32_t>(known_.size()));
  std::uint32_t m = 0, h = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    // Held points this decision no longer lists have left the window.
    for (; h < count_ && held_[h].point < d[i].point; ++h) depart(held_[h].point, held_[h].kept);
    if (h < count_ && held_[h].point == d[i].point) ++h;
    const std::uint8_t k = known_[i];
    if (k & kReturned) departed_->erase(d[i].point);  // in the window again
    if (d[i].verdict != Verdict::kSkip) {
      next_[m++] = Entry{d[i].point, d[i].verdict == Verdict::kKeep};
    } else if (k != kFresh) {
      next_[m++] = Entry{d[i].point, (k & kKnownKept) != 0};
    }
  }
  for (; h < count_; ++h) depart(held_[h].point, held_[h].kept);
  held_.swap(next_);
  count_ = m;
}

std::uint32_t track_share_count(double share, std::uint32_t take) {
  return static_cast<std::uint32_t>(std::floor(share * take + 0.5));
}

double track_share_at(const KeepBudget& budget, std::uint64_t take, std::uint64_t candidates) {
  const double from = budget.track_share_from, to = budget.track_share_to;
  bool applies = true;
  if (from > 0.0 || to < 1.0) {
    const double n = static_cast<double>(candidates), k = static_cast<double>(take);
    switch (budget.kind) {
      case BudgetKind::kFraction: applies = budget.fraction >= from && budget.fraction <= to; break;
      case BudgetKind::kPoints: applies = k >= from * n && k <= to * n; break;
      default: applies = false; break;
    }
  }
  return applies ? budget.track_share : 0.0;
}

void take_longest_tracks(std::uint32_t* ranked, std::uint32_t candidates, std::uint32_t take, double share,
                         const std::uint32_t* views, std::uint32_t max_views, std::uint32_t* histogram,
                         std::uint32_t* scratch) {
  const std::uint32_t by_track = track_share_count(share, take);
  if (by_track == 0) return;
  const std::uint32_t first = take - by_track;
  const auto v = [&](std::uint32_t i) { return std::min(views[i], max_views); };
  std::fill(histogram, histogram + max_views + 1, 0u);
  for (std::uint32_t j = first; j < candidates; ++j) ++histogram[v(ranked[j])];
  // The cut: every candidate with more than `cut` views, and the first
  // `at_cut` with exactly `cut` in the network's order.
  std::uint32_t cut = max_views, above = 0;
  while (cut > 0 && above + histogram[cut] < by_track) above += histogram[cut--];
  std::uint32_t at_cut = by_track - above;
  // The longest tracks go first, most views first (ties in the network's
  // order), so a prefix of them (what Params::tracked_first leaves of the
  // count) is still the longest: histogram becomes each view count's first
  // position among them.
  std::uint32_t position = 0;
  for (std::uint32_t n = max_views + 1; n-- > cut;) {
    const std::uint32_t here = n == cut ? at_cut : histogram[n];
    histogram[n] = position;
    position += here;
  }
  std::copy(ranked + first, ranked + candidates, scratch);
  std::uint32_t rest = first + by_track;
  for (std::uint32_t j = 0; j < candidates - first; ++j) {  // stable within each part
    const std::uint32_t i = scratch[j];
    bool longest = v(i) > cut;
    if (v(i) == cut && at_cut > 0) {
      longest = true;
      --at_cut;
    }
    if (longest) {
      ranked[first + histogram[v(i)]++] = i;
    } else {
      ranked[rest++] = i;
    }
  }
}

}  // namespace keepless::core
