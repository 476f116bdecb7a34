#include "keepless/core/sparsifier.hpp"

#include <cmath>
#include <memory>
#include <vector>

#include "solver_status.hpp"

namespace keepless::core {

namespace {

solver::Capacity larger(solver::Capacity a, solver::Capacity b) {
  return {std::max(a.max_nodes, b.max_nodes), std::max(a.max_arcs, b.max_arcs)};
}

}  // namespace

struct Sparsifier::Impl {
  Params params;
  SolveMode mode;
  PaperNetwork network;
  std::unique_ptr<IncrementalNetwork> incremental;  // kIncremental only
  solver::MinCostFlow solver;  // shared: run() resets it, update() keeps it
  bool solver_incremental = false;  // the solver holds the incremental network
  bool resume = false;              // the last update stopped for budget: carry on from its state
  bool resumed = false;             // the last update was such a resumption
  std::vector<PointDecision> decisions;  // [max_points]
  std::uint32_t count = 0;
  Summary summary;
  const solver::Clock* clock = nullptr;
  StageTimes times;

  std::uint64_t now() const { return clock != nullptr ? clock->now_ns() : 0; }

  Impl(const Capacities& c, const Params& p, SolveMode m)
      : params(p),
        mode(m),
        network(c),
        incremental(m == SolveMode::kIncremental ? std::make_unique<IncrementalNetwork>(c) : nullptr),
        solver(m == SolveMode::kIncremental
                   ? larger(PaperNetwork::solver_capacity(c), IncrementalNetwork::solver_capacity(c))
                   : PaperNetwork::solver_capacity(c)) {
    decisions.resize(c.max_points);
  }

  // Decisions from the source arcs' flows; an unfinished solve culls nothing.
  template <typename Net>
  void decide_all(const Net& net, bool finished) {
    Summary& sum = summary;
    for (std::uint32_t i = 0; i < net.point_count(); ++i) {
      PointDecision& d = decisions[i];
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
      d.flow = solver.flow(arc);
      d.verdict = finished ? decide(d.flow, d.capacity, params.theta) : Verdict::kKeep;
      if (d.verdict == Verdict::kKeep) {
        ++sum.kept;
      } else {
        ++sum.culled;
      }
    }
    count = net.point_count();
    sum.points = net.point_count();
    sum.evaluated = net.evaluated_count();
    sum.pairs = net.pair_count();
    sum.arcs = net.evaluated_count() + net.pair_arc_count() + net.pair_count();
    sum.max_flow = solver.flow_value();
    sum.total_cost = solver.total_cost();
  }
};

Sparsifier::Sparsifier(const Capacities& capacities, const Params& params, SolveMode mode)
    : impl_(std::make_unique<Impl>(capacities, params, mode)) {}
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
  s.solver_incremental = false;  // build() resets the solver
  const std::uint64_t t0 = s.now();
  if (Status b = s.network.build(window, s.params, s.solver); b != Status::kOk) return b;
  const std::uint64_t t1 = s.now();
  const Status result = from_solver(s.solver.solve(s.network.source(), s.network.sink(), budget));
  const std::uint64_t t2 = s.now();
  if (result != Status::kOk && result != Status::kBudgetExhausted) return result;
  s.summary.keyframes = window.keyframe_count();
  s.decide_all(s.network, result == Status::kOk);
  s.times = StageTimes{t1 - t0, t2 - t1, s.now() - t2};
  return result;
}

Status Sparsifier::update(const Window& window, const solver::Budget& budget) {
  Impl& s = *impl_;
  if (!s.incremental) return run(window, budget);
  s.count = 0;
  s.summary = Summary{};
  if (Status v = validate(s.params); v != Status::kOk) return v;
  IncrementalNetwork& net = *s.incremental;
  if (!s.solver_incremental) {  // run() used the solver since
    net.clear();
    s.resume = s.resumed = false;
  }
  s.solver_incremental = true;
  const std::uint64_t t0 = s.now();
  if (Status u = net.update(window, s.params, s.solver); u != Status::kOk) {
    net.clear();
    return u;
  }
  const std::uint64_t t1 = s.now();
  // The network's arc ids are recycled, so the solver is told the order
  // its tie-break must follow: source arcs by ascending point id, as in
  // PaperNetwork. A solve from zero flow in that order finds run()'s optimum
  // directly. Only after a stop for budget does the next call re-optimise
  // from the flow and potentials left behind (keeping the progress made);
  // that can land on another optimum among ties, so canonicalize() then
  // moves to the one run() finds. A slide's repair from that state costs
  // more than a fresh solve, so if the resumption runs out too, the next
  // call starts afresh: sustained overload cannot lock the path into it.
  const auto evaluated = static_cast<std::int32_t>(net.evaluated_count());
  Status result = from_solver(s.solver.set_tie_order(net.canonical_order(), evaluated));
  const bool warm = s.resume && !s.resumed;
  if (result == Status::kOk && !warm) {
    result = from_solver(s.solver.solve(net.source(), net.sink(), budget));
  } else if (result == Status::kOk) {
    result = from_solver(s.solver.solve_warm(net.source(), net.sink(), budget));
    if (result == Status::kOk) {
      // The rest of the work budget (the clock's deadline is absolute).
      solver::Budget rest = budget;
      const std::uint64_t used = s.solver.stats().work_units;
      rest.work_units = budget.work_units > used ? budget.work_units - used : 0;
      result = from_solver(s.solver.canonicalize(net.canonical_order(), evaluated, rest));
    }
  }
  s.resume = result == Status::kBudgetExhausted;
  s.resumed = warm;
  const std::uint64_t t2 = s.now();
  if (result != Status::kOk && result != Status::kBudgetExhausted) {
    net.clear();
    return result;
  }
  s.summary.keyframes = window.keyframe_count();
  s.decide_all(net, result == Status::kOk);
  s.times = StageTimes{t1 - t0, t2 - t1, s.now() - t2};
  return result;
}

void Sparsifier::set_clock(const solver::Clock* clock) { impl_->clock = clock; }
const StageTimes& Sparsifier::stage_times() const { return impl_->times; }
const Summary& Sparsifier::summary() const { return impl_->summary; }
std::uint32_t Sparsifier::decision_count() const { return impl_->count; }
const PointDecision* Sparsifier::decisions() const { return impl_->decisions.data(); }
const Params& Sparsifier::params() const { return impl_->params; }
const PaperNetwork& Sparsifier::network() const { return impl_->network; }
const IncrementalNetwork* Sparsifier::incremental_network() const {
  return impl_->incremental.get();
}
SolveMode Sparsifier::mode() const { return impl_->mode; }
const solver::MinCostFlow& Sparsifier::solver() const { return impl_->solver; }

std::size_t Sparsifier::memory_bytes() const {
  const Impl& s = *impl_;
  // network.memory_bytes() already counts its own handle, held inside Impl.
  return sizeof(Sparsifier) + sizeof(Impl) - sizeof(PaperNetwork) + s.network.memory_bytes() +
         (s.incremental ? s.incremental->memory_bytes() : 0) + s.solver.memory_bytes() +
         s.decisions.capacity() * sizeof(PointDecision);
}

}  // namespace keepless::core
