// Decisions must not depend on the architecture: a board (aarch64) and the
// x86-64 machine that tuned it must keep the same points. These tests hash
// everything the decision path outputs for a fixed, generated workload and
// compare with hashes recorded on x86-64; the aarch64 and the 32-bit armhf
// suites (ctest under qemu, toolchains/cross_build.sh) assert the same
// constants.
//
// If a deliberate change to the costs, the network or the solver's tie-break
// changes the decisions, the failure prints the new hash: re-record it here
// and check that the aarch64 suite agrees (docs/embedded/bit-identical.md).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/costs.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/use.hpp"
#include "keepless/core/window.hpp"

namespace keepless::core {
namespace {

// Recorded from the x86-64 release build; see the file comment.
constexpr std::uint64_t kExpectedCostHash = 0x231e8d5f5870d2a7ULL;
constexpr std::uint64_t kExpectedDecisionHash = 0x6da842663cdda28eULL;
constexpr std::uint64_t kExpectedPolicyHash = 0x8092a28e8907ad34ULL;
// 2026-12-04: the budget workload's kept fractions remember points that left.
constexpr std::uint64_t kExpectedBudgetHash = 0x092d7eb36f52bbcaULL;
constexpr std::uint64_t kExpectedTrackHash = 0x458af2d5de07218dULL;
constexpr std::uint64_t kExpectedAutoScopeHash = 0x6cb2f6d7607062d1ULL;

// splitmix64: a fixed, portable stream (std:: distributions are not
// specified bit for bit across standard libraries).
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>(next() % n); }
  // k / 2^bits, exactly representable: the inputs themselves never differ.
  double fraction(int bits) {
    return std::ldexp(static_cast<double>(next() >> (64 - bits)), -bits);
  }

 private:
  std::uint64_t state_;
};

// FNV-1a 64 over explicit little-endian bytes (no struct padding, no
// host byte order).
class Fnv1a64 {
 public:
  void add(std::uint64_t value, int bytes = 8) {
    for (int i = 0; i < bytes; ++i) {
      hash_ ^= (value >> (8 * i)) & 0xffu;
      hash_ *= 0x100000001b3ULL;
    }
  }
  void add_signed(std::int64_t value) { add(static_cast<std::uint64_t>(value)); }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xcbf29ce484222325ULL;
};

std::string hex(std::uint64_t v) {
  char text[32];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(v));
  return text;
}

// ---------------------------------------------------------------------------
// The float paths that feed integer costs, on their own, including the inputs
// where a last-bit difference would flip the result.

