// Units of keepless_eval (perf/eval): per-input seeding, ATE alignment, the
// culled-keyframe trajectory, tracking's motion-only BA, the local BA's
// outlier stage, and the contract's statistics.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "local_ba.hpp"
#include "metrics.hpp"
#include "prng.hpp"
#include "report.hpp"
#include "run_record.hpp"
#include "window_sizes.hpp"

namespace ke = keepless::eval;

namespace {

ke::Pose pose(double yaw, const Eigen::Vector3d& t) {
  ke::Pose p;
  p.q = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()));
  p.t = t;
  return p;
}

// A curved, non-planar trajectory (alignment is well determined).
std::vector<ke::Pose> trajectory() {
  std::vector<ke::Pose> out;
  for (int i = 0; i < 30; ++i) out.push_back(pose(0.05 * i, Eigen::Vector3d(std::cos(0.2 * i), 0.1 * i, std::sin(0.2 * i))));
  return out;
}

TEST(EvalSeeding, AnInputsSeedDependsOnItsNameNotItsPosition) {
  EXPECT_EQ(ke::input_seed(1, "fr1_xyz"), ke::input_seed(1, std::string("fr1_") + "xyz"));
  EXPECT_NE(ke::input_seed(1, "fr1_xyz"), ke::input_seed(1, "MH01"));
  EXPECT_NE(ke::input_seed(1, "fr1_xyz"), ke::input_seed(2, "fr1_xyz"));
  EXPECT_EQ(ke::name_hash(""), 0xCBF29CE484222325ull);  // FNV-1a offset basis: stable across platforms
}

