#include "orb_frame.hpp"

#include <algorithm>
#include <cmath>

namespace keepless::eval::vo {

ScalePyramid::ScalePyramid() {
  for (int l = 0; l < kLevels; ++l) {
    scale[l] = std::pow(kScaleFactor, l);
    inv_sigma2[l] = 1.0 / (scale[l] * scale[l]);
  }
}

const ScalePyramid& pyramid() {
  static const ScalePyramid p;
  return p;
}

void Frame::build_grid(int width, int height) {
  cols_ = (width + kCell - 1) / kCell;
  rows_ = (height + kCell - 1) / kCell;
  cells_.assign(static_cast<std::size_t>(cols_ * rows_), {});
  for (int i = 0; i < static_cast<int>(keys.size()); ++i) {
    const int cx = std::clamp(static_cast<int>(keys[i].pt.x) / kCell, 0, cols_ - 1);
    const int cy = std::clamp(static_cast<int>(keys[i].pt.y) / kCell, 0, rows_ - 1);
    cells_[static_cast<std::size_t>(cy * cols_ + cx)].push_back(i);
  }
}

void Frame::features_in_area(double x, double y, double r, int min_level, int max_level,
                             std::vector<int>* out) const {
  out->clear();
  const int x0 = std::max(0, static_cast<int>(std::floor((x - r) / kCell)));
  const int x1 = std::min(cols_ - 1, static_cast<int>(std::floor((x + r) / kCell)));
  const int y0 = std::max(0, static_cast<int>(std::floor((y - r) / kCell)));
  const int y1 = std::min(rows_ - 1, static_cast<int>(std::floor((y + r) / kCell)));
  for (int cy = y0; cy <= y1; ++cy) {
    for (int cx = x0; cx <= x1; ++cx) {
      for (int i : cells_[static_cast<std::size_t>(cy * cols_ + cx)]) {
        const cv::KeyPoint& k = keys[static_cast<std::size_t>(i)];
        if (min_level >= 0 && k.octave < min_level) continue;
        if (max_level >= 0 && k.octave > max_level) continue;
        if (std::abs(k.pt.x - x) <= r && std::abs(k.pt.y - y) <= r) out->push_back(i);
      }
    }
  }
}

OrbExtractor::OrbExtractor(int features, const PinholeCamera& camera) : features_(features), camera_(camera) {
  // Over-detect (4x) at FAST 20 and at 7, then spread over cells below.
  strict_ = cv::ORB::create(4 * features, static_cast<float>(kScaleFactor), kLevels, 19, 0, 2,
                            cv::ORB::HARRIS_SCORE, 31, 20);
  loose_ = cv::ORB::create(4 * features, static_cast<float>(kScaleFactor), kLevels, 19, 0, 2,
                           cv::ORB::HARRIS_SCORE, 31, 7);
}

namespace {

// ORB-SLAM2's per-level quota: features * (1 - 1/s) / (1 - (1/s)^L) * (1/s)^l.
std::array<int, kLevels> level_quota(int features) {
  std::array<int, kLevels> q{};
  const double inv = 1.0 / kScaleFactor;
  double per = features * (1 - inv) / (1 - std::pow(inv, kLevels));
  int sum = 0;
  for (int l = 0; l < kLevels - 1; ++l) {
    q[l] = static_cast<int>(std::lround(per));
    sum += q[l];
    per *= inv;
  }
  q[kLevels - 1] = std::max(features - sum, 0);
  return q;
}

// Per level, keypoints bucketed into 30 px cells of that level's image, the
// strongest of each cell taken in turn until the level's quota is met.
std::vector<int> spread(const std::vector<cv::KeyPoint>& keys, int features, int width, int height) {
  const std::array<int, kLevels> quota = level_quota(features);
  std::vector<int> chosen;
  for (int l = 0; l < kLevels; ++l) {
    const double cell = 30.0 * pyramid().scale[l];
    const int cols = std::max(1, static_cast<int>(std::ceil(width / cell)));
    const int rows = std::max(1, static_cast<int>(std::ceil(height / cell)));
    std::vector<std::vector<int>> cells(static_cast<std::size_t>(cols * rows));
    for (int i = 0; i < static_cast<int>(keys.size()); ++i) {
      if (keys[i].octave != l) continue;
      const int cx = std::clamp(static_cast<int>(keys[i].pt.x / cell), 0, cols - 1);
      const int cy = std::clamp(static_cast<int>(keys[i].pt.y / cell), 0, rows - 1);
      cells[static_cast<std::size_t>(cy * cols + cx)].push_back(i);
    }
    for (auto& c : cells) {
      std::sort(c.begin(), c.end(), [&](int a, int b) {
        return keys[a].response != keys[b].response ? keys[a].response > keys[b].response : a < b;
      });
    }
    int taken = 0;
    for (std::size_t round = 0; taken < quota[l]; ++round) {
      bool any = false;
      for (auto& c : cells) {
        if (round < c.size() && taken < quota[l]) {
          chosen.push_back(c[round]);
          ++taken;
          any = true;
        }
      }
      if (!any) break;
    }
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

// Depth at a keypoint: the centre of a valid, consistent 3x3 patch.
float consistent_depth(const cv::Mat& depth, const cv::Point2f& p) {
  const int x = static_cast<int>(std::lround(p.x)), y = static_cast<int>(std::lround(p.y));
  if (x < 1 || y < 1 || x >= depth.cols - 1 || y >= depth.rows - 1) return 0;
  const float d = depth.at<float>(y, x);
  if (!(d > 0.1f)) return 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const float n = depth.at<float>(y + dy, x + dx);
      if (!(n > 0) || std::abs(n - d) > 0.02f * d + 0.01f) return 0;
    }
  }
  return d;
}

}  // namespace

void OrbExtractor::extract(const cv::Mat& grey, const cv::Mat* depth, Frame* out) const {
  std::vector<cv::KeyPoint> keys;
  cv::Mat desc;
  strict_->detectAndCompute(grey, cv::noArray(), keys, desc);
  if (static_cast<int>(keys.size()) < features_) {  // weak texture: FAST 7
    keys.clear();
    loose_->detectAndCompute(grey, cv::noArray(), keys, desc);
  }
  const std::vector<int> chosen = spread(keys, features_, grey.cols, grey.rows);
  out->keys.clear();
  out->descriptors.create(static_cast<int>(chosen.size()), 32, CV_8U);
  for (std::size_t i = 0; i < chosen.size(); ++i) {
    out->keys.push_back(keys[static_cast<std::size_t>(chosen[i])]);
    desc.row(chosen[i]).copyTo(out->descriptors.row(static_cast<int>(i)));
  }
  const std::size_t n = out->keys.size();
  out->depth.assign(n, 0.f);
  out->ur.assign(n, -1.f);
  if (depth != nullptr) {
    for (std::size_t i = 0; i < n; ++i) {
      const float d = consistent_depth(*depth, out->keys[i].pt);
      if (d <= 0) continue;
      out->depth[i] = d;
      out->ur[i] = static_cast<float>(out->keys[i].pt.x - camera_.bf / d);
    }
  }
  out->build_grid(grey.cols, grey.rows);
}

}  // namespace keepless::eval::vo