TEST(CrossArchitecture, FloatFedCostsMatchRecordedHash) {
  SplitMix64 rng(0x6b6565706c657373ULL);  // "keepless"
  Fnv1a64 hash;
  std::uint64_t checked = 0;

  // Baseline: random centres, plus distances where 10 / (0.1 d + 1) is an
  // integer (d = 0, 10, 15, 40, 90) or lands next to one.
  for (int i = 0; i < 20000; ++i) {
    double a[3], b[3];
    for (int c = 0; c < 3; ++c) {
      a[c] = (static_cast<double>(rng.below(4001)) - 2000.0) / 7.0 + rng.fraction(20);
      b[c] = a[c] + (static_cast<double>(rng.below(201)) - 100.0) * rng.fraction(30);
    }
    hash.add_signed(baseline_cost(a, b));
    ++checked;
  }
  // On the axis these distances are exact and so is c_b (the paper's values).
  const struct {
    double d;
    std::int64_t c_b;
  } on_axis[] = {{0.0, 10}, {2.5, 8}, {10.0, 5}, {15.0, 4}, {40.0, 2}, {90.0, 1}};
  for (const auto& e : on_axis) {
    const double a[3] = {1.0, -2.0, 0.5};
    const double b[3] = {1.0 + e.d, -2.0, 0.5};
    EXPECT_EQ(baseline_cost(a, b), e.c_b) << "d = " << e.d;
  }
  const double exact[] = {0.0, 10.0,      15.0, 40.0, 90.0,
                          2.5, 1.0 / 3.0, 0.1,  30.0, 23.333333333333332};
  for (double d : exact) {
    for (int step = -2; step <= 2; ++step) {
      double dd = d;
      for (int s = 0; s < std::abs(step); ++s) dd = std::nextafter(dd, step < 0 ? -1.0 : 1e9);
      const double a[3] = {0.0, 0.0, 0.0};
      const double b[3] = {dd, 0.0, 0.0};
      const double c[3] = {dd * 0.6, dd * 0.8, 0.0};  // the same length off-axis, rounded
      hash.add_signed(baseline_cost(a, b));
      hash.add_signed(baseline_cost(a, c));
      checked += 2;
    }
  }

  // Box tests: random offsets, and offsets on and one ulp either side of the
  // box edge, for the paper's box and odd-sized ones.
  const std::int32_t boxes[][2] = {{64, 48}, {63, 47}, {1, 1}, {0, 0}, {640, 480}};
  for (const auto& box : boxes) {
    for (int i = 0; i < 4000; ++i) {
      const double du = (static_cast<double>(rng.below(2001)) - 1000.0) / 13.0;
      const double dv = (static_cast<double>(rng.below(2001)) - 1000.0) / 17.0;
      hash.add(in_box(du, dv, box[0], box[1]) ? 1 : 0, 1);
      ++checked;
    }
    const double hu = 0.5 * box[0], hv = 0.5 * box[1];
    // The box is closed: its edge is inside, one ulp beyond is not.
    EXPECT_TRUE(in_box(-hu, hv, box[0], box[1]));
    EXPECT_FALSE(in_box(std::nextafter(hu, 1e9), 0.0, box[0], box[1]));
    EXPECT_FALSE(in_box(0.0, -std::nextafter(hv, 1e9), box[0], box[1]));
    for (double su : {-1.0, 1.0}) {
      for (double sv : {-1.0, 1.0}) {
        for (double eu : {std::nextafter(hu, 0.0), hu, std::nextafter(hu, 1e9)}) {
          for (double ev : {std::nextafter(hv, 0.0), hv, std::nextafter(hv, 1e9)}) {
            hash.add(in_box(su * eu, sv * ev, box[0], box[1]) ? 1 : 0, 1);
            ++checked;
          }
        }
      }
    }
  }

  // Keep-or-cull threshold: flow against theta * n(n-1)/2 at the boundary.
  for (double theta : {0.0, 0.1, 0.3, 0.5, 0.7, 1.0, 1.0 / 3.0}) {
    for (std::int64_t n = 2; n <= 40; ++n) {
      const std::int64_t capacity = n * (n - 1) / 2;
      for (std::int64_t flow = 0; flow <= capacity; ++flow) {
        hash.add(static_cast<std::uint64_t>(decide(flow, capacity, theta)), 1);
        ++checked;
      }
    }
  }

  EXPECT_GT(checked, 40000u);
  EXPECT_EQ(hash.value(), kExpectedCostHash)
      << "float-fed costs hash " << hex(hash.value()) << " (expected " << hex(kExpectedCostHash)
      << "): the costs changed on this architecture or by a code change";
}

// ---------------------------------------------------------------------------
// Whole windows through the Sparsifier.

struct GeneratedWindow {
  std::vector<Keyframe> keyframes;
  std::vector<std::vector<Observation>> observations;  // per keyframe
  Params params;
};

