#include "lcm_mode.hpp"

#ifdef KEEPLESS_HAVE_LCM

#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "keepless/decision_t.hpp"
#include "keepless/keyframe_t.hpp"
#include "keepless/platform/message_validation.hpp"
#include "keepless/status_t.hpp"
#include "stream.hpp"

extern char** environ;

namespace keepless::perf {
namespace {

std::uint64_t now_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

struct Listener {
  std::int64_t last_sequence = 0;
  std::uint64_t last_arrival = 0;
  bool status_seen = false;
  void on_decision(const lcm::ReceiveBuffer*, const std::string&, const keepless::decision_t* d) {
    last_sequence = d->sequence;
    last_arrival = now_ns();
  }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const keepless::status_t*) {
    status_seen = true;
  }
};

double nearest_rank(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(v.size())));
  return v[std::min(v.size(), std::max<std::size_t>(rank, 1)) - 1];
}

// Keyframe k of the stream as keyframe_t, with every optional array the
// stream carries (depths, intrinsics, unmapped keypoints, tracked flags,
// point quality), so the node's cost model reads what the in-process path does.
void to_message(const KeyframeStream& stream, std::size_t k, keepless::keyframe_t* msg) {
  const core::Keyframe& kf = stream.keyframes[k];
  const std::vector<core::Observation>& obs = stream.observations[k];
  const std::size_t n = obs.size();
  msg->sequence = static_cast<std::int64_t>(k) + 1;
  msg->utime = (static_cast<std::int64_t>(k) + 1) * 100'000;
  msg->keyframe_id = static_cast<std::int64_t>(kf.id);
  std::copy(kf.centre, kf.centre + 3, msg->centre);
  std::copy(kf.orientation, kf.orientation + 4, msg->orientation);
  msg->image_width = 640;
  msg->image_height = 480;
  msg->num_observations = static_cast<std::int32_t>(n);
  msg->point_id.resize(n);
  msg->u.resize(n);
  msg->v.resize(n);
  bool any_depth = false;
  for (std::size_t i = 0; i < n; ++i) {
    msg->point_id[i] = static_cast<std::int64_t>(obs[i].point);
    msg->u[i] = static_cast<float>(obs[i].u);
    msg->v[i] = static_cast<float>(obs[i].v);
    any_depth = any_depth || obs[i].depth > 0;
  }
  msg->num_depths = any_depth ? static_cast<std::int32_t>(n) : 0;
  msg->depth.resize(any_depth ? n : 0);
  for (std::size_t i = 0; i < msg->depth.size(); ++i) msg->depth[i] = static_cast<float>(obs[i].depth);
  msg->num_intrinsics = kf.fx > 0 ? 4 : 0;
  msg->intrinsics.clear();
  if (kf.fx > 0) msg->intrinsics = {kf.fx, kf.fy, kf.cx, kf.cy};
  msg->num_unmapped = static_cast<std::int32_t>(kf.unmapped_count);
  msg->unmapped_u.resize(kf.unmapped_count);
  msg->unmapped_v.resize(kf.unmapped_count);
  for (std::uint32_t i = 0; i < kf.unmapped_count; ++i) {
    msg->unmapped_u[i] = static_cast<float>(kf.unmapped[i].u);
    msg->unmapped_v[i] = static_cast<float>(kf.unmapped[i].v);
  }
  msg->num_tracked = kf.tracked != nullptr ? static_cast<std::int32_t>(n) : 0;
  msg->tracked.resize(kf.tracked != nullptr ? n : 0);
  for (std::size_t i = 0; i < msg->tracked.size(); ++i) msg->tracked[i] = static_cast<std::int8_t>(kf.tracked[i] != 0);
  const std::size_t q = kf.quality != nullptr ? n : 0;
  msg->num_quality = static_cast<std::int32_t>(q);
  msg->track_length.resize(q);
  msg->age.resize(q);
  msg->reprojection_error.resize(q);
  msg->triangulation_angle.resize(q);
  for (std::size_t i = 0; i < q; ++i) {
    msg->track_length[i] = static_cast<std::int32_t>(std::min<std::uint32_t>(kf.quality[i].track_length, INT32_MAX));
    msg->age[i] = kf.quality[i].age;
    msg->reprojection_error[i] = kf.quality[i].reprojection_error;
    msg->triangulation_angle[i] = kf.quality[i].triangulation_angle;
  }
}

}  // namespace

