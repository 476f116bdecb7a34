// What the bridge gives the cost models from a finished map (intrinsics,
// depths, unmapped keypoints; keepless/io/keyframes.hpp), and that the
// models then use it: on the shared COLMAP fixture the depths reproject
// every observation through the camera; `information` and `authors` decide
// differently from `paper` (and `authors` from itself without the unmapped
// keypoints), repeatably; `paper` ignores all of it.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "keepless/io/bal_problem.hpp"
#include "keepless/io/colmap_model.hpp"
#include "keepless/io/keyframes.hpp"
#include "maps_support.hpp"
#include "sparsify/exact_count.hpp"
#include "sparsify/modes.hpp"

namespace keepless {
namespace {

using maps_test::fixture;

struct Fixture {
  io::ColmapModel model;
  io::Similarity sim;
};

Fixture read_fixture() {
  Fixture f;
  io::ColmapFormat format;
  std::string error;
  EXPECT_TRUE(io::read_colmap_model(fixture("sparse"), &f.model, &format, &error)) << error;
  EXPECT_TRUE(io::read_similarity(fixture("sim3_to_kitti_gt.txt"), &f.sim, &error)) << error;
  return f;
}

core::Params params_for(const io::ColmapModel& m, core::CostModel cost) {
  core::Params p;
  p.pair_capacity = 30;
  p.cost_model = cost;
  p.image_width = static_cast<std::int32_t>(m.cameras.front().width);
  p.image_height = static_cast<std::int32_t>(m.cameras.front().height);
  return p;
}

std::vector<core::PointDecision> decide(const io::Keyframes& k, sparsify::Mode mode, const core::Params& p) {
  sparsify::ModeResult r;
  EXPECT_EQ(sparsify::decide(k.file, mode, p, 20, &r), core::Status::kOk);
  return r.decisions;
}

bool same_verdicts(const std::vector<core::PointDecision>& a, const std::vector<core::PointDecision>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const auto& x, const auto& y) {
    return x.point == y.point && x.verdict == y.verdict;
  });
}

bool same_decisions(const std::vector<core::PointDecision>& a, const std::vector<core::PointDecision>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const auto& x, const auto& y) {
    return x.point == y.point && x.verdict == y.verdict && x.flow == y.flow && x.capacity == y.capacity;
  });
}

// Replay: verdicts; whole: verdicts or flows (at M = 30 the whole map
// keeps the same 42 longest tracks whatever the costs; which pairs' flow
// they win moves).
bool differ(sparsify::Mode mode, const std::vector<core::PointDecision>& a, const std::vector<core::PointDecision>& b) {
  return mode == sparsify::Mode::kReplay ? !same_verdicts(a, b) : !same_decisions(a, b);
}

