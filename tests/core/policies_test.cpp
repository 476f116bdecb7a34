// The decision policies (Params::scope, Params::coverage_floor) and the cost
// models (Params::cost_model) against the independent reference in
// tests/support (reference_sparsifier.hpp, reference_policies.hpp): seeded
// random windows full of ties, both starts, run() and update() over sliding
// windows; plus the cost functions at their bin edges and the floor's and
// the scope's guarantees on hand-made windows.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <tuple>
#include <memory>
#include <vector>

#include "case_count.hpp"
#include "decision_checks.hpp"
#include "flow_certificate.hpp"
#include "keepless/core/costs.hpp"
#include "keepless/core/sparsifier.hpp"
#include "random_window.hpp"
#include "reference_policies.hpp"
#include "reference_sparsifier.hpp"

namespace keepless::core {
namespace {

const Capacities kCaps{16, 2048, 8192, 32768, 4096};

::testing::AssertionResult agrees(const Sparsifier& s, const test::RefResult& ref) {
  const Summary& sum = s.summary();
  std::uint32_t verdicts[3];
  if (auto match = test::decisions_match(s, ref, verdicts); !match) return match;
  const std::uint32_t kept = verdicts[0], culled = verdicts[1], skipped = verdicts[2];
  if (sum.max_flow != ref.max_flow || sum.total_cost != ref.total_cost) {
    return ::testing::AssertionFailure() << "max flow " << sum.max_flow << " vs " << ref.max_flow
                                         << ", cost " << sum.total_cost << " vs " << ref.total_cost;
  }
  if (sum.kept != kept || sum.culled != culled || sum.skipped != skipped ||
      sum.evaluated != ref.evaluated || sum.out_of_scope != ref.out_of_scope ||
      sum.floor_keyframes != ref.floor_keyframes || sum.floor_promoted != ref.floor_promoted ||
      sum.floor_short != ref.floor_short) {
    return ::testing::AssertionFailure()
           << "summary: kept " << sum.kept << "/" << kept << " culled " << sum.culled << "/"
           << culled << " out of scope " << sum.out_of_scope << "/" << ref.out_of_scope
           << " floor " << sum.floor_keyframes << "/" << ref.floor_keyframes << " promoted "
           << sum.floor_promoted << "/" << ref.floor_promoted << " short " << sum.floor_short
           << "/" << ref.floor_short;
  }
  return ::testing::AssertionSuccess();
}

// The floor's guarantee, from the window itself: every keyframe has at least
// L evaluated points not culled, or none of its evaluated points is culled.
::testing::AssertionResult floor_holds(const Window& w, const Sparsifier& s) {
  const std::uint32_t floor = s.params().coverage_floor;
  std::map<PointId, std::uint32_t> views;
  for (std::uint32_t k = 0; k < w.keyframe_count(); ++k) {
    for (std::uint32_t i = 0; i < w.observation_count(k); ++i) ++views[w.observations(k)[i].point];
  }
  std::map<PointId, Verdict> verdict;
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    verdict[s.decisions()[i].point] = s.decisions()[i].verdict;
  }
  for (std::uint32_t k = 0; k < w.keyframe_count(); ++k) {
    std::uint32_t covered = 0, culled = 0;
    for (std::uint32_t i = 0; i < w.observation_count(k); ++i) {
      const PointId p = w.observations(k)[i].point;
      if (views[p] < 2) continue;
      (verdict[p] == Verdict::kCull ? culled : covered) += 1;
    }
    if (covered < floor && culled > 0) {
      return ::testing::AssertionFailure() << "keyframe slot " << k << ": " << covered
                                           << " covered, " << culled << " culled, floor " << floor;
    }
  }
  return ::testing::AssertionSuccess();
}

// Sparsifiers by their parameters, reused while they stay in the cache. At
// most kHeld at once, the oldest dropped first: almost every case draws new
// parameters, and each Sparsifier holds its capacities (a few MB), so an
// unbounded cache kept one per case and start: 9 GB resident on x86-64, and
// past a 32-bit board's address space (std::bad_alloc on armhf).
class Cache {
 public:
  Sparsifier& get(const Params& p, Start start, SolveMode mode = SolveMode::kFromScratch) {
    const Key key = std::make_tuple(p.pair_capacity, p.theta, p.box_width, p.box_height,
                                    static_cast<int>(p.scope), p.coverage_floor,
                                    static_cast<int>(p.cost_model), p.image_width,
                                    static_cast<int>(start), static_cast<int>(mode));
    auto found = cache_.find(key);
    if (found != cache_.end()) return *found->second;
    if (order_.size() == kHeld) {
      cache_.erase(order_.front());
      order_.pop_front();
    }
    order_.push_back(key);
    auto& slot = cache_[key];
    slot = std::make_unique<Sparsifier>(kCaps, p, mode, start);
    return *slot;
  }

