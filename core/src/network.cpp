#include "keepless/core/network.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "cost_model.hpp"
#include "keepless/core/costs.hpp"
#include "solver_status.hpp"

namespace keepless::core {

namespace {

std::int32_t saturate_i32(std::uint64_t x) {
  const auto max = static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max());
  return static_cast<std::int32_t>(std::min(x, max));
}

}  // namespace

struct PaperNetwork::Impl {
  struct Record {  // one observation, sorted by (point, slot)
    PointId point;
    std::uint32_t slot;
    std::uint32_t index;  // into the window's observations, flattened in slot order
  };

  Capacities caps;
  // Scratch over observations.
  std::vector<Record> records;
  ObservationScorer scorer;  // N(p, f) (or the information level), one keyframe at a time
  std::vector<std::uint32_t> neighbours;  // N(p, f) by flattened index
  std::vector<std::uint32_t> slot_begin;  // [max_keyframes + 1]
  // Points, ascending id.
  std::vector<PointId> point_id;
  std::vector<std::uint32_t> point_views;
  std::vector<std::uint32_t> point_first;  // first record
  std::vector<std::int32_t> point_arc;
  // Pairs.
  std::vector<std::int32_t> pair_of;  // [K * K], slot j * K + slot k
  std::vector<std::uint32_t> pair_j, pair_k;
  std::vector<solver::ArcId> pair_sink;
  std::vector<std::int64_t> pair_cb;
  // Point -> pair arcs.
  std::vector<std::uint32_t> arc_point, arc_pair;
  std::vector<std::int64_t> arc_cs;
  std::vector<std::int64_t> cm;  // c_m(n), [max_keyframes + 1]
  std::vector<solver::ArcId> source_arcs;  // 0, 1, ...: the source arcs come first, by point id

  std::uint32_t points = 0, evaluated = 0, pairs = 0, arcs = 0, m = 0;
  solver::NodeId sink = 1;

  explicit Impl(const Capacities& c) : caps(c), scorer(keyframe_observation_limit(c)) {
    const std::size_t k = c.max_keyframes;
    const std::size_t q = k * (k - (k > 0 ? 1 : 0)) / 2;
    records.resize(c.max_observations);
    neighbours.resize(c.max_observations);
    slot_begin.resize(k + 1);
    point_id.resize(c.max_points);
    point_views.resize(c.max_points);
    point_first.resize(c.max_points);
    point_arc.resize(c.max_points);
    pair_of.resize(k * k);
    pair_j.resize(q);
    pair_k.resize(q);
    pair_sink.resize(q);
    pair_cb.resize(q);
    arc_point.resize(c.max_pair_arcs);
    arc_pair.resize(c.max_pair_arcs);
    arc_cs.resize(c.max_pair_arcs);
    cm.resize(k + 1);
    source_arcs.resize(c.max_points);
    for (std::size_t i = 0; i < source_arcs.size(); ++i) source_arcs[i] = static_cast<solver::ArcId>(i);
  }

  void clear() {
    points = evaluated = pairs = arcs = m = 0;
    sink = 1;
  }
};

PaperNetwork::PaperNetwork(const Capacities& capacities)
    : impl_(std::make_unique<Impl>(capacities)) {}
PaperNetwork::~PaperNetwork() = default;

solver::Capacity PaperNetwork::solver_capacity(const Capacities& c) {
  const std::uint64_t k = c.max_keyframes;
  const std::uint64_t q = k * (k > 0 ? k - 1 : 0) / 2;
  solver::Capacity cap;
  cap.max_nodes = saturate_i32(2 + std::uint64_t{c.max_points} + q);
  cap.max_arcs = saturate_i32(std::uint64_t{c.max_points} + c.max_pair_arcs + q);
  return cap;
}