TEST(ColmapBridge, GivesTheCamerasIntrinsicsAndDepthsThatReprojectEachObservation) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  const Fixture f = read_fixture();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const io::Keyframes k = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim);
  std::unordered_map<std::uint32_t, const io::ColmapImage*> images;
  for (const auto& im : f.model.images) images[im.id] = &im;
  std::unordered_map<std::uint64_t, Eigen::Vector3d> xyz;
  for (const auto& p : f.model.points) xyz[p.id] = Eigen::Vector3d(p.xyz[0], p.xyz[1], p.xyz[2]);
  std::size_t n = 0;
  double sum = 0, worst = 0;
  for (std::size_t i = 0; i < k.file.keyframes.size(); ++i) {
    const core::Keyframe& kf = k.file.keyframes[i];
    const io::ColmapImage& im = *images.at(static_cast<std::uint32_t>(kf.id));
    const io::ColmapCamera& cam = f.model.cameras.front();
    ASSERT_EQ(im.camera_id, cam.id);
    ASSERT_STREQ(io::camera_model_by_id(cam.model_id)->name, "PINHOLE");
    EXPECT_EQ(kf.fx, cam.params[0]);
    EXPECT_EQ(kf.fy, cam.params[1]);
    EXPECT_EQ(kf.cx, cam.params[2]);
    EXPECT_EQ(kf.cy, cam.params[3]);
    EXPECT_EQ(kf.unmapped_count, 0u);  // not asked for
    const Eigen::Quaterniond q(im.qvec[0], im.qvec[1], im.qvec[2], im.qvec[3]);
    const Eigen::Vector3d t(im.tvec[0], im.tvec[1], im.tvec[2]);
    for (const core::Observation& o : k.file.observations[i]) {
      ASSERT_GT(o.depth, 0) << "point " << o.point << " in image " << kf.id;  // COLMAP keeps points in front
      // The point in the camera, in metres: its x and y over the bridge's
      // depth, through the intrinsics, land on the keypoint.
      const Eigen::Vector3d c = f.sim.scale * (q.normalized() * xyz.at(o.point) + t);
      EXPECT_NEAR(o.depth, c.z(), 1e-9 * c.z());
      const double du = kf.fx * c.x() / o.depth + kf.cx - o.u, dv = kf.fy * c.y() / o.depth + kf.cy - o.v;
      const double e = std::hypot(du, dv);
      sum += e;
      worst = std::max(worst, e);
      ++n;
    }
  }
  ASSERT_GT(n, 80000u);
  EXPECT_LT(sum / n, 1.0) << "mean reprojection error, px";
  EXPECT_LT(worst, 4.0) << "COLMAP's mapper filters observations above 4 px";
}

TEST(ColmapBridge, OneFocalLengthOrTwoPerCameraModelAndUnmappedKeypointsOnRequest) {
  io::ColmapModel m;
  m.cameras.push_back({1, io::camera_model_by_name("SIMPLE_RADIAL")->id, 100, 80, {300, 50, 40, 0.1}});
  m.cameras.push_back({2, io::camera_model_by_name("OPENCV")->id, 100, 80, {310, 320, 51, 41, 0, 0, 0, 0}});
  m.cameras.push_back({3, io::camera_model_by_name("PINHOLE")->id, 100, 80, {0, 320, 51, 41}});
  for (std::uint32_t id = 1; id <= 3; ++id) {
    io::ColmapImage im;
    im.id = id;
    im.camera_id = id;
    im.tvec[2] = id == 2 ? -10 : 1;  // image 2's camera has the point behind it
    im.name = "i" + std::to_string(id);
    im.points2D = {{50, 40, 7}, {1, 2, io::kNoPoint3D}, {3, 4, io::kNoPoint3D}};
    m.images.push_back(im);
  }
  io::ColmapPoint3D p;
  p.id = 7;
  p.xyz[2] = 4;  // depth 5 in images 1 and 3, -6 in image 2
  m.points.push_back(p);
  io::Similarity twice;
  twice.scale = 2;
  const io::Keyframes plain = io::keyframes_from_colmap(m, io::KeyframeOrder::kId, twice);
  const io::Keyframes k = io::keyframes_from_colmap(m, io::KeyframeOrder::kId, twice, true);
  for (const io::Keyframes* x : {&plain, &k}) {
    const auto& kfs = x->file.keyframes;
    EXPECT_EQ(kfs[0].fx, 300);
    EXPECT_EQ(kfs[0].fy, 300);
    EXPECT_EQ(kfs[0].cx, 50);
    EXPECT_EQ(kfs[0].cy, 40);
    EXPECT_EQ(kfs[1].fx, 310);
    EXPECT_EQ(kfs[1].fy, 320);
    EXPECT_EQ(kfs[1].cx, 51);
    EXPECT_EQ(kfs[1].cy, 41);
    EXPECT_EQ(kfs[2].fx, 0);  // f = 0: unknown
    EXPECT_EQ(kfs[2].fy, 0);
    EXPECT_EQ(x->file.observations[0][0].depth, 10);  // metres: twice the model's 5
    EXPECT_EQ(x->file.observations[1][0].depth, 0);   // behind: unknown
    EXPECT_EQ(x->file.observations[2][0].depth, 10);
  }
  EXPECT_EQ(plain.file.needs.max_unmapped_keypoints, 0u);
  EXPECT_EQ(plain.unmapped.size(), 0u);
  EXPECT_EQ(k.file.needs.max_unmapped_keypoints, 6u);
  for (const core::Keyframe& kf : k.file.keyframes) {
    ASSERT_EQ(kf.unmapped_count, 2u);
    EXPECT_EQ(kf.unmapped[0].u, 1);
    EXPECT_EQ(kf.unmapped[1].v, 4);
  }
  // Moving keeps the storage the keyframes point into.
  const core::Keypoint* at = nullptr;
  io::Keyframes moved = io::keyframes_from_colmap(m, io::KeyframeOrder::kId, twice, true);
  at = moved.file.keyframes[2].unmapped;
  const io::Keyframes again = std::move(moved);
  EXPECT_EQ(again.file.keyframes[2].unmapped, at);
  EXPECT_EQ(again.file.keyframes[2].unmapped, again.unmapped.data() + 4);
}

