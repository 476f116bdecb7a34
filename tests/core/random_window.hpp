#pragma once
// Seeded random windows shaped like a SLAM local map: points tracked over runs
// of consecutive keyframes, keypoints clustered on a lattice (so box borders
// are hit exactly and c_s repeats), and camera centres drawn from a small pool
// (so c_b repeats). Heavy ties are the point: they exercise the tie-break.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "reference_sparsifier.hpp"

namespace keepless::test {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  std::uint64_t next() { return engine_(); }
  // Uniform-enough integer in [lo, hi]; a plain modulo keeps the sequence
  // identical across standard libraries.
  std::int64_t between(std::int64_t lo, std::int64_t hi) {
    return lo + static_cast<std::int64_t>(engine_() % static_cast<std::uint64_t>(hi - lo + 1));
  }
  bool chance(int percent) { return between(0, 99) < percent; }

 private:
  std::mt19937_64 engine_;
};

struct RandomCase {
  std::vector<RefKeyframe> frames;
  core::Params params;
};

inline RandomCase random_case(std::uint64_t seed, std::uint32_t max_keyframes = 12,
                              std::uint32_t max_points = 60) {
  Rng rng(seed);
  RandomCase c;
  const auto k = static_cast<std::uint32_t>(rng.between(2, max_keyframes));
  // Dense windows crowd many keypoints into one box, so c_s reaches 3 and 4.
  const bool dense = rng.chance(15);
  const auto p = static_cast<std::uint32_t>(
      dense ? rng.between(max_points, 3 * max_points) : rng.between(3, max_points));
  const std::int64_t spread = dense ? 2 : 5;

  // Camera centres: a small pool of integer positions, plus a few one-offs.
  double pool[3][3];
  for (auto& centre : pool) {
    for (double& x : centre) x = static_cast<double>(rng.between(-15, 15));
  }
  std::set<std::uint64_t> ids;
  c.frames.resize(k);
  for (auto& f : c.frames) {
    do {
      f.id = static_cast<std::uint64_t>(rng.between(0, 10 * k));
    } while (!ids.insert(f.id).second);
    if (rng.chance(70)) {
      const auto& centre = pool[rng.between(0, 2)];
      std::copy(centre, centre + 3, f.centre);
    } else {
      for (double& x : f.centre) x = static_cast<double>(rng.between(-400, 400)) / 8.0;
    }
  }

  // Per-frame keypoint clusters on a lattice of 8 x 6 pixels.
  std::vector<std::vector<std::pair<double, double>>> clusters(k);
  for (auto& cl : clusters) {
    const auto count = dense ? 1 : rng.between(1, 4);
    for (std::int64_t i = 0; i < count; ++i) {
      cl.push_back({static_cast<double>(8 * rng.between(0, 80)),
                    static_cast<double>(6 * rng.between(0, 80))});
    }
  }
  const auto keypoint = [&](std::uint32_t slot) -> std::pair<double, double> {
    if (rng.chance(10)) {  // off-lattice
      return {static_cast<double>(rng.between(0, 64000)) / 100.0,
              static_cast<double>(rng.between(0, 48000)) / 100.0};
    }
    const auto& cl = clusters[slot][static_cast<std::size_t>(
        rng.between(0, static_cast<std::int64_t>(clusters[slot].size()) - 1))];
    return {cl.first + 8.0 * static_cast<double>(rng.between(-spread, spread)),
            cl.second + 6.0 * static_cast<double>(rng.between(-spread, spread))};
  };

  // Points: sparse ids (some huge), tracked over a run of consecutive frames,
  // sometimes over a random subset.
  std::set<std::uint64_t> point_ids;
  for (std::uint32_t i = 0; i < p; ++i) {
    std::uint64_t id;
    do {
      id = rng.chance(10) ? (std::uint64_t{1} << 63) + rng.next() % 1000
                          : static_cast<std::uint64_t>(rng.between(0, 4 * p));
    } while (!point_ids.insert(id).second);
    std::vector<std::uint32_t> slots;
    if (rng.chance(20)) {
      for (std::uint32_t s = 0; s < k; ++s) {
        if (rng.chance(40)) slots.push_back(s);
      }
    } else {
      const auto start = static_cast<std::uint32_t>(rng.between(0, k - 1));
      const auto length = static_cast<std::uint32_t>(rng.between(1, std::min<std::uint32_t>(k - start, 7)));
      for (std::uint32_t s = start; s < start + length; ++s) slots.push_back(s);
    }
    for (std::uint32_t s : slots) {
      const auto uv = keypoint(s);
      c.frames[s].observations.push_back({id, uv.first, uv.second});
    }
  }
  for (auto& f : c.frames) {  // observation order within a keyframe is arbitrary
    for (std::size_t i = f.observations.size(); i > 1; --i) {
      std::swap(f.observations[i - 1],
                f.observations[static_cast<std::size_t>(rng.between(0, static_cast<std::int64_t>(i) - 1))]);
    }
  }

  // Small M so pair capacities bind; sometimes the paper's defaults.
  c.params.pair_capacity = rng.chance(10) ? 100 : rng.between(1, 5);
  const double thetas[] = {0.0, 0.25, 0.5, 0.75, 1.0};
  c.params.theta = thetas[rng.between(0, 4)];
  if (rng.chance(20)) {
    const std::int32_t boxes[][2] = {{0, 0}, {63, 47}, {16, 12}, {128, 96}};
    const auto& b = boxes[rng.between(0, 3)];
    c.params.box_width = b[0];
    c.params.box_height = b[1];
  }
  return c;
}

