#pragma once
// Bundle Adjustment in the Large (BAL) problems, text:
//   <ncams> <npoints> <nobs>
//   <cam_idx> <point_idx> <x> <y>              nobs lines (pixels from the image centre)
//   9 values per camera (Rodrigues r[3], t[3], f, k1, k2), then 3 per point
// Numbers keep their text, so a problem written back is byte-identical for
// files laid out as the BAL dataset's are ("%d %d     x y", one value a line).

#include <cstdint>
#include <string>
#include <vector>

namespace keepless::io {

struct BalObservation {
  std::uint32_t camera = 0;
  std::uint32_t point = 0;
  double x = 0;
  double y = 0;
  std::string x_text, y_text;  // as read (written back as is)
};

struct BalProblem {
  std::uint32_t num_cameras = 0;
  std::uint32_t num_points = 0;
  std::vector<BalObservation> observations;  // file order
  std::vector<double> camera_params;         // 9 per camera
  std::vector<double> point_params;          // 3 per point
  std::vector<std::string> camera_text;      // as read, same indexing
  std::vector<std::string> point_text;
};

// Parses `text` (named `name` in errors). On failure false and *error is
// "NAME:LINE: reason". Indices must be in range and numbers finite; the
// counts are checked against the lines present before anything is sized.
[[nodiscard]] bool parse_bal(const std::string& name, const std::string& text, BalProblem* out, std::string* error);
[[nodiscard]] bool read_bal(const std::string& path, BalProblem* out, std::string* error);

std::string format_bal(const BalProblem& problem);

// The problem without the points whose `culled[i]` is set, and without their
// observations; the other points keep their order (and are renumbered).
BalProblem remove_points(const BalProblem& problem, const std::vector<bool>& culled);

// Camera centre -R(r)^T t of camera `i` (BAL: P = R X + t).
void bal_camera_centre(const BalProblem& problem, std::uint32_t i, double centre[3]);

}  // namespace keepless::io