TEST(BalBridge, FocalLengthAndMinusZDepthReprojectTheRealProblem) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  io::BalProblem p;
  std::string error;
  ASSERT_TRUE(io::read_bal(std::string(KEEPLESS_MAPS_DATA) + "/bal_zenslam/problem-49-7776-pre.txt", &p, &error))
      << error;
  const io::Keyframes k = io::keyframes_from_bal(p, io::KeyframeOrder::kFile, {});
  std::size_t n = 0, with_depth = 0;
  std::vector<double> errors;
  for (std::uint32_t c = 0; c < p.num_cameras; ++c) {
    const core::Keyframe& kf = k.file.keyframes[c];
    const double* cam = &p.camera_params[9 * std::size_t{c}];
    EXPECT_EQ(kf.fx, cam[6]);
    EXPECT_EQ(kf.fy, cam[6]);
    EXPECT_EQ(kf.cx, 0);
    EXPECT_EQ(kf.cy, 0);
    EXPECT_EQ(kf.unmapped_count, 0u);
    const Eigen::Vector3d r(cam[0], cam[1], cam[2]);
    const Eigen::AngleAxisd R(r.norm(), r.norm() > 0 ? Eigen::Vector3d(r.normalized()) : Eigen::Vector3d::UnitX());
    for (const core::Observation& o : k.file.observations[c]) {
      ++n;
      const double* X = &p.point_params[3 * o.point];
      const Eigen::Vector3d P = R * Eigen::Vector3d(X[0], X[1], X[2]) + Eigen::Vector3d(cam[3], cam[4], cam[5]);
      if (!(-P.z() > 0)) {
        EXPECT_EQ(o.depth, 0);
        continue;
      }
      ++with_depth;
      EXPECT_NEAR(o.depth, -P.z(), 1e-9 * -P.z());
      // BAL's projection with its distortion, from the bridge's depth:
      // (P.x, P.y) / depth is BAL's -P / P.z.
      const double x = P.x() / o.depth, y = P.y() / o.depth, rr = x * x + y * y;
      const double d = 1 + cam[7] * rr + cam[8] * rr * rr;
      errors.push_back(std::hypot(kf.fx * d * x - o.u, kf.fy * d * y - o.v));
    }
  }
  EXPECT_GT(with_depth, n * 99 / 100);
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 2.0) << "median reprojection error, px (the problem before its BA)";
}

