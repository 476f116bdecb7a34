// Scope::kAuto: the share of window points that come back, smoothed over
// calls, against a reference count (a map from point to its window slots);
// while it is at least a third the decisions are Scope::kNewest's, below it
// Scope::kWindow's, with run() and update() alike.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <numeric>
#include <vector>

#include "decision_checks.hpp"
#include "keepless/core/sparsifier.hpp"

namespace keepless::core {
namespace {

const Capacities kCaps{8, 4000, 16000, 64000, 0};
constexpr std::uint32_t kWindowKeyframes = 8;

// Keyframe f makes 20 points and sees the previous keyframe's 20 again
// (forward motion: none comes back); with `landmarks` it also sees that many
// landmark points on every `period`-th keyframe (period 4: three keyframes
// without them between, so each comes back; 3: two, so none does).
void add_keyframe(Window& w, std::uint32_t f, std::uint32_t landmarks, std::uint32_t period = 4) {
  if (w.keyframe_count() == kWindowKeyframes) {
    ASSERT_EQ(w.remove_keyframe(w.keyframe(0).id), Status::kOk);
  }
  std::vector<Observation> obs;
  for (std::uint32_t i = 0; i < 20; ++i) obs.push_back({PointId{100} * f + i, 30.0 * i, 20.0 * (i % 7), 0});
  for (std::uint32_t i = 0; f > 0 && i < 20; ++i) {
    obs.push_back({PointId{100} * (f - 1) + i, 30.0 * i + 3, 20.0 * (i % 7) + 2, 0});
  }
  for (std::uint32_t i = 0; f % period == 0 && i < landmarks; ++i) {
    obs.push_back({PointId{1000000} + i, 7.0 * i, 300.0 + (i % 5), 0});
  }
  Keyframe kf;
  kf.id = 1000 + f;
  kf.centre[0] = f;
  ASSERT_EQ(w.add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size())), Status::kOk);
}

// The window's evaluated points and those a keyframe saw again after
// kReturnGap or more keyframes without them, from the window's observations.
std::pair<std::uint64_t, std::uint64_t> returning(const Window& w) {
  std::map<PointId, std::vector<std::uint32_t>> slots;
  for (std::uint32_t s = 0; s < w.keyframe_count(); ++s) {
    for (std::uint32_t o = 0; o < w.observation_count(s); ++o) slots[w.observations(s)[o].point].push_back(s);
  }
  std::uint64_t evaluated = 0, returned = 0;
  for (const auto& [point, at] : slots) {
    if (at.size() < 2) continue;
    ++evaluated;
    bool back = false;
    for (std::size_t i = 1; i < at.size(); ++i) back = back || at[i] - at[i - 1] - 1 >= kReturnGap;
    returned += back ? 1 : 0;
  }
  return {evaluated, returned};
}

// A stream with landmarks for keyframes [0, stop), then without: the auto
// scope follows the reference's smoothed share, and decides as the fixed
// scope it chose, by run() and by update(). Returns, per keyframe, whether
// it decided as kNewest.
std::vector<bool> follow_stream(std::uint32_t landmarks, std::uint32_t stop, std::uint32_t keyframes,
                                std::uint32_t period = 4) {
  std::vector<bool> newest_at;
  Params p;
  p.pair_capacity = 4;
  Params fixed_window = p, fixed_newest = p;
  p.scope = Scope::kAuto;
  fixed_newest.scope = Scope::kNewest;
  Sparsifier by_run(kCaps, p), by_update(kCaps, p, SolveMode::kIncremental);
  Sparsifier window_scope(kCaps, fixed_window), newest_scope(kCaps, fixed_newest);
  Window w(kCaps);
  std::uint64_t evaluated_sum = 0, returned_sum = 0;
  for (std::uint32_t f = 0; f < keyframes; ++f) {
    add_keyframe(w, f, f < stop ? landmarks : 0, period);
    EXPECT_EQ(by_run.run(w), Status::kOk);
    EXPECT_EQ(by_update.update(w), Status::kOk);
    EXPECT_EQ(window_scope.run(w), Status::kOk);
    EXPECT_EQ(newest_scope.run(w), Status::kOk);
    const auto [evaluated, returned] = returning(w);
    evaluated_sum = evaluated_sum - evaluated_sum / 16 + evaluated;
    returned_sum = returned_sum - returned_sum / 16 + returned;
    const bool newest = evaluated_sum > 0 && returned_sum * 1000 >= kReturningForNewestPermille * evaluated_sum;
    const Summary& s = by_run.summary();
    EXPECT_EQ(s.returning_permille, evaluated_sum == 0 ? 0 : returned_sum * 1000 / evaluated_sum) << f;
    EXPECT_EQ(s.decided_newest, newest) << f;
    EXPECT_TRUE(test::same_decisions(by_run, by_update)) << f;
    EXPECT_EQ(by_update.summary().returning_permille, s.returning_permille) << f;
    EXPECT_TRUE(test::same_decisions(by_run, newest ? newest_scope : window_scope)) << f;
    newest_at.push_back(s.decided_newest);
  }
  return newest_at;
}