// A camera moving through a scene: points are tracked over a few consecutive
// keyframes (sometimes with a gap), keypoints cluster in image regions so
// that box counts vary, and some coordinates sit on a coarse grid so that box
// edges are hit exactly.
GeneratedWindow generate_window(SplitMix64& rng, std::uint32_t index) {
  GeneratedWindow w;
  const std::uint32_t k = 2 + rng.below(11);  // 2..12 keyframes
  const std::uint32_t points = 10 + rng.below(240);
  const std::int64_t pair_capacities[] = {1, 2, 3, 5, 8, 20, 100};
  const double thetas[] = {0.5, 0.5, 0.25, 0.75, 1.0 / 3.0};
  w.params.pair_capacity = pair_capacities[rng.below(7)];
  w.params.theta = thetas[rng.below(5)];
  if (index % 4 == 3) {
    w.params.box_width = 16 + 2 * static_cast<std::int32_t>(rng.below(40));
    w.params.box_height = 12 + static_cast<std::int32_t>(rng.below(60));
  }

  double position[3] = {0.0, 0.0, 1.5};
  w.keyframes.resize(k);
  w.observations.resize(k);
  for (std::uint32_t f = 0; f < k; ++f) {
    Keyframe& kf = w.keyframes[f];
    kf.id = 1000u * index + 7u * f + rng.below(7);
    if (index % 3 == 1) {
      // Steps of a length where ceil(10 / (0.1 d + 1)) is an exact integer,
      // in a random direction: the computed distance lands within an ulp or
      // so of it, so any change in how it is rounded (a fused multiply-add,
      // excess precision) moves c_b and the total cost.
      const double critical[] = {2.5, 10.0, 15.0, 40.0};
      const double d = critical[rng.below(4)];
      double dir[3] = {rng.fraction(30) - 0.5, rng.fraction(30) - 0.5, rng.fraction(30) - 0.5};
      const double norm = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
      for (int c = 0; c < 3; ++c) position[c] += norm > 0.0 ? d * dir[c] / norm : 0.0;
    } else {
      // Steps from standing still to 12 m; some windows revisit a centre.
      const double step = (index % 5 == 0 && f % 3 == 2) ? 0.0 : 12.0 * rng.fraction(16);
      position[0] += step;
      position[1] += (rng.fraction(12) - 0.5) * step;
      position[2] += (rng.fraction(10) - 0.5) * 0.2;
    }
    for (int c = 0; c < 3; ++c) kf.centre[c] = position[c];
  }

  const std::uint32_t clusters = 1 + rng.below(6);
  for (std::uint32_t p = 0; p < points; ++p) {
    const PointId id = 5000u * index + 3u * p + rng.below(3);
    const std::uint32_t first = rng.below(k);
    const std::uint32_t length = 1 + rng.below(k - first < 7 ? k - first : 7);
    const std::uint32_t gap =
        rng.below(5) == 0 ? first + rng.below(length) : k;  // one missed keyframe
    const std::uint32_t cluster = rng.below(clusters);
    const bool on_grid = rng.below(4) == 0;
    for (std::uint32_t f = first; f < first + length; ++f) {
      if (f == gap && length > 2) continue;
      Observation o;
      o.point = id;
      if (on_grid) {
        o.u = 16.0 * rng.below(40);
        o.v = 12.0 * rng.below(40);
      } else {
        o.u = 80.0 + 100.0 * cluster + 120.0 * rng.fraction(24) - 9.5 * (f - first);
        o.v = 60.0 + 70.0 * cluster + 90.0 * rng.fraction(24);
      }
      w.observations[f].push_back(o);
    }
  }
  // The tracker's order, not sorted by id.
  for (auto& list : w.observations) {
    for (std::size_t i = list.size(); i > 1; --i) {
      std::swap(list[i - 1], list[rng.below(static_cast<std::uint32_t>(i))]);
    }
  }
  return w;
}

// Room for any generated window.
Capacities generated_capacities() {
  Capacities capacities;
  capacities.max_keyframes = 16;
  capacities.max_points = 1024;
  capacities.max_observations = 4096;
  capacities.max_pair_arcs = 32768;
  capacities.max_unmapped_keypoints = 4096;
  return capacities;
}

