#include "kitti_images.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

namespace keepless::eval {
namespace {

bool read_calib(const std::string& path, Camera* cam, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ":0: cannot open";
    return false;
  }
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    std::vector<double> v;
    double x;
    while (s >> x) v.push_back(x);
    // "P0: ..." (KITTI) or a bare first line of 12 numbers.
    if ((tag == "P0:" && v.size() == 12) || (lineno == 1 && tag != "P0:" && v.size() == 11)) {
      if (tag != "P0:") v.insert(v.begin(), std::stod(tag));
      cam->fx = v[0];
      cam->cx = v[2];
      cam->fy = v[5];
      cam->cy = v[6];
      cam->baseline = 0;  // the left images only: monocular
      return true;
    }
  }
  *error = path + ":" + std::to_string(lineno) + ": no P0 projection matrix";
  return false;
}

}  // namespace

bool make_image_scenario(const std::string& image_dir, const std::string& calib_file,
                         const std::string& poses_file, const ImageOptions& o, Scenario* out,
                         std::string* error) {
  namespace fs = std::filesystem;
  Scenario s;
  s.input = image_dir;
  s.name = fs::path(image_dir).lexically_normal().parent_path().filename().string();
  if (s.name.empty()) s.name = "images";
  s.group = "kitti_images";
  s.kind = "images";
  if (!read_calib(calib_file, &s.cam, error)) return false;
  std::vector<Pose> gt;
  if (!read_kitti_poses(poses_file, &gt, error)) return false;

  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(image_dir, ec))
    if (e.path().extension() == ".png") files.push_back(e.path().string());
  if (ec || files.empty()) {
    *error = image_dir + ":0: no .png images";
    return false;
  }
  std::sort(files.begin(), files.end());
  std::size_t n = std::min(files.size(), gt.size());
  if (o.max_frames > 0) n = std::min<std::size_t>(n, static_cast<std::size_t>(o.max_frames));
  if (n < 3) {
    *error = image_dir + ":0: fewer than 3 images with poses";
    return false;
  }

  cv::setNumThreads(1);
  cv::Ptr<cv::ORB> orb = cv::ORB::create(o.features);
  cv::BFMatcher matcher(cv::NORM_HAMMING, true);
  cv::Mat prev_desc;
  std::vector<std::vector<int>> prev_of(n);  // per frame, per keypoint: matched keypoint in frame k-1, or -1
  for (std::size_t k = 0; k < n; ++k) {
    const cv::Mat img = cv::imread(files[k], cv::IMREAD_GRAYSCALE);
    if (img.empty()) {
      *error = files[k] + ":0: unreadable image";
      return false;
    }
    s.cam.width = img.cols;
    s.cam.height = img.rows;
    std::vector<cv::KeyPoint> kps;
    cv::Mat desc;
    orb->detectAndCompute(img, cv::noArray(), kps, desc);
    ScenarioFrame f;
    f.gt = gt[k];
    f.source_index = k;
    for (const cv::KeyPoint& c : kps) {
      KeyPoint p;
      p.u = std::clamp(static_cast<double>(c.pt.x), 0.0, img.cols - 1e-6);
      p.v = std::clamp(static_cast<double>(c.pt.y), 0.0, img.rows - 1e-6);
      p.response = c.response;
      f.keypoints.push_back(p);
    }
    prev_of[k].assign(kps.size(), -1);
    if (k > 0 && !prev_desc.empty() && !desc.empty()) {
      std::vector<cv::DMatch> matches;
      matcher.match(desc, prev_desc, matches);
      for (const cv::DMatch& m : matches)
        if (m.distance <= 50) prev_of[k][static_cast<std::size_t>(m.queryIdx)] = m.trainIdx;
    }
    prev_desc = desc;
    s.frames.push_back(std::move(f));
  }
  add_odometry(&s, o.odom_noise_t, o.odom_noise_r_deg, o.seed);

  // Epipolar check against the noisy odometry (what a tracker would have): a
  // match further than 10 px (Sampson) from its epipolar line is dropped.
  for (std::size_t k = 1; k < n; ++k) {
    const Pose& rel = s.odometry[k];  // T_{k-1,k}: x_{k-1} = R x_k + t
    Eigen::Matrix3d tx;
    tx << 0, -rel.t.z(), rel.t.y(), rel.t.z(), 0, -rel.t.x(), -rel.t.y(), rel.t.x(), 0;
    const Eigen::Matrix3d E = tx * rel.R();
    for (std::size_t i = 0; i < prev_of[k].size(); ++i) {
      const int j = prev_of[k][i];
      if (j < 0) continue;
      const KeyPoint& p = s.frames[k].keypoints[i];
      const KeyPoint& q = s.frames[k - 1].keypoints[static_cast<std::size_t>(j)];
      const Eigen::Vector3d x1((p.u - s.cam.cx) / s.cam.fx, (p.v - s.cam.cy) / s.cam.fy, 1);
      const Eigen::Vector3d x0((q.u - s.cam.cx) / s.cam.fx, (q.v - s.cam.cy) / s.cam.fy, 1);
      const Eigen::Vector3d Ex1 = E * x1, Etx0 = E.transpose() * x0;
      const double den = Ex1.x() * Ex1.x() + Ex1.y() * Ex1.y() + Etx0.x() * Etx0.x() + Etx0.y() * Etx0.y();
      const double sampson_px = den > 0 ? std::abs(x0.dot(Ex1)) / std::sqrt(den) * s.cam.fx : 0;
      if (sampson_px > 10.0) prev_of[k][i] = -1;
    }
  }
  // Chain the surviving matches into tracks: the landmarks.
  std::uint64_t next_track = 0;
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t i = 0; i < s.frames[k].keypoints.size(); ++i) {
      const int j = prev_of[k][i];
      s.frames[k].keypoints[i].landmark =
          j >= 0 ? s.frames[k - 1].keypoints[static_cast<std::size_t>(j)].landmark : next_track++;
    }
  s.landmark_count = next_track;
  *out = std::move(s);
  return true;
}

}  // namespace keepless::eval