 private:
  static constexpr std::size_t kHeld = 16;
  using Key = std::tuple<std::int64_t, double, std::int32_t, std::int32_t, int, std::uint32_t, int,
                         std::int32_t, int, int>;
  std::map<Key, std::unique_ptr<Sparsifier>> cache_;
  std::deque<Key> order_;  // insertion order, oldest first
};

TEST(Policies, RandomWindowsMatchReference) {
  Cache cache;
  Window window(kCaps);
  std::uint32_t bound = 0, promoted = 0, scoped = 0, culled = 0, by_model[3] = {0, 0, 0};
  for (std::uint64_t seed = 1; seed <= test::cases(900) && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(seed);
    test::random_policies(c, seed);
    ASSERT_TRUE(test::load(window, c.frames)) << "seed " << seed;
    const test::RefResult ref = test::reference_decide(c.frames, c.params);
    for (Start start : {Start::kClosedForm, Start::kZeroFlow}) {
      Sparsifier& s = cache.get(c.params, start);
      ASSERT_EQ(s.run(window), Status::kOk) << "seed " << seed;
      ASSERT_TRUE(agrees(s, ref)) << "seed " << seed << " start " << static_cast<int>(start)
                                  << " model " << static_cast<int>(c.params.cost_model);
      ASSERT_TRUE(floor_holds(window, s)) << "seed " << seed;
      if (start == Start::kClosedForm) {
        ASSERT_TRUE(s.solver().stats().certified) << "seed " << seed;
        if (seed % 7 == 0) {
          ASSERT_TRUE(test::flow_certificate(s.solver(), s.network().source(), s.network().sink()));
        }
      }
    }
    bound += ref.floor_keyframes;
    promoted += ref.floor_promoted;
    scoped += ref.out_of_scope;
    for (const auto& p : ref.points) culled += p.verdict == Verdict::kCull;
    ++by_model[static_cast<int>(c.params.cost_model)];
  }
  // The cases the check is for.
  EXPECT_GT(bound, test::cases(200));
  EXPECT_GT(promoted, test::cases(500));
  EXPECT_GT(scoped, test::cases(500));
  EXPECT_GT(culled, test::cases(1000));
  for (std::uint32_t n : by_model) EXPECT_GT(n, test::cases(250));
}

// A window sliding over a stream: update() on the incremental network (both
// starts) decides exactly what run() does, and both what the reference does.
TEST(Policies, UpdateMatchesRunAndReference) {
  std::uint32_t windows = 0, promoted = 0;
  for (std::uint64_t seed = 1; seed <= 60 && !HasFailure(); ++seed) {
    test::RandomCase c = test::random_case(7000 + seed, 16, 200);
    test::random_policies(c, 7000 + seed);
    if (seed % 4 == 0) c.params.coverage_floor = 20;  // binds often
    const std::uint32_t size = 3 + static_cast<std::uint32_t>(seed % 6);
    const auto check = [&](const Window& window, const Sparsifier& run, const Sparsifier& closed,
                           const Sparsifier& zero, const test::RefKeyframe& f) {
      ASSERT_TRUE(test::same_decisions(run, closed)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(test::same_decisions(run, zero)) << "seed " << seed << " keyframe " << f.id;
      ASSERT_TRUE(agrees(run, test::reference_decide(test::ref_frames_of(window), c.params)))
          << "seed " << seed << " keyframe " << f.id;
      ++windows;
      promoted += run.summary().floor_promoted;
    };
    test::slide_run_and_update(kCaps, c, size, seed % 3 == 0, check);
  }
  EXPECT_GT(windows, 500u);
  EXPECT_GT(promoted, 100u);
}

// A keyframe carrying unmapped keypoints matches the network's copy only by
// its stamp: a window rebuilt keyframe by keyframe (new stamps) still gives
// update() the decisions of run().
TEST(Policies, RebuiltWindowWithUnmappedKeypoints) {
  test::RandomCase c = test::random_case(4242, 10, 120);
  test::random_policies(c, 4242);
  c.params.cost_model = CostModel::kAuthors;
  Window a(kCaps), b(kCaps);
  ASSERT_TRUE(test::load(a, c.frames));
  Sparsifier run(kCaps, c.params);
  Sparsifier inc(kCaps, c.params, SolveMode::kIncremental);
  ASSERT_EQ(inc.update(a), Status::kOk);
  // The same keyframes added afresh, one with other unmapped keypoints.
  c.frames[0].unmapped.assign(60, {12.0, 18.0});
  ASSERT_TRUE(test::load(b, c.frames));
  ASSERT_EQ(inc.update(b), Status::kOk);
  ASSERT_EQ(run.run(b), Status::kOk);
  EXPECT_TRUE(test::same_decisions(run, inc));
  EXPECT_TRUE(agrees(run, test::reference_decide(c.frames, c.params)));
}

// --- the cost functions -------------------------------------------------------

TEST(CostModels, AuthorsSpatialBins) {
  const struct {
    std::uint64_t a, b;
    std::int64_t cost;
  } cases[] = {{0, 0, 0},   {9, 11, 0},  {10, 10, 2}, {1, 499, 2}, {20, 25, 4},
               {1, 1199, 4}, {30, 40, 6}, {1000, 1000, 6}};
  for (const auto& c : cases) {
    EXPECT_EQ(authors_spatial_cost(c.a, c.b), c.cost) << c.a << " x " << c.b;
    EXPECT_EQ(test::ref_authors_spatial_cost(c.a, c.b), c.cost);
  }
}

TEST(CostModels, AuthorsBaselineSteps) {
  const double origin[3] = {0, 0, 0};
  const struct {
    double d;
    std::int64_t cost;
  } cases[] = {{0, 100}, {9.999, 100}, {10, 90}, {55, 50}, {99.99, 10}, {100, 0}, {250, 0}};
  for (const auto& c : cases) {
    const double at[3] = {0, c.d, 0};
    EXPECT_EQ(authors_baseline_cost(origin, at), c.cost) << "d = " << c.d;
    EXPECT_EQ(test::ref_authors_baseline_cost(origin, at), c.cost);
  }
}

// ORB-SLAM2's grid: 10 x 10 pixel cells on a 640 x 480 image; the 3x3 cells
// around a keypoint's (rounded) cell, clamped at the border; unmapped
// keypoints count, keypoints off the image do not.
TEST(CostModels, GridNeighbours) {
  const Observation obs[] = {{1, 100, 100}, {2, 109, 100}, {3, 115, 100}, {4, 0, 0}, {5, 639, 479}};
  const Keypoint unmapped[] = {{91, 91}, {121, 100}, {-20, 0}, {5, 5}, {700, 479}};
  Keyframe kf;
  kf.unmapped = unmapped;
  kf.unmapped_count = 5;
  std::vector<std::uint32_t> cells(kGridColumns * kGridRows), out(5);
  grid_neighbours(kf, obs, 5, 640, 480, cells.data(), out.data());
  // Cells: (10,10), (11,10), (12,10) [11.5 rounds away], (0,0), (64,48) off
  // the grid; unmapped (9,9), (12,10), off, (1,1) [0.5 rounds away], off.
  EXPECT_EQ(out[0], 3u);  // itself, 109, (9,9)
  EXPECT_EQ(out[1], 4u);  // 100, itself, 115, (12,10)
  EXPECT_EQ(out[2], 3u);  // 109, itself, (12,10)
  EXPECT_EQ(out[3], 2u);  // itself, (1,1)
  EXPECT_EQ(out[4], 0u);  // its cell is off the grid; (63,47) is empty
  test::RefKeyframe ref;
  for (const auto& o : obs) ref.observations.push_back({o.point, o.u, o.v});
  for (const auto& k : unmapped) ref.unmapped.push_back({k.u, k.v});
  Params p;
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(test::ref_grid_neighbours(ref, i, p), out[i]);
}

Keyframe camera() {
  Keyframe kf;
  kf.fx = 520.9;
  kf.fy = 521.0;
  kf.cx = 325.1;
  kf.cy = 249.7;
  return kf;
}

// A point alone in one corner carries much of the pose's information; one of
// a tight crowd little. Levels are invariant to reparametrising the pose:
// scaling every depth by 2 rescales the translation columns only.
TEST(CostModels, InformationLevels) {
  std::vector<Observation> obs;
  PointId id = 1;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      obs.push_back({id++, 300.0 + 4.0 * i, 200.0 + 4.0 * j, 2.0 + 0.1 * ((i * 7 + j) % 5)});
    }
  }
  obs.push_back({id++, 20.0, 460.0, 3.0});   // alone
  obs.push_back({id++, 620.0, 30.0, 6.0});   // alone
  obs.push_back({id++, 600.0, 450.0, 1.5});  // alone
  obs.push_back({id++, 50.0, 40.0, 0.0});    // no depth
  const Keyframe kf = camera();
  std::vector<std::uint32_t> levels(obs.size());
  information_levels(kf, obs.data(), static_cast<std::uint32_t>(obs.size()), levels.data());
  for (std::size_t i = 100; i < 103; ++i) EXPECT_EQ(levels[i], 0u) << i;
  std::uint32_t crowd_worst = 0;
  for (std::size_t i = 0; i < 100; ++i) crowd_worst = std::max(crowd_worst, levels[i]);
  EXPECT_EQ(crowd_worst, 4u);
  EXPECT_EQ(levels[103], kNeutralInformationLevel);

