#pragma once
// The bridge from a model to the keyframes the decision path sees: one
// keyframe per image (COLMAP) or camera (BAL), its camera centre in metres
// and its observations, as a core::WindowFile in the order of replay.
//
// Ids: a COLMAP keyframe's id is its image id, an observation's point its
// point3D id; a BAL keyframe's id is the camera index, a point its index.
// A track that sees a point twice in one image (two 2D points of one image
// naming one 3D point) gives the keyframe that point once, at the first of
// those 2D points in the image's order; the others follow the point's fate
// (kept or culled with it). duplicates counts the observations so merged.
//
// What the cost models need (core::CostModel), from the model itself:
// - Intrinsics fx, fy, cx, cy: COLMAP, the pinhole part of the image's
//   camera (one f for SIMPLE_PINHOLE, SIMPLE_RADIAL, RADIAL and their
//   fisheye kin, fx and fy for the others; distortion is ignored); BAL,
//   fx = fy = f, cx = cy = 0 (its keypoints are relative to the image centre;
//   k1, k2 ignored). A focal length <= 0 leaves all four 0 (unknown).
// - Observation::depth, metres (model units times the similarity's scale):
//   COLMAP, z of R X + t; BAL, -z of R X + t (BAL projects -P / P.z, so its
//   cameras look down -z: (P.x, P.y, -P.z) is the point in the +z-forward
//   pinhole frame the keypoint back-projects into, a mirror of BAL's frame,
//   which leaves every leverage unchanged). Not finite or <= 0: 0 (unknown).
// - Unmapped keypoints (COLMAP only, and only with `unmapped`): an image's
//   2D points that name no 3D point. BAL stores observations only, so none.
// - Point quality (CostModel::kTrack), per observation: COLMAP, the track's
//   length (its elements, all images) and its ERROR (mean reprojection
//   error, pixels); BAL, the point's observations (track length) only. Age
//   and triangulation angle are unknown (neither model orders its images in
//   time; the angle is left to the SLAM that sends it).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "keepless/core/window_file.hpp"
#include "keepless/io/bal_problem.hpp"
#include "keepless/io/colmap_model.hpp"

namespace keepless::io {

// Model units to metres: x_metric = scale * R * x + t (the layout of the
// fixture's sim3 file: s, then R row-major, then t, 13 numbers). Costs use
// distances between centres, so only the scale changes decisions.
struct Similarity {
  double scale = 1;
  double rotation[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double translation[3] = {0, 0, 0};
};
void to_metric(const Similarity& s, const double in[3], double out[3]);
bool read_similarity(const std::string& path, Similarity* out, std::string* error);

enum class KeyframeOrder {
  kName,  // COLMAP image name (byte order); images' ids follow feature extraction, not time
  kId,    // image id / camera index / keyframe id
  kFile,  // as stored in the file
};
const char* to_string(KeyframeOrder order);

struct Keyframes {
  // Keyframes in replay order; needs.max_unmapped_keypoints is the total
  // held in `unmapped` (a window of all of them fits).
  core::WindowFile file;
  std::uint64_t duplicates = 0;  // observations merged into an earlier one of the same image
  // Storage of every keyframe's unmapped keypoints, in keyframe order: the
  // keyframes point into it, so Keyframes moves (which keeps the storage)
  // but does not copy.
  std::vector<core::Keypoint> unmapped;
  // Every keyframe's point quality (one per observation), in keyframe order:
  // the keyframes point into it.
  std::vector<std::vector<core::PointQuality>> quality;

  Keyframes() = default;
  Keyframes(Keyframes&&) = default;
  Keyframes& operator=(Keyframes&&) = default;
  Keyframes(const Keyframes&) = delete;
  Keyframes& operator=(const Keyframes&) = delete;
};

// The centre of an image: -R(q)^T t.
void colmap_camera_centre(const ColmapImage& image, double centre[3]);

// The camera centres of the images `a` and `b` share (matched by id), in
// `a`'s order: for comparing two solutions of one model.
void matched_centres(const ColmapModel& a, const ColmapModel& b, std::vector<std::array<double, 3>>* in_a,
                     std::vector<std::array<double, 3>>* in_b);

// `unmapped`: also give each keyframe its unmapped keypoints (for
// CostModel::kAuthors; they are most of a COLMAP image's 2D points, so
// leave it off otherwise).
Keyframes keyframes_from_colmap(const ColmapModel& model, KeyframeOrder order, const Similarity& to_metric,
                                bool unmapped = false);
Keyframes keyframes_from_bal(const BalProblem& problem, KeyframeOrder order, const Similarity& to_metric);

// Each keyframe's image's observed 3D point ids (its 2D points that map one,
// repeats kept), in the keyframes' order: what a per-image floor counts.
std::vector<std::vector<core::PointId>> observed_point_ids(const ColmapModel& model, const Keyframes& keyframes);

}  // namespace keepless::io