TEST(CrossArchitecture, SparsifierDecisionsMatchRecordedHash) {
  constexpr std::uint32_t kWindows = 40;
  const Capacities capacities = generated_capacities();

  SplitMix64 rng(0x2024'0511'0000'0005ULL);
  Fnv1a64 hash;
  Window window(capacities);
  std::uint64_t kept = 0, culled = 0, skipped = 0;
  // Text copy of the decisions for diffing two architectures by hand.
  const char* dump_path = std::getenv("KEEPLESS_DECISIONS_DUMP");
  std::FILE* dump = dump_path != nullptr ? std::fopen(dump_path, "w") : nullptr;

  for (std::uint32_t index = 0; index < kWindows; ++index) {
    const GeneratedWindow g = generate_window(rng, index);
    window.clear();
    for (std::size_t f = 0; f < g.keyframes.size(); ++f) {
      ASSERT_EQ(window.add_keyframe(g.keyframes[f], g.observations[f].data(),
                                    static_cast<std::uint32_t>(g.observations[f].size())),
                Status::kOk)
          << "window " << index << " keyframe " << f;
    }
    Sparsifier sparsifier(capacities, g.params);
    ASSERT_EQ(sparsifier.run(window), Status::kOk) << "window " << index;

    const Summary& s = sparsifier.summary();
    ASSERT_EQ(sparsifier.decision_count(), window.distinct_points());
    ASSERT_EQ(s.kept + s.culled + s.skipped, s.points);
    hash.add(index, 4);
    hash.add(sparsifier.decision_count(), 4);
    const PointDecision* d = sparsifier.decisions();
    for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
      hash.add(d[i].point);
      hash.add(static_cast<std::uint64_t>(d[i].verdict), 1);
      hash.add_signed(d[i].flow);
      hash.add_signed(d[i].capacity);
      if (dump != nullptr) {
        std::fprintf(dump, "%u %llu %s %lld %lld\n", index,
                     static_cast<unsigned long long>(d[i].point), to_string(d[i].verdict),
                     static_cast<long long>(d[i].flow), static_cast<long long>(d[i].capacity));
      }
    }
    hash.add_signed(s.max_flow);
    hash.add_signed(s.total_cost);
    if (dump != nullptr) {
      std::fprintf(dump, "%u max_flow %lld cost %lld\n", index, static_cast<long long>(s.max_flow),
                   static_cast<long long>(s.total_cost));
    }
    kept += s.kept;
    culled += s.culled;
    skipped += s.skipped;
  }
  if (dump != nullptr) std::fclose(dump);

  // The workload exercises every verdict, so the hash covers real decisions.
  EXPECT_GT(kept, 0u);
  EXPECT_GT(culled, 0u);
  EXPECT_GT(skipped, 0u);
  EXPECT_EQ(hash.value(), kExpectedDecisionHash)
      << "decision hash " << hex(hash.value()) << " (expected " << hex(kExpectedDecisionHash)
      << "; kept " << kept << ", culled " << culled << ", skipped " << skipped << ")";
}

