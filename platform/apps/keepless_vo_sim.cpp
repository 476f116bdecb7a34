// keepless_vo_sim: a visual-odometry stand-in that publishes a realistic
// keyframe stream over LCM (built-in street/room scene, or a real trajectory
// file), waits for keepless_node's decision on each keyframe and applies it to
// its own map, so culled points are never observed again (the paper's closed
// loop). Prints a live progress line and a summary table; --report DIR writes
// CSV and SVG. Deterministic for a given --seed. See docs/node.md.

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "cli/cli.hpp"
#include "keepless/decision_t.hpp"
#include "keepless/core/window_file.hpp"
#include "keepless/decision_timing_t.hpp"
#include "keepless/keyframe_t.hpp"
#include "keepless/map_event_t.hpp"
#include "keepless/platform/monotonic_clock.hpp"
#include "keepless/status_t.hpp"
#include "vo_sim/report.hpp"
#include "vo_sim/scene.hpp"
#include "vo_sim/trajectory.hpp"

namespace {

using namespace keepless::vo_sim;
using keepless::platform::monotonic_ns;

struct SimConfig {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::string keyframe_channel = "KEEPLESS_KEYFRAME";
  std::string event_channel = "KEEPLESS_MAP_EVENT";
  std::string decision_channel = "KEEPLESS_DECISION";
  std::string timing_channel = "KEEPLESS_DECISION_TIMING";
  std::string status_channel = "KEEPLESS_STATUS";
  std::string scene = "street";
  std::string trajectory;
  std::string format;
  double kf_distance = -1;  // auto by scene/format
  double kf_angle = 15;
  std::size_t keyframes = 300;
  std::uint64_t seed = 1;
  int max_keypoints = 1000;
  int retriangulate_after = 20;
  double pixel_noise = 0.7;
  int event_every = 25;
  int decision_timeout_ms = 5000;
  int wait_node_ms = 10000;
  std::string report;
  bool quiet = false;
};

const std::vector<keepless::cli::Flag> kFlags = {
    {"--url", "URL", "LCM URL (default udpm://239.255.76.67:7667?ttl=0)"},
    {"--keyframe-channel", "NAME", "keyframe_t output, as keepless_node's (default KEEPLESS_KEYFRAME)"},
    {"--event-channel", "NAME", "map_event_t output (default KEEPLESS_MAP_EVENT)"},
    {"--decision-channel", "NAME", "decision_t input (default KEEPLESS_DECISION)"},
    {"--timing-channel", "NAME", "decision_timing_t input (default KEEPLESS_DECISION_TIMING)"},
    {"--status-channel", "NAME", "status_t input (default KEEPLESS_STATUS)"},
    {"--scene", "street|room", "built-in scene (default street; not with --trajectory)"},
    {"--trajectory", "FILE", "follow a real trajectory instead (KITTI: street; TUM/EuRoC: indoor scene)"},
    {"--format", "tum|euroc|euroc-cam|kitti", "the trajectory's format (euroc: IMU body ground truth, cam0\n"
                                              "mounting applied; euroc-cam: ORB-SLAM3 EuRoC_left_cam files)"},
    {"--kf-distance", "M", "with --trajectory: new keyframe after moving M metres (default: kitti\n"
                            "1.0, indoor 0.1)"},
    {"--kf-angle", "DEG", "with --trajectory: ... or turning DEG degrees (default 15)"},
    {"--keyframes", "N", "keyframes to publish (default 300)"},
    {"--seed", "S", "scene and noise seed (default 1)"},
    {"--max-keypoints", "N", "detector budget per keyframe (default 1000)"},
    {"--pixel-noise", "SIGMA", "keypoint noise in pixels (default 0.7)"},
    {"--retriangulate-after", "N", "a culled feature may become a new map point N keyframes later\n"
                                   "(default 20, the node's window; -1: never)"},
    {"--event-every", "N", "every N keyframes, delete a few outliers with a map_event_t\n"
                           "(default 25, 0: never)"},
    {"--decision-timeout-ms", "N", "wait this long for each decision (default 5000)"},
    {"--wait-node-ms", "N", "wait this long for the node's first status (default 10000)"},
    {"--report", "DIR", "write keyframes.csv, points.csv, map_topdown.svg, keyframe_NNNN.svg,\n"
                        "summary.txt"},
    {"--quiet", nullptr, "no progress line"},
};

std::string usage() { return keepless::cli::usage("usage: keepless_vo_sim [options]", kFlags); }

bool parse_args(int argc, char** argv, SimConfig& c, std::string& error, bool& help, bool& version) {
  bool scene_given = false;
  const char* trajectory_only = nullptr;  // the first of --format, --kf-distance, --kf-angle
  for (int i = 1; i < argc; ++i) {
    const keepless::cli::Flag* entry = nullptr;
    const char* arg = nullptr;
    switch (keepless::cli::next(kFlags, argc, argv, &i, &entry, &arg, &error)) {
      case keepless::cli::Arg::kHelp: help = true; return true;
      case keepless::cli::Arg::kVersion: version = true; return true;
      case keepless::cli::Arg::kError: return false;
      case keepless::cli::Arg::kFlag: break;
    }
    const std::string flag = entry->name;
    if (flag == "--quiet") {
      c.quiet = true;
      continue;
    }
    const std::string value = arg;
    scene_given = scene_given || flag == "--scene";
    if (trajectory_only == nullptr && (flag == "--format" || flag == "--kf-distance" || flag == "--kf-angle")) {
      trajectory_only = entry->name;
    }
    char* end = nullptr;
    errno = 0;
    auto as_u64 = [&](std::uint64_t lo, std::uint64_t hi, std::uint64_t& out) {
      std::uint64_t v = 0;  // digits only (strtoull alone reads " -1" as 2^64 - 1)
      if (!keepless::core::parse_uint64(value, &v) || v < lo || v > hi) return false;
      out = v;
      return true;
    };
    auto as_double = [&](double lo, double hi, double& out) {
      double v = 0;  // plain decimal (strtod alone takes leading blanks and hex floats)
      if (!keepless::core::parse_finite_double(value, &v) || v < lo || v > hi) return false;
      out = v;
      return true;
    };
    std::uint64_t n = 0;
    bool ok = true;
    if (flag == "--url") c.url = value;
    else if (flag == "--keyframe-channel") c.keyframe_channel = value;
    else if (flag == "--event-channel") c.event_channel = value;
    else if (flag == "--decision-channel") c.decision_channel = value;
    else if (flag == "--timing-channel") c.timing_channel = value;
    else if (flag == "--status-channel") c.status_channel = value;
    else if (flag == "--scene") ok = (value == "street" || value == "room") && (c.scene = value, true);
    else if (flag == "--trajectory") c.trajectory = value;
    else if (flag == "--format") c.format = value;
    else if (flag == "--kf-distance") ok = as_double(0, 1000, c.kf_distance);
    else if (flag == "--kf-angle") ok = as_double(0, 180, c.kf_angle);
    else if (flag == "--keyframes") ok = as_u64(1, 10000000, n) && (c.keyframes = n, true);
    else if (flag == "--seed") ok = as_u64(0, ~0ull, c.seed);
    else if (flag == "--max-keypoints") ok = as_u64(1, 1u << 20, n) && (c.max_keypoints = static_cast<int>(n), true);
    else if (flag == "--pixel-noise") ok = as_double(0, 100, c.pixel_noise);
    else if (flag == "--retriangulate-after") {
      const long v = std::strtol(value.c_str(), &end, 10);
      ok = errno == 0 && end != value.c_str() && *end == '\0' && v >= -1 && v <= 1000000;
      if (ok) c.retriangulate_after = static_cast<int>(v);
    }
    else if (flag == "--event-every") ok = as_u64(0, 1u << 30, n) && (c.event_every = static_cast<int>(n), true);
    else if (flag == "--decision-timeout-ms") ok = as_u64(1, 3600000, n) && (c.decision_timeout_ms = static_cast<int>(n), true);
    else if (flag == "--wait-node-ms") ok = as_u64(0, 3600000, n) && (c.wait_node_ms = static_cast<int>(n), true);
    else if (flag == "--report") c.report = value;
    else {
      error = keepless::cli::unknown_option(flag);
      return false;
    }
    if (!ok || value.empty()) {
      error = flag + " '" + value + "': invalid value";
      return false;
    }
  }
  if (!c.trajectory.empty() && c.format.empty()) {
    error = "--trajectory needs --format tum|euroc|euroc-cam|kitti";
    return false;
  }
  // A flag of the other source would be ignored: refused instead.
  if (c.trajectory.empty() && trajectory_only != nullptr) {
    error = std::string(trajectory_only) + " needs --trajectory (the built-in scenes have their own path)";
    return false;
  }
  if (!c.trajectory.empty() && scene_given) {
    error = "--scene and --trajectory exclude each other (a trajectory's scene follows its --format)";
    return false;
  }
  return true;
}

// Everything heard on the bus.
struct Listener {
  std::map<std::int64_t, keepless::decision_t> decisions;  // by sequence
  std::map<std::int64_t, std::uint64_t> received_ns;
  std::map<std::int64_t, keepless::decision_timing_t> timings;
  keepless::status_t status{};
  bool have_status = false;
  std::size_t statuses = 0;

