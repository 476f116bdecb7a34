#include "keepless/solver/min_cost_flow.hpp"

#include <algorithm>
#include <memory>

#include "min_cost_flow_impl.hpp"

namespace keepless::solver {

using namespace detail;

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
  std::fill(m.pot_ext.begin(), m.pot_ext.begin() + node_count, 0);
  return Status::kOptimal;
}

Status MinCostFlow::add_arc(NodeId from, NodeId to, Flow capacity, Cost cost) {
  Impl& m = *impl_;
  if (from < 0 || from >= m.nodes || to < 0 || to >= m.nodes) return Status::kInvalidInput;
  if (capacity < 0 || capacity > kMaxArcCapacity || cost < 0 || cost > kMaxArcCost) {
    return Status::kInvalidInput;
  }
  if (m.arcs >= m.limits.max_arcs) return Status::kCapacityExceeded;
  m.arc[m.arcs].tail = from;
  m.arc[m.arcs].head = to;
  m.arc[m.arcs].capacity = static_cast<std::int32_t>(capacity);
  m.arc[m.arcs].cost = static_cast<std::int32_t>(cost);
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
  if (m.arc[a].capacity == capacity && m.arc[a].cost == cost) return Status::kOptimal;
  if (m.arc[a].cost != cost && m.is_recosted[a] == 0) {
    m.is_recosted[a] = 1;
    m.recosted[m.recosted_count++] = a;
  }
  m.arc[a].capacity = static_cast<std::int32_t>(capacity);
  m.arc[a].cost = static_cast<std::int32_t>(cost);
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
  m.arc[a].tail = from;
  m.arc[a].head = to;
  m.arc[a].capacity = static_cast<std::int32_t>(capacity);
  m.arc[a].cost = static_cast<std::int32_t>(cost);
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
  // Validated against the marks before anything is replaced: a refused
  // order leaves the one in force (and the solver's state) as it was.
  for (std::int32_t k = 0; k < m.tie_count; ++k) m.in_tie_order[m.tie_order[k]] = 0;
  for (std::int32_t k = 0; k < count; ++k) {
    const ArcId a = order[k];
    if (a < 0 || a >= m.arcs || m.in_tie_order[a] != 0) {
      for (std::int32_t j = 0; j < k; ++j) m.in_tie_order[order[j]] = 0;
      for (std::int32_t j = 0; j < m.tie_count; ++j) m.in_tie_order[m.tie_order[j]] = 1;
      return Status::kInvalidInput;
    }
    m.in_tie_order[a] = 1;
  }
  std::copy(order, order + count, m.tie_order.begin());
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


std::int32_t MinCostFlow::node_count() const { return impl_->nodes; }
std::int32_t MinCostFlow::arc_count() const { return impl_->arcs; }
NodeId MinCostFlow::tail(ArcId a) const { return impl_->arc[a].tail; }
NodeId MinCostFlow::head(ArcId a) const { return impl_->arc[a].head; }
Flow MinCostFlow::capacity(ArcId a) const { return impl_->arc[a].capacity; }
Cost MinCostFlow::cost(ArcId a) const { return impl_->arc[a].cost; }
const Arc* MinCostFlow::arc_data() const { return impl_->arc.data(); }
Flow MinCostFlow::flow(ArcId a) const { return impl_->arc_flow[a]; }
Flow MinCostFlow::flow_value() const { return impl_->value; }
Cost MinCostFlow::total_cost() const { return impl_->cost_total; }
bool MinCostFlow::balanced() const { return impl_->is_balanced; }
Cost MinCostFlow::potential(NodeId v) const { return impl_->pot_ext[v]; }
const SolveStats& MinCostFlow::stats() const { return impl_->stats; }
const Capacity& MinCostFlow::capacity_limits() const { return impl_->limits; }
std::size_t MinCostFlow::memory_bytes() const { return sizeof(Impl) + impl_->bytes(); }

}  // namespace keepless::solver