// The decision policies and cost models beside the paper's: the same kind of
// windows, given intrinsics, depths (where the information levels' float
// path can differ) and unmapped keypoints, decided under every cost model
// with the newest keyframe's scope and a binding coverage floor.
TEST(CrossArchitecture, PolicyDecisionsMatchRecordedHash) {
  constexpr std::uint32_t kWindows = 24;
  const Capacities capacities = generated_capacities();

  SplitMix64 rng(0x706f6c6963790001ULL);
  SplitMix64 extra(0x706f6c6963790002ULL);
  Fnv1a64 hash;
  Window window(capacities);
  std::uint64_t culled = 0, promoted = 0, out_of_scope = 0, informative = 0;
  std::vector<Keypoint> unmapped;
  for (std::uint32_t index = 0; index < kWindows; ++index) {
    GeneratedWindow g = generate_window(rng, index);
    window.clear();
    for (std::size_t f = 0; f < g.keyframes.size(); ++f) {
      Keyframe kf = g.keyframes[f];
      kf.fx = 500.0 + 100.0 * extra.fraction(20);
      kf.fy = kf.fx * (1.0 + 0.01 * extra.fraction(10));
      kf.cx = 320.0 + 10.0 * extra.fraction(20);
      kf.cy = 240.0 + 10.0 * extra.fraction(20);
      unmapped.resize(extra.below(200));
      for (Keypoint& k : unmapped) k = {700.0 * extra.fraction(24) - 30.0, 520.0 * extra.fraction(24) - 20.0};
      kf.unmapped = unmapped.data();
      kf.unmapped_count = static_cast<std::uint32_t>(unmapped.size());
      for (Observation& o : g.observations[f]) {
        o.depth = extra.below(10) == 0 ? 0.0 : 0.3 + 30.0 * extra.fraction(30);
      }
      ASSERT_EQ(window.add_keyframe(kf, g.observations[f].data(),
                                    static_cast<std::uint32_t>(g.observations[f].size())),
                Status::kOk)
          << "window " << index << " keyframe " << f;
      // The float-fed scores themselves.
      const auto count = static_cast<std::uint32_t>(g.observations[f].size());
      std::vector<std::uint32_t> levels(count), neighbours(count),
          cells(static_cast<std::size_t>(kGridColumns) * kGridRows);
      information_levels(kf, g.observations[f].data(), count, levels.data());
      grid_neighbours(kf, g.observations[f].data(), count, 640, 480, cells.data(),
                      neighbours.data());
      for (std::uint32_t i = 0; i < count; ++i) {
        hash.add(levels[i], 1);
        hash.add(neighbours[i], 4);
        informative += levels[i] != kNeutralInformationLevel;
      }
    }
    for (CostModel model : {CostModel::kPaper, CostModel::kAuthors, CostModel::kInformation}) {
      Params p = g.params;
      p.cost_model = model;
      p.scope = index % 2 == 0 ? Scope::kNewest : Scope::kWindow;
      p.coverage_floor = 5 + 3 * (index % 4);
      Sparsifier sparsifier(capacities, p);
      ASSERT_EQ(sparsifier.run(window), Status::kOk) << "window " << index;
      const Summary& s = sparsifier.summary();
      hash.add(index, 4);
      hash.add(static_cast<std::uint64_t>(model), 1);
      const PointDecision* d = sparsifier.decisions();
      for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
        hash.add(d[i].point);
        hash.add(static_cast<std::uint64_t>(d[i].verdict), 1);
        hash.add_signed(d[i].flow);
      }
      hash.add_signed(s.max_flow);
      hash.add_signed(s.total_cost);
      hash.add(s.floor_promoted, 4);
      culled += s.culled;
      promoted += s.floor_promoted;
      out_of_scope += s.out_of_scope;
    }
  }
  EXPECT_GT(culled, 0u);
  EXPECT_GT(promoted, 0u);
  EXPECT_GT(out_of_scope, 0u);
  EXPECT_GT(informative, 1000u);
  EXPECT_EQ(hash.value(), kExpectedPolicyHash)
      << "policy decision hash " << hex(hash.value()) << " (expected " << hex(kExpectedPolicyHash)
      << ")";
}