TEST(EvalAlignment, Sim3RemovesAScaleErrorThatSe3Cannot) {
  const std::vector<ke::Pose> gt = trajectory();
  const Eigen::Quaterniond R(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  const Eigen::Vector3d t(4, -2, 1);
  for (double s : {1.0, 0.5}) {
    std::vector<ke::Pose> est;
    for (const ke::Pose& g : gt) {
      ke::Pose e;
      e.q = R * g.q;
      e.t = s * (R * g.t) + t;
      est.push_back(e);
    }
    const ke::Ate sim3 = ke::absolute_trajectory_error(est, gt, true);
    const ke::Ate se3 = ke::absolute_trajectory_error(est, gt, false);
    EXPECT_LT(sim3.rms_m, 1e-9) << s;
    EXPECT_LT(sim3.rms_r_deg, 1e-6) << s;
    if (s == 1.0) EXPECT_LT(se3.rms_m, 1e-9);
    else EXPECT_GT(se3.rms_m, 0.2);  // a half-scale copy cannot be aligned rigidly
  }
}

// A straight road: the estimate's positions are the ground truth's but every
// orientation is 5 degrees off in heading. The position error is Umeyama's,
// zero: the orientations do not move the positions' alignment (they did
// until 2026-12-05, charging 1.26 m here). ATE_r aligns the orientations
// on such a road, so a constant offset is aligned away.
TEST(EvalAlignment, OnAStraightRoadHeadingErrorIsNotPositionError) {
  std::vector<ke::Pose> gt, est;
  const Eigen::Quaterniond heading(Eigen::AngleAxisd(5.0 * 3.141592653589793 / 180.0, Eigen::Vector3d::UnitY()));
  for (int i = 0; i < 50; ++i) {
    ke::Pose g;
    g.t = Eigen::Vector3d(0.01 * std::sin(0.3 * i), 0.002 * std::cos(0.7 * i), 1.0 * i);  // along z, nearly
    gt.push_back(g);
    ke::Pose e = g;
    e.q = heading * g.q;
    est.push_back(e);
  }
  for (bool with_scale : {true, false}) {
    const ke::Ate ate = ke::absolute_trajectory_error(est, gt, with_scale);
    EXPECT_LT(ate.rms_m, 1e-9) << with_scale;
    EXPECT_LT(ate.rms_r_deg, 1e-6) << with_scale;
  }
}

TEST(EvalTrajectory, ACulledKeyframeFollowsItsParentsCorrection) {
  // Keyframe 1 culled with parent 0, keyframe 2 culled later with parent 1:
  // after keyframe 0 moves, both follow, composing the stored relative poses.
  std::vector<ke::Pose> p{pose(0, {0, 0, 0}), pose(0.1, {1, 0, 0}), pose(0.2, {2, 0, 0}), pose(0, {3, 0, 0})};
  std::vector<ke::CulledLink> link(4);
  link[1] = ke::CulledLink{0, p[0].inverse() * p[1]};
  link[2] = ke::CulledLink{1, p[1].inverse() * p[2]};
  const ke::Pose correction = pose(0.3, {0.5, -0.2, 0.1});
  p[0] = correction * p[0];
  const ke::Pose frozen1 = p[1], frozen2 = p[2];
  const std::vector<ke::Pose> out = ke::resolve_keyframe_poses(p, link);
  const ke::Pose want1 = correction * frozen1, want2 = correction * frozen2;
  EXPECT_LT((out[1].t - want1.t).norm(), 1e-12);
  EXPECT_LT((out[2].t - want2.t).norm(), 1e-12);
  EXPECT_LT(out[2].q.angularDistance(want2.q), 1e-12);
  EXPECT_EQ(out[0].t, p[0].t);  // alive keyframes keep their own pose
  EXPECT_EQ(out[3].t, p[3].t);
}

TEST(EvalTracking, MotionOnlyBaRecoversThePoseAndFlagsAWrongMatch) {
  ke::Camera cam;  // 640x480, f 500, monocular
  const ke::Pose truth = pose(0.1, {0.2, -0.1, 0.3});
  const ke::Pose T_cw = truth.inverse();
  std::vector<Eigen::Vector3d> X;
  std::vector<ke::PoseObservation> obs;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3d pc(-1.5 + 0.05 * i, -1.0 + 0.033 * (i % 7) * 9, 3.0 + 0.05 * (i % 5));
    X.push_back(truth * pc);
  }
  for (std::size_t i = 0; i < X.size(); ++i) {
    const Eigen::Vector3d pc = T_cw * X[i];
    obs.push_back(ke::PoseObservation{X[i].data(), cam.fx * pc.x() / pc.z() + cam.cx, cam.fy * pc.y() / pc.z() + cam.cy, -1});
  }
  obs[7].u += 30;  // a wrong association
  std::array<double, 6> block = ke::to_block(pose(0.12, {0.25, -0.08, 0.32}));  // the odometry prior
  const ke::PoseResult r = ke::optimize_pose(cam, obs, block.data());
  const ke::Pose got = ke::from_block(block.data());
  EXPECT_LT((got.t - truth.t).norm(), 1e-6);
  EXPECT_LT(got.q.angularDistance(truth.q), 1e-6);
  EXPECT_TRUE(r.outlier[7]);
  EXPECT_EQ(r.inliers, 59);
}

