#include "keepless/io/keyframes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

#include "keepless/io/atomic_file.hpp"
#include "rotation.hpp"
#include "token_text.hpp"

namespace keepless::io {

void to_metric(const Similarity& s, const double c[3], double out[3]) {
  for (int i = 0; i < 3; ++i) {
    const double* r = s.rotation + 3 * i;
    out[i] = s.scale * (r[0] * c[0] + r[1] * c[1] + r[2] * c[2]) + s.translation[i];
  }
}

bool read_similarity(const std::string& path, Similarity* out, std::string* error) {
  // 13 numbers: a far larger file is no similarity, and reading it whole
  // would hold it outside --max-memory-mb.
  constexpr std::uint64_t kMaxBytes = 65536;
  std::string text;
  if (!read_file(path, &text, error, kMaxBytes)) return false;
  double v[13];
  std::size_t n = 0, at = 0, line = 1;
  while (at < text.size()) {
    const std::size_t end = std::min(text.find_first_of(" \t\r\n", at), text.size());
    if (end == at) {
      line += text[at] == '\n';
      ++at;
      continue;
    }
    const std::string word = text.substr(at, end - at);
    if (n == 13) {
      *error = path + ":" + std::to_string(line) + ": more than 13 numbers (s, R row-major, t)";
      return false;
    }
    if (!core::parse_finite_double(word, &v[n])) {
      *error = path + ":" + std::to_string(line) + ": bad number '" + detail::shown_token(word) + "'";
      return false;
    }
    ++n;
    at = end;
  }
  if (n != 13) {
    *error = path + ":" + std::to_string(line) + ": expected 13 numbers (s, R row-major, t), got " + std::to_string(n);
    return false;
  }
  if (!(v[0] > 0)) {
    *error = path + ":1: the scale must be positive";
    return false;
  }
  // A similarity's R is a rotation: R^T R = I to 1e-4 (a matrix printed with
  // six decimals passes) and det R > 0; anything else would silently distort
  // every camera centre.
  const double* r = v + 1;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double dot = r[i] * r[j] + r[3 + i] * r[3 + j] + r[6 + i] * r[6 + j];
      if (!(std::fabs(dot - (i == j ? 1.0 : 0.0)) <= 1e-4)) {
        *error = path + ":1: R is not a rotation (its columns must be orthonormal)";
        return false;
      }
    }
  }
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
                     r[2] * (r[3] * r[7] - r[4] * r[6]);
  if (!(det > 0)) {
    *error = path + ":1: R is not a rotation (a reflection: det R = -1)";
    return false;
  }
  out->scale = v[0];
  std::copy(v + 1, v + 10, out->rotation);
  std::copy(v + 10, v + 13, out->translation);
  return true;
}

const char* to_string(KeyframeOrder order) {
  switch (order) {
    case KeyframeOrder::kName: return "name";
    case KeyframeOrder::kId: return "id";
    case KeyframeOrder::kFile: return "file";
  }
  return "?";
}

void colmap_camera_centre(const ColmapImage& image, double centre[3]) {
  double r[9];
  detail::quaternion_matrix(image.qvec, r);
  const double* t = image.tvec;
  for (int i = 0; i < 3; ++i) centre[i] = -(r[i] * t[0] + r[3 + i] * t[1] + r[6 + i] * t[2]);
}

void matched_centres(const ColmapModel& a, const ColmapModel& b, std::vector<std::array<double, 3>>* in_a,
                     std::vector<std::array<double, 3>>* in_b) {
  std::unordered_map<std::uint32_t, const ColmapImage*> in_b_by_id;
  for (const ColmapImage& im : b.images) in_b_by_id[im.id] = &im;
  in_a->clear();
  in_b->clear();
  for (const ColmapImage& im : a.images) {
    const auto it = in_b_by_id.find(im.id);
    if (it == in_b_by_id.end()) continue;
    colmap_camera_centre(im, in_a->emplace_back().data());
    colmap_camera_centre(*it->second, in_b->emplace_back().data());
  }
}