  std::vector<Observation> deeper = obs;
  for (auto& o : deeper) o.depth *= 2.0;
  std::vector<std::uint32_t> again(obs.size());
  information_levels(kf, deeper.data(), static_cast<std::uint32_t>(deeper.size()), again.data());
  EXPECT_EQ(again, levels);

  test::RefKeyframe ref;
  ref.fx = kf.fx;
  ref.fy = kf.fy;
  ref.cx = kf.cx;
  ref.cy = kf.cy;
  for (const auto& o : obs) ref.observations.push_back({o.point, o.u, o.v, o.depth});
  const auto expected = test::ref_information_levels(ref);
  for (std::size_t i = 0; i < obs.size(); ++i) EXPECT_EQ(levels[i], expected[i]) << i;
}

TEST(CostModels, InformationNeutralWithoutIntrinsicsOrRank) {
  std::vector<Observation> obs = {{1, 100, 100, 2.0}, {2, 200, 100, 2.0}, {3, 300, 300, 0.0}};
  std::vector<std::uint32_t> levels(3);
  Keyframe no_intrinsics;
  information_levels(no_intrinsics, obs.data(), 3, levels.data());
  EXPECT_EQ(levels, std::vector<std::uint32_t>(3, kNeutralInformationLevel));
  // Two points with depth: rank 4 < 6, singular.
  information_levels(camera(), obs.data(), 3, levels.data());
  EXPECT_EQ(levels, std::vector<std::uint32_t>(3, kNeutralInformationLevel));
}

