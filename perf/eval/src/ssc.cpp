#include "ssc.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace keepless::eval {

std::vector<std::uint32_t> ssc_select(const std::vector<SscPoint>& points, std::uint32_t k, int cols,
                                      int rows, double tolerance) {
  const std::uint32_t n = static_cast<std::uint32_t>(points.size());
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (points[a].response != points[b].response) return points[a].response > points[b].response;
    return points[a].id < points[b].id;
  });
  if (k >= n) return order;
  if (k <= 1) return std::vector<std::uint32_t>(order.begin(), order.begin() + k);

  // Bailo's closed-form bounds on the width.
  const double K = k;
  const double exp1 = rows + cols + 2.0 * K;
  const double exp2 = 4.0 * cols + 4.0 * K + 4.0 * rows * K + double(rows) * rows + double(cols) * cols -
                      2.0 * rows * cols + 4.0 * rows * cols * K;
  const double exp3 = std::sqrt(exp2);
  const double exp4 = K - 1.0;
  const double sol1 = -std::round((exp1 + exp3) / exp4);
  const double sol2 = -std::round((exp1 - exp3) / exp4);
  int high = static_cast<int>(std::max(sol1, sol2));
  int low = static_cast<int>(std::floor(std::sqrt(double(n) / K)));
  low = std::max(low, 1);
  high = std::max(high, low);
  const std::uint32_t kmin = static_cast<std::uint32_t>(std::round(K - K * tolerance));
  const std::uint32_t kmax = static_cast<std::uint32_t>(std::round(K + K * tolerance));

  std::vector<std::uint32_t> result, best;
  int prev_width = -1;
  for (int guard = 0; guard < 64; ++guard) {  // binary search: bounded
    const int width = low + (high - low) / 2;
    if (width == prev_width || low > high) break;
    result.clear();
    const double c = std::max(width / 2.0, 0.5);
    const int ncols = static_cast<int>(std::floor(cols / c));
    const int nrows = static_cast<int>(std::floor(rows / c));
    std::vector<char> covered(static_cast<std::size_t>(nrows + 1) * static_cast<std::size_t>(ncols + 1), 0);
    const int reach = static_cast<int>(std::floor(width / c));
    for (std::uint32_t idx : order) {
      const int row = std::clamp(static_cast<int>(std::floor(points[idx].y / c)), 0, nrows);
      const int col = std::clamp(static_cast<int>(std::floor(points[idx].x / c)), 0, ncols);
      if (covered[static_cast<std::size_t>(row) * (ncols + 1) + col]) continue;
      result.push_back(idx);
      const int r0 = std::max(0, row - reach), r1 = std::min(nrows, row + reach);
      const int c0 = std::max(0, col - reach), c1 = std::min(ncols, col + reach);
      for (int r = r0; r <= r1; ++r)
        for (int cc = c0; cc <= c1; ++cc) covered[static_cast<std::size_t>(r) * (ncols + 1) + cc] = 1;
    }
    best = result;
    if (result.size() >= kmin && result.size() <= kmax) break;
    if (result.size() < kmin) high = width - 1;
    else low = width + 1;
    prev_width = width;
  }
  // Exactly k: SSC keeps its selections in response order, so trimming keeps
  // the strongest; a short set is topped up with the strongest unselected.
  if (best.size() > k) best.resize(k);
  if (best.size() < k) {
    std::vector<char> taken(n, 0);
    for (std::uint32_t i : best) taken[i] = 1;
    for (std::uint32_t idx : order) {
      if (best.size() >= k) break;
      if (!taken[idx]) best.push_back(idx);
    }
  }
  return best;
}

std::vector<std::vector<std::uint32_t>> ssc_select_shared(const std::vector<std::vector<SscPoint>>& groups,
                                                          std::uint32_t k, int cols, int rows) {
  std::size_t total = 0;
  for (const auto& g : groups) total += g.size();
  const std::uint32_t keep = static_cast<std::uint32_t>(std::min<std::size_t>(k, total));
  std::vector<std::uint32_t> quota(groups.size(), 0);
  std::vector<std::pair<double, std::size_t>> remainder;  // (-fraction, group): largest first, then order
  std::uint32_t given = 0;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const double exact = total == 0 ? 0.0 : double(keep) * double(groups[g].size()) / double(total);
    quota[g] = static_cast<std::uint32_t>(std::floor(exact));
    given += quota[g];
    remainder.emplace_back(-(exact - std::floor(exact)), g);
  }
  std::sort(remainder.begin(), remainder.end());
  for (std::size_t j = 0; given < keep && j < remainder.size(); ++j, ++given) ++quota[remainder[j].second];
  std::vector<std::vector<std::uint32_t>> kept(groups.size());
  for (std::size_t g = 0; g < groups.size(); ++g) kept[g] = ssc_select(groups[g], quota[g], cols, rows);
  return kept;
}

}  // namespace keepless::eval