// Keep budgets (points, fraction, observations) with every cost model, a
// scope and a floor: the decisions, each point's keep threshold M*, the
// budget's M and the kept-count curve.
TEST(CrossArchitecture, BudgetDecisionsMatchRecordedHash) {
  constexpr std::uint32_t kWindows = 24;
  const Capacities capacities = generated_capacities();

  SplitMix64 rng(0x6275646765740001ULL);
  SplitMix64 extra(0x6275646765740002ULL);
  Fnv1a64 hash;
  Window window(capacities);
  std::uint64_t kept = 0, culled = 0;
  std::vector<Keypoint> unmapped;
  for (std::uint32_t index = 0; index < kWindows; ++index) {
    GeneratedWindow g = generate_window(rng, index);
    window.clear();
    for (std::size_t f = 0; f < g.keyframes.size(); ++f) {
      Keyframe kf = g.keyframes[f];
      kf.fx = 500.0 + 100.0 * extra.fraction(20);
      kf.fy = kf.fx * (1.0 + 0.01 * extra.fraction(10));
      kf.cx = 320.0 + 10.0 * extra.fraction(20);
      kf.cy = 240.0 + 10.0 * extra.fraction(20);
      unmapped.resize(extra.below(200));
      for (Keypoint& k : unmapped) k = {700.0 * extra.fraction(24) - 30.0, 520.0 * extra.fraction(24) - 20.0};
      kf.unmapped = unmapped.data();
      kf.unmapped_count = static_cast<std::uint32_t>(unmapped.size());
      for (Observation& o : g.observations[f]) {
        o.depth = extra.below(10) == 0 ? 0.0 : 0.3 + 30.0 * extra.fraction(30);
      }
      ASSERT_EQ(window.add_keyframe(kf, g.observations[f].data(),
                                    static_cast<std::uint32_t>(g.observations[f].size())),
                Status::kOk)
          << "window " << index << " keyframe " << f;
    }
    const KeepBudget budgets[] = {{BudgetKind::kPoints, 40u + 13u * index, 0.0},
                                  {BudgetKind::kFraction, 0, 0.05 * (1 + index % 12)},
                                  {BudgetKind::kObservations, 150u + 41u * index, 0.0}};
    for (CostModel model : {CostModel::kPaper, CostModel::kAuthors, CostModel::kInformation}) {
      Params p = g.params;
      p.cost_model = model;
      p.scope = index % 2 == 0 ? Scope::kNewest : Scope::kWindow;
      p.coverage_floor = index % 3 == 0 ? 0 : 5 + 3 * (index % 4);
      p.budget = budgets[(index + static_cast<std::uint32_t>(model)) % 3];
      Sparsifier sparsifier(capacities, p);
      ASSERT_EQ(sparsifier.run(window), Status::kOk) << "window " << index;
      const Summary& s = sparsifier.summary();
      hash.add(index, 4);
      hash.add(static_cast<std::uint64_t>(model), 1);
      const PointDecision* d = sparsifier.decisions();
      for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
        hash.add(d[i].point);
        hash.add(static_cast<std::uint64_t>(d[i].verdict), 1);
        hash.add_signed(d[i].flow);
        hash.add(sparsifier.keep_thresholds()[i], 4);
      }
      hash.add_signed(s.max_flow);
      hash.add_signed(s.total_cost);
      hash.add_signed(s.budget_m);
      hash.add(s.budget_observations);
      hash.add(s.floor_promoted, 4);
      for (std::int64_t m = 1; m <= 64; ++m) hash.add(sparsifier.kept_at(m), 4);
      kept += s.kept;
      culled += s.culled;
    }
  }
  EXPECT_GT(kept, 0u);
  EXPECT_GT(culled, 0u);
  EXPECT_EQ(hash.value(), kExpectedBudgetHash)
      << "budget decision hash " << hex(hash.value()) << " (expected " << hex(kExpectedBudgetHash) << ")";
}