// --- the policies on hand-made windows ------------------------------------------

// Three keyframes; M = 1 keeps one point per pair, so most points are culled.
void three_keyframes(Window& w) {
  w.clear();
  for (KeyframeId k = 0; k < 3; ++k) {
    Keyframe kf;
    kf.id = 10 + k;
    kf.centre[0] = static_cast<double>(k);
    std::vector<Observation> obs;
    for (PointId p = 0; p < 8; ++p) {
      if (k == 2 && p >= 6) continue;  // the newest does not see points 6 and 7
      obs.push_back({p, 20.0 * static_cast<double>(p), 10.0});
    }
    if (k == 0) obs.push_back({100, 5.0, 5.0});  // seen once: skipped
    ASSERT_EQ(w.add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size())), Status::kOk);
  }
}

TEST(Policies, FloorPromotesNearestFirst) {
  Window w(kCaps);
  three_keyframes(w);
  Params p;
  p.pair_capacity = 1;
  Sparsifier plain(kCaps, p);
  ASSERT_EQ(plain.run(w), Status::kOk);
  p.coverage_floor = 4;
  Sparsifier floored(kCaps, p);
  ASSERT_EQ(floored.run(w), Status::kOk);
  const Summary& s = floored.summary();
  EXPECT_GT(plain.summary().culled, floored.summary().culled);
  EXPECT_EQ(s.floor_keyframes, 1u);  // slot 0 lifts the others too
  EXPECT_EQ(s.floor_promoted, 4u - plain.summary().kept);
  EXPECT_EQ(s.floor_short, 0u);
  EXPECT_TRUE(floor_holds(w, floored));
  // A floor above every keyframe's points keeps everything evaluated.
  p.coverage_floor = 100;
  Sparsifier all(kCaps, p);
  ASSERT_EQ(all.run(w), Status::kOk);
  EXPECT_EQ(all.summary().culled, 0u);
  EXPECT_EQ(all.summary().floor_short, 3u);
  EXPECT_TRUE(agrees(all, test::reference_decide(test::ref_frames_of(w), p)));
}