namespace {

// The pinhole part of a COLMAP camera: fx, fy, cx, cy (unknown, all 0, when
// the focal length is not positive).
void colmap_intrinsics(const ColmapCamera& camera, core::Keyframe* kf) {
  const CameraModelInfo* info = camera_model_by_id(camera.model_id);
  if (info == nullptr || camera.params.size() < 3) return;
  const bool one_f = info->focal_lengths == 1;
  const std::vector<double>& p = camera.params;
  if (!one_f && p.size() < 4) return;
  const double fx = p[0], fy = one_f ? p[0] : p[1];
  if (!(fx > 0) || !(fy > 0)) return;
  kf->fx = fx;
  kf->fy = fy;
  kf->cx = p[one_f ? 1 : 2];
  kf->cy = p[one_f ? 2 : 3];
}

// Depth in metres from a model-frame z, or 0 (unknown).
double metric_depth(double z, const Similarity& s) {
  const double d = s.scale * z;
  return std::isfinite(d) && d > 0 ? d : 0;
}

}  // namespace

Keyframes keyframes_from_colmap(const ColmapModel& model, KeyframeOrder order, const Similarity& to_metric_frame,
                                bool unmapped) {
  std::vector<std::size_t> slots(model.images.size());
  std::iota(slots.begin(), slots.end(), 0);
  const auto& im = model.images;
  if (order == KeyframeOrder::kName) {
    std::stable_sort(slots.begin(), slots.end(), [&](std::size_t a, std::size_t b) {
      return im[a].name != im[b].name ? im[a].name < im[b].name : im[a].id < im[b].id;
    });
  } else if (order == KeyframeOrder::kId) {
    std::stable_sort(slots.begin(), slots.end(), [&](std::size_t a, std::size_t b) { return im[a].id < im[b].id; });
  }
  std::unordered_map<std::uint32_t, const ColmapCamera*> cameras;
  for (const ColmapCamera& c : model.cameras) cameras.emplace(c.id, &c);
  std::unordered_map<std::uint64_t, const ColmapPoint3D*> points;
  for (const ColmapPoint3D& p : model.points) points.emplace(p.id, &p);
  Keyframes out;
  out.quality.resize(im.size());
  if (unmapped) {
    std::size_t total = 0;
    for (const ColmapImage& image : im) {
      for (const ColmapPoint2D& p : image.points2D) total += p.point3D_id == kNoPoint3D;
    }
    out.unmapped.reserve(total);  // the keyframes point into it: no reallocation below
  }
  std::unordered_set<std::uint64_t> seen;
  for (const std::size_t i : slots) {
    const ColmapImage& image = im[i];
    core::Keyframe kf;
    kf.id = image.id;
    double c[3];
    colmap_camera_centre(image, c);
    to_metric(to_metric_frame, c, kf.centre);
    // Camera-to-model rotation, the conjugate of COLMAP's world-to-camera.
    detail::unit_quaternion(image.qvec, kf.orientation);
    for (int k = 1; k < 4; ++k) kf.orientation[k] = -kf.orientation[k];
    const auto camera = cameras.find(image.camera_id);
    if (camera != cameras.end()) colmap_intrinsics(*camera->second, &kf);
    double r[9];
    detail::quaternion_matrix(image.qvec, r);
    const std::size_t first_unmapped = out.unmapped.size();
    std::vector<core::Observation> obs;
    std::vector<core::PointQuality>& quality = out.quality[out.file.keyframes.size()];
    seen.clear();
    for (const ColmapPoint2D& p : image.points2D) {
      if (p.point3D_id == kNoPoint3D) {
        if (unmapped) out.unmapped.push_back({p.x, p.y});
        continue;
      }
      if (!seen.insert(p.point3D_id).second) {
        ++out.duplicates;
        continue;
      }
      core::Observation& o = obs.emplace_back(core::Observation{p.point3D_id, p.x, p.y});
      core::PointQuality& q = quality.emplace_back();
      const auto x = points.find(p.point3D_id);
      if (x != points.end()) {
        const double* X = x->second->xyz;
        o.depth = metric_depth(r[6] * X[0] + r[7] * X[1] + r[8] * X[2] + image.tvec[2], to_metric_frame);
        q.track_length = static_cast<std::uint32_t>(x->second->track.size());
        if (std::isfinite(x->second->error) && x->second->error >= 0) {
          // A float: an error beyond its range stays the largest, not infinity (which the window refuses).
          q.reprojection_error =
              static_cast<float>(std::min(x->second->error, static_cast<double>(std::numeric_limits<float>::max())));
        }
      }
    }
    kf.unmapped_count = static_cast<std::uint32_t>(out.unmapped.size() - first_unmapped);
    if (kf.unmapped_count > 0) kf.unmapped = out.unmapped.data() + first_unmapped;
    kf.quality = quality.empty() ? nullptr : quality.data();
    out.file.keyframes.push_back(kf);
    out.file.keyframe_lines.push_back(0);
    out.file.observations.push_back(std::move(obs));
  }
  out.file.needs = core::compute_needs(out.file);
  out.file.needs.max_unmapped_keypoints = static_cast<std::uint32_t>(out.unmapped.size());
  return out;
}

