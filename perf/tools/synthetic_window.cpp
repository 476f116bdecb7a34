#include "synthetic_window.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace keepless::perf {

namespace {

// Scene and camera constants.
constexpr double kFocal = 500.0;
constexpr double kCx = 320.0;
constexpr double kCy = 240.0;
constexpr double kWidth = 640.0;
constexpr double kHeight = 480.0;
constexpr double kMinDepth = 0.1;
constexpr double kMaxDepth = 15.0;
constexpr double kHalfCorridor = 3.0;  // walls at y = +-3 m
constexpr double kCeiling = 3.0;       // floor z = 0, ceiling z = 3 m
constexpr double kTile = 0.6;          // floor tile, m
constexpr double kStep = 0.25;         // keyframe spacing along the path, m
constexpr double kPixelSigma = 0.7;
constexpr double kSingleViewShare = 0.06;  // points seen once (skipped by the sparsifier)

std::uint64_t splitmix64(std::uint64_t* state) {
  std::uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// xoshiro256**: portable, so the same seed gives the same stream everywhere
// (std::uniform_*_distribution differs between standard libraries).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) {
    std::uint64_t x = seed;
    for (auto& w : s_) w = splitmix64(&x);
  }
  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  // Uniform in [0, 1).
  double u01() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  // Uniform in [0, n), by multiply-shift (no modulo bias worth noting).
  std::uint32_t below(std::uint32_t n) {
    return static_cast<std::uint32_t>(((next() >> 32) * n) >> 32);
  }
  // Approximately normal (Irwin-Hall of 4 uniforms): arithmetic only.
  double gauss(double sigma) {
    const double s = u01() + u01() + u01() + u01() - 2.0;  // variance 1/3
    return s * sigma * 1.7320508075688772;
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
};

struct Vec3 {
  double x, y, z;
};
Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Vec3 normalize(Vec3 a) { return a * (1.0 / std::sqrt(dot(a, a))); }

// A smooth (C1) periodic wave in [-1, 1] of period 1 from two parabolas: no
// libm trigonometry, whose last bits vary between libraries.
double wave(double x) {
  const double f = x - std::floor(x);
  if (f < 0.5) return 8.0 * f * (1.0 - 2.0 * f);
  const double g = f - 0.5;
  return -8.0 * g * (1.0 - 2.0 * g);
}

Vec3 path(double s) { return {s, 0.8 * wave(s / 12.0), 1.4 + 0.05 * wave(s / 3.7)}; }

// Camera axes in world coordinates: x right, y down, z forward (optical axis).
struct Pose {
  Vec3 c, x, y, z;
};

Pose pose_at(double s) {
  Vec3 t = path(s + 0.05) - path(s - 0.05);
  t.z = 0;
  t = normalize(t);
  const Vec3 left{-t.y, t.x, 0};
  const double pan = 0.3 * wave(s / 6.3 + 0.2);  // the camera looks around a little
  const Vec3 forward = normalize(t + left * pan + Vec3{0, 0, -0.15});
  Pose p;
  p.c = path(s);
  p.z = forward;
  p.x = normalize(cross(forward, Vec3{0, 0, 1}));
  p.y = cross(p.z, p.x);
  return p;
}

// Unit quaternion (w, x, y, z) of the camera-to-world rotation [x y z]
// (Shepperd's method: sqrt only).
void orientation(const Pose& p, double q[4]) {
  const double m00 = p.x.x, m01 = p.y.x, m02 = p.z.x;
  const double m10 = p.x.y, m11 = p.y.y, m12 = p.z.y;
  const double m20 = p.x.z, m21 = p.y.z, m22 = p.z.z;
  const double tr = m00 + m11 + m22;
  if (tr > 0) {
    const double s = std::sqrt(tr + 1.0) * 2;
    q[0] = 0.25 * s, q[1] = (m21 - m12) / s, q[2] = (m02 - m20) / s, q[3] = (m10 - m01) / s;
  } else if (m00 > m11 && m00 > m22) {
    const double s = std::sqrt(1.0 + m00 - m11 - m22) * 2;
    q[0] = (m21 - m12) / s, q[1] = 0.25 * s, q[2] = (m01 + m10) / s, q[3] = (m02 + m20) / s;
  } else if (m11 > m22) {
    const double s = std::sqrt(1.0 + m11 - m00 - m22) * 2;
    q[0] = (m02 - m20) / s, q[1] = (m01 + m10) / s, q[2] = 0.25 * s, q[3] = (m12 + m21) / s;
  } else {
    const double s = std::sqrt(1.0 + m22 - m00 - m11) * 2;
    q[0] = (m10 - m01) / s, q[1] = (m02 + m20) / s, q[2] = (m12 + m21) / s, q[3] = 0.25 * s;
  }
}

std::uint64_t hash_cell(std::int64_t a, std::int64_t b, std::uint64_t salt) {
  std::uint64_t x = salt ^ (static_cast<std::uint64_t>(a) * 0x9e3779b97f4a7c15ULL) ^
                    (static_cast<std::uint64_t>(b) * 0xc2b2ae3d27d4eb4fULL);
  return splitmix64(&x);
}

// Distance from x to the nearest multiple of `period`.
double grid_distance(double x, double period) {
  const double r = x - std::floor(x / period) * period;
  return std::min(r, period - r);
}

// Probability that a surface point carries a tracked feature: tile corners
// and posters are dense, grout lines medium, paint and tile faces weak.
double texture(Vec3 p, int surface, std::uint64_t salt) {
  switch (surface) {
    case 0: {  // floor
      const double dx = grid_distance(p.x, kTile), dy = grid_distance(p.y, kTile);
      if (dx < 0.03 && dy < 0.03) return 1.0;
      if (dx < 0.015 || dy < 0.015) return 0.35;
      return 0.02;
    }
    case 1: {  // ceiling: lamps every 3 m on the centre line
      if (grid_distance(p.x, 3.0) < 0.3 && std::fabs(p.y) < 0.3) return 0.5;
      return 0.01;
    }
    default: {  // walls: 1 m cells, a third of them posters
      const auto cx = static_cast<std::int64_t>(std::floor(p.x));
      const auto cz = static_cast<std::int64_t>(std::floor(p.z));
      const std::uint64_t h = hash_cell(cx, cz * 2 + (surface == 2 ? 0 : 1), salt);
      return (h % 3 == 0) ? 0.6 : 0.01;
    }
  }
}

// The surface a pixel ray of `pose` hits first: floor 0, ceiling 1, walls 2/3.
bool cast(const Pose& pose, double u, double v, Vec3* hit, int* surface) {
  const Vec3 d = pose.x * ((u - kCx) / kFocal) + pose.y * ((v - kCy) / kFocal) + pose.z;
  double best = kMaxDepth;  // t equals the camera-frame depth (d.z_cam = 1)
  int which = -1;
  const auto consider = [&](double t, int s) {
    if (t > kMinDepth && t < best) best = t, which = s;
  };
  if (d.z < 0) consider(-pose.c.z / d.z, 0);
  if (d.z > 0) consider((kCeiling - pose.c.z) / d.z, 1);
  if (d.y > 0) consider((kHalfCorridor - pose.c.y) / d.y, 2);
  if (d.y < 0) consider((-kHalfCorridor - pose.c.y) / d.y, 3);
  if (which < 0) return false;
  *hit = pose.c + d * best;
  *surface = which;
  return true;
}

// Camera-frame z of a world point.
double depth_in(const Pose& pose, Vec3 p) { return dot(pose.z, p - pose.c); }

bool project(const Pose& pose, Vec3 p, Rng* rng, double* u, double* v, double* depth) {
  const Vec3 d = p - pose.c;
  const double z = depth_in(pose, p);
  *depth = z;
  if (z < kMinDepth || z > kMaxDepth) return false;
  *u = kFocal * dot(pose.x, d) / z + kCx + rng->gauss(kPixelSigma);
  *v = kFocal * dot(pose.y, d) / z + kCy + rng->gauss(kPixelSigma);
  return *u >= 0 && *u < kWidth && *v >= 0 && *v < kHeight;
}

double round_to(double x, double scale) { return std::round(x * scale) / scale; }

struct Track {
  std::uint32_t first = 0;         // keyframe index of the first view
  std::vector<std::uint32_t> kfs;  // ascending
  std::vector<double> uv;          // u, v per view
  std::vector<double> depth;       // camera-frame z per view
};

// A surface point with a feature, seen from `pose`: rejection sampling on the
// texture, bounded (acceptance is >= 1% in every view direction).
void sample_point(const Pose& pose, std::uint64_t salt, Rng* rng, Vec3* point, double* u,
                  double* v) {
  *point = pose.c + pose.z * 2.0;  // fallback, never reached in practice
  *u = kCx, *v = kCy;
  for (int attempt = 0; attempt < (1 << 16); ++attempt) {
    const double pu = rng->u01() * kWidth, pv = rng->u01() * kHeight;
    Vec3 hit;
    int surface = 0;
    if (!cast(pose, pu, pv, &hit, &surface)) continue;
    *point = hit, *u = pu, *v = pv;
    if (rng->u01() < texture(hit, surface, salt)) return;
  }
}

// Each point: an anchor keyframe, a feature there, then a track of L views
// (L = 1, or 2 + geometric with mean `extra_mean`) around the anchor, cut
// where the point leaves the view. Anchors range `margin` keyframes beyond
// both ends of the window (poses[0] is keyframe -margin) and only views
// inside the window are kept, so the first and last keyframes see tracks
// that began before or continue after the window, as in a sliding window.
std::vector<Track> generate(const SyntheticSpec& spec, const std::vector<Pose>& poses,
                            std::uint32_t margin, std::uint64_t salt, double extra_mean) {
  Rng rng(spec.seed);
  const std::int64_t k = spec.keyframes;
  const std::int64_t lo = -static_cast<std::int64_t>(margin), hi = k + margin;
  const double go_on = extra_mean / (1.0 + extra_mean);
  const auto pose = [&](std::int64_t g) -> const Pose& { return poses[g - lo]; };
  std::vector<Track> tracks(spec.points);
  std::vector<std::int64_t> before;
  std::vector<double> before_uv, before_depth;
  for (Track& t : tracks) {
    // A track wholly outside the window is drawn again; after 64 tries the
    // anchor is forced inside (bounded; the chance is >= 1/3 per try).
    for (int attempt = 0; t.kfs.empty(); ++attempt) {
      const std::int64_t anchor = attempt < 64 ? lo + rng.below(static_cast<std::uint32_t>(hi - lo))
                                               : rng.below(static_cast<std::uint32_t>(k));
      Vec3 p;
      double u = 0, v = 0;
      sample_point(pose(anchor), salt, &rng, &p, &u, &v);
      u = std::min(std::max(u + rng.gauss(kPixelSigma), 0.0), kWidth - 0.01);
      v = std::min(std::max(v + rng.gauss(kPixelSigma), 0.0), kHeight - 0.01);

      std::uint32_t length = 1;
      if (rng.u01() >= kSingleViewShare) {
        length = 2;
        while (length < hi - lo && rng.u01() < go_on) ++length;
      }
      const std::uint32_t back = rng.below(length);
      const std::uint32_t ahead = length - 1 - back;

      before.clear(), before_uv.clear(), before_depth.clear();
      for (std::int64_t g = anchor - 1; g >= anchor - back && g >= lo; --g) {
        double pu = 0, pv = 0, z = 0;
        if (!project(pose(g), p, &rng, &pu, &pv, &z)) break;
        before.push_back(g), before_uv.push_back(pu), before_uv.push_back(pv), before_depth.push_back(z);
      }
      const auto keep = [&](std::int64_t g, double pu, double pv, double z) {
        if (g < 0 || g >= k) return;
        t.kfs.push_back(static_cast<std::uint32_t>(g));
        t.uv.push_back(pu), t.uv.push_back(pv);
        t.depth.push_back(z);
      };
      for (std::size_t i = before.size(); i-- > 0;) {
        keep(before[i], before_uv[2 * i], before_uv[2 * i + 1], before_depth[i]);
      }
      keep(anchor, u, v, depth_in(pose(anchor), p));
      for (std::int64_t g = anchor + 1; g <= anchor + ahead && g < hi; ++g) {
        double pu = 0, pv = 0, z = 0;
        if (!project(pose(g), p, &rng, &pu, &pv, &z)) break;
        keep(g, pu, pv, z);
      }
    }
    t.first = t.kfs.front();
  }
  return tracks;
}

std::uint64_t total_views(const std::vector<Track>& tracks) {
  std::uint64_t n = 0;
  for (const Track& t : tracks) n += t.kfs.size();
  return n;
}

}  // namespace

