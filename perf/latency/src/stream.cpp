#include "stream.hpp"

#include <algorithm>
#include <unordered_map>

#include "synthetic_window.hpp"

namespace keepless::perf {

bool make_stream(const std::string& name, std::uint32_t total, std::uint64_t seed,
                 const StreamExtras& extras, KeyframeStream* out) {
  SyntheticSpec spec;
  if (!workload_spec(name, &spec)) return false;
  out->workload = name;
  out->window = spec.keyframes;
  // Same points per keyframe as the workload's window, over the whole stream.
  const double per_keyframe = static_cast<double>(spec.points) / spec.keyframes;
  spec.points = static_cast<std::uint32_t>(per_keyframe * std::max(total, spec.keyframes));
  spec.keyframes = std::max(total, spec.keyframes);
  spec.seed = seed;
  spec.camera = extras.camera;
  spec.unmapped_per_kf = extras.unmapped_per_kf;
  core::WindowFile file = make_synthetic_window(spec, &out->unmapped);
  out->keyframes = std::move(file.keyframes);
  out->observations = std::move(file.observations);
  return true;
}

core::Capacities window_needs(const KeyframeStream& s) {
  // Slide the window, keeping per-point view counts: distinct points and
  // sum n(n-1)/2 change by one view at a time.
  std::unordered_map<core::PointId, std::uint32_t> views;
  std::uint64_t observations = 0, pair_arcs = 0, unmapped = 0;
  core::Capacities need{s.window, 0, 0, 0, 0};
  const auto n = static_cast<std::uint32_t>(s.keyframes.size());
  for (std::uint32_t k = 0; k < n; ++k) {
    if (k >= s.window) {
      for (const core::Observation& o : s.observations[k - s.window]) {
        std::uint32_t& v = views[o.point];
        pair_arcs -= v - 1;
        if (--v == 0) views.erase(o.point);
      }
      observations -= s.observations[k - s.window].size();
      unmapped -= s.keyframes[k - s.window].unmapped_count;
    }
    for (const core::Observation& o : s.observations[k]) {
      std::uint32_t& v = views[o.point];
      pair_arcs += v;
      ++v;
    }
    observations += s.observations[k].size();
    unmapped += s.keyframes[k].unmapped_count;
    need.max_unmapped_keypoints =
        std::max<std::uint32_t>(need.max_unmapped_keypoints, static_cast<std::uint32_t>(unmapped));
    need.max_observations = std::max<std::uint32_t>(need.max_observations, static_cast<std::uint32_t>(observations));
    need.max_points = std::max<std::uint32_t>(need.max_points, static_cast<std::uint32_t>(views.size()));
    need.max_pair_arcs = std::max<std::uint32_t>(need.max_pair_arcs, static_cast<std::uint32_t>(pair_arcs));
  }
  return need;
}

}  // namespace keepless::perf