  // Plain functions for subscribeFunction: GCC's UBSan misreports the
  // pointer-to-member call behind LCM's member-function subscribe.
  static void on_decision(const lcm::ReceiveBuffer*, const std::string&, const keepless::decision_t* d,
                          Listener* self) {
    self->received_ns[d->sequence] = monotonic_ns();
    self->decisions[d->sequence] = *d;
  }
  static void on_timing(const lcm::ReceiveBuffer*, const std::string&, const keepless::decision_timing_t* t,
                        Listener* self) {
    self->timings[t->sequence] = *t;
  }
  static void on_status(const lcm::ReceiveBuffer*, const std::string&, const keepless::status_t* s,
                        Listener* self) {
    self->status = *s;
    self->have_status = true;
    ++self->statuses;
  }
};

// Handles LCM until `done()` or `timeout_ms` elapsed; true if done.
template <class Done>
bool wait_for(lcm::LCM& bus, int timeout_ms, Done done) {
  const std::uint64_t deadline = monotonic_ns() + static_cast<std::uint64_t>(timeout_ms) * 1000000ull;
  while (!done()) {
    const std::uint64_t now = monotonic_ns();
    if (now >= deadline) return false;
    const int left = static_cast<int>((deadline - now) / 1000000ull) + 1;
    if (bus.handleTimeout(std::min(left, 50)) < 0 && errno != EINTR) return done();
  }
  return true;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}
std::string with_commas(long long v) {
  std::string s = std::to_string(v < 0 ? -v : v);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<std::size_t>(i), ",");
  return v < 0 ? "-" + s : s;
}

}  // namespace