TEST(CostModelsOnTheFixture, InformationUsesTheDepthsAndRepeats) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  const Fixture f = read_fixture();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const io::Keyframes k = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim);
  for (const sparsify::Mode mode : {sparsify::Mode::kReplay, sparsify::Mode::kWhole}) {
    const auto paper = decide(k, mode, params_for(f.model, core::CostModel::kPaper));
    const auto info = decide(k, mode, params_for(f.model, core::CostModel::kInformation));
    EXPECT_TRUE(differ(mode, paper, info)) << sparsify::to_string(mode);
    EXPECT_TRUE(same_decisions(info, decide(k, mode, params_for(f.model, core::CostModel::kInformation))));
    // Without the depths it is neutral: a level 2 on every observation.
    io::Keyframes blind = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim);
    for (auto& obs : blind.file.observations) {
      for (auto& o : obs) o.depth = 0;
    }
    EXPECT_TRUE(differ(mode, info, decide(blind, mode, params_for(f.model, core::CostModel::kInformation))));
  }
}

TEST(CostModelsOnTheFixture, AuthorsCountsTheUnmappedKeypointsAndPaperIgnoresThem) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  const Fixture f = read_fixture();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const io::Keyframes mapped = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim);
  const io::Keyframes all = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim, true);
  std::size_t unmapped = 0;
  for (const auto& im : f.model.images) {
    for (const auto& p : im.points2D) unmapped += p.point3D_id == io::kNoPoint3D;
  }
  ASSERT_GT(unmapped, 0u);
  EXPECT_EQ(all.unmapped.size(), unmapped);
  EXPECT_EQ(all.file.needs.max_unmapped_keypoints, unmapped);
  for (const sparsify::Mode mode : {sparsify::Mode::kReplay, sparsify::Mode::kWhole}) {
    const auto authors = decide(all, mode, params_for(f.model, core::CostModel::kAuthors));
    EXPECT_TRUE(differ(mode, authors, decide(mapped, mode, params_for(f.model, core::CostModel::kAuthors))))
        << sparsify::to_string(mode);
    EXPECT_TRUE(same_decisions(authors, decide(all, mode, params_for(f.model, core::CostModel::kAuthors))));
    EXPECT_TRUE(same_decisions(decide(mapped, mode, params_for(f.model, core::CostModel::kPaper)),
                               decide(all, mode, params_for(f.model, core::CostModel::kPaper))));
  }
}

// Point quality from the model: every observation's track length is its
// 3D point's track and its error the point's ERROR (COLMAP); BAL gives the
// point's observations; age and angle stay unknown. `track` then decides
// differently from `paper`, repeatably, and without the quality it falls
// back (every keyframe counted) to the window alone.
TEST(CostModelsOnTheFixture, TrackUsesTheModelsTrackLengthsAndErrors) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  const Fixture f = read_fixture();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const io::Keyframes k = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim);
  std::unordered_map<std::uint64_t, const io::ColmapPoint3D*> points;
  for (const auto& p : f.model.points) points[p.id] = &p;
  std::size_t checked = 0;
  for (std::size_t i = 0; i < k.file.keyframes.size(); ++i) {
    const core::PointQuality* q = k.file.keyframes[i].quality;
    ASSERT_NE(q, nullptr);
    for (std::size_t j = 0; j < k.file.observations[i].size(); ++j) {
      const io::ColmapPoint3D& p = *points.at(k.file.observations[i][j].point);
      ASSERT_EQ(q[j].track_length, p.track.size());
      ASSERT_EQ(q[j].reprojection_error, static_cast<float>(p.error));
      ASSERT_LT(q[j].age, 0);
      ASSERT_EQ(q[j].triangulation_angle, 0.f);
      ++checked;
    }
  }
  EXPECT_GT(checked, 10000u);
  for (const sparsify::Mode mode : {sparsify::Mode::kReplay, sparsify::Mode::kWhole}) {
    const auto paper = decide(k, mode, params_for(f.model, core::CostModel::kPaper));
    const auto track = decide(k, mode, params_for(f.model, core::CostModel::kTrack));
    EXPECT_TRUE(differ(mode, paper, track)) << sparsify::to_string(mode);
    EXPECT_TRUE(same_decisions(track, decide(k, mode, params_for(f.model, core::CostModel::kTrack))));
    io::Keyframes bare = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim);
    for (auto& kf : bare.file.keyframes) kf.quality = nullptr;
    sparsify::ModeResult r;
    ASSERT_EQ(sparsify::decide(bare.file, mode, params_for(f.model, core::CostModel::kTrack), 20, &r),
              core::Status::kOk);
    EXPECT_TRUE(differ(mode, track, r.decisions)) << sparsify::to_string(mode);
    EXPECT_GT(r.totals.track_fallback, 0u) << sparsify::to_string(mode);
  }
}

