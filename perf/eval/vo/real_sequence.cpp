#include "real_sequence.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace keepless::eval::vo {
namespace fs = std::filesystem;
namespace {

std::vector<double> numbers_in(const std::string& text) {
  std::istringstream s(text);
  std::vector<double> v;
  std::string tok;
  while (s >> tok) {
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);
    if (end != tok.c_str() && *end == '\0') v.push_back(x);
  }
  return v;
}

bool read_text(const std::string& path, std::string* text, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  *text = ss.str();
  return true;
}

// KITTI calib.txt ("P0: 12 numbers" or a bare first line of 12) or a K.txt (3x3).
bool read_calibration(const std::string& path, PinholeCamera* cam, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::string line, all;
  while (std::getline(in, line)) {
    const std::vector<double> v = numbers_in(line);
    if (v.size() == 12 && (line.rfind("P0:", 0) == 0 || all.empty())) {
      cam->fx = v[0], cam->cx = v[2], cam->fy = v[5], cam->cy = v[6];
      return true;
    }
    all += line + "\n";
  }
  const std::vector<double> k = numbers_in(all);
  if (k.size() == 9 && k[8] == 1 && k[0] > 0 && k[4] > 0) {
    cam->fx = k[0], cam->cx = k[2], cam->fy = k[4], cam->cy = k[5];
    return true;
  }
  *error = path + ": neither a P0 projection matrix nor a 3x3 K";
  return false;
}

// Camera-to-world from the first 12 row-major numbers of a 3x4 or 4x4 matrix.
bool pose_from_rows(const std::vector<double>& v, Pose* out) {
  Eigen::Matrix3d R;
  R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
  if (!R.allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 ||
      R.determinant() <= 0) {
    return false;
  }
  out->q = Eigen::Quaterniond(R).normalized();
  out->t = Eigen::Vector3d(v[3], v[7], v[11]);
  return out->t.allFinite();
}

// The image size, from the first frame.
bool probe_size(RealSequence* s, std::string* error) {
  const cv::Mat probe = cv::imread(s->image_files[0], cv::IMREAD_GRAYSCALE);
  if (probe.empty()) {
    *error = s->image_files[0] + ": cannot read image";
    return false;
  }
  s->camera.width = probe.cols;
  s->camera.height = probe.rows;
  return true;
}

// The selected frames as positions a, a + step, ... <= b into `numbers`
// (ascending, non-empty): a sequence may start at any frame number.
bool select_frames(const std::string& dir, const std::vector<long>& numbers, const FrameSelection& f, std::size_t* a,
                   std::size_t* b, std::string* error) {
  const int first = f.first, last = f.last;
  const auto lo = std::lower_bound(numbers.begin(), numbers.end(), static_cast<long>(first));
  const auto hi = last < 0 ? numbers.end() : std::upper_bound(numbers.begin(), numbers.end(), static_cast<long>(last));
  if (first < 0 || (last >= 0 && last < first) || lo >= hi) {
    *error = dir + ": frames " + std::to_string(first) + ":" + (last < 0 ? std::string("end") : std::to_string(last)) +
             " select none of its frames " + std::to_string(numbers.front()) + ".." + std::to_string(numbers.back());
    return false;
  }
  *a = static_cast<std::size_t>(lo - numbers.begin());
  *b = static_cast<std::size_t>(hi - numbers.begin()) - 1;
  if (f.step < 1) {
    *error = dir + ": a frame step of " + std::to_string(f.step) + " (at least 1)";
    return false;
  }
  const auto step = static_cast<std::size_t>(f.step);
  if (f.max_frames > 0) *b = std::min(*b, *a + (static_cast<std::size_t>(f.max_frames) - 1) * step);
  return true;
}

// The number in a file name's stem after `prefix` ("frame-000600.color.jpg" with
// prefix "frame-" and suffix ".color.jpg": 600), or -1.
long frame_number(const std::string& name, const std::string& prefix, const std::string& suffix) {
  if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
    return -1;
  }
  const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stol(digits);
}

std::string name_of(const std::string& dir, bool parent) {
  fs::path p = fs::path(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return (parent ? p.parent_path().filename() : p.filename()).string();
}

}  // namespace

bool RealSequence::load(std::size_t frame, cv::Mat* grey, cv::Mat* depth, std::string* error) const {
  *grey = cv::imread(image_files[frame], cv::IMREAD_GRAYSCALE);
  if (grey->empty()) {
    *error = image_files[frame] + ": cannot read image";
    return false;
  }
  if (rgbd) {
    cv::Mat raw = cv::imread(depth_files[frame], cv::IMREAD_ANYDEPTH);
    if (raw.empty() || raw.type() != CV_16U || raw.size() != grey->size()) {
      *error = depth_files[frame] + ": not a 16-bit depth image of the colour image's size";
      return false;
    }
    raw.setTo(0, raw == 65535);  // 7-Scenes marks invalid depth 0 or 65535
    raw.convertTo(*depth, CV_32F, 1e-3);
  }
  return true;
}

double RealSequence::path_length() const {
  double d = 0;
  for (std::size_t i = 1; i < ground_truth.size(); ++i) d += (ground_truth[i].t - ground_truth[i - 1].t).norm();
  return d;
}

