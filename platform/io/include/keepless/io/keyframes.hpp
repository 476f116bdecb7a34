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
  core::WindowFile file;       // keyframes in replay order
  std::uint64_t duplicates = 0;  // observations merged into an earlier one of the same image
};

// The centre of an image: -R(q)^T t.
void colmap_camera_centre(const ColmapImage& image, double centre[3]);

// The camera centres of the images `a` and `b` share (matched by id), in
// `a`'s order: for comparing two solutions of one model.
void matched_centres(const ColmapModel& a, const ColmapModel& b, std::vector<std::array<double, 3>>* in_a,
                     std::vector<std::array<double, 3>>* in_b);

Keyframes keyframes_from_colmap(const ColmapModel& model, KeyframeOrder order, const Similarity& to_metric);
Keyframes keyframes_from_bal(const BalProblem& problem, KeyframeOrder order, const Similarity& to_metric);

}  // namespace keepless::io
