// keepless_latency: replays a deterministic keyframe stream through the
// decision path (ingest -> network update -> solve -> decide -> publish) and
// reports each stage's latency histogram and the end-to-end one, decisions
// whose budget ran out, heap allocations after warm-up (a counting global
// operator new, replaced for this binary), and the fixed footprint. On
// sampled windows of the same run it times the from-scratch solvers (ours
// as the decision path runs it and ours from zero flow, LEMON's
// NetworkSimplex and CostScaling after Preflow, the per-pair closed form)
// and checks that every path decides the same: each window is also decided
// from scratch by successive shortest paths from zero flow, independently
// of the closed-form start. --use, --scope, --floor, --cost and the keep
// budgets set the decision policy (core::Params) as keepless_node's flags
// do; the stream then carries what the cost model reads
// (intrinsics and depths, unmapped keypoints), and a second replay of the
// same stream with the paper's defaults, in the same process, is the
// reference the figures are divided by; the defaults replayed once more,
// last, are an A/A control (the noise a ratio carries on this machine).
// With --lcm it measures keyframe-published -> decision-received across
// keepless_node on loopback (the node with the same policy flags). The last
// stdout line is one JSON object.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "cli/cli.hpp"
#include "compare.hpp"
#include "counting_new.hpp"  // this binary's only inclusion
#include "keepless/core/closed_form.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/use.hpp"
#include "keepless/platform/cpu_pinning.hpp"
#include "keepless/platform/monotonic_clock.hpp"
#include "lcm_mode.hpp"
#include "node_memory.hpp"
#include "publish.hpp"
#include "stream.hpp"
#include "synthetic_window.hpp"