Status PaperNetwork::build(const Window& window, const Params& params,
                           solver::MinCostFlow& solver) {
  Impl& n = *impl_;
  n.clear();
  if (params.box_width < 0 || params.box_height < 0 || params.pair_capacity < 0 ||
      (params.cost_model == CostModel::kAuthors &&
       (params.image_width <= 0 || params.image_height <= 0))) {
    return Status::kInvalidArgument;
  }
  const std::uint32_t k = window.keyframe_count();
  const std::uint32_t total = window.total_observations();
  if (k > n.caps.max_keyframes || total > n.caps.max_observations ||
      window.distinct_points() > n.caps.max_points || !keyframes_fit(window, n.caps)) {
    return Status::kCapacityExceeded;
  }

  // Observations sorted by (point, slot): each point's run lists the slots
  // that observe it in slot order.
  std::uint32_t g = 0;
  for (std::uint32_t s = 0; s < k; ++s) {
    n.slot_begin[s] = g;
    const Observation* obs = window.observations(s);
    const std::uint32_t count = window.observation_count(s);
    for (std::uint32_t i = 0; i < count; ++i, ++g) n.records[g] = {obs[i].point, s, g};
  }
  n.slot_begin[k] = g;
  std::sort(n.records.begin(), n.records.begin() + total, [](const auto& a, const auto& b) {
    return a.point != b.point ? a.point < b.point : a.slot < b.slot;
  });

  std::uint32_t points = 0, evaluated = 0, m = 0;
  std::uint64_t pair_arcs = 0;
  for (std::uint32_t r = 0; r < total;) {
    std::uint32_t end = r + 1;
    while (end < total && n.records[end].point == n.records[r].point) ++end;
    if (points >= n.caps.max_points) return Status::kCapacityExceeded;
    const std::uint32_t views = end - r;
    n.point_id[points] = n.records[r].point;
    n.point_views[points] = views;
    n.point_first[points] = r;
    n.point_arc[points] = views >= 2 ? static_cast<std::int32_t>(evaluated++) : -1;
    if (views >= 2) pair_arcs += std::uint64_t{views} * (views - 1) / 2;
    m = std::max(m, views);
    ++points;
    r = end;
  }
  if (pair_arcs > n.caps.max_pair_arcs) return Status::kCapacityExceeded;
  // c_m(2) would pass the solver's cost bound (kMaxPointViews).
  if ((params.cost_terms & kConnectivityCost) && m > kMaxPointViews) return Status::kCapacityExceeded;

  // Pairs that share at least one evaluated point, numbered in (j, k) order.
  std::fill(n.pair_of.begin(), n.pair_of.begin() + std::size_t{k} * k, -1);
  for (std::uint32_t i = 0; i < points; ++i) {
    if (n.point_arc[i] < 0) continue;
    const Impl::Record* rec = n.records.data() + n.point_first[i];
    for (std::uint32_t x = 0; x < n.point_views[i]; ++x) {
      for (std::uint32_t y = x + 1; y < n.point_views[i]; ++y) {
        n.pair_of[std::size_t{rec[x].slot} * k + rec[y].slot] = 0;
      }
    }
  }
  std::uint32_t pairs = 0;
  for (std::uint32_t j = 0; j < k; ++j) {
    for (std::uint32_t kk = j + 1; kk < k; ++kk) {
      std::int32_t& q = n.pair_of[std::size_t{j} * k + kk];
      if (q < 0) continue;
      q = static_cast<std::int32_t>(pairs);
      n.pair_j[pairs] = j;
      n.pair_k[pairs] = kk;
      n.pair_cb[pairs] =
          pair_sink_cost(params, window.keyframe(j).centre, window.keyframe(kk).centre);
      ++pairs;
    }
  }

  const std::uint64_t node_count = 2 + std::uint64_t{evaluated} + pairs;
  const std::uint64_t arc_count = std::uint64_t{evaluated} + pair_arcs + pairs;
  const solver::Capacity& room = solver.capacity_limits();
  if (node_count > static_cast<std::uint64_t>(std::max(room.max_nodes, 0)) ||
      arc_count > static_cast<std::uint64_t>(std::max(room.max_arcs, 0))) {
    return Status::kCapacityExceeded;
  }

  // N(p, f) (or the information level) for every keypoint, one keyframe at a time.
  for (std::uint32_t s = 0; s < k; ++s) {
    n.scorer.score(window.keyframe(s), window.observations(s), window.observation_count(s),
                   params, n.neighbours.data() + n.slot_begin[s]);
  }
  connectivity_costs(m, n.cm.data());
  if (!(params.cost_terms & kConnectivityCost)) std::fill(n.cm.begin(), n.cm.begin() + m + 1, 0);

  // The solver network, in the documented node and arc order.
  const auto node = [](std::uint64_t x) { return static_cast<solver::NodeId>(x); };
  const solver::NodeId sink = node(node_count - 1);
  const auto fail = [&n](solver::Status s) {
    n.clear();
    return from_solver(s);
  };
  if (solver::Status s = solver.reset(node(node_count)); s != solver::Status::kOptimal) {
    return fail(s);
  }
  for (std::uint32_t i = 0; i < points; ++i) {
    if (n.point_arc[i] < 0) continue;
    const std::int64_t views = n.point_views[i];
    const solver::Status s = solver.add_arc(0, node(1 + n.point_arc[i]), views * (views - 1) / 2,
                                            n.cm[n.point_views[i]]);
    if (s != solver::Status::kOptimal) return fail(s);
  }
  std::uint32_t a = 0;
  for (std::uint32_t i = 0; i < points; ++i) {
    if (n.point_arc[i] < 0) continue;
    const Impl::Record* rec = n.records.data() + n.point_first[i];
    for (std::uint32_t x = 0; x < n.point_views[i]; ++x) {
      for (std::uint32_t y = x + 1; y < n.point_views[i]; ++y, ++a) {
        const auto q = static_cast<std::uint32_t>(
            n.pair_of[std::size_t{rec[x].slot} * k + rec[y].slot]);
        n.arc_point[a] = i;
        n.arc_pair[a] = q;
        n.arc_cs[a] =
            pair_arc_cost(params, n.neighbours[rec[x].index], n.neighbours[rec[y].index]);
        const solver::Status s = solver.add_arc(node(1 + n.point_arc[i]),
                                                node(1 + std::uint64_t{evaluated} + q), 1,
                                                n.arc_cs[a]);
        if (s != solver::Status::kOptimal) return fail(s);
      }
    }
  }
  for (std::uint32_t q = 0; q < pairs; ++q) {
    n.pair_sink[q] = static_cast<solver::ArcId>(std::uint64_t{evaluated} + pair_arcs + q);
    const solver::Status s = solver.add_arc(node(1 + std::uint64_t{evaluated} + q), sink,
                                            params.pair_capacity, n.pair_cb[q]);
    if (s != solver::Status::kOptimal) return fail(s);
  }

  n.points = points;
  n.evaluated = evaluated;
  n.pairs = pairs;
  n.arcs = a;
  n.m = m;
  n.sink = sink;
  return Status::kOk;
}

