#pragma once
// One image's ORB features as ORB-SLAM2 extracts them: 8 levels at scale
// 1.2, FAST 20 with a fall-back to 7, responses spread over 30 px cells of
// every level, descriptors from OpenCV's ORB; plus a pixel grid for radius
// searches and, for RGB-D, each keypoint's depth.

#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "real_sequence.hpp"

namespace keepless::eval::vo {

constexpr int kLevels = 8;
constexpr double kScaleFactor = 1.2;

struct ScalePyramid {
  std::array<double, kLevels> scale{}, inv_sigma2{};
  ScalePyramid();
};
const ScalePyramid& pyramid();

struct Frame {
  std::vector<cv::KeyPoint> keys;
  cv::Mat descriptors;       // keys.size() x 32, CV_8U
  std::vector<float> depth;  // metres, 0 = none (RGB-D only)
  std::vector<float> ur;     // virtual right image column u - bf/z, < 0 = none

  // Keypoints within radius r of (x, y) at levels [min_level, max_level]
  // (negative: any), by grid cell.
  void features_in_area(double x, double y, double r, int min_level, int max_level,
                        std::vector<int>* out) const;
  void build_grid(int width, int height);

 private:
  static constexpr int kCell = 20;
  int cols_ = 0, rows_ = 0;
  std::vector<std::vector<int>> cells_;
};

class OrbExtractor {
 public:
  OrbExtractor(int features, const PinholeCamera& camera);
  // Fills keys, descriptors, grid; depth and ur when `depth` is given
  // (metres, CV_32F): a keypoint gets a depth only where the 3x3 patch
  // around it is valid and agrees (7-Scenes depth is not registered to the
  // colour image pixel for pixel, so edges would give wrong depths).
  void extract(const cv::Mat& grey, const cv::Mat* depth, Frame* out) const;
  int features() const { return features_; }

 private:
  int features_;
  PinholeCamera camera_;
  cv::Ptr<cv::ORB> strict_, loose_;
};

// Hamming distance of two 32-byte ORB descriptors. Inline and popcount by
// bit arithmetic: the x86-64 baseline has no popcnt instruction, so
// __builtin_popcountll would be a libgcc call per word, and this is the
// inner loop of every descriptor search. Byte counts (<= 8 each) are summed
// over the four words (<= 32 per byte) before the horizontal add.
inline int hamming(const std::uint8_t* a, const std::uint8_t* b) {
  std::uint64_t bytes = 0;
  for (int i = 0; i < 4; ++i) {
    std::uint64_t wa, wb;
    std::memcpy(&wa, a + 8 * i, 8);
    std::memcpy(&wb, b + 8 * i, 8);
    std::uint64_t x = wa ^ wb;
    x -= (x >> 1) & 0x5555555555555555ULL;
    x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
    bytes += (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  }
  // Bytes to 16-bit lanes (<= 64 each) first: the total, up to 256, does not fit a byte.
  const std::uint64_t halves = (bytes & 0x00ff00ff00ff00ffULL) + ((bytes >> 8) & 0x00ff00ff00ff00ffULL);
  return static_cast<int>((halves * 0x0001000100010001ULL) >> 48);
}
inline int hamming(const cv::Mat& a, int ra, const cv::Mat& b, int rb) { return hamming(a.ptr(ra), b.ptr(rb)); }

}  // namespace keepless::eval::vo