namespace keepless::perf {
namespace {

constexpr double kNodeDefaultBudgetMs = 5.0;  // the node's default latency target

struct Options {
  std::string workload = "orbslam";
  std::uint32_t keyframes = 0;  // measured decisions; 0: the workload's default
  std::uint32_t warmup = 0;     // extra decisions before measuring; 0: K
  std::uint64_t seed = 1;
  std::string cpus;
  bool mlock = false;
  double budget_ms = kNodeDefaultBudgetMs;  // 0: unlimited
  double budget_fraction = 0;               // > 0: budget = fraction * calibrated median
  std::uint32_t compare = 25;               // sampled windows for the from-scratch comparisons
  std::uint32_t reps = 3;                   // timing repetitions per sampled window (min kept)
  bool lcm = false;
  std::string log;
  core::Params params;  // the use's fields, scope, coverage_floor, cost_model, budget; the rest the paper's
  std::string use;      // --use NAME, or empty
  std::vector<std::string> node_flags;  // the policy flags as given, for keepless_node with --lcm
  std::int64_t unmapped = -1;  // unmapped keypoints per keyframe; -1: see usage()
  std::string profile;         // keepless_node's --profile whose memory is reported
};

// A JSON number, or null when not measured.
std::string json_or_null(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  return buf;
}

// The policy is the paper's method as the library defaults it. (The
// deferral, defer_keyframes, is the node's: the decisions do not read it.)
bool is_reference(const core::Params& p) {
  const core::Params paper;
  return p.scope == paper.scope && p.coverage_floor == paper.coverage_floor && p.cost_model == paper.cost_model &&
         p.maturity_keyframes == paper.maturity_keyframes && p.budget.kind == core::BudgetKind::kNone;
}

constexpr const char* kTool = "keepless_latency";

const std::vector<cli::Flag> kFlags = {
    {"--workload", "small|orbslam|large|map", "the synthetic keyframe stream (default orbslam)"},
    {"--keyframes", "N", "decisions measured after warm-up (default: 1000; map: 3)"},
    {"--warmup", "N", "decisions before measuring after the K - 1 that fill the window\n"
                      "(default: the window's K; with --log, counted from the first keyframe)"},
    {"--seed", "S", "stream seed (default 1)"},
    {"--cpus", "LIST", "pin to these CPUs, e.g. 0,1 or 2-3 (reported if refused)"},
    {"--mlock", nullptr, "lock memory with mlockall (reported if refused)"},
    {"--budget-ms", "MS", "latency target per decision, from keyframe arrival; the solver's\n"
                          "deadline is at 90% of it (default 5.0, the node's; 0: none)"},
    {"--budget-fraction", "F", "run once without a budget, then again with F x its median"},
    {"--compare", "W", "windows sampled for the from-scratch solvers (default 25; 0: none)"},
    {"--reps", "R", "timing repetitions per sampled window, the minimum kept (default 3)"},
    {"--lcm", nullptr, "also measure published -> received through keepless_node"},
    {"--log", "FILE", "replay the keyframe_t messages of an LCM log instead"},
    {"--use", "NAME", "a use (keepless_node's flag: core::apply_use) before the other policy\n"
                      "flags, which refine it: paper, monocular, monocular-deferred, rgbd,\n"
                      "offline. The replay measures its decisions; the deferral of\n"
                      "monocular-deferred is the node's, measured with --lcm"},
    {"--scope", "S", "decision scope, window, newest or auto (keepless_node's flag; default window)"},
    {"--floor", "L", "coverage floor (keepless_node's flag; default 0)"},
    {"--cost", "paper|authors|information|track", "cost model (keepless_node's flag; default paper)"},
    {"--unmapped", "N", "unmapped keypoints per keyframe (default: half the workload's\n"
                        "observations per keyframe with --cost authors, else 0)"},
    {"--keep-points", "K", "a keep budget instead of M (keepless_node's flag): K points"},
    {"--keep-fraction", "F", "a keep budget: the share F of the points evaluated (F of those new to\n"
                             "each decision, plus those kept before)"},
    {"--keep-observations", "B", "a keep budget: points while their observations sum to <= B;\n"
                                 "with a budget the paper's M = 100 is the reference"},
    {"--track-share", "S", "with --keep-points or --keep-fraction: the share S in [0, 1] of the\n"
                           "count taken by track length, at every budget (keepless_node's flag)"},
    {"--profile", "small|default|large", "also report keepless_node's fixed memory with that --profile\n"
                                         "(predicted, counted by the node, resident-set growth) and\n"
                                         "whether this workload's windows fit its capacities"},
};

std::string usage() {
  return cli::usage("usage: keepless_latency [options]", kFlags,
                    "With a policy other than the defaults (--use, --scope, --floor, --cost, a keep\n"
                    "budget, --track-share), the same stream is replayed again with the defaults as\n"
                    "the reference of the *_ratio_to_paper figures; the defaults are then replayed\n"
                    "once more, last, as an A/A control (aa_*: what the machine alone moves a ratio\n"
                    "by). The last stdout line is a JSON summary.");
}

// Returns -1 to go on, else the exit status.
int parse(int argc, char** argv, Options* o) {
  const std::string help = usage();
  if (const char* name = cli::last_value(argc, argv, "--use")) {
    core::Use use{};
    if (!core::parse_use(name, &use)) {
      return cli::usage_error(kTool, std::string("bad value for --use: '") + name + "' (" + core::kUseNames + ")");
    }
    core::apply_use(use, &o->params);
    o->use = name;
  }
  bool share_given = false;  // --track-share, named by the refusal below
  for (int i = 1; i < argc; ++i) {
    const cli::Flag* flag = nullptr;
    const char* v = nullptr;
    int status = 0;
    if (!cli::next_flag(kTool, help, kFlags, argc, argv, &i, &flag, &v, &status)) return status;
    const std::string a = flag->name;
    char* end = nullptr;
    const auto bad = [&](const char* expected) {
      return cli::usage_error(kTool, "bad value for " + a + ": '" + v + "' (" + expected + ")");
    };
    for (const char* policy : {"--use", "--scope", "--floor", "--cost", "--keep-points", "--keep-fraction",
                               "--keep-observations", "--track-share"}) {
      if (a == policy) o->node_flags.insert(o->node_flags.end(), {a, v});
    }
    if (a == "--use") {
      continue;  // applied above
    } else if (a == "--mlock") {
      o->mlock = true;
    } else if (a == "--lcm") {
      o->lcm = true;
    } else if (a == "--workload") {
      o->workload = v;
    } else if (a == "--cpus") {
      o->cpus = v;
    } else if (a == "--log") {
      o->log = v;
    } else if (a == "--profile") {
      o->profile = v;
    } else if (a == "--scope") {
      if (!core::parse_scope(v, &o->params.scope)) return bad("window, newest or auto");
    } else if (a == "--cost") {
      if (!core::parse_cost_model(v, &o->params.cost_model)) return bad("paper, authors, information or track");
    } else if (a == "--keep-fraction") {
      const double x = std::strtod(v, &end);
      if (end == v || *end != '\0' || !(x >= 0 && x <= 1) || o->params.budget.kind != core::BudgetKind::kNone) {
        return bad("one keep budget, F in [0, 1]");
      }
      o->params.budget.kind = core::BudgetKind::kFraction;  // the use's track share kept
      o->params.budget.fraction = x;
    } else if (a == "--keep-points" || a == "--keep-observations") {
      const unsigned long long x = std::strtoull(v, &end, 10);
      if (end == v || *end != '\0' || v[0] == '-' || x > 0xffffffffull ||
          o->params.budget.kind != core::BudgetKind::kNone) {
        return bad("one keep budget, an integer");
      }
      o->params.budget.kind = a == "--keep-points" ? core::BudgetKind::kPoints : core::BudgetKind::kObservations;
      o->params.budget.count = x;
    } else if (a == "--track-share") {
      const double s = std::strtod(v, &end);
      if (end == v || *end != '\0' || !(s >= 0 && s <= 1)) return bad("a number in [0, 1]");
      core::share_at_every_budget(s, &o->params.budget);
      share_given = true;
    } else if (a == "--budget-ms" || a == "--budget-fraction") {
      const double x = std::strtod(v, &end);
      if (end == v || *end != '\0' || !std::isfinite(x) || x < 0) return bad("a number >= 0");
      (a == "--budget-ms" ? o->budget_ms : o->budget_fraction) = x;
    } else if (a == "--keyframes" || a == "--warmup" || a == "--seed" || a == "--compare" || a == "--reps" ||
               a == "--floor" || a == "--unmapped") {
      const unsigned long long x = std::strtoull(v, &end, 10);
      if (end == v || *end != '\0' || v[0] == '-') return bad("an integer >= 0");
      if (a == "--seed") {
        o->seed = x;
      } else if (a == "--floor" || a == "--unmapped") {
        if (x > 0xffffffffull) return bad("an integer in 0..4294967295");
        if (a == "--floor") o->params.coverage_floor = static_cast<std::uint32_t>(x);
        if (a == "--unmapped") o->unmapped = static_cast<std::int64_t>(x);
      } else {
        std::uint32_t& t = a == "--keyframes" ? o->keyframes
                           : a == "--warmup"  ? o->warmup
                           : a == "--compare" ? o->compare
                                              : o->reps;
        if (x > (1u << 30)) return bad("an integer in 0..1073741824");
        t = static_cast<std::uint32_t>(x);
      }
    }
  }
  // The policy as keepless_node checks it: refused here, not by every decision of the replay.
  if (core::Sparsifier::validate(o->params) != core::Status::kOk) {
    const core::KeepBudget& b = o->params.budget;
    if (core::share_needs_a_count(b) && !core::keeps_a_count(b.kind)) {
      return cli::usage_error(kTool, (share_given ? std::string("--track-share") : "--use " + o->use) +
                                         " takes a share of a count: give --keep-points or --keep-fraction");
    }
    return cli::usage_error(kTool, "invalid policy parameters");
  }
  return -1;
}

double ms(std::uint64_t ns) { return static_cast<double>(ns) * 1e-6; }

// This thread's CPU time: the decision path's cost without the time another
// process held the core (on a shared machine the wall-clock tail is mostly
// that).
std::uint64_t thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

// Nearest-rank percentile of a sorted sample.
std::uint64_t percentile(const std::vector<std::uint64_t>& sorted, double p) {
  if (sorted.empty()) return 0;
  const auto rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(sorted.size())));
  return sorted[std::min(sorted.size(), std::max<std::size_t>(rank, 1)) - 1];
}

double median_ms(std::vector<std::uint64_t> v) {
  std::sort(v.begin(), v.end());
  return ms(percentile(v, 0.5));
}

struct Histogram {
  const char* name;
  std::vector<std::uint64_t> ns;
  double p(double q) const {
    std::vector<std::uint64_t> s = ns;
    std::sort(s.begin(), s.end());
    return ms(percentile(s, q));
  }
  double max() const { return ns.empty() ? 0 : ms(*std::max_element(ns.begin(), ns.end())); }
};