bool run_lcm_mode(const char* argv0, const KeyframeStream& stream, std::uint32_t warmup, double latency_target_ms,
                  const std::vector<std::string>& node_flags, LcmResult* out, std::string* error) {
  std::string dir = argv0;
  const std::size_t slash = dir.rfind('/');
  dir = slash == std::string::npos ? "." : dir.substr(0, slash);
  const std::string node = dir + "/keepless_node";
  if (access(node.c_str(), X_OK) != 0) {
    *error = "no executable " + node;
    return false;
  }
  const int port = 7700 + static_cast<int>(getpid() % 1000);
  const std::string url = "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0";
  std::uint32_t per_frame = 1;
  for (const auto& o : stream.observations) per_frame = std::max<std::uint32_t>(per_frame, static_cast<std::uint32_t>(o.size()));
  const core::Capacities need = window_needs(stream);
  std::vector<std::string> args = {
      node, "--url", url, "--window", std::to_string(stream.window), "--max-observations",
      std::to_string(per_frame), "--max-points", std::to_string(std::max(need.max_points, per_frame)),
      "--max-window-observations", std::to_string(std::max(need.max_observations, per_frame)),
      "--max-pair-arcs", std::to_string(need.max_pair_arcs + 1), "--status-period-ms", "200", "--quiet",
      "--latency-target-ms", std::to_string(latency_target_ms)};
  std::uint32_t unmapped_per_frame = 0;
  for (const core::Keyframe& kf : stream.keyframes) {
    unmapped_per_frame = std::max(unmapped_per_frame, kf.unmapped_count);
  }
  if (unmapped_per_frame > 0) args.insert(args.end(), {"--max-unmapped", std::to_string(unmapped_per_frame)});
  args.insert(args.end(), node_flags.begin(), node_flags.end());
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, node.c_str(), nullptr, nullptr, argv.data(), environ) != 0) {
    *error = "cannot start " + node;
    return false;
  }
  const auto stop = [pid]() {
    kill(pid, SIGTERM);
    int status = 0;
    waitpid(pid, &status, 0);
  };

  lcm::LCM bus(url);
  if (!bus.good()) {
    stop();
    *error = "cannot open " + url;
    return false;
  }
  Listener listener;
  bus.subscribe("KEEPLESS_DECISION", &Listener::on_decision, &listener);
  bus.subscribe("KEEPLESS_STATUS", &Listener::on_status, &listener);
  const std::uint64_t give_up = now_ns() + 10'000'000'000ull;
  while (!listener.status_seen && now_ns() < give_up) bus.handleTimeout(100);
  if (!listener.status_seen) {
    stop();
    *error = "keepless_node sent no status within 10 s";
    return false;
  }

  std::vector<double> latencies;
  keepless::keyframe_t msg{};
  for (std::size_t k = 0; k < stream.keyframes.size(); ++k) {
    to_message(stream, k, &msg);
    const std::uint64_t sent = now_ns();
    bus.publish("KEEPLESS_KEYFRAME", &msg);
    const std::uint64_t deadline = sent + 2'000'000'000ull;
    while (listener.last_sequence < msg.sequence && now_ns() < deadline) bus.handleTimeout(50);
    if (k < warmup) continue;
    if (listener.last_sequence >= msg.sequence) {
      latencies.push_back(static_cast<double>(listener.last_arrival - sent) * 1e-6);
    } else {
      ++out->lost;
    }
  }
  stop();
  out->decisions = static_cast<std::uint32_t>(latencies.size());
  out->p50_ms = nearest_rank(latencies, 0.5);
  out->p90_ms = nearest_rank(latencies, 0.9);
  out->p99_ms = nearest_rank(latencies, 0.99);
  out->max_ms = latencies.empty() ? 0 : *std::max_element(latencies.begin(), latencies.end());
  return true;
}