TEST(EvalLocalBa, TheSecondStageReportsTheChiSquareOutlier) {
  ke::Camera cam;
  cam.baseline = 0.1;
  std::vector<ke::Pose> truth{pose(0, {0, 0, 0}), pose(0.05, {0.3, 0, 0}), pose(0.1, {0.6, 0.05, 0})};
  std::vector<std::array<double, 6>> blocks;
  for (const ke::Pose& t : truth) blocks.push_back(ke::to_block(t));
  blocks[2][3] += 0.02;  // a perturbed free pose
  ke::BaInput in;
  for (auto& b : blocks) in.poses.push_back(b.data());
  in.pose_fixed = {true, true, false};
  std::vector<std::array<double, 3>> pts;
  for (int i = 0; i < 40; ++i) pts.push_back({-1.0 + 0.05 * i, -0.5 + 0.025 * (i % 9) * 4, 3.0 + 0.1 * (i % 4)});
  for (auto& p : pts) in.points.push_back(p.data());
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 40; ++j) {
      const Eigen::Vector3d pc = truth[k].inverse() * Eigen::Vector3d(pts[j][0], pts[j][1], pts[j][2]);
      const double u = cam.fx * pc.x() / pc.z() + cam.cx, v = cam.fy * pc.y() / pc.z() + cam.cy;
      in.observations.push_back(ke::BaObservation{k, j, u, v, u - cam.fx * cam.baseline / pc.z()});
    }
  in.observations[2 * 40 + 5].v += 25;  // one wrong match in the free keyframe
  const ke::BaResult r = ke::solve_local_ba(cam, in, 5, 10);
  ASSERT_EQ(r.outlier.size(), in.observations.size());
  for (std::size_t i = 0; i < r.outlier.size(); ++i) EXPECT_EQ(r.outlier[i], i == 2 * 40 + 5) << i;
  EXPECT_LT((ke::from_block(blocks[2].data()).t - truth[2].t).norm(), 1e-4);
}

ke::RunRecord rec(double ate, std::uint64_t mps, std::uint64_t obs, std::uint64_t seed) {
  ke::RunRecord r;
  r.ate_m = ate;
  r.mps = mps;
  r.kfs = 10;
  r.observations = obs;
  r.ba_s = 1;
  r.seed = seed;
  return r;
}

// --window-sizes: a window's points, observations (a point once per
// keyframe), pair arcs (sum of n(n-1)/2) and unmapped keypoints; the maximum
// is taken per figure.
TEST(EvalWindowSizes, AWindowCountsEachPointsPairsOnce) {
  using keepless::eval::WindowMeasure;
  using keepless::eval::WindowSize;
  WindowMeasure m;
  m.add_keyframe({1, 2, 3, 3}, 5);  // 3 repeated: one observation
  m.add_keyframe({2, 3, 4}, 0);
  m.add_keyframe({3, 9}, 2);
  const WindowSize s = m.size();
  EXPECT_EQ(s.keyframes, 3u);
  EXPECT_EQ(s.points, 5u);        // 1 2 3 4 9
  EXPECT_EQ(s.observations, 8u);  // 3 + 3 + 2
  EXPECT_EQ(s.pair_arcs, 4u);     // 2 in two keyframes (1), 3 in three (3)
  EXPECT_EQ(s.unmapped, 7u);
  m.clear();
  m.add_keyframe({7}, 0);
  WindowSize most = m.size();
  most.max_with(s);
  EXPECT_EQ(most.points, 5u);
  EXPECT_EQ(most.pair_arcs, 4u);
  EXPECT_EQ(most.keyframes, 3u);
}

// The auto scope's choices over a run: decisions of the new keyframe's
// points, and each change of scope (the first decision starts from the window).
TEST(EvalSelectorCounts, AutoScopeSwitchesAreCountedEachWay) {
  ke::SelectorCounts c;
  for (bool newest : {false, true, true, false, true, true, true}) {
    keepless::core::Summary s;
    s.decided_newest = newest;
    s.floor_promoted = 2;
    c.add(s);
  }
  EXPECT_EQ(c.windows, 7u);
  EXPECT_EQ(c.decided_newest, 5u);
  EXPECT_EQ(c.scope_switches, 3u);
  EXPECT_EQ(c.floor_promoted, 14u);
}

