// An onboard module's use of keepless: size the window once, feed keyframes
// as the tracker makes them, decide which map points to keep. Exits non-zero
// if the library's answer breaks its own contract.

#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <string>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"
#include "keepless/io/atomic_file.hpp"
#include "keepless/platform/monotonic_clock.hpp"

#ifdef ONBOARD_MODULE_WITH_LCM
#include <vector>

#include "keepless/decision_t.hpp"
#include "keepless/keyframe_t.hpp"
#include "keepless/platform/message_validation.hpp"
#endif
#ifdef ONBOARD_MODULE_WITH_OPENCV
#include <vector>

#include "keepless/opencv/keyframe_adapter.hpp"
#endif

namespace {

constexpr std::uint32_t kKeyframes = 6;
constexpr std::uint32_t kPointsPerKeyframe = 24;
constexpr std::uint32_t kPointStride = 8;  // each keyframe sees 16 of the previous one's points

}  // namespace

int main() {
  using namespace keepless;

  core::Capacities capacities;
  capacities.max_keyframes = 8;
  capacities.max_points = 256;
  capacities.max_observations = 512;
  capacities.max_pair_arcs = 2048;
  // The paper's theta and 64x48 box; a small pair capacity M so that this
  // small window has more candidates per keyframe pair than M and must cull.
  core::Params params;
  params.pair_capacity = 8;
  if (core::Sparsifier::validate(params) != core::Status::kOk) return 1;

  core::Window window(capacities);
  core::Sparsifier sparsifier(capacities, params);

  // A camera flying along x; each keyframe sees a band of points that
  // overlaps its neighbours', at pixel positions that drift with the motion.
  core::Observation observations[kPointsPerKeyframe];
  for (std::uint32_t k = 0; k < kKeyframes; ++k) {
    core::Keyframe keyframe;
    keyframe.id = 100 + k;
    keyframe.centre[0] = 0.5 * k;
    for (std::uint32_t i = 0; i < kPointsPerKeyframe; ++i) {
      const std::uint32_t point = k * kPointStride + i;
      observations[i].point = point;
      observations[i].u = 20.0 + 25.0 * (point % 24) - 40.0 * k;
      observations[i].v = 30.0 + 17.0 * (point % 7);
    }
    const core::Status added = window.add_keyframe(keyframe, observations, kPointsPerKeyframe);
    if (added != core::Status::kOk) {
      std::printf("add_keyframe(%u): %s\n", k, core::to_string(added));
      return 1;
    }
  }

  const std::uint64_t start_ns = platform::monotonic_ns();
  const core::Status status = sparsifier.run(window);
  const std::uint64_t elapsed_ns = platform::monotonic_ns() - start_ns;
  if (status != core::Status::kOk) {
    std::printf("run: %s\n", core::to_string(status));
    return 1;
  }

  const core::Summary& s = sparsifier.summary();
  std::printf(
      "onboard_module: %u keyframes, %u points: kept %u, culled %u, skipped %u "
      "(max flow %" PRId64 ", cost %" PRId64 ", %zu bytes reserved)\n",
      s.keyframes, s.points, s.kept, s.culled, s.skipped, s.max_flow, s.total_cost,
      sparsifier.memory_bytes());
  std::fprintf(stderr, "onboard_module: decided in %.1f us\n", elapsed_ns / 1e3);

  // The contract an integrator relies on: one decision per distinct point in
  // ascending id order, a verdict for each, flow within the point's capacity.
  std::uint32_t count[3] = {0, 0, 0};  // by Verdict
  const core::PointDecision* d = sparsifier.decisions();
  for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
    if (i > 0 && d[i].point <= d[i - 1].point) return 1;
    if (d[i].flow < 0 || d[i].flow > d[i].capacity) return 1;
    const auto verdict = static_cast<std::uint32_t>(d[i].verdict);
    if (verdict > 2) return 1;
    if (count[verdict]++ == 0) {  // the first point of each verdict
      std::printf("  point %" PRIu64 ": %s (flow %" PRId64 " of %" PRId64 ")\n", d[i].point,
                  core::to_string(d[i].verdict), d[i].flow, d[i].capacity);
    }
  }
  const std::uint32_t kept = count[static_cast<int>(core::Verdict::kKeep)];
  const std::uint32_t culled = count[static_cast<int>(core::Verdict::kCull)];
  const std::uint32_t skipped = count[static_cast<int>(core::Verdict::kSkip)];
  const bool consistent = sparsifier.decision_count() == s.points && kept == s.kept &&
                          culled == s.culled && skipped == s.skipped &&
                          s.points == window.distinct_points();
  if (!consistent || s.kept == 0 || s.culled == 0) {
    std::printf("onboard_module: inconsistent decisions\n");
    return 1;
  }