// What the other cost models read, on a case: intrinsics (sometimes
// missing), depths (some unknown), unmapped keypoints on the same lattice
// (some off the image); and a random cost model, scope and floor.
inline void random_policies(RandomCase& c, std::uint64_t seed) {
  Rng rng(seed ^ 0x706f6c6963696573ULL);
  for (auto& f : c.frames) {
    if (rng.chance(90)) {
      f.fx = 400.0 + static_cast<double>(rng.between(0, 400)) + 0.37;
      f.fy = rng.chance(50) ? f.fx : f.fx * 1.01;
      f.cx = 320.5 + static_cast<double>(rng.between(-30, 30)) / 3.0;
      f.cy = 240.25 + static_cast<double>(rng.between(-30, 30)) / 7.0;
    }
    for (auto& o : f.observations) {
      o.depth = rng.chance(85) ? 0.5 + static_cast<double>(rng.between(0, 2000)) / 97.0 : 0.0;
    }
    const auto unmapped = rng.between(0, 40);
    for (std::int64_t i = 0; i < unmapped; ++i) {
      f.unmapped.push_back({static_cast<double>(8 * rng.between(-5, 85)),
                            static_cast<double>(6 * rng.between(-5, 85))});
    }
  }
  const core::CostModel models[] = {core::CostModel::kPaper, core::CostModel::kAuthors,
                                    core::CostModel::kInformation};
  c.params.cost_model = models[seed % 3];
  c.params.scope = rng.chance(50) ? core::Scope::kNewest : core::Scope::kWindow;
  c.params.coverage_floor = rng.chance(25) ? 0 : static_cast<std::uint32_t>(rng.between(1, 12));
  if (rng.chance(30)) {
    c.params.image_width = 320;
    c.params.image_height = 240;
  }
}

// Tracking-safe culling on a case: a maturity guard A in 0..4 and tracked
// flags on some keyframes (the newest's protect, the others' must be ignored).
inline void random_guard(RandomCase& c, std::uint64_t seed) {
  Rng rng(seed ^ 0x6775617264ULL);
  c.params.maturity_keyframes = static_cast<std::uint32_t>(rng.between(0, 4));
  for (auto& f : c.frames) {
    f.tracked.clear();
    if (!rng.chance(60)) continue;
    const int percent = static_cast<int>(rng.between(5, 60));
    for (std::size_t i = 0; i < f.observations.size(); ++i) {
      f.tracked.push_back(rng.chance(percent) ? static_cast<std::uint8_t>(rng.between(1, 255)) : 0);
    }
  }
}