TEST(EvalContract, SummarizeGivesMeanSdSeedCountsAndRatios) {
  ke::Comparison c;
  c.info.input = "x";
  c.info.kind = "trajectory";
  c.info.error_floor_m = 0.3;
  c.M = 42;
  c.original = {rec(1.0, 100, 400, 1), rec(2.0, 100, 400, 2), rec(3.0, 100, 400, 3)};
  c.ours = {rec(0.5, 30, 100, 1), rec(2.5, 30, 100, 2), rec(3.5, 36, 100, 3)};
  c.random = {rec(1.0, 30, 100, 1), rec(2.0, 30, 100, 2), rec(4.0, 30, 100, 3)};
  const ke::ContractRun r = ke::summarize(c);
  EXPECT_EQ(r.seeds, 3);
  EXPECT_DOUBLE_EQ(r.ate_ours.mean, 6.5 / 3);
  EXPECT_NEAR(r.ate_original.sd, 1.0, 1e-12);
  EXPECT_EQ(r.better_seeds, 1);
  EXPECT_EQ(r.worse_seeds, 2);
  EXPECT_EQ(r.below_random_seeds, 2);
  EXPECT_NEAR(r.mp_percent.mean, 32.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.sqrt_obs_ratio, 2.0);
  EXPECT_DOUBLE_EQ(r.sqrt_obs_ratio_random, 2.0);
  EXPECT_TRUE(std::isnan(r.sqrt_obs_ratio_anms));
  EXPECT_NEAR(r.ate_ratio, (6.5 / 3) / 2.0, 1e-12);
  const double an = 6.5 / 3;
  EXPECT_NEAR(r.ate_ratio_floored, std::sqrt(an * an + 0.09) / std::sqrt(4.0 + 0.09), 1e-12);
  EXPECT_EQ(r.ate_anms.n, 0);  // not run: no figure
  const std::string j = ke::contract_json({r}, "");
  EXPECT_EQ(j.rfind("{\"runs\":[{", 0), 0u);
  for (const char* k : {"input", "kind", "seeds", "M", "mp_percent", "kf_percent", "ba_time_percent", "ate_original_m",
                        "ate_ours_m", "ate_ours_sd_m", "ate_random_m", "ate_longest_track_m", "ate_anms_m",
                        "better_seeds", "worse_seeds", "sqrt_obs_ratio"})
    EXPECT_NE(j.find(std::string("\"") + k + "\":"), std::string::npos) << k;
  EXPECT_NE(j.find("\"ate_anms_m\":null"), std::string::npos);
}

// The real VO's runs carry frames and frames tracked per variant; the other
// kinds' objects do not grow those keys.
TEST(EvalContract, RealVoRunsReportFramesTracked) {
  ke::Comparison c;
  c.info.input = "seq";
  c.info.kind = "rgbd";
  c.original = {rec(1.0, 100, 400, 1), rec(1.0, 100, 400, 2)};
  c.ours = {rec(1.0, 30, 100, 1), rec(1.0, 30, 100, 2)};
  // Not a real VO: frames 0, nothing failed (every run object carries the keys).
  const std::string none = ke::contract_json({ke::summarize(c)}, "");
  EXPECT_NE(none.find("\"frames\":0,\"frames_tracked\":0"), std::string::npos) << none;
  EXPECT_NE(none.find("\"failed_seeds\":{\"original\":0,\"ours\":0,"), std::string::npos) << none;
  for (auto* v : {&c.original, &c.ours})
    for (ke::RunRecord& r : *v) r.frames = 60, r.frames_tracked = 60;
  c.ours[1].frames_tracked = 50;
  const ke::ContractRun r = ke::summarize(c);
  EXPECT_EQ(r.frames, 60);
  EXPECT_DOUBLE_EQ(r.frames_tracked.mean, 55.0);
  EXPECT_DOUBLE_EQ(r.frames_tracked_original.mean, 60.0);
  EXPECT_EQ(r.frames_tracked_random.n, 0);
  const std::string j = ke::contract_json({r}, "");
  EXPECT_NE(j.find("\"frames\":60,"), std::string::npos) << j;
  EXPECT_NE(j.find("\"frames_tracked\":55.00"), std::string::npos) << j;
  EXPECT_NE(j.find("\"frames_tracked_original\":60.00"), std::string::npos) << j;
  EXPECT_NE(j.find("\"frames_tracked_random\":null"), std::string::npos) << j;
  // The run that lost 10 frames is a failure of ours, and only of ours.
  EXPECT_EQ(r.failed.ours, 1);
  EXPECT_EQ(r.failed.original, 0);
  EXPECT_NE(j.find("\"failed_seeds\":{\"original\":0,\"ours\":1,\"random\":0,\"longest_track\":0,\"anms\":0}"),
            std::string::npos)
      << j;
}