#ifdef ONBOARD_MODULE_WITH_OPENCV
  // The same window from an ORB-SLAM-style tracker's own types: cv::KeyPoint,
  // map point ids and Tcw as a cv::Mat; the culled ids come back as a set.
  core::Window cv_window(capacities);
  core::Sparsifier cv_sparsifier(capacities, params);
  opencv::KeyframeAdapter adapter(capacities);
  for (std::uint32_t k = 0; k < kKeyframes; ++k) {
    std::vector<cv::KeyPoint> keypoints;
    std::vector<core::PointId> ids;
    for (std::uint32_t i = 0; i < kPointsPerKeyframe; ++i) {
      const std::uint32_t point = k * kPointStride + i;
      keypoints.emplace_back(float(20.0 + 25.0 * (point % 24) - 40.0 * k), float(30.0 + 17.0 * (point % 7)),
                             31.f);
      ids.push_back(point);
    }
    cv::Mat Tcw = cv::Mat::eye(4, 4, CV_32F);
    Tcw.at<float>(0, 3) = -0.5f * float(k);  // centre at x = 0.5 k
    opencv::CameraPose pose;
    if (opencv::pose_from_tcw(Tcw, &pose) != opencv::Status::kOk ||
        adapter.add_keyframe(cv_window, 100 + k, pose, keypoints, ids) != opencv::Status::kOk) {
      std::printf("opencv adapter rejected keyframe %u\n", k);
      return 1;
    }
  }
  std::vector<core::PointId> cv_culled;
  if (cv_sparsifier.run(cv_window) != core::Status::kOk) return 1;
  opencv::culled_points(cv_sparsifier, &cv_culled);
  if (cv_culled.size() != culled) {
    std::printf("onboard_module: the OpenCV adapter's window decided differently\n");
    return 1;
  }
  std::printf("  keepless::opencv: %zu culled ids, the same decisions\n", cv_culled.size());
#endif

#ifdef ONBOARD_MODULE_WITH_LCM
  // What the module would publish on the bus: the summary and the culled ids.
  keepless::decision_t message{};
  message.keyframe_id = static_cast<std::int64_t>(window.keyframe(window.keyframe_count() - 1).id);
  message.status = keepless::decision_t::STATUS_OPTIMAL;
  message.reject_reason = -1;
  message.points = static_cast<std::int32_t>(s.points);
  message.evaluated = static_cast<std::int32_t>(s.evaluated);
  message.kept = static_cast<std::int32_t>(s.kept);
  message.culled = static_cast<std::int32_t>(s.culled);
  message.skipped = static_cast<std::int32_t>(s.skipped);
  message.pairs = static_cast<std::int32_t>(s.pairs);
  message.max_flow = s.max_flow;
  message.total_cost = s.total_cost;
  for (std::uint32_t i = 0; i < window.keyframe_count(); ++i) {
    message.window_keyframe_id.push_back(static_cast<std::int64_t>(window.keyframe(i).id));
  }
  for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
    if (d[i].verdict == core::Verdict::kCull) {
      message.culled_point_id.push_back(static_cast<std::int64_t>(d[i].point));
    }
  }
  message.num_window_keyframes = static_cast<std::int32_t>(message.window_keyframe_id.size());
  message.num_culled = static_cast<std::int32_t>(message.culled_point_id.size());
  std::vector<std::uint8_t> buffer(static_cast<std::size_t>(message.getEncodedSize()));
  const int encoded = message.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
  keepless::decision_t decoded;
  if (encoded != static_cast<int>(buffer.size()) ||
      decoded.decode(buffer.data(), 0, encoded) != encoded ||
      decoded.num_culled != message.num_culled ||
      decoded.culled_point_id != message.culled_point_id) {
    std::printf("onboard_module: decision_t did not round-trip\n");
    return 1;
  }
  std::printf("  decision_t: %d bytes, %d culled ids\n", encoded, decoded.num_culled);
  // keepless::platform_lcm: the node's byte checks on an incoming keyframe_t.
  keepless::keyframe_t keyframe{};
  keyframe.orientation[0] = 1;
  keyframe.image_width = 640;
  keyframe.image_height = 480;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(keyframe.getEncodedSize()));
  keyframe.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (platform::check_keyframe_bytes(bytes.data(), bytes.size(), platform::MessageLimits{}) !=
      platform::RejectReason::kNone) {
    std::printf("onboard_module: a valid keyframe_t failed the node's byte checks\n");
    return 1;
  }
#endif
  // keepless::io: the culled ids written atomically and read back.
  std::string text;
  for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
    if (d[i].verdict == core::Verdict::kCull) text += std::to_string(d[i].point) + "\n";
  }
  const std::string path = "onboard_module_culled.txt";
  std::string back, error;
  if (!io::write_file_atomically(path, text, &error) || !io::read_file(path, &back, &error) || back != text) {
    std::printf("onboard_module: keepless::io did not round-trip the culled ids: %s\n", error.c_str());
    return 1;
  }
  std::remove(path.c_str());
  std::printf("  keepless::io: %zu bytes written and read back\n", back.size());
  return 0;
}
