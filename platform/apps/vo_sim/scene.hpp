#pragma once
// The simulated world the VO "sees": a floor plan of square cells around the
// camera path. Cells near the path are free (street, room); the rest are solid
// blocks whose faces are walls. Points live on walls (textured, with dense
// poster/window clusters and weak-texture plain faces), on the floor (random
// texture, and tiled patches whose corners form dense clusters) and on the
// ceiling indoors. A point is observed when it is in view, facing the camera,
// not hidden behind a solid cell, in range, and among the strongest
// `max_keypoints` candidates (a feature detector's budget); keypoints get
// Gaussian pixel noise. Everything is a pure function of the seed.
//
// Features and map points: a scene feature becomes a map point (a fresh id)
// when first detected. A culled map point is gone for good; its feature is
// still detected but not mapped until `retriangulate_after` keyframes later,
// when it becomes a new map point with a new id (ORB-SLAM2's local mapping
// re-triangulates unmatched features the same way). A feature deleted by the
// VO itself (an outlier) never returns.

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "sim_math.hpp"
#include "splitmix64.hpp"
#include "trajectory.hpp"

namespace keepless::vo_sim {

struct Camera {
  int width = 640;
  int height = 480;
  double fx = 450, fy = 450, cx = 319.5, cy = 239.5;
};

struct SceneConfig {
  std::string name = "street";
  double cell = 2.0;         // floor-plan cell, metres
  double free_radius = 7.0;  // cells this close to the path are open space
  double floor_z = 0.0;
  double wall_top = 12.0;
  bool ceiling = false;
  double max_range = 30.0;  // metres
  // Points per square metre.
  double wall_density = 3.5;
  double floor_density = 1.5;
  double ceiling_density = 0.0;
  double cluster_density = 15.0;  // posters, windows
  double tile_spacing = 0.5;     // floor tiles, metres
  double p_weak_face = 0.25;     // plain, weak-texture wall faces
  double p_cluster_face = 0.35;  // faces with a poster/window cluster
  double p_tile_cell = 0.3;      // tiled floor cells
  double pixel_noise = 0.7;      // keypoint noise, pixels (sigma)
  int max_keypoints = 1000;      // detector budget per keyframe
  int retriangulate_after = 20;  // keyframes; < 0: never
};

// Presets for the built-in scenes and for trajectory files.
SceneConfig street_scene();
SceneConfig room_scene();

enum class PointKind : std::uint8_t { kWall = 0, kWallCluster, kWeak, kFloor, kFloorTile, kCeiling };
const char* to_string(PointKind k);

enum class PointState : std::uint8_t { kUnseen = 0, kMapped, kCulled, kDeleted };

// A scene feature; `landmark` is its current map point id (0: none).
struct ScenePoint {
  std::int64_t landmark = 0;
  std::int32_t culled_at = -1;  // keyframe index of the last cull
  std::int32_t landmarks = 0;   // map point ids it had so far
  Vec3 position;
  Vec3 normal;
  std::int64_t home_cx = 0, home_cy = 0;  // the free cell it faces
  float strength = 0;                     // detector response, 0..1
  PointKind kind = PointKind::kWall;
  PointState state = PointState::kUnseen;
  std::int32_t first_keyframe = -1;
  std::int32_t observations = 0;
};

struct SimObservation {
  std::uint32_t point = 0;  // index into World::points()
  float u = 0, v = 0;
  bool mapped = false;      // observation of a map point (sent), or a detection only
};

class World {
 public:
  // `path` are the keyframe poses (they shape the free space).
  World(const SceneConfig& config, const Camera& camera, const std::vector<Pose>& path, std::uint64_t seed);

  // What keyframe `index` at `pose` detects (ascending feature index); those
  // with `mapped` set are its map point observations. Issues map point ids
  // for new (or re-triangulated) features.
  void observe(const Pose& pose, std::int32_t index, std::vector<SimObservation>& out);

  // Closed loop: the node culled map point `landmark` at keyframe `index`.
  // False if the id is not a live map point.
  bool cull(std::int64_t landmark, std::int32_t index);
  // The VO deletes the map point of feature `point` for good.
  void remove(std::uint32_t point);

  const std::vector<ScenePoint>& points() const { return points_; }
  std::int64_t landmarks_issued() const { return static_cast<std::int64_t>(landmark_feature_.size()); }
  const SceneConfig& config() const { return config_; }
  const Camera& camera() const { return camera_; }
  std::size_t candidates_last() const { return candidates_last_; }

 private:
  struct Cell {
    bool free = false;
    bool generated = false;
    std::vector<std::uint32_t> points;
  };
  static std::int64_t key(std::int64_t cx, std::int64_t cy) { return cx * 1000003 + cy; }
  std::int64_t cell_of(double v) const { return static_cast<std::int64_t>(std::floor(v / config_.cell)); }
  bool is_free(std::int64_t cx, std::int64_t cy) const;
  void generate(std::int64_t cx, std::int64_t cy, Cell& cell);
  void add_point(Cell& cell, Vec3 p, Vec3 n, std::int64_t cx, std::int64_t cy, float strength, PointKind kind);
  bool occluded(Vec3 from, std::int64_t to_cx, std::int64_t to_cy) const;

  SceneConfig config_;
  Camera camera_;
  std::uint64_t seed_;
  std::unordered_map<std::int64_t, Cell> cells_;
  std::vector<ScenePoint> points_;
  std::vector<std::uint32_t> landmark_feature_;  // map point id - 1 -> feature
  SplitMix64 noise_;
  std::size_t candidates_last_ = 0;
};

}  // namespace keepless::vo_sim