// A lost original is scored at its few tracked frames held still: every
// comparison with the original skips its failed seeds and says how many it used.
TEST(EvalContract, RatiosToTheOriginalSkipTheSeedsItFailed) {
  ke::Comparison c;
  c.info.input = "seq";
  c.info.name = "seq";
  c.info.kind = "images";
  c.info.error_floor_m = 0.5;
  c.target_fraction = 0.1;
  c.original = {rec(1.0, 100, 400, 1), rec(30.0, 10, 40, 2), rec(2.0, 100, 400, 3)};
  c.ours = {rec(1.5, 30, 100, 1), rec(1.0, 30, 100, 2), rec(2.5, 30, 100, 3)};
  c.random = {rec(2.0, 30, 100, 1), rec(9.0, 30, 100, 2), rec(1.0, 30, 100, 3)};
  for (auto* v : {&c.original, &c.ours, &c.random})
    for (ke::RunRecord& r : *v) r.frames = 60, r.frames_tracked = 60;
  c.original[1].frames_tracked = 5;
  const ke::ContractRun r = ke::summarize(c);
  EXPECT_EQ(r.seeds, 3);
  EXPECT_EQ(r.ratio_seeds, 2);
  EXPECT_DOUBLE_EQ(r.ate_original.mean, 11.0);  // the plain mean keeps every run, marked failed
  EXPECT_DOUBLE_EQ(r.ate_ratio, 4.0 / 3.0);     // (1.5 + 2.5) / (1 + 2), not 5 / 33
  EXPECT_DOUBLE_EQ(r.ate_ratio_random, 1.0);    // (2 + 1) / (1 + 2)
  EXPECT_TRUE(std::isnan(r.ate_ratio_anms));    // not run
  EXPECT_NEAR(r.ate_ratio_floored, std::sqrt(4.0 + 0.25) / std::sqrt(2.25 + 0.25), 1e-12);
  EXPECT_EQ(r.better_seeds, 0);  // seed 2 is not a win over a lost original
  EXPECT_EQ(r.worse_seeds, 2);
  EXPECT_EQ(r.below_random_seeds, 2);  // between selectors every seed counts
  // ... and so does the paired difference: 1.5 - 2, 1 - 9, 2.5 - 1.
  EXPECT_EQ(r.ate_diff_random.n, 3);
  EXPECT_DOUBLE_EQ(r.ate_diff_random.mean, -7.0 / 3.0);
  EXPECT_NEAR(r.ate_diff_random.se(), std::sqrt((std::pow(-0.5 + 7.0 / 3, 2) + std::pow(-8.0 + 7.0 / 3, 2) +
                                                  std::pow(1.5 + 7.0 / 3, 2)) / 2.0 / 3.0), 1e-12);
  EXPECT_EQ(r.ate_diff_anms.n, 0);  // not run
  EXPECT_DOUBLE_EQ(r.mp_percent.mean, 30.0);  // not 300 % of the lost original's 10 points
  EXPECT_DOUBLE_EQ(r.sqrt_obs_ratio, 2.0);
  const std::string j = ke::contract_json({r}, "");
  EXPECT_NE(j.find("\"ratio_seeds\":2"), std::string::npos) << j;
  EXPECT_NE(j.find("\"ate_ratio_random\":1.0000"), std::string::npos) << j;
  EXPECT_NE(j.find("\"ate_diff_random_m\":-2.333333,\"ate_diff_random_se_m\":2.891559"), std::string::npos) << j;
  EXPECT_NE(j.find("\"ate_diff_anms_m\":null,\"ate_diff_anms_se_m\":null"), std::string::npos) << j;
  ke::EvalSummary s;
  s.comparisons = {c};
  s.runs = {r};
  const std::string md = ke::markdown_tables(s);
  EXPECT_NE(md.find("| 1.33 (2 seeds) |"), std::string::npos) << md;
  EXPECT_NE(md.find("1.33 (2.00) / 1.00 (2.00) / – (–) / – (–) (2 seeds)"), std::string::npos) << md;
  EXPECT_NE(md.find("| 2 / 3 (-2.333 ± 2.892) | – | – |"), std::string::npos) << md;
}

