#include "keepless/platform/memory_estimate.hpp"

#include "keepless/core/window.hpp"

namespace keepless::platform {

double MemoryModel::bytes(const core::Capacities& c) const {
  const double k = c.max_keyframes;
  return base + per_keyframe * k + per_keyframe_pair * k * (k - 1) / 2 + per_point * c.max_points +
         per_observation * c.max_observations + per_pair_arc * c.max_pair_arcs +
         per_keyframe_observation * core::keyframe_observation_limit(c) +
         per_table_slot * table_slots(c.max_points);
}

double MemoryModel::table_slots(std::uint32_t points) {
  double size = 2;
  while (size < 2.0 * points) size *= 2;
  return size;
}

namespace {

double measure(const core::Capacities& c, const core::Params& params, core::SolveMode mode, std::uint32_t windows) {
  const core::Window w(c);
  const core::Sparsifier s(c, params, mode);
  return static_cast<double>(windows * w.memory_bytes() + s.memory_bytes());
}

}  // namespace

MemoryModel probe_memory_model(const core::Params& params, core::SolveMode mode, std::uint32_t windows) {
  // Probes large enough that rounding inside the containers is noise.
  // Points from 4097 to 8192 keep the tables' 16384 slots: a pure slope;
  // 4096 points halve them, which prices a slot.
  constexpr std::uint32_t kStep = 4096;
  // One keyframe's limit half the window's, so that the window's slope leaves it alone.
  core::Capacities base{8, kStep + 1, kStep, kStep, 0, kStep / 2};
  base.hold_quality = params.cost_model == core::CostModel::kTrack;  // as window_capacities() sizes the node
  const double b = measure(base, params, mode, windows);
  const auto slope = [&](core::Capacities c, std::uint32_t core::Capacities::*field, std::uint32_t step) {
    c.*field += step;
    return (measure(c, params, mode, windows) - b) / step;
  };
  MemoryModel m;
  m.per_point = slope(base, &core::Capacities::max_points, kStep - 1);
  core::Capacities halved = base;
  halved.max_points = kStep;
  m.per_table_slot = (b - measure(halved, params, mode, windows) - m.per_point) /
                     (MemoryModel::table_slots(kStep + 1) - MemoryModel::table_slots(kStep));
  m.per_observation = slope(base, &core::Capacities::max_observations, kStep);
  m.per_pair_arc = slope(base, &core::Capacities::max_pair_arcs, kStep);
  m.per_keyframe_observation = slope(base, &core::Capacities::max_keyframe_observations, kStep / 2);
  // Keyframes: f(8), f(16), f(24) fix a linear and a pair term.
  core::Capacities c16 = base, c24 = base;
  c16.max_keyframes = 16;
  c24.max_keyframes = 24;
  const double f16 = measure(c16, params, mode, windows), f24 = measure(c24, params, mode, windows);
  const auto pairs = [](double k) { return k * (k - 1) / 2; };
  // f(k) = base' + a k + p pairs(k): two differences, two unknowns.
  const double d1 = f16 - b, d2 = f24 - f16;
  const double p1 = pairs(16) - pairs(8), p2 = pairs(24) - pairs(16);
  m.per_keyframe_pair = (d2 - d1) / (p2 - p1);
  m.per_keyframe = (d1 - m.per_keyframe_pair * p1) / 8;
  m.base = b - m.per_keyframe * 8 - m.per_keyframe_pair * pairs(8) - m.per_point * base.max_points -
           m.per_table_slot * MemoryModel::table_slots(base.max_points) - m.per_observation * kStep -
           m.per_pair_arc * kStep - m.per_keyframe_observation * base.max_keyframe_observations;
  return m;
}

}  // namespace keepless::platform