std::uint32_t PaperNetwork::point_count() const { return impl_->points; }
PointId PaperNetwork::point_id(std::uint32_t i) const { return impl_->point_id[i]; }
std::uint32_t PaperNetwork::point_views(std::uint32_t i) const { return impl_->point_views[i]; }
std::int32_t PaperNetwork::point_source_arc(std::uint32_t i) const { return impl_->point_arc[i]; }
void PaperNetwork::read_points(std::uint32_t begin, std::uint32_t count, PointId* id,
                               std::uint32_t* views, solver::ArcId* source_arc) const {
  const Impl& n = *impl_;
  std::copy(n.point_id.begin() + begin, n.point_id.begin() + begin + count, id);
  std::copy(n.point_views.begin() + begin, n.point_views.begin() + begin + count, views);
  std::copy(n.point_arc.begin() + begin, n.point_arc.begin() + begin + count, source_arc);
}
void PaperNetwork::point_slots(std::uint32_t* at, std::uint32_t* slots) const {
  const Impl& n = *impl_;
  std::uint32_t r = 0;  // records are sorted by (point, slot): in point order already
  for (std::uint32_t i = 0; i < n.points; ++i) {
    at[i] = r;
    for (std::uint32_t x = 0; x < n.point_views[i]; ++x, ++r) slots[r] = n.records[r].slot;
  }
  at[n.points] = r;
}
std::uint32_t PaperNetwork::evaluated_count() const { return impl_->evaluated; }
std::uint32_t PaperNetwork::pair_count() const { return impl_->pairs; }
std::uint32_t PaperNetwork::pair_arc_count() const { return impl_->arcs; }
std::uint32_t PaperNetwork::max_views() const { return impl_->m; }
std::int64_t PaperNetwork::connectivity_cost(std::uint32_t n) const { return impl_->cm[n]; }
std::uint32_t PaperNetwork::pair_slot_j(std::uint32_t q) const { return impl_->pair_j[q]; }
std::uint32_t PaperNetwork::pair_slot_k(std::uint32_t q) const { return impl_->pair_k[q]; }
solver::ArcId PaperNetwork::pair_sink_arc(std::uint32_t q) const { return impl_->pair_sink[q]; }
const solver::ArcId* PaperNetwork::canonical_order() const { return impl_->source_arcs.data(); }
std::int64_t PaperNetwork::pair_baseline_cost(std::uint32_t q) const { return impl_->pair_cb[q]; }
std::uint32_t PaperNetwork::arc_point(std::uint32_t a) const { return impl_->arc_point[a]; }
std::uint32_t PaperNetwork::arc_pair(std::uint32_t a) const { return impl_->arc_pair[a]; }
std::int64_t PaperNetwork::arc_spatial_cost(std::uint32_t a) const { return impl_->arc_cs[a]; }
solver::ArcId PaperNetwork::arc_solver_id(std::uint32_t a) const {
  return static_cast<solver::ArcId>(impl_->evaluated + a);
}
solver::NodeId PaperNetwork::source() const { return 0; }
solver::NodeId PaperNetwork::sink() const { return impl_->sink; }

std::size_t PaperNetwork::memory_bytes() const {
  const Impl& n = *impl_;
  const auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return sizeof(PaperNetwork) + sizeof(Impl) + bytes(n.records) + n.scorer.memory_bytes() +
         bytes(n.neighbours) + bytes(n.slot_begin) + bytes(n.point_id) + bytes(n.point_views) +
         bytes(n.point_first) + bytes(n.point_arc) + bytes(n.pair_of) + bytes(n.pair_j) +
         bytes(n.pair_k) + bytes(n.pair_sink) + bytes(n.pair_cb) + bytes(n.arc_point) +
         bytes(n.arc_pair) + bytes(n.arc_cs) + bytes(n.cm) + bytes(n.source_arcs);
}

}  // namespace keepless::core