// Review: runs were paired by position, so `--report` merging a directory
// with keepless's seed 1 and one with random's seed 2 set seed 2's random
// against seed 1's original and keepless. Paired by seed: what has no
// partner is left out.
TEST(EvalContract, RunsArePairedBySeedNotPosition) {
  ke::Comparison c;
  c.info.input = "seq";
  c.info.name = "seq";
  c.info.kind = "images";
  c.target_fraction = 0.2;
  c.original = {rec(1.0, 100, 400, 1), rec(2.0, 100, 400, 2)};
  c.ours = {rec(1.5, 30, 100, 1)};
  c.random = {rec(4.0, 30, 100, 2), rec(3.0, 30, 100, 3)};  // seed 3: no original, no keepless run
  for (auto* v : {&c.original, &c.ours, &c.random})
    for (ke::RunRecord& r : *v) r.frames = 60, r.frames_tracked = 60;
  const ke::ContractRun r = ke::summarize(c);
  EXPECT_DOUBLE_EQ(r.ate_ratio, 1.5);         // seed 1: 1.5 / 1
  EXPECT_DOUBLE_EQ(r.ate_ratio_random, 2.0);  // seed 2: 4 / 2 (seed 3 has no original)
  EXPECT_EQ(r.ate_diff_random.n, 0);          // no seed both ran
  EXPECT_EQ(r.below_random_seeds, 0);
  c.random.push_back(rec(1.0, 30, 100, 1));
  const ke::ContractRun q = ke::summarize(c);
  EXPECT_EQ(q.ate_diff_random.n, 1);
  EXPECT_DOUBLE_EQ(q.ate_diff_random.mean, 0.5);  // seed 1: 1.5 - 1
  EXPECT_EQ(q.below_random_seeds, 0);
}

