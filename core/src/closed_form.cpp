#include "keepless/core/closed_form.hpp"

#include <algorithm>
#include <vector>

namespace keepless::core {

struct ClosedForm::Impl {
  struct Unit {  // one point -> pair arc as a candidate of its pair
    std::int64_t cost;  // c_c + c_s
    std::uint32_t point;
    std::uint32_t arc;
  };

  std::vector<Unit> units;                // [max_pair_arcs], grouped by pair
  std::vector<std::uint32_t> pair_begin;  // [pairs + 1]
  std::vector<std::int64_t> flow;         // [max_points]
  std::vector<std::uint8_t> selected;     // [max_pair_arcs]
  std::int64_t max_flow = 0;
  std::int64_t total_cost = 0;

  explicit Impl(const Capacities& c) {
    const std::size_t k = c.max_keyframes;
    units.resize(c.max_pair_arcs);
    pair_begin.resize(k * (k > 0 ? k - 1 : 0) / 2 + 1);
    flow.resize(c.max_points);
    selected.resize(c.max_pair_arcs);
  }
};

ClosedForm::ClosedForm(const Capacities& capacities) : impl_(std::make_unique<Impl>(capacities)) {}
ClosedForm::~ClosedForm() = default;

void ClosedForm::solve(const PaperNetwork& network, const Params& params) {
  Impl& c = *impl_;
  const std::uint32_t points = network.point_count();
  const std::uint32_t pairs = network.pair_count();
  const std::uint32_t arcs = network.pair_arc_count();
  std::fill(c.flow.begin(), c.flow.begin() + points, 0);
  std::fill(c.selected.begin(), c.selected.begin() + arcs, 0);
  c.max_flow = 0;
  c.total_cost = 0;

  // Counting sort by pair; arcs come by ascending point, so each pair's group
  // starts in point order and the sort below only reorders by cost.
  std::fill(c.pair_begin.begin(), c.pair_begin.begin() + pairs + 1, 0);
  for (std::uint32_t a = 0; a < arcs; ++a) ++c.pair_begin[network.arc_pair(a) + 1];
  for (std::uint32_t q = 0; q < pairs; ++q) c.pair_begin[q + 1] += c.pair_begin[q];
  for (std::uint32_t a = 0; a < arcs; ++a) {
    const std::uint32_t q = network.arc_pair(a);
    const std::uint32_t p = network.arc_point(a);
    const std::int64_t cost =
        network.connectivity_cost(network.point_views(p)) + network.arc_spatial_cost(a);
    c.units[c.pair_begin[q]++] = {cost, p, a};
  }
  for (std::uint32_t q = pairs; q > 0; --q) c.pair_begin[q] = c.pair_begin[q - 1];
  c.pair_begin[0] = 0;

  for (std::uint32_t q = 0; q < pairs; ++q) {
    Impl::Unit* first = c.units.data() + c.pair_begin[q];
    Impl::Unit* last = c.units.data() + c.pair_begin[q + 1];
    std::sort(first, last, [](const Impl::Unit& a, const Impl::Unit& b) {
      return a.cost != b.cost ? a.cost < b.cost : a.point < b.point;
    });
    const std::int64_t shared = last - first;
    const std::int64_t take = std::max<std::int64_t>(0, std::min(params.pair_capacity, shared));
    const std::int64_t cb = network.pair_baseline_cost(q);
    for (std::int64_t i = 0; i < take; ++i) {
      ++c.flow[first[i].point];
      c.selected[first[i].arc] = 1;
      c.total_cost += first[i].cost + cb;
    }
    c.max_flow += take;
  }
}

std::int64_t ClosedForm::point_flow(std::uint32_t point_index) const {
  return impl_->flow[point_index];
}
bool ClosedForm::arc_selected(std::uint32_t pair_arc) const {
  return impl_->selected[pair_arc] != 0;
}
std::int64_t ClosedForm::max_flow() const { return impl_->max_flow; }
std::int64_t ClosedForm::total_cost() const { return impl_->total_cost; }

}  // namespace keepless::core