// Forward motion; a tenth of the points coming back; landmarks back after
// only two keyframes without them (not returning points): the window throughout.
TEST(AutoScope, TheWindowWhereFewPointsComeBack) {
  for (const auto& [landmarks, period] : {std::pair{0u, 4u}, {10u, 4u}, {100u, 3u}}) {
    const std::vector<bool> newest = follow_stream(landmarks, 60, 60, period);
    EXPECT_EQ(std::count(newest.begin(), newest.end(), true), 0) << landmarks << " landmarks every " << period;
  }
}

// 100 landmarks against about 140 chained points: the share passes a third
// once they have come back, and falls below it some keyframes after they stop.
TEST(AutoScope, ReturningPointsDecideTheNewestKeyframeWhileTheyReturn) {
  const std::vector<bool> newest = follow_stream(100, 20, 60);
  EXPECT_FALSE(newest.front());
  EXPECT_TRUE(newest[19]);
  EXPECT_FALSE(newest.back());
  // One switch each way: the smoothing does not flicker on this stream.
  const auto flips = std::inner_product(newest.begin() + 1, newest.end(), newest.begin(), 0, std::plus<>(),
                                        std::not_equal_to<>());
  EXPECT_EQ(flips, 2);
}

// A new map (forget_history) measures from nothing again; the other scopes
// report no share.
TEST(AutoScope, ANewMapForgetsTheShare) {
  Params p;
  p.pair_capacity = 4;
  p.scope = Scope::kAuto;
  Sparsifier s(kCaps, p);
  Window w(kCaps);
  for (std::uint32_t f = 0; f < 12; ++f) {
    add_keyframe(w, f, 100);
    ASSERT_EQ(s.run(w), Status::kOk);
  }
  ASSERT_TRUE(s.summary().decided_newest);
  s.forget_history();
  w.clear();
  for (std::uint32_t f = 0; f < 3; ++f) add_keyframe(w, f, 0);
  ASSERT_EQ(s.run(w), Status::kOk);
  EXPECT_EQ(s.summary().returning_permille, 0u);
  EXPECT_FALSE(s.summary().decided_newest);
  for (Scope scope : {Scope::kWindow, Scope::kNewest}) {
    p.scope = scope;
    Sparsifier other(kCaps, p);
    ASSERT_EQ(other.run(w), Status::kOk);
    EXPECT_EQ(other.summary().returning_permille, 0u);
    EXPECT_FALSE(other.summary().decided_newest);
  }
}

TEST(AutoScope, Name) {
  Scope scope = Scope::kWindow;
  ASSERT_TRUE(parse_scope("auto", &scope));
  EXPECT_EQ(scope, Scope::kAuto);
  EXPECT_STREQ(to_string(Scope::kAuto), "auto");
  Params p;
  p.scope = Scope::kAuto;
  EXPECT_EQ(Sparsifier::validate(p), Status::kOk);
}

}  // namespace
}  // namespace keepless::core
