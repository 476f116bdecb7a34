#include "box_neighbours.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace keepless::core {

namespace {

// Portable popcount (no -mpopcnt on the x86-64 baseline).
inline std::uint32_t popcount(std::uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<std::uint32_t>((x * 0x0101010101010101ULL) >> 56);
}

// Set bits of `bits` at positions [first, end), first < end.
inline std::uint32_t count_range(const std::uint64_t* bits, std::uint32_t first,
                                 std::uint32_t end) {
  const std::uint32_t wa = first >> 6, wb = (end - 1) >> 6;
  const std::uint64_t head = ~0ULL << (first & 63);
  const std::uint64_t tail = ~0ULL >> (63 - ((end - 1) & 63));
  if (wa == wb) return popcount(bits[wa] & head & tail);
  std::uint32_t total = popcount(bits[wa] & head) + popcount(bits[wb] & tail);
  for (std::uint32_t w = wa + 1; w < wb; ++w) total += popcount(bits[w]);
  return total;
}

inline double coordinate(const Observation& o, bool v_axis) { return v_axis ? o.v : o.u; }

// Sentinels after the sorted coordinates: a pointer tests four ahead.
constexpr std::uint32_t kPad = 4;

}  // namespace

BoxCounter::BoxCounter(std::uint32_t max_count) {
  const std::size_t n = max_count;
  keys_.resize(n);
  spare_.resize(n);
  su_.resize(n + kPad);  // + sentinels
  sv_.resize(n + kPad);
  by_u_.resize(n + kPad);
  v_rank_.resize(n + 1);
  active_.resize(n / 64 + 1);
}

std::size_t BoxCounter::memory_bytes() const {
  const auto b = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return b(keys_) + b(spare_) + b(su_) + b(sv_) + b(by_u_) + b(v_rank_) + b(active_);
}

const std::uint64_t* BoxCounter::sort_axis(const Observation* obs, std::uint32_t n, bool v_axis,
                                           double* coord) {
  double lo = coordinate(obs[0], v_axis), hi = lo;
  for (std::uint32_t i = 1; i < n; ++i) {
    const double c = coordinate(obs[i], v_axis);
    lo = std::min(lo, c);
    hi = std::max(hi, c);
  }
  // key = floor((c - lo) * scale): a composition of rounded monotone
  // operations, so c <= c' implies key <= key'. An overflowing or degenerate
  // span gives scale 0: one run, sorted exactly below.
  double scale = hi - lo > 0 ? 65535.0 / (hi - lo) : 0.0;
  if (!std::isfinite(scale)) scale = 0.0;
  std::uint32_t count[2][256] = {};
  for (std::uint32_t i = 0; i < n; ++i) {
    const double q = scale > 0 ? (coordinate(obs[i], v_axis) - lo) * scale : 0.0;
    const std::uint64_t key = q < 65535.0 ? static_cast<std::uint64_t>(q) : 65535u;
    spare_[i] = key << 32 | i;
    ++count[0][key & 255];
    ++count[1][key >> 8];
  }
  // Two stable counting passes (low byte, high byte): spare -> keys -> spare.
  std::uint64_t* from = spare_.data();
  std::uint64_t* to = keys_.data();
  for (int pass = 0; pass < 2; ++pass) {
    std::uint32_t at = 0;
    for (std::uint32_t& c : count[pass]) {
      const std::uint32_t k = c;
      c = at;
      at += k;
    }
    const int shift = 32 + 8 * pass;
    for (std::uint32_t i = 0; i < n; ++i) to[count[pass][(from[i] >> shift) & 255]++] = from[i];
    std::swap(from, to);
  }
  // Runs of equal keys, by exact coordinate then index.
  const auto before = [obs, v_axis](std::uint64_t a, std::uint64_t b) {
    const double ca = coordinate(obs[static_cast<std::uint32_t>(a)], v_axis);
    const double cb = coordinate(obs[static_cast<std::uint32_t>(b)], v_axis);
    return ca != cb ? ca < cb : static_cast<std::uint32_t>(a) < static_cast<std::uint32_t>(b);
  };
  for (std::uint32_t r = 0; r < n;) {
    std::uint32_t end = r + 1;
    while (end < n && (from[end] >> 32) == (from[r] >> 32)) ++end;
    if (end - r > 1) std::sort(from + r, from + end, before);
    r = end;
  }
  for (std::uint32_t r = 0; r < n; ++r)
    coord[r] = coordinate(obs[static_cast<std::uint32_t>(from[r])], v_axis);
  return from;
}