struct Replay {
  // Per measured decision.
  Histogram ingest{"ingest", {}}, network{"network", {}}, solve{"solve", {}}, decide{"decide", {}},
      publish{"publish", {}}, e2e{"end-to-end", {}}, e2e_cpu{"CPU time", {}};
  std::uint32_t decisions = 0, exhausted = 0, deferred = 0, late = 0, mismatches = 0, failures = 0;
  // The policy at work: decisions where the coverage floor bound, the points
  // it promoted back, and points skipped as out of scope, over all decisions.
  std::uint32_t floor_bound = 0;
  std::uint64_t floor_promoted = 0, out_of_scope = 0;
  // FNV-1a over every measured decision's digest() (see Answer): the same
  // for the same stream and policy when no budget ran out (--budget-ms 0).
  std::uint64_t digest = 0;
  std::uint64_t allocations = 0;
  std::size_t footprint = 0;
  core::Capacities caps{};
  // Sampled windows.
  std::vector<std::uint64_t> ours, ours_solve, ours_zero_flow, lemon_ns, lemon_cs, closed, incremental, slide_scratch,
      slide_zero_flow, slide_incremental;
  std::uint32_t compared = 0, lemon_checked = 0, cost_mismatches = 0, lemon_decision_mismatches = 0,
                closed_mismatches = 0;
  double points_mean = 0, arcs_mean = 0;
};

// What the decision path answered for a measured window. The checks run in
// a second pass over the stream: between the timed decisions, a from-scratch
// solve (and on sampled windows LEMON's) would evict the path's data from
// the caches before every keyframe, which a node's own core does not do.
struct Answer {
  std::uint32_t keyframe = 0;
  bool exhausted = false, deferred = false, sampled = false;
  std::uint32_t count = 0;  // decision_count()
  std::uint64_t culled = 0, kept = 0;
  std::uint64_t digest = 0;  // see digest()
  std::int64_t max_flow = 0, total_cost = 0;
  std::uint64_t solve_ns = 0, slide_ns = 0;  // sampled windows: update()'s solve, and all of it
};

constexpr std::uint64_t kFnvBasis = 1469598103934665603ull;
void fnv_mix(std::uint64_t* h, std::uint64_t x) {
  for (int b = 0; b < 8; ++b) *h = (*h ^ ((x >> (8 * b)) & 0xff)) * 1099511628211ull;
}

// FNV-1a over each point's id, verdict and flow; for an unfinished decision
// over each id and whether it was skipped, all that is fixed then (and that
// nothing is culled, checked apart).
std::uint64_t digest(const core::Sparsifier& s, bool unfinished) {
  std::uint64_t h = kFnvBasis;
  const auto mix = [&h](std::uint64_t x) { fnv_mix(&h, x); };
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    const core::PointDecision& d = s.decisions()[i];
    mix(d.point);
    if (unfinished) {
      mix(d.verdict == core::Verdict::kSkip);
    } else {
      mix(static_cast<std::uint64_t>(d.verdict));
      mix(static_cast<std::uint64_t>(d.flow));
    }
  }
  return h;
}

Answer answer_of(std::uint32_t k, const core::Sparsifier& inc, core::Status status) {
  Answer a;
  a.keyframe = k;
  a.exhausted = status == core::Status::kBudgetExhausted;
  a.deferred = inc.deferred();
  a.count = inc.decision_count();
  a.culled = inc.summary().culled;
  a.kept = inc.summary().kept;
  a.digest = digest(inc, a.exhausted);
  a.max_flow = inc.summary().max_flow;
  a.total_cost = inc.summary().total_cost;
  return a;
}

// Same verdicts and flows as `ref`, a from-scratch decision of the same
// window; an unfinished one must keep every point the full solve evaluates
// (nothing culled), and a deferred one decides nothing and keeps everything.
bool agrees(const Answer& a, const core::Sparsifier& ref) {
  if (a.deferred) return a.exhausted && a.count == 0 && a.culled == 0 && a.kept == ref.summary().points;
  if (a.count != ref.decision_count() || a.digest != digest(ref, a.exhausted)) return false;
  if (a.exhausted) return a.culled == 0;
  return a.total_cost == ref.summary().total_cost && a.max_flow == ref.summary().max_flow;
}

// `scratch`: the window decided from scratch without the policies (scope
// window, no floor), whose verdicts follow from the flows alone.
void compare_window(const core::Sparsifier& scratch, const core::Capacities& caps, const Options& o,
                    const solver::Clock& clock, Replay* r) {
  ArcList net;
  network_arcs(scratch, &net);
  solver::MinCostFlow mcf(core::PaperNetwork::solver_capacity(caps));
  core::PairwiseStart start(mcf.capacity_limits());
  std::uint64_t best = ~0ull, best_solve = ~0ull, best_zero = ~0ull, best_ns = ~0ull, best_closed = ~0ull;
  solver::Flow value = 0, v2 = 0;
  solver::Cost cost = 0, c2 = 0;
  for (std::uint32_t k = 0; k < std::max(o.reps, 1u); ++k) {
    std::uint64_t solve_ns = 0;
    best = std::min(best, time_ours(net, clock, mcf, start, &value, &cost, &solve_ns));
    best_solve = std::min(best_solve, solve_ns);
    best_zero = std::min(best_zero, time_ours_zero_flow(net, clock, mcf, &v2, &c2));
  }
  const solver::Cost expected = scratch.summary().total_cost;
  if (value != scratch.summary().max_flow || cost != expected) ++r->cost_mismatches;
  if (v2 != value || c2 != expected) ++r->cost_mismatches;
  r->ours.push_back(best);
  r->ours_solve.push_back(best_solve);
  r->ours_zero_flow.push_back(best_zero);
  for (std::uint32_t k = 0; k < std::max(o.reps, 1u); ++k) {
    best_ns = std::min(best_ns, time_lemon_network_simplex(net, clock, &v2, &c2));
  }
  if (v2 != value || c2 != expected) ++r->cost_mismatches;
  r->lemon_ns.push_back(best_ns);
  std::uint64_t best_cs = ~0ull;
  for (std::uint32_t k = 0; k < std::max(o.reps, 1u); ++k) {
    best_cs = std::min(best_cs, time_lemon_cost_scaling(net, clock, &v2, &c2));
  }
  if (v2 != value || c2 != expected) ++r->cost_mismatches;
  r->lemon_cs.push_back(best_cs);
  std::vector<solver::Flow> flows;
  if (lemon_canonical_flows(net, value, &flows)) {
    ++r->lemon_checked;
    std::uint32_t e = 0;
    for (std::uint32_t i = 0; i < scratch.decision_count(); ++i) {
      const core::PointDecision& d = scratch.decisions()[i];
      if (d.verdict == core::Verdict::kSkip) continue;
      const core::Verdict lemon = core::decide(flows[e], d.capacity, scratch.params().theta);
      if (flows[e] != d.flow || lemon != d.verdict) {
        ++r->lemon_decision_mismatches;
        break;
      }
      ++e;
    }
  }
  core::ClosedForm closed(caps);
  for (std::uint32_t k = 0; k < std::max(o.reps, 1u); ++k) {
    const std::uint64_t t0 = clock.now_ns();
    closed.solve(scratch.network(), scratch.params());
    best_closed = std::min(best_closed, clock.now_ns() - t0);
  }
  r->closed.push_back(best_closed);
  for (std::uint32_t i = 0; i < scratch.decision_count(); ++i) {
    if (closed.point_flow(i) != scratch.decisions()[i].flow) {
      ++r->closed_mismatches;
      break;
    }
  }
  ++r->compared;
}

