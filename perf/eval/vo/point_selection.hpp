#pragma once
// The baselines that cull as many points as keepless does on the same
// window: random (a fixed priority per point and seed), longest-track-first
// (the shortest tracks go), and ANMS (SSC on the new keyframe's responses).

#include <cstdint>
#include <vector>

#include "keepless/core/config.hpp"
#include "real_vo.hpp"

namespace keepless::eval::vo {

struct Candidate {
  core::PointId id = 0;
  float u = 0, v = 0, response = 0;  // its keypoint in `keyframe`
  int track_length = 0;              // observations so far: the online map when the window is decided
  int keyframe = 0;                  // the newest deciding keyframe that observes it (where u, v are)
};

// The ids (ascending) of exactly min(cull, candidates) candidates that
// `selector` (a baseline, not kKeepless/kOriginal) removes. ANMS judges each
// candidate among those of its own keyframe (SSC on one image), the
// keyframes sharing the kept count in proportion to their candidates
// (largest remainder), as the synthetic back end's ANMS does; `anms` says
// what it ranks by (AnmsVariant).
std::vector<core::PointId> baseline_culls(Selector selector, const std::vector<Candidate>& candidates,
                                          std::size_t cull, std::uint64_t seed, int width, int height,
                                          AnmsVariant anms = AnmsVariant::kSsc);

}  // namespace keepless::eval::vo