// CostModel::kTrack: float-fed point quality (some unknown, some keyframes
// without any) under each set of terms, without and with a keep budget: the
// levels and the decisions.
TEST(CrossArchitecture, TrackCostDecisionsMatchRecordedHash) {
  constexpr std::uint32_t kWindows = 24;
  const Capacities capacities = generated_capacities();

  SplitMix64 rng(0x747261636b000001ULL);
  SplitMix64 extra(0x747261636b000002ULL);
  Fnv1a64 hash;
  Window window(capacities);
  std::uint64_t culled = 0, fallback = 0;
  std::vector<PointQuality> quality;
  std::vector<std::vector<PointQuality>> held;
  for (std::uint32_t index = 0; index < kWindows; ++index) {
    GeneratedWindow g = generate_window(rng, index);
    window.clear();
    held.assign(g.keyframes.size(), {});
    for (std::size_t f = 0; f < g.keyframes.size(); ++f) {
      Keyframe kf = g.keyframes[f];
      const std::size_t n = g.observations[f].size();
      if (extra.below(8) != 0) {
        quality.resize(n);
        for (PointQuality& q : quality) {
          q.track_length = static_cast<std::uint32_t>(extra.below(40));
          q.age = static_cast<std::int32_t>(extra.below(30)) - 1;
          q.reprojection_error = static_cast<float>(6.0 * extra.fraction(24) - 0.5);
          q.triangulation_angle = static_cast<float>(12.0 * extra.fraction(24) - 0.5);
        }
        held[f] = quality;
        kf.quality = held[f].data();
      }
      ASSERT_EQ(window.add_keyframe(kf, g.observations[f].data(), static_cast<std::uint32_t>(n)), Status::kOk)
          << "window " << index << " keyframe " << f;
      std::vector<std::uint32_t> levels(n);
      track_levels(kf, static_cast<std::uint32_t>(n), kTrackLength | kTrackAge | kTrackError | kTrackAngle,
                   levels.data());
      for (std::uint32_t v : levels) hash.add(v, 1);
    }
    for (std::uint8_t terms : {std::uint8_t{15}, std::uint8_t{kTrackLength}, std::uint8_t{kTrackError | kTrackAngle}}) {
      Params p = g.params;
      p.cost_model = CostModel::kTrack;
      p.track_terms = terms;
      p.scope = index % 2 == 0 ? Scope::kNewest : Scope::kWindow;
      p.coverage_floor = index % 3 == 0 ? 0 : 5;
      if (index % 4 == 1) p.budget = {BudgetKind::kFraction, 0, 0.05 * (1 + index % 12)};
      Sparsifier sparsifier(capacities, p);
      ASSERT_EQ(sparsifier.run(window), Status::kOk) << "window " << index;
      const Summary& s = sparsifier.summary();
      hash.add(index, 4);
      hash.add(terms, 1);
      const PointDecision* d = sparsifier.decisions();
      for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
        hash.add(d[i].point);
        hash.add(static_cast<std::uint64_t>(d[i].verdict), 1);
        hash.add_signed(d[i].flow);
      }
      hash.add_signed(s.max_flow);
      hash.add_signed(s.total_cost);
      hash.add_signed(s.budget_m);
      hash.add(s.track_fallback, 4);
      culled += s.culled;
      fallback += s.track_fallback;
    }
  }
  EXPECT_GT(culled, 0u);
  EXPECT_GT(fallback, 0u);
  EXPECT_EQ(hash.value(), kExpectedTrackHash)
      << "track cost decision hash " << hex(hash.value()) << " (expected " << hex(kExpectedTrackHash) << ")";
}