// Keyframe k of the stream into `window`, in place of the oldest once K are
// held, as the node's window slides: the windows both passes of replay()
// decide.
core::Status slide_in(const KeyframeStream& stream, std::uint32_t k, core::Window& window) {
  const core::Keyframe& kf = stream.keyframes[k];
  const std::vector<core::Observation>& obs = stream.observations[k];
  const auto n = static_cast<std::uint32_t>(obs.size());
  return window.keyframe_count() == stream.window ? window.slide(kf, obs.data(), n)
                                                  : window.add_keyframe(kf, obs.data(), n);
}

// One pass over the stream. budget_ns == 0: no deadline.
bool replay(const KeyframeStream& stream, std::uint32_t warmup, std::uint64_t budget_ns,
            const core::Params& params, const Options& o, bool compare, Replay* r) {
  const core::Capacities caps = window_needs(stream);
  r->caps = caps;
  core::Window window(caps);
  core::Sparsifier inc(caps, params, core::SolveMode::kIncremental);
  // The independent check: from scratch, successive shortest paths from zero flow.
  core::Sparsifier scratch(caps, params, core::SolveMode::kFromScratch, core::Start::kZeroFlow);
  core::Sparsifier fresh(caps, params);  // run() as the library does it, timed on sampled windows
  // The sampled windows' solvers are compared on the optimum before the
  // policies act on it (same cost model).
  core::Params unpolicied = params;
  unpolicied.scope = core::Scope::kWindow;
  unpolicied.coverage_floor = 0;
  unpolicied.maturity_keyframes = 0;
  unpolicied.budget = core::KeepBudget{};  // the solvers are compared at M
  std::unique_ptr<core::Sparsifier> raw;
  if (params.scope != core::Scope::kWindow || params.coverage_floor > 0 || params.maturity_keyframes > 0 ||
      params.budget.kind != core::BudgetKind::kNone) {
    raw = std::make_unique<core::Sparsifier>(caps, unpolicied, core::SolveMode::kFromScratch,
                                             core::Start::kZeroFlow);
  }
  DecisionEncoder encoder(caps);
  platform::MonotonicClock clock;
  inc.set_clock(&clock);
  scratch.set_clock(&clock);
  r->footprint = window.memory_bytes() + inc.memory_bytes() + encoder.memory_bytes();

  const auto total = static_cast<std::uint32_t>(stream.keyframes.size());
  const std::uint32_t measured = total > warmup ? total - warmup : 0;
  for (Histogram* h : {&r->ingest, &r->network, &r->solve, &r->decide, &r->publish, &r->e2e, &r->e2e_cpu}) {
    h->ns.clear();
    h->ns.reserve(measured);
  }
  const std::uint32_t stride = compare && o.compare > 0 ? std::max<std::uint32_t>(1, measured / o.compare) : 0;
  double points = 0, arcs = 0;
  std::vector<Answer> answers;
  answers.reserve(measured);
  std::uint32_t sampled = 0;
  // A kept fraction remembers what earlier decisions kept (FractionBudget),
  // so its checks decide every window the timed pass decided, warm-up
  // included and deferrals not, to hold the same memory.
  const bool sequential = params.budget.kind == core::BudgetKind::kFraction;
  std::vector<std::uint8_t> decided(total, 0);
  test::AllocationCounter counter;  // armed only around the measured decision path
  counter.pause();
  for (std::uint32_t k = 0; k < total; ++k) {
    const bool measuring = k >= warmup;
    if (measuring) counter.resume();
    // --- the decision path ---
    const std::uint64_t t0 = clock.now_ns();  // the keyframe arrives
    const std::uint64_t cpu0 = thread_cpu_ns();
    const core::Status added = slide_in(stream, k, window);
    const std::uint64_t t1 = clock.now_ns();
    // The solver gets 90% of the budget; the rest is for deciding and
    // publishing, which follow it.
    solver::Budget budget;
    if (budget_ns > 0) {
      budget.clock = &clock;
      budget.deadline_ns = t0 + budget_ns - budget_ns / 10;
    }
    const core::Status status = inc.update(window, budget);
    const std::uint64_t t2 = clock.now_ns();
    encoder.encode(k + 1, window, inc, status);
    const std::uint64_t t3 = clock.now_ns();
    const std::uint64_t cpu3 = thread_cpu_ns();
    counter.pause();
    // --- outside the path: bookkeeping and checks ---
    if (added != core::Status::kOk ||
        (status != core::Status::kOk && status != core::Status::kBudgetExhausted)) {
      std::fprintf(stderr, "keepless_latency: keyframe %u: %s / %s\n", k, core::to_string(added),
                   core::to_string(status));
      ++r->failures;
      continue;
    }
    decided[k] = !inc.deferred();
    if (!measuring) continue;
    const core::StageTimes& st = inc.stage_times();
    r->ingest.ns.push_back(t1 - t0);
    r->network.ns.push_back(st.network_ns);
    r->solve.ns.push_back(st.solve_ns);
    r->decide.ns.push_back(st.decide_ns);
    r->publish.ns.push_back(t3 - t2);
    r->e2e.ns.push_back(t3 - t0);
    r->e2e_cpu.ns.push_back(cpu3 - cpu0);
    ++r->decisions;
    r->exhausted += status == core::Status::kBudgetExhausted;
    r->deferred += inc.deferred();
    r->late += budget_ns > 0 && t3 - t0 > budget_ns;
    points += inc.summary().points;
    arcs += inc.summary().arcs;
    r->floor_bound += inc.summary().floor_keyframes > 0;
    r->floor_promoted += inc.summary().floor_promoted;
    r->out_of_scope += inc.summary().out_of_scope;

    Answer a = answer_of(k, inc, status);
    if (stride > 0 && (k - warmup) % stride == stride / 2 && sampled < o.compare &&
        status == core::Status::kOk) {
      a.sampled = true;
      a.solve_ns = st.solve_ns;
      a.slide_ns = st.network_ns + st.solve_ns + st.decide_ns;
      ++sampled;
    }
    answers.push_back(a);
  }
  r->allocations = counter.count();

  // Second pass: the same windows, decided from scratch by successive
  // shortest paths from zero flow, and on the sampled ones the from-scratch
  // solvers timed.
  core::Window check(caps);
  std::size_t next = 0;
  for (std::uint32_t k = 0; k < total && next < answers.size(); ++k) {
    (void)slide_in(stream, k, check);  // a refusal was counted in the first pass
    // `fresh` decides every window the path decided, so that its buffers are
    // as warm as the path's when a sampled window times it (and, under a kept
    // fraction, it holds the same memory).
    const bool fresh_runs = !sequential || decided[k];
    if (answers[next].keyframe != k) {
      if (sequential && decided[k]) (void)scratch.run(check);
      if (fresh_runs) (void)fresh.run(check);
      continue;
    }
    const Answer& a = answers[next++];
    // A deferral keeps the window's points (raw: no budget). The checks
    // (agrees) stay outside the timed spans.
    core::Sparsifier& zero_flow = sequential && !decided[k] ? *raw : scratch;
    const std::uint64_t s0 = clock.now_ns();
    const core::Status zero_status = zero_flow.run(check);
    const std::uint64_t s1 = clock.now_ns();
    if (zero_status != core::Status::kOk || !agrees(a, zero_flow)) ++r->mismatches;
    if (fresh_runs && !a.sampled) (void)fresh.run(check);
    if (!a.sampled) continue;
    r->incremental.push_back(a.solve_ns);
    r->slide_incremental.push_back(a.slide_ns);
    r->slide_zero_flow.push_back(s1 - s0);
    const std::uint64_t f0 = clock.now_ns();
    const core::Status fresh_status = fresh.run(check);
    r->slide_scratch.push_back(clock.now_ns() - f0);
    if (fresh_status != core::Status::kOk || !agrees(a, fresh)) ++r->mismatches;
    if (raw && raw->run(check) != core::Status::kOk) {
      ++r->mismatches;
      continue;
    }
    compare_window(raw ? *raw : scratch, caps, o, clock, r);
  }
  r->digest = kFnvBasis;
  for (const Answer& a : answers) fnv_mix(&r->digest, a.digest);
  r->points_mean = r->decisions > 0 ? points / r->decisions : 0;
  r->arcs_mean = r->decisions > 0 ? arcs / r->decisions : 0;
  return true;
}

}  // namespace
}  // namespace keepless::perf