TEST(Policies, NewestScopeSkipsTheRest) {
  Window w(kCaps);
  three_keyframes(w);
  Params p;
  p.pair_capacity = 1;
  p.scope = Scope::kNewest;
  Sparsifier s(kCaps, p);
  ASSERT_EQ(s.run(w), Status::kOk);
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    const PointDecision& d = s.decisions()[i];
    if (d.point >= 6) {
      EXPECT_EQ(d.verdict, Verdict::kSkip) << d.point;
    }
  }
  EXPECT_EQ(s.summary().out_of_scope, 2u);
  EXPECT_EQ(s.summary().skipped, 3u);
  EXPECT_TRUE(agrees(s, test::reference_decide(test::ref_frames_of(w), p)));
}

// Keyframe f of a stream makes 20 points and sees the previous keyframe's
// 20 again: only keyframe f's scope (A = 0) decides keyframe f - 1's points.
void add_chained(Window& w, std::uint32_t f, std::uint32_t window_keyframes) {
  if (w.keyframe_count() == window_keyframes) {
    ASSERT_EQ(w.remove_keyframe(w.keyframe(0).id), Status::kOk);
  }
  std::vector<Observation> obs;
  for (std::uint32_t i = 0; i < 20; ++i) obs.push_back({PointId{100} * f + i, 10.0 * i, 10.0 * i, 0});
  for (std::uint32_t i = 0; f > 0 && i < 20; ++i) {
    obs.push_back({PointId{100} * (f - 1) + i, 10.0 * i + 3, 10.0 * i, 0});
  }
  Keyframe kf;
  kf.id = 1000 + f;
  kf.centre[0] = f;
  ASSERT_EQ(w.add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size())), Status::kOk);
}