void BoxCounter::count(const Observation* obs, std::uint32_t n, std::int32_t box_width,
                       std::int32_t box_height, std::uint32_t* out) {
  if (n == 0) return;
  // The same arithmetic as in_box: |q - o| <= half, with q - o rounded once.
  const double half_w = 0.5 * box_width;
  const double half_h = 0.5 * box_height;
  double* su = su_.data();
  double* sv = sv_.data();
  std::uint32_t* by_u = by_u_.data();
  std::uint32_t* v_rank = v_rank_.data();
  std::uint64_t* active = active_.data();
  const std::uint64_t* sorted = sort_axis(obs, n, false, su);
  for (std::uint32_t r = 0; r < n; ++r) by_u[r] = static_cast<std::uint32_t>(sorted[r]);
  sorted = sort_axis(obs, n, true, sv);
  for (std::uint32_t r = 0; r < n; ++r) v_rank[static_cast<std::uint32_t>(sorted[r])] = r;
  std::uint64_t* band = keys_.data();  // free again: first | end << 32, by v rank

  // A pointer's moves: the keypoints passing its test form a prefix of the
  // sorted run ahead of it, so the next four tests (independent loads, not
  // a chain of dependent ones) give the move when it is under four; longer
  // moves finish in a loop. The +inf sentinels fail every forward test.
  for (std::uint32_t i = n; i < n + kPad; ++i)
    sv[i] = su[i] = std::numeric_limits<double>::infinity();

  // Each keypoint's v run: v ranks [first, end) with -half_h <= v - o.v <= half_h.
  // It holds o itself, so first <= rank(o) < end.
  for (std::uint32_t r = 0, first = 0, end = 0; r < n; ++r) {
    const double o = sv[r];
    const std::uint32_t below = (sv[first] - o < -half_h) + (sv[first + 1] - o < -half_h) +
                                (sv[first + 2] - o < -half_h) + (sv[first + 3] - o < -half_h);
    first += below;
    if (below == 4) {
      while (sv[first] - o < -half_h) ++first;
    }
    const std::uint32_t within = (sv[end] - o <= half_h) + (sv[end + 1] - o <= half_h) +
                                 (sv[end + 2] - o <= half_h) + (sv[end + 3] - o <= half_h);
    end += within;
    if (within == 4) {
      while (sv[end] - o <= half_h) ++end;
    }
    band[r] = first | std::uint64_t{end} << 32;
  }

  // Sweep u: `active` holds the v ranks of the keypoints in o's u run. The
  // sentinels' rank n is never set.
  std::fill(active, active + (n >> 6) + 1, 0ULL);
  for (std::uint32_t i = n; i < n + kPad; ++i) by_u[i] = n;
  v_rank[n] = n;
  const auto flip = [&](std::uint32_t at, bool on) {  // toggles rank of u position `at` if `on`
    const std::uint32_t b = v_rank[by_u[at]];
    active[b >> 6] ^= std::uint64_t{on} << (b & 63);
  };
  for (std::uint32_t r = 0, first = 0, end = 0; r < n; ++r) {
    const double o = su[r];
    const bool e0 = su[end] - o <= half_w, e1 = su[end + 1] - o <= half_w;
    const bool e2 = su[end + 2] - o <= half_w, e3 = su[end + 3] - o <= half_w;
    flip(end, e0);
    flip(end + 1, e1);
    flip(end + 2, e2);
    flip(end + 3, e3);
    end += e0 + e1 + e2 + e3;
    if (e3) {
      while (su[end] - o <= half_w) flip(end++, true);
    }
    const bool l0 = su[first] - o < -half_w, l1 = su[first + 1] - o < -half_w;
    const bool l2 = su[first + 2] - o < -half_w, l3 = su[first + 3] - o < -half_w;
    flip(first, l0);
    flip(first + 1, l1);
    flip(first + 2, l2);
    flip(first + 3, l3);
    first += l0 + l1 + l2 + l3;
    if (l3) {
      while (su[first] - o < -half_w) flip(first++, true);
    }
    const std::uint32_t rank = v_rank[by_u[r]];
    out[by_u[r]] = count_range(active, static_cast<std::uint32_t>(band[rank]),
                               static_cast<std::uint32_t>(band[rank] >> 32)) -
                   1;  // minus o itself
  }
}

}  // namespace keepless::core