int main(int argc, char** argv) {
  using namespace keepless;
  using namespace keepless::perf;
  Options o;
  if (const int status = parse(argc, argv, &o); status >= 0) return status;
  // Before anything else is allocated: the resident-set growth is then the node's own pages.
  NodeMemory node_memory;
  if (!o.profile.empty()) {
    std::string error;
    if (!measure_node_memory(o.profile, &node_memory, &error)) {
      std::fprintf(stderr, "keepless_latency: --profile: %s\n", error.c_str());
      return 2;
    }
  }
  std::string granted = platform::current_cpus();
  std::string pin_note = "not requested";
  bool pinned = false, locked = false;  // what was granted, for the JSON
  if (!o.cpus.empty()) {
    const platform::PinResult pin = platform::pin_to_cpus(o.cpus);
    granted = pin.granted;
    pinned = pin.ok;
    pin_note = pin.ok ? "ok" : "refused: " + pin.error;
  }
  std::string lock_note = "not requested";
  if (o.mlock) {
    const platform::LockResult lock = platform::lock_memory();
    locked = lock.ok;
    lock_note = lock.ok ? "ok" : "refused: " + lock.error;
  }

  KeyframeStream stream;
  std::string source = "synthetic";
  if (!o.log.empty()) {
    std::string error;
    if (!read_lcm_log(o.log, &stream, &error)) {
      std::fprintf(stderr, "keepless_latency: %s\n", error.c_str());
      return 2;
    }
    source = "log " + o.log;
    o.workload = "log";
  } else {
    const std::uint32_t measured = o.keyframes > 0 ? o.keyframes : (o.workload == "map" ? 3 : 1000);
    SyntheticSpec spec;
    if (!workload_spec(o.workload, &spec)) {
      return cli::usage_error(kTool, unknown_workload(o.workload));
    }
    const std::uint32_t k = spec.keyframes;
    const std::uint32_t warmup = o.warmup > 0 ? o.warmup : k;
    StreamExtras extras;
    extras.camera = o.params.cost_model == core::CostModel::kInformation;
    const bool authors = o.params.cost_model == core::CostModel::kAuthors;
    extras.unmapped_per_kf = o.unmapped >= 0 ? static_cast<std::uint32_t>(o.unmapped)
                             : authors      ? spec.obs_per_kf / 2
                                            : 0;
    try {
      if (!make_stream(o.workload, k - 1 + warmup + measured, o.seed, extras, &stream)) return 2;
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "keepless_latency: a stream of %u keyframes does not fit in memory\n",
                   k - 1 + warmup + measured);
      return 2;
    }
    o.warmup = k - 1 + warmup;
  }
  if (!o.log.empty() && o.warmup == 0) o.warmup = stream.window;

  std::printf("keepless_latency: workload %s (%s), window %u keyframes, %zu keyframes, seed %llu\n",
              o.workload.c_str(), source.c_str(), stream.window, stream.keyframes.size(),
              static_cast<unsigned long long>(o.seed));
  std::printf("cpus: requested %s, granted %s (%s); mlock: %s\n", o.cpus.empty() ? "-" : o.cpus.c_str(),
              granted.c_str(), pin_note.c_str(), lock_note.c_str());
  const bool with_reference = !is_reference(o.params);
  const std::uint32_t unmapped_per_kf = stream.keyframes.empty() ? 0 : stream.keyframes[0].unmapped_count;
  // Intrinsics on the keyframes and a depth on every observation.
  bool camera = !stream.keyframes.empty();
  for (std::size_t k = 0; k < stream.keyframes.size() && camera; ++k) {
    camera = stream.keyframes[k].fx > 0;
    for (const core::Observation& ob : stream.observations[k]) camera = camera && ob.depth > 0;
  }
  std::printf("keep budget: %s", core::to_string(o.params.budget.kind));
  if (o.params.budget.kind == core::BudgetKind::kFraction) std::printf(" %.3f", o.params.budget.fraction);
  if (o.params.budget.kind == core::BudgetKind::kPoints || o.params.budget.kind == core::BudgetKind::kObservations)
    std::printf(" %llu", static_cast<unsigned long long>(o.params.budget.count));
  std::printf("\n");
  std::printf("policy: use %s, scope %s, maturity %u, floor %u, cost %s, track share %.2f from %.2f to %.2f; stream:"
              " intrinsics and depths %s, %u unmapped keypoints per keyframe; reference: %s\n",
              o.use.empty() ? "-" : o.use.c_str(), core::to_string(o.params.scope), o.params.maturity_keyframes,
              o.params.coverage_floor, core::to_string(o.params.cost_model), o.params.budget.track_share,
              o.params.budget.track_share_from, o.params.budget.track_share_to,
              camera ? "yes" : "no", unmapped_per_kf,
              with_reference ? "the paper's defaults on the same stream, replayed after" : "this run");

  double budget_ms = o.budget_ms;
  Replay calibration;
  if (o.budget_fraction > 0) {
    if (!replay(stream, o.warmup, 0, o.params, o, false, &calibration)) return 1;
    budget_ms = o.budget_fraction * calibration.e2e.p(0.5);
    std::printf("calibration: end-to-end median %.3f ms without a budget -> budget %.3f ms\n",
                calibration.e2e.p(0.5), budget_ms);
  }
  Replay r;
  const auto budget_ns = static_cast<std::uint64_t>(budget_ms * 1e6);
  if (!replay(stream, o.warmup, budget_ns, o.params, o, true, &r)) return 1;
  // The reference right after, on the same stream with the same budget: the
  // ratios below compare like with like under whatever else the machine runs.
  Replay ref_run;
  if (with_reference && !replay(stream, o.warmup, budget_ns, core::Params{}, o, false, &ref_run)) return 1;
  const Replay& ref = with_reference ? ref_run : r;
  // A/A control: the reference's policy replayed once more, last. Its ratios
  // to the reference are what the machine alone moves a ratio by in this run.
  Replay again;
  if (!replay(stream, o.warmup, budget_ns, core::Params{}, o, false, &again)) return 1;

  std::printf("capacities: %u keyframes, %u points, %u observations, %u pair arcs; footprint %zu bytes;"
              " publish as %s\n",
              r.caps.max_keyframes, r.caps.max_points, r.caps.max_observations, r.caps.max_pair_arcs,
              r.footprint, DecisionEncoder::format());
  std::printf("windows: %.0f points, %.0f arcs on average; %u decisions measured after %u warm-up\n",
              r.points_mean, r.arcs_mean, r.decisions, o.warmup);
  if (budget_ns > 0) {
    std::printf("budget: %.3f ms per decision from keyframe arrival; exhausted %u (network update deferred %u),"
                " later than the budget %u\n",
                budget_ms, r.exhausted, r.deferred, r.late);
  } else {
    std::printf("budget: none\n");
  }
  std::printf("%-12s %9s %9s %9s %9s %9s  (ms)\n", "stage", "p50", "p90", "p99", "p99.9", "max");
  for (const Histogram* h : {&r.ingest, &r.network, &r.solve, &r.decide, &r.publish, &r.e2e, &r.e2e_cpu}) {
    std::printf("%-12s %9.3f %9.3f %9.3f %9.3f %9.3f\n", h->name, h->p(0.5), h->p(0.9), h->p(0.99),
                h->p(0.999), h->max());
  }
  const double ours = median_ms(r.ours), zero = median_ms(r.ours_zero_flow), lemon_ns = median_ms(r.lemon_ns),
               lemon_cs = median_ms(r.lemon_cs), closed = median_ms(r.closed), inc = median_ms(r.incremental),
               ours_solve = median_ms(r.ours_solve);
  const auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
  if (r.compared > 0) {
    std::printf("from scratch on %u sampled windows (median of per-window best of %u, ms):\n", r.compared,
                std::max(o.reps, 1u));
    std::printf("  ours %.3f | LEMON NetworkSimplex %.3f (%.1fx ours) | LEMON CostScaling %.3f (%.1fx ours)"
                " | closed form %.3f (ours %.2fx it)\n",
                ours, lemon_ns, ratio(lemon_ns, ours), lemon_cs, ratio(lemon_cs, ours), closed,
                ratio(ours, closed));
    std::printf("  ours from zero flow %.3f (LEMON NetworkSimplex %.1fx it; it %.2fx the closed form)\n", zero,
                ratio(lemon_ns, zero), ratio(zero, closed));
    std::printf("  incremental solve %.3f (scratch solve, network loaded, %.3f: %.2fx it); slide incl. network:"
                " scratch %.3f, incremental %.3f (%.2fx); scratch from zero flow %.3f\n",
                inc, ours_solve, ratio(ours_solve, inc), median_ms(r.slide_scratch), median_ms(r.slide_incremental),
                ratio(median_ms(r.slide_scratch), median_ms(r.slide_incremental)),
                median_ms(r.slide_zero_flow));
  }
  const bool identical = r.mismatches == 0 && r.cost_mismatches == 0 && r.lemon_decision_mismatches == 0 &&
                         r.closed_mismatches == 0 && r.failures == 0 && r.decisions > 0 &&
                         ref.mismatches == 0 && ref.failures == 0 && ref.decisions == r.decisions &&
                         again.mismatches == 0 && again.failures == 0 && again.decisions == r.decisions;
  std::printf("identical decisions: %s (%u windows incremental vs run() from zero flow; %u LEMON canonical, %u closed form;"
              " cost mismatches %u)\n",
              identical ? "true" : "false", r.decisions, r.lemon_checked, r.compared, r.cost_mismatches);
  std::printf("heap allocations after warm-up: %llu\n", static_cast<unsigned long long>(r.allocations));
  std::printf("policy at work: floor bound in %u decisions (%llu points promoted), %.1f points out of scope"
              " per decision\n",
              r.floor_bound, static_cast<unsigned long long>(r.floor_promoted),
              r.decisions > 0 ? static_cast<double>(r.out_of_scope) / r.decisions : 0.0);
  double budget_share_p50 = NAN, budget_share_p99 = NAN;
  if (with_reference) {
    std::printf("reference (paper, replayed after): end-to-end p50 %.3f p99 %.3f ms, budget exhausted %u,"
                " allocations %llu; this policy's p50 %.2fx, p99 %.2fx the reference's\n",
                ref.e2e.p(0.5), ref.e2e.p(0.99), ref.exhausted, static_cast<unsigned long long>(ref.allocations),
                ratio(r.e2e.p(0.5), ref.e2e.p(0.5)), ratio(r.e2e.p(0.99), ref.e2e.p(0.99)));
    if (o.params.budget.kind != core::BudgetKind::kNone) {
      // With a budget there is no solve: the decide stage computes the
      // thresholds and selects. Its cost is the whole decision's CPU time
      // against the reference's (M = 100, solved), as a share of the latter.
      budget_share_p50 = ratio(r.e2e_cpu.p(0.5), ref.e2e_cpu.p(0.5)) - 1.0;
      budget_share_p99 = ratio(r.e2e_cpu.p(0.99), ref.e2e_cpu.p(0.99)) - 1.0;
      std::printf("keep budget's cost: decision CPU time p50 %.3f ms (reference %.3f, %+.1f %%), p99 %.3f ms"
                  " (reference %.3f, %+.1f %%); thresholds and selection (decide stage) p50 %.3f ms in place of"
                  " the reference's solve %.3f + decide %.3f; end-to-end p99 %.3f ms (reference %.3f)\n",
                  r.e2e_cpu.p(0.5), ref.e2e_cpu.p(0.5), 100.0 * budget_share_p50, r.e2e_cpu.p(0.99),
                  ref.e2e_cpu.p(0.99), 100.0 * budget_share_p99, r.decide.p(0.5), ref.solve.p(0.5),
                  ref.decide.p(0.5), r.e2e.p(0.99), ref.e2e.p(0.99));
    }
    for (const auto& [mine, theirs] : {std::pair{&r.ingest, &ref.ingest}, {&r.network, &ref.network},
                                       {&r.solve, &ref.solve}, {&r.decide, &ref.decide}, {&r.e2e_cpu, &ref.e2e_cpu}}) {
      std::printf("  %-10s p50 %.3f (reference %.3f, %.2fx)  p99 %.3f (reference %.3f, %.2fx)\n", mine->name,
                  mine->p(0.5), theirs->p(0.5), ratio(mine->p(0.5), theirs->p(0.5)), mine->p(0.99),
                  theirs->p(0.99), ratio(mine->p(0.99), theirs->p(0.99)));
    }
  }

  std::printf("A/A control (the %s replayed again, last): end-to-end p50 %.3f p99 %.3f ms, CPU p99 %.3f ms:"
              " p50 %.2fx, p99 %.2fx, CPU p99 %.2fx the first run's; ratios nearer 1 than these are this"
              " machine's noise\n",
              with_reference ? "reference" : "policy", again.e2e.p(0.5), again.e2e.p(0.99), again.e2e_cpu.p(0.99),
              ratio(again.e2e.p(0.5), ref.e2e.p(0.5)), ratio(again.e2e.p(0.99), ref.e2e.p(0.99)),
              ratio(again.e2e_cpu.p(0.99), ref.e2e_cpu.p(0.99)));

  // keepless_node's fixed memory with --profile (measured first, above), and
  // whether the workload's windows fit it (the decision path above is sized
  // by the stream's needs).
  bool fits = false;
  if (!o.profile.empty()) {
    const core::Capacities& p = node_memory.caps;
    fits = r.caps.max_keyframes <= p.max_keyframes && r.caps.max_points <= p.max_points &&
           r.caps.max_observations <= p.max_observations && r.caps.max_pair_arcs <= p.max_pair_arcs &&
           r.caps.max_unmapped_keypoints <= p.max_unmapped_keypoints;
    std::printf("keepless_node --profile %s: capacities %u keyframes, %u points, %u observations, %u pair arcs;"
                " fixed memory predicted %.2f MB, counted by the node %.2f MB, resident-set growth %.2f MB;"
                " this workload's windows %s it\n",
                o.profile.c_str(), p.max_keyframes, p.max_points, p.max_observations, p.max_pair_arcs,
                node_memory.predicted_bytes / 1e6, static_cast<double>(node_memory.counted_bytes) / 1e6,
                static_cast<double>(node_memory.rss_growth_bytes) / 1e6, fits ? "fit" : "do not fit");
  }
  const std::uint64_t peak_rss = peak_resident_bytes();
  std::printf("process memory: resident %.2f MB, peak resident %.2f MB\n", static_cast<double>(resident_bytes()) / 1e6,
              static_cast<double>(peak_rss) / 1e6);

  LcmResult lcm;
  bool lcm_failed = false;  // the run exits 1: its lcm_* figures are not measurements
  if (o.lcm) {
    std::string error;
    if (!run_lcm_mode(argv[0], stream, o.warmup, budget_ms, o.node_flags, &lcm, &error)) {
      lcm_failed = true;
      std::fprintf(stderr, "keepless_latency: --lcm: %s\n", error.c_str());
    } else {
      std::printf("over LCM (keepless_node on loopback, published -> decision received): %u decisions,"
                  " p50 %.3f p90 %.3f p99 %.3f max %.3f ms, %u lost\n",
                  lcm.decisions, lcm.p50_ms, lcm.p90_ms, lcm.p99_ms, lcm.max_ms, lcm.lost);
    }
  }

  std::printf(
      "{\"workload\":\"%s\",\"window\":%u,\"decisions\":%u,\"cpus\":\"%s\",\"pinned\":%s,\"mlock\":%s,"
      "\"mlock_ok\":%s,"
      "\"e2e_p50_ms\":%.4f,\"e2e_p90_ms\":%.4f,\"e2e_p99_ms\":%.4f,\"e2e_p999_ms\":%.4f,\"e2e_max_ms\":%.4f,"
      "\"ingest_p50_ms\":%.4f,\"ingest_p99_ms\":%.4f,\"network_p50_ms\":%.4f,\"network_p99_ms\":%.4f,"
      "\"solve_p50_ms\":%.4f,\"solve_p99_ms\":%.4f,\"decide_p50_ms\":%.4f,\"decide_p99_ms\":%.4f,"
      "\"publish_p50_ms\":%.4f,\"publish_p99_ms\":%.4f,"
      "\"budget_ms\":%.4f,\"budget_exhausted\":%u,\"deferred_decisions\":%u,\"late_decisions\":%u,"
      "\"allocations_after_warmup\":%llu,\"footprint_bytes\":%zu,"
      "\"compared_windows\":%u,\"ours_scratch_median_ms\":%.4f,\"ours_scratch_solve_median_ms\":%.4f,"
      "\"incremental_median_ms\":%.4f,"
      "\"lemon_ns_median_ms\":%.4f,\"lemon_cs_median_ms\":%.4f,\"closed_form_median_ms\":%.4f,"
      "\"lemon_ns_over_ours\":%.3f,\"ours_over_closed_form\":%.3f,\"scratch_over_incremental\":%.3f,"
      "\"ours_zero_flow_median_ms\":%.4f,\"lemon_ns_over_ours_zero_flow\":%.3f,"
      "\"slide_scratch_median_ms\":%.4f,\"slide_incremental_median_ms\":%.4f,"
      "\"slide_zero_flow_median_ms\":%.4f,"
      "\"lcm_decisions\":%u,\"lcm_lost\":%u,\"lcm_p50_ms\":%.4f,\"lcm_p99_ms\":%.4f,\"lcm_max_ms\":%.4f,",
      o.workload.c_str(), stream.window, r.decisions, granted.c_str(), pinned ? "true" : "false",
      o.mlock ? "true" : "false", locked ? "true" : "false",
      r.e2e.p(0.5), r.e2e.p(0.9), r.e2e.p(0.99), r.e2e.p(0.999), r.e2e.max(), r.ingest.p(0.5), r.ingest.p(0.99),
      r.network.p(0.5), r.network.p(0.99), r.solve.p(0.5), r.solve.p(0.99), r.decide.p(0.5), r.decide.p(0.99),
      r.publish.p(0.5), r.publish.p(0.99), budget_ms, r.exhausted, r.deferred, r.late,
      static_cast<unsigned long long>(r.allocations), r.footprint, r.compared, ours, ours_solve, inc, lemon_ns,
      lemon_cs, closed, ratio(lemon_ns, ours), ratio(ours, closed), ratio(ours_solve, inc), zero, ratio(lemon_ns, zero),
      median_ms(r.slide_scratch), median_ms(r.slide_incremental), median_ms(r.slide_zero_flow), lcm.decisions,
      lcm.lost, lcm.p50_ms, lcm.p99_ms, lcm.max_ms);
  // The policy and its reference. Digests are hex strings (64 bits do not
  // survive a JSON number as a double).
  std::printf(
      "\"keep_budget\":\"%s\",\"keep_budget_value\":%.4f,\"keep_budget_share_p50\":%s,\"keep_budget_share_p99\":%s,"
      "\"use\":\"%s\",\"scope\":\"%s\",\"maturity_keyframes\":%u,\"defer_keyframes\":%u,\"track_share\":%.3f,\"track_share_from\":%.3f,"
      "\"track_share_to\":%.3f,\"coverage_floor\":%u,\"cost_model\":\"%s\",\"intrinsics_and_depths\":%s,"
      "\"unmapped_per_kf\":%u,\"floor_bound_decisions\":%u,\"floor_promoted\":%llu,\"out_of_scope_mean\":%.1f,"
      "\"decisions_digest\":\"%016llx\",\"reference\":\"%s\",\"reference_e2e_p50_ms\":%.4f,"
      "\"reference_e2e_p99_ms\":%.4f,\"reference_budget_exhausted\":%u,"
      "\"reference_allocations_after_warmup\":%llu,\"reference_decisions_digest\":\"%016llx\","
      "\"p50_ratio_to_paper\":%.3f,\"p99_ratio_to_paper\":%.3f,"
      "\"e2e_cpu_p50_ms\":%.4f,\"e2e_cpu_p99_ms\":%.4f,\"reference_e2e_cpu_p50_ms\":%.4f,"
      "\"reference_e2e_cpu_p99_ms\":%.4f,\"cpu_p50_ratio_to_paper\":%.3f,\"cpu_p99_ratio_to_paper\":%.3f,"
      "\"aa_e2e_p50_ms\":%.4f,\"aa_e2e_p99_ms\":%.4f,\"aa_e2e_cpu_p99_ms\":%.4f,\"aa_p50_ratio\":%.3f,"
      "\"aa_p99_ratio\":%.3f,\"aa_cpu_p99_ratio\":%.3f,\"aa_allocations_after_warmup\":%llu,"
      "\"aa_decisions_digest\":\"%016llx\",",
      core::to_string(o.params.budget.kind),
      o.params.budget.kind == core::BudgetKind::kFraction ? o.params.budget.fraction
                                                          : static_cast<double>(o.params.budget.count),
      json_or_null(budget_share_p50).c_str(), json_or_null(budget_share_p99).c_str(), o.use.c_str(),
      core::to_string(o.params.scope), o.params.maturity_keyframes, o.params.defer_keyframes,
      o.params.budget.track_share, o.params.budget.track_share_from, o.params.budget.track_share_to,
      o.params.coverage_floor,
      core::to_string(o.params.cost_model), camera ? "true" : "false", unmapped_per_kf, r.floor_bound,
      static_cast<unsigned long long>(r.floor_promoted),
      r.decisions > 0 ? static_cast<double>(r.out_of_scope) / r.decisions : 0.0,
      static_cast<unsigned long long>(r.digest), with_reference ? "paper" : "self", ref.e2e.p(0.5), ref.e2e.p(0.99),
      ref.exhausted, static_cast<unsigned long long>(ref.allocations), static_cast<unsigned long long>(ref.digest),
      ratio(r.e2e.p(0.5), ref.e2e.p(0.5)), ratio(r.e2e.p(0.99), ref.e2e.p(0.99)), r.e2e_cpu.p(0.5),
      r.e2e_cpu.p(0.99), ref.e2e_cpu.p(0.5), ref.e2e_cpu.p(0.99), ratio(r.e2e_cpu.p(0.5), ref.e2e_cpu.p(0.5)),
      ratio(r.e2e_cpu.p(0.99), ref.e2e_cpu.p(0.99)), again.e2e.p(0.5), again.e2e.p(0.99), again.e2e_cpu.p(0.99),
      ratio(again.e2e.p(0.5), ref.e2e.p(0.5)), ratio(again.e2e.p(0.99), ref.e2e.p(0.99)),
      ratio(again.e2e_cpu.p(0.99), ref.e2e_cpu.p(0.99)), static_cast<unsigned long long>(again.allocations),
      static_cast<unsigned long long>(again.digest));
  std::printf("\"profile\":\"%s\",\"profile_fits\":%s,\"node_memory_predicted_bytes\":%.0f,"
              "\"node_memory_bytes\":%llu,\"node_rss_growth_bytes\":%lld,\"peak_rss_bytes\":%llu,",
              o.profile.c_str(), fits ? "true" : "false", node_memory.predicted_bytes,
              static_cast<unsigned long long>(node_memory.counted_bytes),
              static_cast<long long>(node_memory.rss_growth_bytes), static_cast<unsigned long long>(peak_rss));
  std::printf("\"identical_decisions\":%s}\n", identical ? "true" : "false");
  return identical && !lcm_failed ? 0 : 1;
}