void count_decided(const Sparsifier& s, std::map<PointId, int>* decided) {
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    if (s.decisions()[i].verdict != Verdict::kSkip) ++(*decided)[s.decisions()[i].point];
  }
}

struct LateClock : solver::Clock {
  std::uint64_t now_ns() const override { return 100; }
};

// A missed turn (an update() deferred on its deadline, or a keyframe the
// caller answered without a call, note_undecided()) passes to the next call
// that decides: it decides the missed keyframes' points too, and every point
// the never-missing Sparsifier decides is decided. After it, and when no
// turn is missed, the decisions are the never-missing one's.
TEST(Policies, NewestScopeCatchesUpAMissedTurn) {
  for (std::uint32_t maturity : {0u, 2u}) {
    for (int how = 0; how < 3; ++how) {  // deferred update(), note_undecided() + update(), + run()
      Params p;
      p.scope = Scope::kNewest;
      p.pair_capacity = 3;
      p.maturity_keyframes = maturity;
      const Capacities caps{6, 2000, 8000, 20000, 0};
      Sparsifier all(caps, p, SolveMode::kIncremental);
      Sparsifier missing(caps, p, how == 2 ? SolveMode::kFromScratch : SolveMode::kIncremental);
      Window w(caps);
      std::map<PointId, int> by_all, by_missing;
      const LateClock late;
      for (std::uint32_t f = 0; f < 14; ++f) {
        add_chained(w, f, 5);
        ASSERT_EQ(all.update(w), Status::kOk);
        EXPECT_EQ(all.summary().caught_up, 0u);
        count_decided(all, &by_all);
        if (f == 6 || f == 7) {  // two turns in a row
          if (how == 0) {
            solver::Budget b;
            b.clock = &late;
            b.deadline_ns = 50;
            ASSERT_EQ(missing.update(w, b), Status::kBudgetExhausted);
            ASSERT_TRUE(missing.deferred());
          } else {
            missing.note_undecided();
          }
          continue;
        }
        ASSERT_EQ(how == 2 ? missing.run(w) : missing.update(w), Status::kOk);
        count_decided(missing, &by_missing);
        EXPECT_EQ(missing.summary().caught_up, f == 8 ? 2u : 0u) << "keyframe " << f;
        if (f == 8) continue;
        // Not catching up: the same scope, so the same decisions.
        ASSERT_EQ(missing.decision_count(), all.decision_count());
        for (std::uint32_t i = 0; i < all.decision_count(); ++i) {
          EXPECT_EQ(missing.decisions()[i].verdict, all.decisions()[i].verdict) << f;
          EXPECT_EQ(missing.decisions()[i].flow, all.decisions()[i].flow) << f;
        }
      }
      EXPECT_FALSE(by_all.empty());
      for (const auto& [point, n] : by_all) {
        EXPECT_EQ(by_missing.count(point), 1u) << "point " << point << " never decided, maturity " << maturity;
      }
      for (const auto& [point, n] : by_missing) EXPECT_EQ(by_all.count(point), 1u) << point;
    }
  }
}

