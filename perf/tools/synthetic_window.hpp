#pragma once
// A deterministic synthetic window or map: a camera moving along a gently
// curving corridor (tiled floor, walls with textured posters on plain paint,
// a ceiling with lamps), pinhole 640x480, f = 500. Points lie on those
// surfaces, denser where the texture is (tile corners, posters) and sparse on
// weak texture; each is tracked over a run of consecutive keyframes while it
// stays in view, with pixel noise. Only integer PRNG output, + - * / and sqrt
// are used, so a seed gives the same file with any standard library.

#include <cstdint>
#include <string>
#include <vector>

#include "keepless/core/window_file.hpp"

namespace keepless::perf {

struct SyntheticSpec {
  std::uint32_t keyframes = 20;
  std::uint32_t points = 8000;
  std::uint32_t obs_per_kf = 1000;  // target mean; the track lengths are calibrated to it
  std::uint64_t seed = 1;
  // Optional keyframe contents for the cost models that read them, off by
  // default; neither changes the points, the views or the keypoints above.
  // camera: the intrinsics on every keyframe and each observation's depth
  // (the point's camera-frame z, which the generator knows).
  bool camera = false;
  // Detected keypoints that observe no map point, per keyframe (features of
  // the same textured scene, drawn from their own seeded stream).
  std::uint32_t unmapped_per_kf = 0;
};

// Presets: small, orbslam, large, map. False for an unknown name.
bool workload_spec(const std::string& name, SyntheticSpec* spec);
// The message for a --workload that workload_spec refused, naming the presets.
std::string unknown_workload(const std::string& name);

// Exactly spec.points points, each seen by >= 1 keyframe; point ids ascend
// with the keyframe that first sees them. With spec.unmapped_per_kf > 0 the
// keyframes' unmapped keypoints are stored in *unmapped (one list per
// keyframe; null: none are made) and each Keyframe::unmapped points into it, so
// *unmapped must outlive the keyframes (moving the outer vector is fine).
core::WindowFile make_synthetic_window(const SyntheticSpec& spec,
                                       std::vector<std::vector<core::Keypoint>>* unmapped = nullptr);

}  // namespace keepless::perf