std::string unknown_workload(const std::string& name) {
  return "--workload: expected small, orbslam, large or map, got '" + name + "'";
}

bool workload_spec(const std::string& name, SyntheticSpec* spec) {
  if (name == "small") {
    spec->keyframes = 10, spec->points = 2000, spec->obs_per_kf = 600;
  } else if (name == "orbslam") {
    spec->keyframes = 20, spec->points = 8000, spec->obs_per_kf = 1000;
  } else if (name == "large") {
    spec->keyframes = 40, spec->points = 20000, spec->obs_per_kf = 1000;
  } else if (name == "map") {
    spec->keyframes = 1000, spec->points = 100000, spec->obs_per_kf = 1000;
  } else {
    return false;
  }
  return true;
}

core::WindowFile make_synthetic_window(const SyntheticSpec& spec,
                                       std::vector<std::vector<core::Keypoint>>* unmapped) {
  core::WindowFile file;
  if (spec.keyframes == 0) return file;
  std::uint64_t salt_state = spec.seed;
  const std::uint64_t salt = splitmix64(&salt_state);

  // Keyframes along the path, spacing jittered by +-20%, with `margin`
  // keyframes before and after the window where tracks may begin or end.
  const std::uint32_t margin = std::min<std::uint32_t>(spec.keyframes, 40);
  Rng path_rng(spec.seed ^ 0x6b6565706c657373ULL);
  std::vector<Pose> poses(spec.keyframes + 2 * margin);
  for (std::uint32_t i = 0; i < poses.size(); ++i) {
    const double index = static_cast<double>(i) - margin;
    poses[i] = pose_at(kStep * (index + 0.4 * (path_rng.u01() - 0.5)));
  }

  // Calibrate the track-length parameter so the mean views per keyframe
  // approach obs_per_kf despite tracks cut at the image and window borders:
  // a few rescalings of the extra views beyond the anchor.
  const double target = static_cast<double>(spec.keyframes) * spec.obs_per_kf;
  const double points = spec.points;
  const double untruncated =
      (target / std::max(points, 1.0) - 2.0 + kSingleViewShare) / (1.0 - kSingleViewShare);
  double extra_mean = std::min(std::max(untruncated, 0.0), static_cast<double>(spec.keyframes));
  std::vector<Track> tracks;
  for (int round = 0; round < 6; ++round) {
    tracks = generate(spec, poses, margin, salt, extra_mean);
    const double beyond = static_cast<double>(total_views(tracks)) - points;
    const double wanted = target - points;
    if (round == 5 || beyond <= 0 || wanted <= 0) break;
    extra_mean =
        std::min(std::max(extra_mean * wanted / beyond, 0.0), static_cast<double>(spec.keyframes));
  }

  // Point ids ascend with the first keyframe that sees them, as in a SLAM map.
  std::vector<std::uint32_t> order(tracks.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return tracks[a].first < tracks[b].first;
  });

  file.keyframes.resize(spec.keyframes);
  file.keyframe_lines.assign(spec.keyframes, 0);
  file.observations.resize(spec.keyframes);
  for (std::uint32_t i = 0; i < spec.keyframes; ++i) {
    const Pose& pose = poses[margin + i];
    core::Keyframe& kf = file.keyframes[i];
    kf.id = 1 + 2ULL * i;  // keyframe ids with gaps, like a SLAM system's
    kf.centre[0] = round_to(pose.c.x, 1e6);
    kf.centre[1] = round_to(pose.c.y, 1e6);
    kf.centre[2] = round_to(pose.c.z, 1e6);
    double q[4];
    orientation(pose, q);
    for (int c = 0; c < 4; ++c) kf.orientation[c] = round_to(q[c], 1e9);
    if (spec.camera) kf.fx = kFocal, kf.fy = kFocal, kf.cx = kCx, kf.cy = kCy;
  }
  for (std::uint32_t rank = 0; rank < order.size(); ++rank) {
    const Track& t = tracks[order[rank]];
    for (std::size_t view = 0; view < t.kfs.size(); ++view) {
      core::Observation o;
      o.point = 1000 + static_cast<std::uint64_t>(rank);
      o.u = round_to(t.uv[2 * view], 1e3);
      o.v = round_to(t.uv[2 * view + 1], 1e3);
      if (spec.camera) o.depth = round_to(t.depth[view], 1e6);
      file.observations[t.kfs[view]].push_back(o);
    }
  }
  if (spec.unmapped_per_kf > 0 && unmapped != nullptr) {
    // Their own stream, after everything above: the map is the same with or
    // without them.
    Rng rng(spec.seed ^ 0x756e6d6170706564ULL);
    unmapped->assign(spec.keyframes, {});
    for (std::uint32_t i = 0; i < spec.keyframes; ++i) {
      std::vector<core::Keypoint>& list = (*unmapped)[i];
      list.resize(spec.unmapped_per_kf);
      for (core::Keypoint& kp : list) {
        Vec3 p;
        double u = 0, v = 0;
        sample_point(poses[margin + i], salt, &rng, &p, &u, &v);
        kp.u = std::min(round_to(u, 1e3), kWidth - 0.001);
        kp.v = std::min(round_to(v, 1e3), kHeight - 0.001);
      }
      file.keyframes[i].unmapped = list.data();
      file.keyframes[i].unmapped_count = spec.unmapped_per_kf;
    }
  }
  file.needs = core::compute_needs(file);
  return file;
}

}  // namespace keepless::perf
