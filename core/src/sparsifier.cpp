#include "keepless/core/sparsifier.hpp"

#include <cmath>
#include <vector>

namespace keepless::core {

struct Sparsifier::Impl {
  Params params;
  PaperNetwork network;
  solver::MinCostFlow solver;
  std::vector<PointDecision> decisions;  // [max_points]
  std::uint32_t count = 0;
  Summary summary;

  Impl(const Capacities& c, const Params& p)
      : params(p), network(c), solver(PaperNetwork::solver_capacity(c)) {
    decisions.resize(c.max_points);
  }
};

Sparsifier::Sparsifier(const Capacities& capacities, const Params& params)
    : impl_(std::make_unique<Impl>(capacities, params)) {}
Sparsifier::~Sparsifier() = default;

Status Sparsifier::validate(const Params& p) {
  if (p.pair_capacity < 1) return Status::kInvalidArgument;
  if (!std::isfinite(p.theta) || p.theta < 0.0 || p.theta > 1.0) return Status::kInvalidArgument;
  if (p.box_width < 0 || p.box_height < 0) return Status::kInvalidArgument;
  return Status::kOk;
}

Status Sparsifier::run(const Window& window, const solver::Budget& budget) {
  Impl& s = *impl_;
  s.count = 0;
  s.summary = Summary{};
  if (Status v = validate(s.params); v != Status::kOk) return v;
  if (Status b = s.network.build(window, s.params, s.solver); b != Status::kOk) return b;

  Status result = Status::kOk;
  switch (s.solver.solve(s.network.source(), s.network.sink(), budget)) {
    case solver::Status::kOptimal: break;
    case solver::Status::kBudgetExhausted: result = Status::kBudgetExhausted; break;
    case solver::Status::kInvalidInput: return Status::kInvalidArgument;
    case solver::Status::kCapacityExceeded: return Status::kCapacityExceeded;
  }

  const PaperNetwork& net = s.network;
  Summary& sum = s.summary;
  for (std::uint32_t i = 0; i < net.point_count(); ++i) {
    PointDecision& d = s.decisions[i];
    d.point = net.point_id(i);
    const std::int32_t arc = net.point_source_arc(i);
    if (arc < 0) {
      d.verdict = Verdict::kSkip;
      d.flow = 0;
      d.capacity = 0;
      ++sum.skipped;
      continue;
    }
    const std::int64_t n = net.point_views(i);
    d.capacity = n * (n - 1) / 2;
    d.flow = s.solver.flow(arc);
    // An unfinished solve culls nothing.
    d.verdict = result == Status::kOk ? decide(d.flow, d.capacity, s.params.theta) : Verdict::kKeep;
    if (d.verdict == Verdict::kKeep) {
      ++sum.kept;
    } else {
      ++sum.culled;
    }
  }
  s.count = net.point_count();
  sum.keyframes = window.keyframe_count();
  sum.points = net.point_count();
  sum.evaluated = net.evaluated_count();
  sum.pairs = net.pair_count();
  sum.arcs = net.evaluated_count() + net.pair_arc_count() + net.pair_count();
  sum.max_flow = s.solver.flow_value();
  sum.total_cost = s.solver.total_cost();
  return result;
}

const Summary& Sparsifier::summary() const { return impl_->summary; }
std::uint32_t Sparsifier::decision_count() const { return impl_->count; }
const PointDecision* Sparsifier::decisions() const { return impl_->decisions.data(); }
const Params& Sparsifier::params() const { return impl_->params; }
const PaperNetwork& Sparsifier::network() const { return impl_->network; }
const solver::MinCostFlow& Sparsifier::solver() const { return impl_->solver; }

std::size_t Sparsifier::memory_bytes() const {
  const Impl& s = *impl_;
  // network.memory_bytes() already counts its own handle, held inside Impl.
  return sizeof(Sparsifier) + sizeof(Impl) - sizeof(PaperNetwork) + s.network.memory_bytes() +
         s.solver.memory_bytes() + s.decisions.capacity() * sizeof(PointDecision);
}

}  // namespace keepless::core