bool load_kitti_sequence(const std::string& image_dir, const std::string& calib_file,
                         const std::string& poses_file, const FrameSelection& frames, RealSequence* out,
                         std::string* error) {
  RealSequence s;
  s.input = image_dir;
  s.name = name_of(image_dir, true);
  s.rgbd = false;
  s.fps = 10;
  if (!read_calibration(calib_file, &s.camera, error)) return false;
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(image_dir, ec)) {
    if (e.path().extension() == ".png") files.push_back(e.path().string());
  }
  if (ec || files.empty()) {
    *error = image_dir + ": no .png images";
    return false;
  }
  std::sort(files.begin(), files.end());
  std::string text;
  if (!read_text(poses_file, &text, error)) return false;
  std::istringstream lines(text);
  std::string line;
  std::vector<Pose> gt;
  int lineno = 0;
  while (std::getline(lines, line)) {
    ++lineno;
    const std::vector<double> v = numbers_in(line);
    if (v.empty()) continue;
    if (v.size() != 12) {
      *error = poses_file + ":" + std::to_string(lineno) + ": expected 12 numbers (3x4 pose)";
      return false;
    }
    Pose pose;
    if (!pose_from_rows(v, &pose)) {
      *error = poses_file + ":" + std::to_string(lineno) + ": not a rigid pose";
      return false;
    }
    gt.push_back(pose);
  }
  // Frame numbers from the names (000600.png: 600); poses pair with the
  // sorted images line by line, as before.
  const std::size_t n = std::min(files.size(), gt.size());
  std::vector<long> numbers;
  for (std::size_t i = 0; i < n; ++i) {
    const long k = frame_number(fs::path(files[i]).filename().string(), "", ".png");
    numbers.push_back(k >= 0 ? k : static_cast<long>(i));
  }
  if (n == 0 || !std::is_sorted(numbers.begin(), numbers.end())) {
    numbers.resize(n);
    for (std::size_t i = 0; i < n; ++i) numbers[i] = static_cast<long>(i);
  }
  if (n == 0) {
    *error = poses_file + ": no poses";
    return false;
  }
  std::size_t a = 0, b = 0;
  if (!select_frames(image_dir, numbers, frames, &a, &b, error)) return false;
  s.fps /= frames.step;
  for (std::size_t i = a; i <= b; i += static_cast<std::size_t>(frames.step)) {
    s.image_files.push_back(files[i]);
    s.ground_truth.push_back(gt[i]);
  }
  if (!probe_size(&s, error)) return false;
  *out = std::move(s);
  return true;
}

bool load_rgbd_sequence(const std::string& dir, const FrameSelection& frames, RealSequence* out, std::string* error) {
  RealSequence s;
  s.input = dir;
  s.name = name_of(dir, false);
  s.rgbd = true;
  s.fps = 30;
  std::string text;
  if (!read_text(dir + "/camera-intrinsics.txt", &text, error)) return false;
  const std::vector<double> k = numbers_in(text);
  if (k.size() != 9 || k[0] <= 0 || k[4] <= 0) {
    *error = dir + "/camera-intrinsics.txt: expected a 3x3 K";
    return false;
  }
  s.camera.fx = k[0], s.camera.cx = k[2], s.camera.fy = k[4], s.camera.cy = k[5];
  // ORB-SLAM2's TUM RGB-D settings: bf = 40 (a 0.07 m virtual baseline at
  // these focal lengths), ThDepth = 40 baselines.
  s.camera.bf = 40.0;
  s.camera.close_depth = 40.0 * s.camera.bf / s.camera.fx;
  // frame-NNNNNN.color.jpg, by number: a sequence may start anywhere (a
  // 7-Scenes slice from frame 600), and --frames names frame numbers.
  std::vector<long> numbers;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const long k = frame_number(e.path().filename().string(), "frame-", ".color.jpg");
    if (k >= 0) numbers.push_back(k);
  }
  if (ec || numbers.empty()) {
    *error = dir + ": no frame-NNNNNN.color.jpg";
    return false;
  }
  std::sort(numbers.begin(), numbers.end());
  std::size_t a = 0, b = 0;
  if (!select_frames(dir, numbers, frames, &a, &b, error)) return false;
  s.fps /= frames.step;
  for (std::size_t i = a; i <= b; i += static_cast<std::size_t>(frames.step)) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "/frame-%06ld", numbers[i]);
    const std::string base = dir + stem;
    std::string pose_text;
    if (!read_text(base + ".pose.txt", &pose_text, error)) return false;
    const std::vector<double> v = numbers_in(pose_text);
    if (v.size() != 16) {
      *error = base + ".pose.txt: expected a 4x4 matrix";
      return false;
    }
    Pose pose;
    if (!pose_from_rows(v, &pose)) {
      *error = base + ".pose.txt: not a rigid pose";
      return false;
    }
    s.image_files.push_back(base + ".color.jpg");
    s.depth_files.push_back(base + ".depth.png");
    s.ground_truth.push_back(pose);
  }
  if (!probe_size(&s, error)) return false;
  *out = std::move(s);
  return true;
}

void drop_depth(RealSequence* s) {
  s->rgbd = false;
  s->name += "_mono";
  s->depth_files.clear();
  s->camera.bf = 0;
  s->camera.close_depth = 0;
}

}  // namespace keepless::eval::vo
