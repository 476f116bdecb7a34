// IncrementalNetwork against PaperNetwork built from nothing on the same
// window, structure first (points by id with their views and evaluation,
// pairs, pair arcs, m), then decisions through Sparsifier: over long slides
// with ascending point ids (the ranking edited in place, its buffer wrapped
// many times, the block arena compacted many times) and with new ids below
// old ones (the ranking merged); a keyframe replaced under its id; the same
// contents from another Window (matched by content, not by stamp).

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "keepless/core/incremental_network.hpp"
#include "keepless/core/network.hpp"
#include "keepless/core/sparsifier.hpp"

namespace keepless::core {
namespace {

struct Frame {
  Keyframe keyframe;
  std::vector<Observation> observations;
};

// Points tracked over runs of keyframes on a coarse lattice (box borders hit
// exactly, N repeats). Ids ascend, or with `lower_ids` a share of new points
// takes an id below every current one.
class Slides {
 public:
  Slides(std::uint64_t seed, std::uint32_t per_frame, bool lower_ids)
      : rng_(seed), per_frame_(per_frame), lower_ids_(lower_ids) {}

  Frame next() {
    Frame f;
    f.keyframe.id = 5 + 2 * frame_++;
    f.keyframe.centre[0] = static_cast<double>(rng_() % 7);
    f.keyframe.centre[2] = static_cast<double>(frame_ % 3);
    std::vector<Track> kept;
    for (Track& t : tracks_) {
      if (t.life-- > 0 && rng_() % 10 != 0) kept.push_back(t);
    }
    tracks_ = kept;
    const std::uint32_t fresh =
        per_frame_ / 3 + static_cast<std::uint32_t>(rng_() % (per_frame_ / 3 + 1));
    for (std::uint32_t i = 0; i < fresh; ++i) {
      Track t;
      t.id = lower_ids_ && rng_() % 5 == 0 ? low_id_-- : high_id_++;
      t.u = static_cast<std::int64_t>(rng_() % 60);
      t.v = static_cast<std::int64_t>(rng_() % 60);
      t.life = static_cast<std::int64_t>(rng_() % 12);
      tracks_.push_back(t);
    }
    for (Track& t : tracks_) {
      t.u += static_cast<std::int64_t>(rng_() % 3) - 1;
      t.v += static_cast<std::int64_t>(rng_() % 3) - 1;
      f.observations.push_back(
          {t.id, 8.0 * static_cast<double>(t.u), 6.0 * static_cast<double>(t.v)});
    }
    return f;
  }