// When the last keyframe decided left the window, the catch-up decides
// every keyframe up to the scope's; a new map (forget_history) forgets.
TEST(Policies, NewestScopeCatchesUpFromTheOldestWhenTheLastDecidedLeft) {
  Params p;
  p.scope = Scope::kNewest;
  p.pair_capacity = 3;
  const Capacities caps{6, 2000, 8000, 20000, 0};
  Sparsifier s(caps, p);
  Window w(caps);
  for (std::uint32_t f = 0; f < 3; ++f) {
    add_chained(w, f, 5);
    ASSERT_EQ(s.run(w), Status::kOk);
  }
  for (std::uint32_t f = 3; f < 9; ++f) {  // keyframe 1002, the last decided, leaves
    add_chained(w, f, 5);
    s.note_undecided();
  }
  add_chained(w, 9, 5);
  ASSERT_EQ(s.run(w), Status::kOk);
  EXPECT_EQ(s.summary().caught_up, 4u);  // slots 0 .. 3 besides the newest
  EXPECT_EQ(s.summary().out_of_scope, 0u);
  EXPECT_EQ(s.summary().skipped, 40u);  // seen once: keyframe 9's own, and 400.. (keyframe 4 left)
  s.note_undecided();
  s.forget_history();  // a new map: nothing missed
  add_chained(w, 10, 5);
  ASSERT_EQ(s.run(w), Status::kOk);
  EXPECT_EQ(s.summary().caught_up, 0u);
}

TEST(Policies, InvalidParams) {
  Params p;
  p.cost_model = CostModel::kAuthors;
  p.image_width = 0;
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
  p = Params{};
  p.cost_model = static_cast<CostModel>(7);
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
  p = Params{};
  p.scope = static_cast<Scope>(9);
  EXPECT_EQ(Sparsifier::validate(p), Status::kInvalidArgument);
}

TEST(Policies, OptionNames) {
  Scope scope = Scope::kWindow;
  EXPECT_TRUE(parse_scope("newest", &scope));
  EXPECT_EQ(scope, Scope::kNewest);
  EXPECT_FALSE(parse_scope("Newest", &scope));
  EXPECT_EQ(scope, Scope::kNewest);
  CostModel model = CostModel::kPaper;
  for (CostModel m : {CostModel::kPaper, CostModel::kAuthors, CostModel::kInformation}) {
    EXPECT_TRUE(parse_cost_model(to_string(m), &model));
    EXPECT_EQ(model, m);
  }
  EXPECT_FALSE(parse_cost_model("", &model));
  EXPECT_STREQ(to_string(Scope::kWindow), "window");
}

TEST(Policies, WindowRefusesUnmappedBeyondCapacity) {
  Capacities caps = kCaps;
  caps.max_unmapped_keypoints = 3;
  Window w(caps);
  const Keypoint k[4] = {{1, 1}, {2, 2}, {3, 3}, {4, 4}};
  Keyframe kf;
  kf.unmapped = k;
  kf.unmapped_count = 4;
  EXPECT_EQ(w.add_keyframe(kf, nullptr, 0), Status::kCapacityExceeded);
  kf.unmapped_count = 2;
  ASSERT_EQ(w.add_keyframe(kf, nullptr, 0), Status::kOk);
  kf.id = 2;
  kf.unmapped = k + 2;
  EXPECT_EQ(w.add_keyframe(kf, nullptr, 0), Status::kCapacityExceeded);  // 2 + 2 > 3
  kf.unmapped_count = 1;
  ASSERT_EQ(w.add_keyframe(kf, nullptr, 0), Status::kOk);
  ASSERT_EQ(w.remove_keyframe(0), Status::kOk);  // compacts: slot 0 now holds keyframe 2
  ASSERT_EQ(w.keyframe(0).unmapped_count, 1u);
  EXPECT_EQ(w.keyframe(0).unmapped[0].u, 3.0);
  EXPECT_EQ(w.total_unmapped(), 1u);
  Keyframe bad;
  bad.id = 5;
  bad.fx = std::numeric_limits<double>::infinity();
  EXPECT_EQ(w.add_keyframe(bad, nullptr, 0), Status::kInvalidArgument);
  const Observation nan_depth[] = {{1, 1, 1, std::numeric_limits<double>::quiet_NaN()}};
  bad.fx = 0;
  EXPECT_EQ(w.add_keyframe(bad, nan_depth, 1), Status::kInvalidArgument);
}

}  // namespace
}  // namespace keepless::core
