// Window::slide and Window::remove_points, the edits the node makes on every
// keyframe, in place: each leaves exactly what removing the oldest and adding
// (or re-adding every keyframe without the points) would, tracked flags and
// quality included; a refused slide changes nothing; stamps change exactly
// where contents did.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "keepless/core/window.hpp"

namespace keepless::core {
namespace {

// One keyframe as the model holds it.
struct Frame {
  KeyframeId id = 0;
  std::vector<Observation> obs;
  std::vector<std::uint8_t> tracked;  // empty: none
  std::vector<PointQuality> quality;  // empty: none
  std::uint32_t unmapped = 0;
};

Status add_to(Window& w, const Frame& f, bool slide) {
  static const std::vector<Keypoint> keypoints(64, Keypoint{1, 2});
  Keyframe k;
  k.id = f.id;
  k.centre[0] = static_cast<double>(f.id);
  k.tracked = f.tracked.empty() ? nullptr : f.tracked.data();
  k.quality = f.quality.empty() ? nullptr : f.quality.data();
  k.unmapped = keypoints.data();
  k.unmapped_count = f.unmapped;
  const auto n = static_cast<std::uint32_t>(f.obs.size());
  return slide ? w.slide(k, f.obs.data(), n) : w.add_keyframe(k, f.obs.data(), n);
}

// The window holds exactly `model`, in order.
void expect_holds(const Window& w, const std::vector<Frame>& model) {
  ASSERT_EQ(w.keyframe_count(), model.size());
  std::set<PointId> distinct;
  std::uint32_t total = 0, unmapped = 0;
  for (std::uint32_t s = 0; s < model.size(); ++s) {
    const Frame& f = model[s];
    const Keyframe& k = w.keyframe(s);
    ASSERT_EQ(k.id, f.id);
    ASSERT_EQ(w.observation_count(s), f.obs.size()) << f.id;
    ASSERT_EQ(k.unmapped_count, f.unmapped);
    ASSERT_EQ(k.tracked != nullptr, !f.tracked.empty() && !f.obs.empty());
    ASSERT_EQ(k.quality != nullptr, !f.quality.empty() && !f.obs.empty());
    for (std::uint32_t i = 0; i < f.obs.size(); ++i) {
      ASSERT_EQ(w.observations(s)[i].point, f.obs[i].point);
      ASSERT_EQ(w.observations(s)[i].u, f.obs[i].u);
      if (k.tracked != nullptr) {
        ASSERT_EQ(k.tracked[i], f.tracked[i]);
      }
      if (k.quality != nullptr) {
        ASSERT_EQ(k.quality[i].track_length, f.quality[i].track_length);
      }
      distinct.insert(f.obs[i].point);
    }
    total += static_cast<std::uint32_t>(f.obs.size());
    unmapped += f.unmapped;
  }
  ASSERT_EQ(w.distinct_points(), distinct.size());
  ASSERT_EQ(w.total_observations(), total);
  ASSERT_EQ(w.total_unmapped(), unmapped);
  for (PointId p : distinct) {
    std::uint32_t views = 0;
    for (const Frame& f : model) {
      for (const Observation& o : f.obs) views += o.point == p ? 1 : 0;
    }
    ASSERT_EQ(w.point_views(p), views) << p;
  }
}

bool fits(const std::vector<Frame>& frames, const Capacities& c) {
  std::set<PointId> distinct;
  std::uint64_t total = 0, unmapped = 0;
  for (const Frame& f : frames) {
    for (const Observation& o : f.obs) distinct.insert(o.point);
    total += f.obs.size();
    unmapped += f.unmapped;
  }
  return frames.size() <= c.max_keyframes && distinct.size() <= c.max_points && total <= c.max_observations &&
         unmapped <= c.max_unmapped_keypoints;
}

std::vector<std::uint64_t> stamps_of(const Window& w) {
  std::vector<std::uint64_t> out;
  for (std::uint32_t s = 0; s < w.keyframe_count(); ++s) out.push_back(w.keyframe_stamp(s));
  return out;
}

// Random slides, additions and point drops near every capacity, with ids that
// collide in the point table (multiples of 2^20), against a model.
TEST(WindowInPlace, SlidesAndDroppedPointsMatchAModel) {
  Capacities caps{5, 40, 120, 1024};
  caps.max_unmapped_keypoints = 100;
  Window w(caps);
  const std::size_t bytes = w.memory_bytes();
  std::mt19937_64 rng(7);
  std::vector<Frame> model;
  KeyframeId next = 1;
  int slides = 0, refused_slides = 0, drops = 0;
  for (int step = 0; step < 4000; ++step) {
    const std::uint64_t op = rng() % 4;
    if (op == 3 && !model.empty()) {
      // Drop a few points, some held and some not, sorted with repeats.
      std::vector<PointId> points;
      for (std::uint64_t i = rng() % 6; i > 0; --i) points.push_back((rng() % 60) << 20);
      std::sort(points.begin(), points.end());
      const std::vector<std::uint64_t> before = stamps_of(w);
      ASSERT_EQ(w.remove_points(points.data(), static_cast<std::uint32_t>(points.size())), Status::kOk);
      ++drops;
      for (std::size_t s = 0; s < model.size(); ++s) {
        Frame& f = model[s];
        Frame kept = f;
        kept.obs.clear();
        kept.tracked.clear();
        kept.quality.clear();
        for (std::size_t i = 0; i < f.obs.size(); ++i) {
          if (std::binary_search(points.begin(), points.end(), f.obs[i].point)) continue;
          kept.obs.push_back(f.obs[i]);
          if (!f.tracked.empty()) kept.tracked.push_back(f.tracked[i]);
          if (!f.quality.empty()) kept.quality.push_back(f.quality[i]);
        }
        const bool changed = kept.obs.size() != f.obs.size();
        ASSERT_EQ(w.keyframe_stamp(static_cast<std::uint32_t>(s)) != before[s], changed) << s;
        f = kept;
      }
    } else {
      Frame f;
      f.id = rng() % 50 == 0 && !model.empty() ? model.front().id : next++;  // now and then the oldest's id
      for (std::uint64_t i = rng() % 30; i > 0; --i) {
        const PointId p = (rng() % 60) << 20;
        if (std::none_of(f.obs.begin(), f.obs.end(), [p](const Observation& o) { return o.point == p; })) {
          f.obs.push_back({p, static_cast<double>(rng() % 640), static_cast<double>(rng() % 480), 0});
        }
      }
      if (rng() % 2) {
        for (std::size_t i = 0; i < f.obs.size(); ++i) f.tracked.push_back(static_cast<std::uint8_t>(rng() % 2));
      }
      if (rng() % 2) {
        for (std::size_t i = 0; i < f.obs.size(); ++i) f.quality.push_back({static_cast<std::uint32_t>(rng() % 9)});
      }
      f.unmapped = static_cast<std::uint32_t>(rng() % 40);
      const bool slide = !model.empty() && (op != 0 || model.size() == caps.max_keyframes);
      std::vector<Frame> after(model.begin() + (slide ? 1 : 0), model.end());
      after.push_back(f);
      const bool duplicate = std::any_of(model.begin(), model.end(), [&](const Frame& m) { return m.id == f.id; });
      const std::vector<std::uint64_t> before = stamps_of(w);
      const Status s = add_to(w, f, slide);
      if (duplicate) {  // capacities are checked before ids, except the points'
        ASSERT_TRUE(s == Status::kDuplicateKeyframe || s == Status::kCapacityExceeded) << to_string(s);
      } else {
        ASSERT_EQ(s, fits(after, caps) ? Status::kOk : Status::kCapacityExceeded);
      }
      if (s == Status::kOk) {
        model = after;
        slides += slide ? 1 : 0;
        // Those that stay keep their stamps; the new keyframe has a new one.
        const std::vector<std::uint64_t> now = stamps_of(w);
        for (std::size_t i = 0; i + 1 < now.size(); ++i) ASSERT_EQ(now[i], before[i + (slide ? 1 : 0)]);
        ASSERT_EQ(std::count(before.begin(), before.end(), now.back()), 0);
      } else {
        refused_slides += slide ? 1 : 0;
        ASSERT_EQ(stamps_of(w), before);
      }
    }
    expect_holds(w, model);
  }
  // Every branch ran often.
  EXPECT_GT(slides, 500);
  EXPECT_GT(refused_slides, 100);
  EXPECT_GT(drops, 500);
  EXPECT_EQ(w.memory_bytes(), bytes);
}

// A slide counts the oldest's points as gone, and those the new keyframe sees
// again as back: it fits exactly where remove-then-add would.
TEST(WindowInPlace, ASlideFreesTheOldestsPoints) {
  const Capacities caps{2, 4, 8, 64};
  Window w(caps);
  ASSERT_EQ(add_to(w, {1, {{1, 0, 0, 0}, {2, 0, 0, 0}}, {}, {}, 0}, false), Status::kOk);
  ASSERT_EQ(add_to(w, {2, {{2, 0, 0, 0}, {3, 0, 0, 0}}, {}, {}, 0}, false), Status::kOk);
  // Points 2, 3 stay; 1 leaves and comes back with 4 and 5: 5 > 4.
  const Frame too_many{3, {{1, 0, 0, 0}, {4, 0, 0, 0}, {5, 0, 0, 0}}, {}, {}, 0};
  EXPECT_EQ(add_to(w, too_many, true), Status::kCapacityExceeded);
  EXPECT_EQ(w.keyframe(0).id, 1u);
  EXPECT_EQ(w.distinct_points(), 3u);
  const Frame exactly{3, {{1, 0, 0, 0}, {4, 0, 0, 0}}, {}, {}, 0};
  ASSERT_EQ(add_to(w, exactly, true), Status::kOk);
  EXPECT_EQ(w.keyframe(0).id, 2u);
  EXPECT_EQ(w.keyframe(1).id, 3u);
  EXPECT_EQ(w.distinct_points(), 4u);
  EXPECT_EQ(w.point_views(1), 1u);
  EXPECT_EQ(w.point_views(2), 1u);
}

TEST(WindowInPlace, RefusedArguments) {
  const Capacities caps{2, 4, 8, 64};
  Window w(caps);
  const Frame first{1, {{1, 0, 0, 0}}, {}, {}, 0};
  EXPECT_EQ(add_to(w, first, true), Status::kInvalidArgument);  // nothing to slide out
  ASSERT_EQ(add_to(w, first, false), Status::kOk);
  const PointId unsorted[] = {3, 1};
  EXPECT_EQ(w.remove_points(unsorted, 2), Status::kInvalidArgument);
  EXPECT_EQ(w.remove_points(nullptr, 1), Status::kInvalidArgument);
  EXPECT_EQ(w.remove_points(nullptr, 0), Status::kOk);
  EXPECT_EQ(w.point_views(1), 1u);
}

}  // namespace
}  // namespace keepless::core
