#pragma once
// The VO simulator's report folder: per-keyframe CSV, the mapped points, a
// top-down SVG map of kept vs culled points, one keyframe's keypoints
// coloured kept/culled, and the summary table.

#include <cstdint>
#include <string>
#include <vector>

#include "scene.hpp"
#include "trajectory.hpp"

namespace keepless::vo_sim {

struct KeyframeRecord {
  std::int32_t index = 0;
  std::int64_t sequence = 0;
  std::int64_t keyframe_id = 0;
  Vec3 centre;
  std::int32_t detected = 0;      // keypoints detected
  std::int32_t observations = 0;  // of live map points (sent)
  std::int32_t new_points = 0;    // map point ids issued
  bool answered = false;
  std::int32_t status = -1;  // decision_t.STATUS_*, -1 if unanswered
  std::int32_t window_keyframes = 0;
  std::int32_t window_points = 0;
  std::int32_t evaluated = 0, kept = 0, culled = 0, skipped = 0;
  double latency_ms = 0;        // publish -> decision received, this process
  double node_total_ms = -1;    // from decision_timing_t, -1 if not received
  double node_sparsify_ms = -1;
  std::int64_t mapped_points = 0;  // features mapped so far
  std::int64_t alive_points = 0;   // features with a live map point
};

struct SnapshotKeyframe {
  std::int32_t index = -1;
  std::vector<SimObservation> observations;
};

// The summary table (also printed): rows of (label, value).
using SummaryRows = std::vector<std::pair<std::string, std::string>>;
std::string format_table(const std::string& title, const SummaryRows& rows);

// Writes DIR/keyframes.csv, DIR/points.csv, DIR/map_topdown.svg,
// DIR/keyframe_<index>.svg and DIR/summary.txt. False with `error` on I/O failure.
bool write_report(const std::string& dir, const World& world, const std::vector<Pose>& path,
                  const std::vector<KeyframeRecord>& records, const SnapshotKeyframe& snapshot,
                  const std::string& summary_text, std::string& error);

}  // namespace keepless::vo_sim