bool read_lcm_log(const std::string& path, KeyframeStream* out, std::string* error) {
  lcm::LogFile log(path, "r");
  if (!log.good()) {
    *error = "cannot read LCM log " + path;
    return false;
  }
  out->workload = "log";
  out->window = 20;
  // The node's own byte checks first: the generated decode throws on a
  // negative count. Events that fail them are skipped, and counted.
  platform::MessageLimits limits;
  limits.max_observations = 1u << 24;
  limits.max_unmapped = 1u << 24;
  std::uint32_t skipped = 0;
  keepless::keyframe_t msg;
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    if (e->channel != "KEEPLESS_KEYFRAME") continue;
    if (e->datalen < 0 || platform::check_keyframe_bytes(e->data, static_cast<std::size_t>(e->datalen), limits) !=
                              platform::RejectReason::kNone ||
        msg.decode(e->data, 0, e->datalen) < 0) {
      ++skipped;
      continue;
    }
    core::Keyframe kf;
    kf.id = static_cast<core::KeyframeId>(msg.keyframe_id);
    std::copy(msg.centre, msg.centre + 3, kf.centre);
    std::copy(msg.orientation, msg.orientation + 4, kf.orientation);
    if (msg.num_intrinsics == 4) {
      kf.fx = msg.intrinsics[0];
      kf.fy = msg.intrinsics[1];
      kf.cx = msg.intrinsics[2];
      kf.cy = msg.intrinsics[3];
    }
    std::vector<core::Observation> obs(static_cast<std::size_t>(msg.num_observations));
    for (std::size_t i = 0; i < obs.size(); ++i) {
      obs[i] = {static_cast<core::PointId>(msg.point_id[i]), msg.u[i], msg.v[i],
                msg.num_depths > 0 ? double{msg.depth[i]} : 0.0};
    }
    std::vector<core::Keypoint> unmapped(static_cast<std::size_t>(msg.num_unmapped));
    for (std::size_t i = 0; i < unmapped.size(); ++i) unmapped[i] = {msg.unmapped_u[i], msg.unmapped_v[i]};
    kf.unmapped_count = static_cast<std::uint32_t>(unmapped.size());
    out->keyframes.push_back(kf);
    out->observations.push_back(std::move(obs));
    out->unmapped.push_back(std::move(unmapped));
  }
  // The keyframes point at their unmapped keypoints once the vectors stop moving.
  for (std::size_t k = 0; k < out->keyframes.size(); ++k) {
    if (out->keyframes[k].unmapped_count > 0) out->keyframes[k].unmapped = out->unmapped[k].data();
  }
  if (skipped > 0) {
    std::fprintf(stderr, "keepless_latency: %s: %u keyframe_t events skipped (their bytes fail the node's checks)\n",
                 path.c_str(), skipped);
  }
  if (out->keyframes.empty()) {
    *error = "no keyframe_t on KEEPLESS_KEYFRAME in " + path;
    return false;
  }
  return true;
}

}  // namespace keepless::perf

#else

namespace keepless::perf {

bool run_lcm_mode(const char*, const KeyframeStream&, std::uint32_t, double, const std::vector<std::string>&,
                  LcmResult*, std::string* error) {
  *error = "built without LCM";
  return false;
}
bool read_lcm_log(const std::string&, KeyframeStream*, std::string* error) {
  *error = "built without LCM";
  return false;
}

}  // namespace keepless::perf

#endif