// A point ERROR beyond a float's range (finite in the model's doubles) is the
// largest float, not infinity, which the window would refuse: the model still
// decides, under every cost model.
TEST(CostModelsOnTheFixture, AnErrorBeyondAFloatIsTheLargest) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  Fixture f = read_fixture();
  ASSERT_FALSE(::testing::Test::HasFailure());
  f.model.points[0].error = 1e39;
  const std::uint64_t id = f.model.points[0].id;
  const io::Keyframes k = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim);
  std::size_t seen = 0;
  for (std::size_t i = 0; i < k.file.keyframes.size(); ++i) {
    for (std::size_t j = 0; j < k.file.observations[i].size(); ++j) {
      if (k.file.observations[i][j].point != id) continue;
      EXPECT_EQ(k.file.keyframes[i].quality[j].reprojection_error, std::numeric_limits<float>::max());
      ++seen;
    }
  }
  EXPECT_GT(seen, 1u);
  for (const core::CostModel model : {core::CostModel::kPaper, core::CostModel::kTrack}) {
    sparsify::ModeResult r;
    EXPECT_EQ(sparsify::decide(k.file, sparsify::Mode::kReplay, params_for(f.model, model), 20, &r),
              core::Status::kOk)
        << core::to_string(model);
  }
}

TEST(BalBridge, TrackLengthIsEachPointsObservations) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  io::BalProblem p;
  std::string error;
  ASSERT_TRUE(io::read_bal(maps_test::bal_problem(), &p, &error)) << error;
  const io::Keyframes k = io::keyframes_from_bal(p, io::KeyframeOrder::kFile, {});
  std::vector<std::uint32_t> views(p.num_points, 0);
  for (const auto& obs : k.file.observations) {
    for (const auto& o : obs) ++views[o.point];
  }
  std::size_t checked = 0;
  for (std::size_t i = 0; i < k.file.keyframes.size(); ++i) {
    const core::PointQuality* q = k.file.keyframes[i].quality;
    if (k.file.observations[i].empty()) continue;
    ASSERT_NE(q, nullptr);
    for (std::size_t j = 0; j < k.file.observations[i].size(); ++j) {
      ASSERT_EQ(q[j].track_length, views[k.file.observations[i][j].point]);
      ASSERT_LT(q[j].reprojection_error, 0.f);  // BAL stores no error
      ++checked;
    }
  }
  EXPECT_EQ(checked, p.observations.size() - k.duplicates);
}