int main(int argc, char** argv) {
  SimConfig cfg;
  std::string error;
  bool help = false, version = false;
  if (!parse_args(argc, argv, cfg, error, help, version)) return keepless::cli::usage_error("keepless_vo_sim", error);
  if (help) {
    std::fputs(usage().c_str(), stdout);
    return 0;
  }
  if (version) return keepless::cli::print_version("keepless_vo_sim");

  // The camera path and the scene around it.
  std::vector<Pose> path;
  SceneConfig scene;
  std::string source;
  if (cfg.trajectory.empty()) {
    if (cfg.scene == "room") {
      scene = room_scene();
      path = room_path(cfg.keyframes, cfg.seed);
    } else {
      scene = street_scene();
      path = street_path(cfg.keyframes, cfg.seed);
    }
    source = "built-in " + scene.name + " scene";
  } else {
    TrajectoryFormat format;
    if (!parse_format(cfg.format, format)) {
      std::fprintf(stderr, "keepless_vo_sim: --format '%s': expected tum, euroc, euroc-cam or kitti\n", cfg.format.c_str());
      return 2;
    }
    std::vector<Pose> poses;
    if (!load_trajectory(cfg.trajectory, format, poses, error)) {
      std::fprintf(stderr, "keepless_vo_sim: %s\n", error.c_str());
      return 2;
    }
    const bool outdoor = format == TrajectoryFormat::kKitti;
    scene = outdoor ? street_scene() : room_scene();
    const double d = cfg.kf_distance >= 0 ? cfg.kf_distance : (outdoor ? 1.0 : 0.1);
    path = select_keyframes(poses, d, cfg.kf_angle, cfg.keyframes);
    // Floor below the lowest camera position; walls (and ceiling) above the highest.
    double zmin = 1e300, zmax = -1e300;
    for (const Pose& p : path) zmin = std::min(zmin, p.centre.z), zmax = std::max(zmax, p.centre.z);
    scene.floor_z = zmin - (outdoor ? 1.65 : 1.2);
    scene.wall_top = outdoor ? scene.floor_z + 12.0 : std::max(zmax + 1.0, scene.floor_z + 2.8);
    source = cfg.trajectory + " (" + cfg.format + ", " + std::to_string(poses.size()) + " poses)";
  }
  scene.max_keypoints = cfg.max_keypoints;
  scene.pixel_noise = cfg.pixel_noise;
  scene.retriangulate_after = cfg.retriangulate_after;
  const Camera camera;
  World world(scene, camera, path, cfg.seed);
  const std::size_t total = path.size();

  lcm::LCM bus(cfg.url);
  if (!bus.good()) {
    std::fprintf(stderr, "keepless_vo_sim: cannot open LCM URL '%s'\n", cfg.url.c_str());
    return 1;
  }
  Listener heard;
  bus.subscribeFunction(cfg.decision_channel, &Listener::on_decision, &heard);
  bus.subscribeFunction(cfg.timing_channel, &Listener::on_timing, &heard);
  bus.subscribeFunction(cfg.status_channel, &Listener::on_status, &heard);

  std::printf("keepless_vo_sim: %s, %zu keyframes, seed %llu, on %s\n", source.c_str(), total,
              static_cast<unsigned long long>(cfg.seed), cfg.url.c_str());
  std::fflush(stdout);
  if (cfg.wait_node_ms > 0 && !wait_for(bus, cfg.wait_node_ms, [&] { return heard.have_status; })) {
    std::fprintf(stderr, "keepless_vo_sim: no status from keepless_node on %s within %d ms\n", cfg.url.c_str(),
                 cfg.wait_node_ms);
    return 1;
  }

  const bool tty = isatty(STDOUT_FILENO) != 0 && !cfg.quiet;
  const std::size_t snapshot_index = total / 2;
  SnapshotKeyframe snapshot;
  std::vector<KeyframeRecord> records;
  std::vector<double> latencies;
  std::vector<SimObservation> obs;
  std::vector<std::uint32_t> mapped_now;
  keepless::keyframe_t msg{};
  std::vector<std::uint8_t> buffer;
  std::int64_t sequence = 0;
  std::int64_t culled_total = 0, deleted_total = 0, observations_total = 0, detected_total = 0;
  std::size_t answered = 0, non_optimal = 0;
  SplitMix64 event_rng(mix_seed(cfg.seed, 99));

  for (std::size_t i = 0; i < total; ++i) {
    const Pose& pose = path[i];
    const auto index = static_cast<std::int32_t>(i);
    const std::int64_t issued_before = world.landmarks_issued();
    world.observe(pose, index, obs);
    KeyframeRecord rec;
    rec.index = index;
    rec.sequence = ++sequence;
    rec.keyframe_id = static_cast<std::int64_t>(i);
    rec.centre = pose.centre;
    rec.detected = static_cast<std::int32_t>(obs.size());
    rec.new_points = static_cast<std::int32_t>(world.landmarks_issued() - issued_before);
    detected_total += rec.detected;
    if (i == snapshot_index) {
      snapshot.index = index;
      snapshot.observations = obs;
    }

    msg.sequence = rec.sequence;
    msg.utime = pose.utime;
    msg.keyframe_id = rec.keyframe_id;
    msg.centre[0] = pose.centre.x, msg.centre[1] = pose.centre.y, msg.centre[2] = pose.centre.z;
    mat_to_quat(pose.rotation, msg.orientation);
    msg.image_width = camera.width;
    msg.image_height = camera.height;
    msg.point_id.clear();
    msg.u.clear();
    msg.v.clear();
    for (const SimObservation& o : obs) {
      if (!o.mapped) continue;
      msg.point_id.push_back(world.points()[o.point].landmark);
      msg.u.push_back(o.u);
      msg.v.push_back(o.v);
    }
    msg.num_observations = static_cast<std::int32_t>(msg.point_id.size());
    rec.observations = msg.num_observations;
    observations_total += rec.observations;
    buffer.resize(static_cast<std::size_t>(msg.getEncodedSize()));
    msg.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
    const std::uint64_t sent_ns = monotonic_ns();
    bus.publish(cfg.keyframe_channel, buffer.data(), static_cast<unsigned>(buffer.size()));

    const std::int64_t seq = rec.sequence;
    if (wait_for(bus, cfg.decision_timeout_ms, [&] { return heard.decisions.count(seq) > 0; })) {
      const keepless::decision_t& d = heard.decisions[seq];
      rec.answered = true;
      ++answered;
      rec.status = d.status;
      if (d.status != keepless::decision_t::STATUS_OPTIMAL) ++non_optimal;
      rec.window_keyframes = d.num_window_keyframes;
      rec.window_points = d.points;
      rec.evaluated = d.evaluated;
      rec.kept = d.kept;
      rec.culled = d.culled;
      rec.skipped = d.skipped;
      rec.latency_ms = static_cast<double>(heard.received_ns[seq] - sent_ns) / 1e6;
      latencies.push_back(rec.latency_ms);
      // Closed loop: culled map points leave the VO's map for good; from a
      // node with --defer, the deleted ones (the sim has no BA to exclude from).
      for (std::int64_t id : d.culled_point_id) {
        if (world.cull(id, index)) ++culled_total;
      }
      for (std::int64_t id : d.deleted_point_id) {
        if (world.cull(id, index)) ++culled_total;
      }
      heard.decisions.erase(seq);
    } else {
      std::fprintf(stderr, "\nkeepless_vo_sim: no decision for keyframe %zu (sequence %lld) within %d ms\n", i,
                   static_cast<long long>(seq), cfg.decision_timeout_ms);
    }

    // Now and then the VO drops a few outliers from its map and says so.
    if (cfg.event_every > 0 && (i + 1) % static_cast<std::size_t>(cfg.event_every) == 0) {
      keepless::map_event_t ev{};
      ev.sequence = ++sequence;
      ev.utime = pose.utime;
      ev.reset = false;
      mapped_now.clear();
      for (const SimObservation& o : obs) {
        if (world.points()[o.point].state == PointState::kMapped) mapped_now.push_back(o.point);
      }
      for (int k = 0; k < 5 && !mapped_now.empty(); ++k) {
        const std::size_t pick = event_rng.below(mapped_now.size());
        const std::uint32_t f = mapped_now[pick];
        mapped_now[pick] = mapped_now.back();
        mapped_now.pop_back();
        ev.deleted_point_id.push_back(world.points()[f].landmark);
        world.remove(f);
        ++deleted_total;
      }
      ev.num_deleted_points = static_cast<std::int32_t>(ev.deleted_point_id.size());
      ev.num_merged_points = 0;
      ev.num_removed_keyframes = 0;
      bus.publish(cfg.event_channel, &ev);
    }

    std::int64_t features_mapped = 0, alive = 0;
    for (const ScenePoint& p : world.points()) {
      features_mapped += p.state != PointState::kUnseen;
      alive += p.state == PointState::kMapped;
    }
    const std::int64_t mapped = features_mapped;
    rec.mapped_points = mapped;
    rec.alive_points = alive;
    const double kept_pct = mapped > 0 ? 100.0 * static_cast<double>(rec.alive_points) / static_cast<double>(mapped) : 100.0;
    if (tty) {
      std::printf("\rkeyframe %zu/%zu | points in window %6d | kept %5.1f%% | last latency %7.2f ms ", i + 1, total,
                  rec.window_points, kept_pct, rec.latency_ms);
      std::fflush(stdout);
    } else if (!cfg.quiet && ((i + 1) % std::max<std::size_t>(1, total / 10) == 0 || i + 1 == total)) {
      std::printf("keyframe %zu/%zu | points in window %6d | kept %5.1f%% | last latency %7.2f ms\n", i + 1, total,
                  rec.window_points, kept_pct, rec.latency_ms);
      std::fflush(stdout);
    }
    records.push_back(rec);
  }
  if (tty) std::printf("\n");

  // The node's own count of rejected messages: its next (or final) status.
  const std::size_t statuses_before = heard.statuses;
  const bool fresh_status = wait_for(bus, 3000, [&] {
    return heard.statuses > statuses_before &&
           (heard.status.is_final || heard.status.decisions_published >= static_cast<std::int64_t>(answered));
  });
  // Stragglers: timings that arrived after their decision.
  bus.handleTimeout(0);

  std::vector<double> node_ms, solve_ms;
  for (KeyframeRecord& r : records) {
    const auto it = heard.timings.find(r.sequence);
    if (it == heard.timings.end()) continue;
    r.node_total_ms = static_cast<double>(it->second.total_ns) / 1e6;
    r.node_sparsify_ms = static_cast<double>(it->second.sparsify_ns) / 1e6;
    node_ms.push_back(r.node_total_ms);
    solve_ms.push_back(r.node_sparsify_ms);
  }

  std::int64_t mapped = 0, alive = 0;
  for (const ScenePoint& p : world.points()) {
    mapped += p.state != PointState::kUnseen;
    alive += p.state == PointState::kMapped;
  }
  const double n_kf = total ? static_cast<double>(total) : 1.0;
  SummaryRows rows;
  rows.push_back({"source", source});
  rows.push_back({"keyframes sent / answered", std::to_string(total) + " / " + std::to_string(answered)});
  rows.push_back({"keypoints detected per keyframe (mean)", fmt("%.0f", static_cast<double>(detected_total) / n_kf)});
  rows.push_back({"map point observations per keyframe (mean)", fmt("%.0f", static_cast<double>(observations_total) / n_kf)});
  rows.push_back({"map points before (features mapped)", with_commas(mapped)});
  rows.push_back({"map points after (kept)", with_commas(alive)});
  rows.push_back({"kept", fmt("%.1f %%", mapped ? 100.0 * static_cast<double>(alive) / static_cast<double>(mapped) : 100.0)});
  rows.push_back({"culled by keepless / deleted by the VO", with_commas(culled_total) + " / " + with_commas(deleted_total)});
  rows.push_back({"map point ids issued (incl. re-triangulated)", with_commas(world.landmarks_issued())});
  rows.push_back({"decision latency p50 (publish -> decision)", fmt("%.2f ms", percentile(latencies, 0.5))});
  rows.push_back({"decision latency p99", fmt("%.2f ms", percentile(latencies, 0.99))});
  rows.push_back({"decision latency max", fmt("%.2f ms", latencies.empty() ? 0.0 : *std::max_element(latencies.begin(), latencies.end()))});
  rows.push_back({"node time p50 / max (receive -> publish)",
                  fmt("%.2f", percentile(node_ms, 0.5)) + " / " + fmt("%.2f ms", node_ms.empty() ? 0.0 : *std::max_element(node_ms.begin(), node_ms.end()))});
  rows.push_back({"decisions not optimal", std::to_string(non_optimal)});
  rows.push_back({"messages rejected (node status)",
                  heard.have_status ? std::to_string(heard.status.messages_rejected) + (fresh_status ? "" : " (stale status)")
                                    : "n/a (no status)"});
  const std::string summary = format_table("keepless closed-loop summary", rows);
  std::printf("%s", summary.c_str());

  if (!cfg.report.empty()) {
    if (!write_report(cfg.report, world, path, records, snapshot, summary, error)) {
      std::fprintf(stderr, "keepless_vo_sim: report: %s\n", error.c_str());
      return 1;
    }
    std::printf("report: %s/ (keyframes.csv, points.csv, map_topdown.svg, keyframe_%04d.svg, summary.txt)\n",
                cfg.report.c_str(), snapshot.index);
  }
  return answered == total ? 0 : 1;
}