 private:
  struct Track {
    PointId id = 0;
    std::int64_t u = 0, v = 0, life = 0;
  };
  std::mt19937_64 rng_;
  std::uint32_t per_frame_;
  bool lower_ids_;
  std::uint64_t frame_ = 0;
  PointId high_id_ = 1000000, low_id_ = 999999;
  std::vector<Track> tracks_;
};

Status add(Window& w, const Frame& f) {
  return w.add_keyframe(f.keyframe, f.observations.data(),
                        static_cast<std::uint32_t>(f.observations.size()));
}

::testing::AssertionResult same_network(const IncrementalNetwork& inc, const PaperNetwork& ref) {
  if (inc.point_count() != ref.point_count() || inc.evaluated_count() != ref.evaluated_count() ||
      inc.pair_count() != ref.pair_count() || inc.pair_arc_count() != ref.pair_arc_count() ||
      inc.max_views() != ref.max_views()) {
    return ::testing::AssertionFailure()
           << "points " << inc.point_count() << "/" << ref.point_count() << ", evaluated "
           << inc.evaluated_count() << "/" << ref.evaluated_count() << ", pairs "
           << inc.pair_count() << "/" << ref.pair_count() << ", pair arcs " << inc.pair_arc_count()
           << "/" << ref.pair_arc_count() << ", m " << inc.max_views() << "/" << ref.max_views();
  }
  std::uint32_t evaluated = 0;
  for (std::uint32_t i = 0; i < ref.point_count(); ++i) {
    if (inc.point_id(i) != ref.point_id(i) || inc.point_views(i) != ref.point_views(i) ||
        (inc.point_source_arc(i) >= 0) != (ref.point_source_arc(i) >= 0)) {
      return ::testing::AssertionFailure()
             << "point " << i << ": id " << inc.point_id(i) << "/" << ref.point_id(i) << ", views "
             << inc.point_views(i) << "/" << ref.point_views(i);
    }
    if (inc.point_source_arc(i) >= 0 &&
        inc.canonical_order()[evaluated++] != inc.point_source_arc(i)) {
      return ::testing::AssertionFailure() << "canonical order differs at point " << i;
    }
  }
  return ::testing::AssertionSuccess();
}

::testing::AssertionResult same_decisions(const Sparsifier& inc, const Sparsifier& ref) {
  if (inc.decision_count() != ref.decision_count()) return ::testing::AssertionFailure() << "count";
  for (std::uint32_t i = 0; i < ref.decision_count(); ++i) {
    const PointDecision& a = inc.decisions()[i];
    const PointDecision& b = ref.decisions()[i];
    if (a.point != b.point || a.verdict != b.verdict || a.flow != b.flow) {
      return ::testing::AssertionFailure()
             << "point " << b.point << ": flow " << a.flow << "/" << b.flow;
    }
  }
  if (inc.summary().total_cost != ref.summary().total_cost)
    return ::testing::AssertionFailure() << "cost";
  return ::testing::AssertionSuccess();
}

// Slides a window of `k` over `steps` keyframes; every window's network and
// decisions must be PaperNetwork's and run()'s.
void slide(std::uint64_t seed, bool lower_ids, std::uint32_t k, std::uint32_t steps) {
  const Capacities caps{k, 800, 2400, 8000};  // tight: the arena compacts every few dozen slides
  Slides slides(seed, 60, lower_ids);
  Window window(caps);
  IncrementalNetwork inc(caps);
  solver::MinCostFlow inc_solver(IncrementalNetwork::solver_capacity(caps));
  PaperNetwork ref(caps);
  solver::MinCostFlow ref_solver(PaperNetwork::solver_capacity(caps));
  Sparsifier inc_path(caps, Params{}, SolveMode::kIncremental);
  Sparsifier ref_path(caps, Params{});
  for (std::uint32_t step = 0; step < steps; ++step) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed << " step " << step);
    if (window.keyframe_count() == k) {
      ASSERT_EQ(window.remove_keyframe(window.keyframe(0).id), Status::kOk);
    }
    ASSERT_EQ(add(window, slides.next()), Status::kOk);
    ASSERT_EQ(inc.update(window, Params{}, inc_solver), Status::kOk);
    ASSERT_EQ(ref.build(window, Params{}, ref_solver), Status::kOk);
    ASSERT_TRUE(same_network(inc, ref));
    if (step > 0) {
      EXPECT_FALSE(inc.changes().rebuilt);
      EXPECT_EQ(inc.changes().frames_added, 1u);
      EXPECT_EQ(inc.changes().arcs_recosted, 0u);
    }
    if (step % 10 == 0) {
      ASSERT_EQ(inc_path.update(window), Status::kOk);
      ASSERT_EQ(ref_path.run(window), Status::kOk);
      ASSERT_TRUE(same_decisions(inc_path, ref_path));
    }
  }
}

TEST(IncrementalNetwork, LongSlidesWithAscendingIds) {
  for (std::uint64_t seed = 1; seed <= 2 && !HasFailure(); ++seed) slide(seed, false, 8, 300);
}

TEST(IncrementalNetwork, LongSlidesWithNewIdsBelowOldOnes) {
  for (std::uint64_t seed = 1; seed <= 2 && !HasFailure(); ++seed) slide(seed, true, 8, 200);
}