// CostModel::kTrack on a case: point quality on most keyframes (values on
// the levels' edges, some unknown), the same point's quality differing
// between keyframes as a map's does over time, and random track terms.
inline void random_quality(RandomCase& c, std::uint64_t seed) {
  Rng rng(seed ^ 0x747261636bULL);
  static constexpr float kErrors[] = {-1.f, 0.f, 0.25f, 0.5f, 0.99f, 1.f, 1.5f, 2.f, 3.99f, 4.f, 9.f};
  static constexpr float kAngles[] = {0.f, -3.f, 0.5f, 1.f, 1.99f, 2.f, 3.f, 4.f, 7.99f, 8.f, 40.f};
  for (auto& f : c.frames) {
    f.quality.clear();
    if (!rng.chance(85)) continue;  // a keyframe without quality (the fallback)
    for (std::size_t i = 0; i < f.observations.size(); ++i) {
      core::PointQuality q;
      q.track_length = static_cast<std::uint32_t>(rng.between(0, 40));
      q.age = static_cast<std::int32_t>(rng.between(-1, 33));
      q.reprojection_error = kErrors[rng.between(0, 10)];
      q.triangulation_angle = kAngles[rng.between(0, 10)];
      f.quality.push_back(q);
    }
  }
  c.params.cost_model = core::CostModel::kTrack;
  c.params.track_terms = static_cast<std::uint8_t>(rng.chance(50) ? 15 : rng.between(0, 15));
}

inline core::Keyframe keyframe_of(const RefKeyframe& f, std::vector<core::Keypoint>& unmapped) {
  core::Keyframe kf;
  kf.id = f.id;
  std::copy(f.centre, f.centre + 3, kf.centre);
  kf.fx = f.fx;
  kf.fy = f.fy;
  kf.cx = f.cx;
  kf.cy = f.cy;
  unmapped.clear();
  for (const auto& k : f.unmapped) unmapped.push_back({k.first, k.second});
  kf.unmapped = unmapped.data();
  kf.unmapped_count = static_cast<std::uint32_t>(unmapped.size());
  kf.tracked = f.tracked.empty() ? nullptr : f.tracked.data();
  kf.quality = f.quality.empty() ? nullptr : f.quality.data();
  return kf;
}

inline std::vector<core::Observation> observations_of(const RefKeyframe& f) {
  std::vector<core::Observation> obs;
  for (const auto& o : f.observations) obs.push_back({o.point, o.u, o.v, o.depth});
  return obs;
}

// Adds one frame to a window.
inline core::Status add_frame(core::Window& window, const RefKeyframe& f) {
  std::vector<core::Keypoint> unmapped;
  const core::Keyframe kf = keyframe_of(f, unmapped);
  const std::vector<core::Observation> obs = observations_of(f);
  return window.add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size()));
}

// Loads frames into a window; false if the window refused one.
inline bool load(core::Window& window, const std::vector<RefKeyframe>& frames) {
  window.clear();
  for (const auto& f : frames) {
    if (add_frame(window, f) != core::Status::kOk) return false;
  }
  return true;
}

// A window of at most `size` keyframes sliding over a case's frames (the
// oldest dropped first, or the second oldest with `drop_second`): per
// keyframe, run() from scratch and update() on the incremental network from
// both starts, then check(window, run, closed, zero, frame), which asserts
// what the caller compares (update() decides what run() does, ...).
template <typename Check>
void slide_run_and_update(const core::Capacities& caps, const RandomCase& c, std::uint32_t size,
                          bool drop_second, Check check) {
  core::Window window(caps);
  core::Sparsifier run(caps, c.params);
  core::Sparsifier closed(caps, c.params, core::SolveMode::kIncremental, core::Start::kClosedForm);
  core::Sparsifier zero(caps, c.params, core::SolveMode::kIncremental, core::Start::kZeroFlow);
  for (const auto& f : c.frames) {
    if (window.keyframe_count() == size) {
      ASSERT_EQ(window.remove_keyframe(window.keyframe(drop_second ? 1 : 0).id), core::Status::kOk);
    }
    ASSERT_EQ(add_frame(window, f), core::Status::kOk);
    ASSERT_EQ(run.run(window), core::Status::kOk);
    ASSERT_EQ(closed.update(window), core::Status::kOk);
    ASSERT_EQ(zero.update(window), core::Status::kOk);
    check(window, run, closed, zero, f);
    if (::testing::Test::HasFailure()) return;
  }
}

}  // namespace keepless::test