// The whole model at exactly the requested count with every image's floor:
// on the fixture with the track cost, each count is met exactly, every
// image keeps at least the floor, and the points taken by the order are a
// prefix of the budget's order (smallest M* first) up to the floor's; with
// a track share it keeps what the library's budget does.
TEST(ExactCount, KeepsExactlyTheCountWithEveryImagesFloor) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  const Fixture f = read_fixture();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const io::Keyframes k = io::keyframes_from_colmap(f.model, io::KeyframeOrder::kName, f.sim);
  const std::vector<std::vector<core::PointId>> images = io::observed_point_ids(f.model, k);
  constexpr std::uint32_t kFloor = 30;
  for (const std::uint64_t count : {800u, 2000u, 5000u}) {
    core::Params p = params_for(f.model, core::CostModel::kTrack);
    p.budget = {core::BudgetKind::kPoints, count, 0.0};
    sparsify::ModeResult r;
    ASSERT_EQ(sparsify::decide(k.file, sparsify::Mode::kWhole, p, 20, &r), core::Status::kOk);
    ASSERT_EQ(r.thresholds.size(), r.decisions.size());
    const sparsify::ExactCount e = sparsify::keep_exactly(images, kFloor, count, r.thresholds, &r.decisions);
    EXPECT_TRUE(e.floor_fits) << count;
    std::uint64_t kept = 0;
    for (const auto& d : r.decisions) kept += d.verdict != core::Verdict::kCull;
    EXPECT_EQ(kept, count);
    EXPECT_EQ(e.kept, count);
    const std::vector<std::uint32_t> per_image = sparsify::kept_observations(images, r.decisions);
    for (std::size_t i = 0; i < images.size(); ++i) {
      EXPECT_GE(per_image[i], std::min<std::size_t>(kFloor, images[i].size())) << "image " << i << ", count " << count;
    }
    EXPECT_GT(e.from_order, 0u);
  }
  // A track share ranks by observations. With an image's repeated
  // observations of a point dropped, as the window drops them, it keeps the
  // library's budget with that share (the floor restores nothing at this
  // count); with them, at share 1 no culled point has more observations
  // than a kept one, and the fixture's repeats change the set.
  std::vector<std::vector<core::PointId>> distinct = images;
  for (std::vector<core::PointId>& image : distinct) {
    std::sort(image.begin(), image.end());
    image.erase(std::unique(image.begin(), image.end()), image.end());
  }
  for (const double share : {0.5, 1.0}) {
    core::Params p = params_for(f.model, core::CostModel::kPaper);
    p.budget = {core::BudgetKind::kPoints, 2000, 0.0};
    sparsify::ModeResult decided;
    ASSERT_EQ(sparsify::decide(k.file, sparsify::Mode::kWhole, p, 20, &decided), core::Status::kOk);
    sparsify::ModeResult r = decided;
    const sparsify::ExactCount e = sparsify::keep_exactly(distinct, kFloor, 2000, r.thresholds, &r.decisions, share);
    EXPECT_EQ(e.kept, 2000u);
    EXPECT_EQ(e.restored, 0u);
    p.budget.track_share = share;
    sparsify::ModeResult library;
    ASSERT_EQ(sparsify::decide(k.file, sparsify::Mode::kWhole, p, 20, &library), core::Status::kOk);
    ASSERT_EQ(library.decisions.size(), r.decisions.size());
    for (std::size_t i = 0; i < r.decisions.size(); ++i) {
      ASSERT_EQ(r.decisions[i].verdict, library.decisions[i].verdict) << "point " << r.decisions[i].point << ", share " << share;
    }
    if (share < 1.0) continue;
    sparsify::ModeResult repeats = decided;
    EXPECT_EQ(sparsify::keep_exactly(images, 0, 2000, repeats.thresholds, &repeats.decisions, share).kept, 2000u);
    std::unordered_map<core::PointId, std::uint32_t> observations;
    for (const std::vector<core::PointId>& image : images) {
      for (const core::PointId id : image) ++observations[id];
    }
    std::uint32_t fewest_kept = UINT32_MAX, most_culled = 0, changed = 0;
    for (std::size_t i = 0; i < repeats.decisions.size(); ++i) {
      const core::PointDecision& d = repeats.decisions[i];
      if (d.verdict == core::Verdict::kKeep) fewest_kept = std::min(fewest_kept, observations[d.point]);
      if (d.verdict == core::Verdict::kCull) most_culled = std::max(most_culled, observations[d.point]);
      changed += d.verdict != r.decisions[i].verdict;
    }
    EXPECT_GE(fewest_kept, most_culled);
    EXPECT_GT(changed, 0u);
  }
  // A count below what the floor needs: the floor's set, said so.
  core::Params p = params_for(f.model, core::CostModel::kTrack);
  p.budget = {core::BudgetKind::kPoints, 10, 0.0};
  sparsify::ModeResult r;
  ASSERT_EQ(sparsify::decide(k.file, sparsify::Mode::kWhole, p, 20, &r), core::Status::kOk);
  const sparsify::ExactCount e = sparsify::keep_exactly(images, kFloor, 10, r.thresholds, &r.decisions);
  EXPECT_FALSE(e.floor_fits);
  EXPECT_GT(e.kept, 10u);
}