TEST(IncrementalNetwork, KeyframeReplacedUnderItsId) {
  const Capacities caps{6, 2000, 6000, 30000};
  Slides slides(9, 50, false);
  std::vector<Frame> frames;
  for (int i = 0; i < 6; ++i) frames.push_back(slides.next());
  Window window(caps);
  for (const Frame& f : frames) ASSERT_EQ(add(window, f), Status::kOk);
  IncrementalNetwork inc(caps);
  solver::MinCostFlow inc_solver(IncrementalNetwork::solver_capacity(caps));
  PaperNetwork ref(caps);
  solver::MinCostFlow ref_solver(PaperNetwork::solver_capacity(caps));
  ASSERT_EQ(inc.update(window, Params{}, inc_solver), Status::kOk);
  // The middle keyframe again, its keypoints moved and half its points gone.
  Frame changed = frames[3];
  changed.observations.resize(changed.observations.size() / 2);
  for (Observation& o : changed.observations) o.u += 3.0;
  ASSERT_EQ(window.remove_keyframe(changed.keyframe.id), Status::kOk);
  ASSERT_EQ(add(window, changed), Status::kOk);
  ASSERT_EQ(inc.update(window, Params{}, inc_solver), Status::kOk);
  EXPECT_EQ(inc.changes().frames_removed, 1u);
  EXPECT_EQ(inc.changes().frames_added, 1u);
  ASSERT_EQ(ref.build(window, Params{}, ref_solver), Status::kOk);
  EXPECT_TRUE(same_network(inc, ref));
  // Only its centre changed: a new keyframe too (c_b depends on it).
  Frame moved = changed;
  moved.keyframe.centre[1] += 1.0;
  ASSERT_EQ(window.remove_keyframe(moved.keyframe.id), Status::kOk);
  ASSERT_EQ(add(window, moved), Status::kOk);
  ASSERT_EQ(inc.update(window, Params{}, inc_solver), Status::kOk);
  EXPECT_EQ(inc.changes().frames_added, 1u);
  ASSERT_EQ(ref.build(window, Params{}, ref_solver), Status::kOk);
  EXPECT_TRUE(same_network(inc, ref));
  // same_network compares the structure; the costs (c_b moved) show in the optimum.
  ASSERT_EQ(inc_solver.solve(inc.source(), inc.sink()), solver::Status::kOptimal);
  ASSERT_EQ(ref_solver.solve(ref.source(), ref.sink()), solver::Status::kOptimal);
  EXPECT_EQ(inc_solver.flow_value(), ref_solver.flow_value());
  EXPECT_EQ(inc_solver.total_cost(), ref_solver.total_cost());
}

TEST(IncrementalNetwork, SameContentsFromAnotherWindowChangeNothing) {
  const Capacities caps{6, 2000, 6000, 30000};
  Slides slides(11, 50, false);
  std::vector<Frame> frames;
  for (int i = 0; i < 6; ++i) frames.push_back(slides.next());
  Window first(caps), second(caps);
  for (const Frame& f : frames) {
    ASSERT_EQ(add(first, f), Status::kOk);
    ASSERT_EQ(add(second, f), Status::kOk);
  }
  for (std::uint32_t s = 0; s < 6; ++s)
    EXPECT_NE(first.keyframe_stamp(s), second.keyframe_stamp(s));
  IncrementalNetwork inc(caps);
  solver::MinCostFlow solver(IncrementalNetwork::solver_capacity(caps));
  ASSERT_EQ(inc.update(first, Params{}, solver), Status::kOk);
  ASSERT_EQ(inc.update(second, Params{}, solver), Status::kOk);
  const IncrementalNetwork::Changes& c = inc.changes();
  EXPECT_FALSE(c.rebuilt);
  EXPECT_EQ(
      c.frames_added + c.frames_removed + c.points_added + c.points_removed + c.points_changed, 0u);
  EXPECT_EQ(c.arcs_added + c.arcs_retired, 0u);
  PaperNetwork ref(caps);
  solver::MinCostFlow ref_solver(PaperNetwork::solver_capacity(caps));
  ASSERT_EQ(ref.build(second, Params{}, ref_solver), Status::kOk);
  EXPECT_TRUE(same_network(inc, ref));
}

}  // namespace
}  // namespace keepless::core