Keyframes keyframes_from_bal(const BalProblem& problem, KeyframeOrder /*order: index = id = file*/,
                             const Similarity& to_metric_frame) {
  Keyframes out;
  out.file.keyframes.resize(problem.num_cameras);
  out.file.keyframe_lines.assign(problem.num_cameras, 0);
  out.file.observations.resize(problem.num_cameras);
  for (std::uint32_t i = 0; i < problem.num_cameras; ++i) {
    core::Keyframe& kf = out.file.keyframes[i];
    kf.id = i;
    double c[3];
    bal_camera_centre(problem, i, c);
    to_metric(to_metric_frame, c, kf.centre);
    const double* r = &problem.camera_params[9 * std::size_t{i}];
    const double theta = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (theta > 0) {  // camera-to-world: the rotation by -r
      const double s = std::sin(theta / 2) / theta;
      kf.orientation[0] = std::cos(theta / 2);
      for (int k = 0; k < 3; ++k) kf.orientation[k + 1] = -r[k] * s;
    }
    const double f = r[6];
    if (f > 0) kf.fx = kf.fy = f;  // cx = cy = 0: BAL's keypoints are relative to the image centre
  }
  std::vector<std::unordered_set<std::uint32_t>> seen(problem.num_cameras);
  for (const BalObservation& o : problem.observations) {
    if (!seen[o.camera].insert(o.point).second) {
      ++out.duplicates;
      continue;
    }
    // P = R X + t; BAL projects -P / P.z, so the depth is -P.z.
    const double* cam = &problem.camera_params[9 * std::size_t{o.camera}];
    double P[3];
    detail::angle_axis_rotate(cam, &problem.point_params[3 * std::size_t{o.point}], P);
    out.file.observations[o.camera].push_back({o.point, o.x, o.y, metric_depth(-(P[2] + cam[5]), to_metric_frame)});
  }
  // Track lengths: each point's observations (duplicates in one camera once).
  std::vector<std::uint32_t> views(problem.num_points, 0);
  for (const auto& obs : out.file.observations) {
    for (const core::Observation& o : obs) ++views[o.point];
  }
  out.quality.resize(problem.num_cameras);
  for (std::uint32_t i = 0; i < problem.num_cameras; ++i) {
    for (const core::Observation& o : out.file.observations[i]) {
      core::PointQuality& q = out.quality[i].emplace_back();
      q.track_length = views[o.point];
    }
    if (!out.quality[i].empty()) out.file.keyframes[i].quality = out.quality[i].data();
  }
  out.file.needs = core::compute_needs(out.file);
  return out;
}

std::vector<std::vector<core::PointId>> observed_point_ids(const ColmapModel& model, const Keyframes& keyframes) {
  std::unordered_map<std::uint32_t, const ColmapImage*> by_id;
  for (const ColmapImage& image : model.images) by_id[image.id] = &image;
  std::vector<std::vector<core::PointId>> images;
  images.reserve(keyframes.file.keyframes.size());
  for (const core::Keyframe& kf : keyframes.file.keyframes) {
    std::vector<core::PointId>& ids = images.emplace_back();
    for (const ColmapPoint2D& p : by_id.at(static_cast<std::uint32_t>(kf.id))->points2D) {
      if (p.point3D_id != kNoPoint3D) ids.push_back(p.point3D_id);
    }
  }
  return images;
}

}  // namespace keepless::io