// Scope::kAuto over a sliding stream, whose share of returning points is
// carried from call to call: landmarks seen every fourth keyframe (some
// missed) in the first and third thirds of the stream, none in the second;
// tracks that go on with probability 3/4 a keyframe, so their lengths differ
// and the track share has a choice. The M decision by run(), and
// monocular-deferred's at F = 0.1 (its track share on) by update(): the
// decisions, the share and the scope each call chose.
TEST(CrossArchitecture, AutoScopeDecisionsOverAStreamMatchRecordedHash) {
  constexpr std::uint32_t kKeyframes = 90, kWindowKeyframes = 8, kLandmarks = 120;
  Capacities capacities = generated_capacities();
  capacities.max_keyframes = kWindowKeyframes;
  SplitMix64 rng(0x6175746f00000001ULL);
  Params by_m;
  by_m.scope = Scope::kAuto;
  Params deferred;
  apply_use(Use::kMonocularDeferred, &deferred);
  deferred.budget.kind = BudgetKind::kFraction;  // field by field: a whole KeepBudget would reset the share
  deferred.budget.fraction = 0.1;
  Params no_share = deferred;
  no_share.budget.track_share = 0.0;
  Sparsifier run_m(capacities, by_m), update_f(capacities, deferred, SolveMode::kIncremental);
  Sparsifier plain(capacities, no_share);  // what the share changes: not hashed
  Window window(capacities);
  Fnv1a64 hash;
  std::uint64_t newest = 0, window_decisions = 0, culled = 0, switches = 0, shared = 0;
  bool was_newest = false;
  std::vector<Observation> obs, previous;
  for (std::uint32_t f = 0; f < kKeyframes; ++f) {
    if (window.keyframe_count() == kWindowKeyframes) {
      ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
    }
    obs.clear();
    const auto at = [&](PointId id) {
      return Observation{id, 640.0 * rng.fraction(20), 480.0 * rng.fraction(20), 0.0};
    };
    for (const Observation& o : previous) {
      if (rng.below(4) != 0) obs.push_back(at(o.point));  // seen again by the next keyframe
    }
    const std::uint32_t born = 15 + rng.below(10);
    for (std::uint32_t i = 0; i < born; ++i) obs.push_back(at(PointId{1000} * (f + 1) + i));
    previous = obs;  // chained and new: a track goes on until a keyframe misses it
    if ((f / 30) % 2 == 0) {
      for (PointId l = 0; l < kLandmarks; ++l) {
        if ((f + l) % 4 == 0 && rng.below(8) != 0) obs.push_back(at(PointId{1000000} + l));
      }
    }
    Keyframe kf;
    kf.id = 10 + f;
    kf.centre[0] = f + rng.fraction(16);
    kf.centre[1] = rng.fraction(16);
    ASSERT_EQ(window.add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size())), Status::kOk) << f;
    ASSERT_EQ(run_m.run(window), Status::kOk) << f;
    ASSERT_EQ(update_f.update(window), Status::kOk) << f;
    ASSERT_EQ(plain.run(window), Status::kOk) << f;
    for (std::uint32_t i = 0; i < plain.decision_count() && i < update_f.decision_count(); ++i) {
      shared += plain.decisions()[i].verdict != update_f.decisions()[i].verdict;
    }
    switches += run_m.summary().decided_newest != was_newest;
    was_newest = run_m.summary().decided_newest;
    for (const Sparsifier* s : {&run_m, &update_f}) {
      const Summary& sum = s->summary();
      hash.add(f, 4);
      for (std::uint32_t i = 0; i < s->decision_count(); ++i) {
        hash.add(s->decisions()[i].point);
        hash.add(static_cast<std::uint64_t>(s->decisions()[i].verdict), 1);
        hash.add_signed(s->decisions()[i].flow);
      }
      hash.add_signed(sum.total_cost);
      hash.add(sum.returning_permille, 4);
      hash.add(sum.decided_newest ? 1 : 0, 1);
      (sum.decided_newest ? newest : window_decisions) += 1;
      culled += sum.culled;
    }
  }
  EXPECT_GT(newest, 0u);  // both scopes chosen: to the newest, back, to the newest again
  EXPECT_GT(window_decisions, 0u);
  EXPECT_GE(switches, 3u) << newest << " newest, " << window_decisions << " window";
  EXPECT_GT(culled, 0u);
  EXPECT_GT(shared, 0u);  // the share took part of the count
  EXPECT_EQ(hash.value(), kExpectedAutoScopeHash)
      << "auto scope decision hash " << hex(hash.value()) << " (expected " << hex(kExpectedAutoScopeHash) << ")";
}

}  // namespace
}  // namespace keepless::core