// A diverged BA is a failure too; the tables mark every mean that includes one.
TEST(EvalContract, FailuresAreCountedInTheTables) {
  ke::Comparison c;
  c.info.input = "seq";
  c.info.name = "seq";
  c.info.kind = "rgbd";
  c.target_fraction = 0.2;
  c.original = {rec(1.0, 100, 400, 1), rec(1.0, 100, 400, 2)};
  c.ours = {rec(1.0, 30, 100, 1), rec(2.0, 30, 100, 2)};
  c.random = {rec(1.0, 30, 100, 1), rec(1.0, 30, 100, 2)};
  for (auto* v : {&c.original, &c.ours, &c.random})
    for (ke::RunRecord& r : *v) r.frames = 60, r.frames_tracked = 60;
  for (ke::RunRecord& r : c.original) r.variant = "original";
  for (ke::RunRecord& r : c.ours) r.variant = "ours";
  for (ke::RunRecord& r : c.random) r.variant = "random";
  c.ours[1].frames_tracked = 7;
  c.random[0].diverged = true;
  EXPECT_TRUE(c.ours[1].failed());
  EXPECT_TRUE(c.random[0].failed());
  EXPECT_FALSE(c.ours[0].failed());
  ke::EvalSummary s;
  s.comparisons = {c};
  ke::Comparison d = c;  // a second fraction makes a sweep
  d.target_fraction = 0.4;
  d.ours[1].frames_tracked = 60;
  s.comparisons.push_back(d);
  for (const ke::Comparison& x : s.comparisons) s.runs.push_back(ke::summarize(x));
  EXPECT_EQ(s.runs[0].failed.ours, 1);
  EXPECT_EQ(s.runs[0].failed.random, 1);
  EXPECT_EQ(s.runs[1].failed.ours, 0);
  const std::string md = ke::markdown_tables(s);
  EXPECT_NE(md.find("#### Failures (F = 0.20"), std::string::npos) << md;
  EXPECT_NE(md.find("(1 failed)"), std::string::npos) << md;
  EXPECT_NE(md.find("| seq | 0 / 2 | 1 / 2 | 1 / 2 | – | – |"), std::string::npos) << md;
  EXPECT_NE(md.find("#### Budget sweep: seq"), std::string::npos) << md;
  EXPECT_NE(md.find("ours 0.40"), std::string::npos) << md;  // smallest F without a failure
  const std::string out = ::testing::TempDir() + "/eval_sweep_outputs";
  std::filesystem::remove_all(out);
  std::filesystem::create_directories(out);
  std::string error;
  ASSERT_TRUE(ke::write_outputs(s, out, &error)) << error;
  const std::string svg = out + "/sweep_seq.svg";
  ASSERT_TRUE(std::filesystem::exists(svg));
  std::ifstream in(svg);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("1/2 failed"), std::string::npos);
  // runs.csv round-trips the failure.
  ke::EvalSummary back;
  ASSERT_TRUE(ke::read_outputs(out, &back, &error)) << error;
  ASSERT_EQ(back.comparisons.size(), 2u);
  ASSERT_EQ(back.comparisons[0].random.size(), 2u);
  ASSERT_EQ(back.comparisons[0].ours.size(), 2u);
  EXPECT_TRUE(back.comparisons[0].random[0].diverged);
  EXPECT_EQ(back.comparisons[0].ours[1].frames_tracked, 7);
}

// Other seeds of the same input, run from another directory (an absolute path
// instead of a relative one), join its comparison instead of making a second row.
TEST(EvalContract, ReportsMergeSeedsOfOneInputWrittenByOtherPaths) {
  const std::string root = ::testing::TempDir() + "/eval_merge";
  std::filesystem::remove_all(root);
  std::string error;
  for (auto [dir, input, seed] : {std::tuple{"a", "../shared/data/seq_x/image_0", 1},
                                  std::tuple{"b", "/work/shared/data/seq_x/image_0/", 2},
                                  std::tuple{"c", "../shared/data/seq_y/image_0", 3}}) {
    ke::Comparison c;
    c.info.input = input;
    c.info.name = "seq";
    c.info.kind = "images";
    c.target_fraction = 0.2;
    c.original = {rec(1.0, 100, 400, seed)};
    c.ours = {rec(1.5, 30, 100, seed)};
    c.original[0].variant = "original";
    c.ours[0].variant = "ours";
    ke::EvalSummary s;
    s.comparisons = {c};
    s.runs = {ke::summarize(c)};
    ASSERT_TRUE(ke::write_outputs(s, root + "/" + dir, &error)) << error;
  }
  ke::EvalSummary back;
  for (const char* dir : {"a", "b", "c"}) ASSERT_TRUE(ke::read_outputs(root + "/" + dir, &back, &error)) << error;
  ASSERT_EQ(back.comparisons.size(), 2u);  // seq_x (seeds 1, 2) and seq_y, another sequence
  EXPECT_EQ(back.comparisons[0].ours.size(), 2u);
  EXPECT_EQ(back.comparisons[0].original.size(), 2u);
  EXPECT_EQ(back.comparisons[1].ours.size(), 1u);
}

}  // namespace