// Where the longest tracks leave the poorest image: by observations (repeats
// count), ties to the smaller id, skipped points kept; and the floor above
// it rounded up as the decimal product is.
TEST(ExactCount, LongestTracksPoorestAndTheFloorOverIt) {
  const std::vector<std::vector<core::PointId>> images = {{1, 2, 2}, {2, 3}, {3, 4}};
  std::vector<core::PointDecision> d(4);
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = {static_cast<core::PointId>(i + 1), core::Verdict::kKeep, 0, 0};
  // Observations: point 1 one, 2 three (twice in image 0), 3 two, 4 one.
  EXPECT_EQ(sparsify::longest_tracks_poorest(images, d, 1), 0u);  // point 2: image 2 keeps none
  EXPECT_EQ(sparsify::longest_tracks_poorest(images, d, 2), 1u);  // 2 and 3: 2, 2, 1
  EXPECT_EQ(sparsify::longest_tracks_poorest(images, d, 3), 1u);  // and 1, not 4 (a tie, smaller id): 3, 2, 1
  EXPECT_EQ(sparsify::longest_tracks_poorest(images, d, 4), 2u);  // everything: 3, 2, 2
  d[3].verdict = core::Verdict::kSkip;                            // point 4 skipped: kept, and counted
  EXPECT_EQ(sparsify::longest_tracks_poorest(images, d, 2), 1u);  // 4 and the longest, 2: 2, 1, 1
  EXPECT_EQ(sparsify::longest_tracks_poorest({}, d, 2), 0u);
  EXPECT_EQ(sparsify::floor_over(1.1, 330), 363u);
  EXPECT_EQ(sparsify::floor_over(1.1, 207), 228u);
  EXPECT_EQ(sparsify::floor_over(1.1, 0), 0u);
  EXPECT_EQ(sparsify::floor_over(100, UINT32_MAX), UINT32_MAX);
}

class CostModelsCli : public maps_test::MapsTest {};

// Through keepless_sparsify: each model's decisions repeat byte for byte
// and the three differ.
TEST_F(CostModelsCli, EachCostModelRepeatsAndTheyDiffer) {
  const std::string sim = fixture("sim3_to_kitti_gt.txt");
  for (const char* mode : {"replay", "whole"}) {
    std::vector<std::string> decisions;
    for (const char* cost : {"paper", "information", "authors"}) {
      for (int run = 0; run < 2; ++run) {
        const std::string d = path(std::string(mode) + cost + std::to_string(run));
        const maps_test::Result r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--sim3", sim, "--mode", mode,
                                              "--cost", cost, "--decisions", d});
        ASSERT_EQ(r.status, 0) << cost << ": " << r.err;
        decisions.push_back(maps_test::read_all(d));
      }
    }
    EXPECT_EQ(decisions[0], decisions[1]) << mode;
    EXPECT_EQ(decisions[2], decisions[3]) << mode;
    EXPECT_EQ(decisions[4], decisions[5]) << mode;
    EXPECT_NE(decisions[0], decisions[2]) << mode;
    EXPECT_NE(decisions[0], decisions[4]) << mode;
    EXPECT_NE(decisions[2], decisions[4]) << mode;
  }
}

}  // namespace
}  // namespace keepless
