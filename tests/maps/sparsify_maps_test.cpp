// keepless_sparsify on maps: replay equals a naive replay built here from
// Sparsifier::run on each window; the floor; and the CLI contract on the
// real fixtures (deterministic decisions, models written in the input's
// format, bad models: exit 2, one FILE:OFFSET line, nothing written).

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <set>
#include <string>
#include <unordered_set>
#include <vector>

#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "keepless/io/bal_problem.hpp"
#include "keepless/io/colmap_model.hpp"
#include "keepless/io/keyframes.hpp"
#include "keepless/platform/window_file_io.hpp"
#include "maps_support.hpp"
#include "sparsify/exact_count.hpp"
#include "sparsify/modes.hpp"

namespace keepless {
namespace {

using maps_test::fixture;
using maps_test::json_number;
using maps_test::last_line;
namespace fs = std::filesystem;

io::Keyframes fixture_keyframes(io::ColmapModel* m) {
  io::ColmapFormat format;
  std::string error;
  EXPECT_TRUE(io::read_colmap_model(fixture("sparse"), m, &format, &error)) << error;
  io::Similarity sim;
  EXPECT_TRUE(io::read_similarity(fixture("sim3_to_kitti_gt.txt"), &sim, &error)) << error;
  return io::keyframes_from_colmap(*m, io::KeyframeOrder::kName, sim);
}

// Records by id (COLMAP's .bin and .txt of one model list them in different orders).
io::ColmapModel sorted(io::ColmapModel m) {
  std::sort(m.images.begin(), m.images.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  std::sort(m.points.begin(), m.points.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return m;
}

// The node's loop written plainly: a fresh window of the last K keyframes
// (minus everything culled so far) decided from scratch at each keyframe.
std::set<core::PointId> naive_replay_culls(const core::WindowFile& f, const core::Params& params, std::uint32_t K) {
  std::set<core::PointId> culled;
  std::deque<std::size_t> members;
  for (std::size_t i = 0; i < f.keyframes.size(); ++i) {
    members.push_back(i);
    if (members.size() > K) members.pop_front();
    core::WindowFile now;
    for (const std::size_t j : members) {
      now.keyframes.push_back(f.keyframes[j]);
      auto& obs = now.observations.emplace_back();
      for (const auto& o : f.observations[j]) {
        if (culled.count(o.point) == 0) obs.push_back(o);
      }
    }
    const core::Capacities caps = core::compute_needs(now);
    core::Window w(caps);
    for (std::size_t j = 0; j < now.keyframes.size(); ++j) {
      const auto& obs = now.observations[j];
      EXPECT_EQ(w.add_keyframe(now.keyframes[j], obs.data(), static_cast<std::uint32_t>(obs.size())), core::Status::kOk);
    }
    core::Sparsifier s(caps, params);
    EXPECT_EQ(s.run(w), core::Status::kOk);
    for (std::uint32_t k = 0; k < s.decision_count(); ++k) {
      if (s.decisions()[k].verdict == core::Verdict::kCull) culled.insert(s.decisions()[k].point);
    }
  }
  return culled;
}

TEST(ReplayMode, CullsWhatANaiveFromScratchReplayCulls) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  io::ColmapModel m;
  const io::Keyframes k = fixture_keyframes(&m);
  for (const std::int64_t M : {30, 200}) {
    core::Params params;
    params.pair_capacity = M;
    sparsify::ModeResult r;
    ASSERT_EQ(sparsify::decide(k.file, sparsify::Mode::kReplay, params, 20, &r), core::Status::kOk);
    std::set<core::PointId> culled;
    for (const auto& d : r.decisions) {
      if (d.verdict == core::Verdict::kCull) culled.insert(d.point);
    }
    EXPECT_EQ(culled, naive_replay_culls(k.file, params, 20)) << "M = " << M;
    EXPECT_EQ(r.slides, 51u);
    EXPECT_GT(culled.size(), 0u);
  }
}

TEST(WholeMode, IsOneRunOverAllKeyframes) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  io::ColmapModel m;
  const io::Keyframes k = fixture_keyframes(&m);
  core::Params params;
  params.pair_capacity = 30;
  sparsify::ModeResult r;
  ASSERT_EQ(sparsify::decide(k.file, sparsify::Mode::kWhole, params, 20, &r), core::Status::kOk);
  EXPECT_EQ(r.totals.kept, 42u);  // the measurement: 42 points at M = 30
  EXPECT_EQ(r.slides, 1u);
}

TEST(Floor, RestoresCulledPointsMostObservedFirstUntilEveryImageHasIt) {
  // Image 0 sees points 1..5, image 1 sees 4..6; all culled but 6.
  const std::vector<std::vector<core::PointId>> images = {{1, 2, 3, 4, 5}, {4, 5, 6}};
  std::vector<core::PointDecision> d;
  for (core::PointId p = 1; p <= 6; ++p) d.push_back({p, p == 6 ? core::Verdict::kKeep : core::Verdict::kCull, 0, 0});
  EXPECT_EQ(sparsify::apply_floor(images, 2, &d), 2u);
  // Image 0 takes 4 and 5 (seen twice), which also lift image 1.
  EXPECT_EQ(d[3].verdict, core::Verdict::kKeep);
  EXPECT_EQ(d[4].verdict, core::Verdict::kKeep);
  EXPECT_EQ(d[0].verdict, core::Verdict::kCull);
  EXPECT_EQ(sparsify::kept_observations(images, d), (std::vector<std::uint32_t>{2, 3}));
  EXPECT_EQ(sparsify::apply_floor(images, 4, &d), 2u);  // 1 then 2 (lower id first)
  EXPECT_EQ(d[0].verdict, core::Verdict::kKeep);
  EXPECT_EQ(d[1].verdict, core::Verdict::kKeep);
  EXPECT_EQ(sparsify::apply_floor(images, 10, &d), 1u);  // all it can
  EXPECT_EQ(sparsify::apply_floor(images, 0, &d), 0u);
}

class SparsifyMaps : public maps_test::MapsTest {};

TEST_F(SparsifyMaps, ReplayOnTheFixtureIsDeterministicAndWritesALoadableModel) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("txt/images.txt"));
  const std::string sim = fixture("sim3_to_kitti_gt.txt");
  std::string json;
  for (int run = 0; run < 2; ++run) {
    const std::string n = std::to_string(run);
    const maps_test::Result r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--sim3", sim, "--out",
                                          path("out" + n), "--decisions", path("d" + n)});
    ASSERT_EQ(r.status, 0) << r.err;
    json = last_line(r.out);
  }
  EXPECT_EQ(maps_test::read_all(path("d0")), maps_test::read_all(path("d1")));
  for (const char* f : {"cameras.bin", "images.bin", "points3D.bin"}) {
    EXPECT_EQ(maps_test::read_all(path("out0/") + f), maps_test::read_all(path("out1/") + f)) << f;
  }
  for (const char* key : {"keyframes", "points", "evaluated", "kept", "culled", "skipped", "pairs", "arcs", "max_flow",
                          "total_cost", "solve_ms", "points_kept", "min_obs_per_image", "median_obs_per_image",
                          "floor_restored", "duplicate_observations", "time_ms"}) {
    EXPECT_FALSE(std::isnan(json_number(json, key))) << key << " missing: " << json;
  }
  EXPECT_NE(json.find("\"mode\":\"replay\""), std::string::npos);
  EXPECT_NE(json.find("\"order\":\"name\""), std::string::npos);
  EXPECT_EQ(json_number(json, "duplicate_observations"), 1154);
  EXPECT_EQ(json_number(json, "K"), 20);
  io::ColmapModel out;
  io::ColmapFormat format;
  std::string error;
  ASSERT_TRUE(io::read_colmap_model(path("out0"), &out, &format, &error)) << error;
  EXPECT_EQ(format, io::ColmapFormat::kBinary);
  EXPECT_EQ(out.points.size(), json_number(json, "points_kept"));
  EXPECT_EQ(out.images.size(), 51u);
  const auto per_image = io::observations_per_image(out);
  EXPECT_EQ(*std::min_element(per_image.begin(), per_image.end()), json_number(json, "min_obs_per_image"));
  EXPECT_GE(json_number(json, "min_obs_per_image"), 30);
  // The decisions file names every culled point; none is left in the model.
  std::unordered_set<std::uint64_t> left;
  for (const auto& p : out.points) left.insert(p.id);
  std::istringstream lines(maps_test::read_all(path("d0")));
  std::uint64_t id;
  std::string verdict, flow, cap;
  std::size_t culled = 0;
  while (lines >> id >> verdict >> flow >> cap) {
    EXPECT_EQ(left.count(id) == 0, verdict == "cull") << id;
    culled += verdict == "cull";
  }
  EXPECT_EQ(culled, json_number(json, "culled"));

  // The same model as text, and from the text input: the same points.
  maps_test::Result t = sparsify({"--colmap", fixture("txt"), "--M", "30", "--sim3", sim, "--out", path("txt")});
  ASSERT_EQ(t.status, 0) << t.err;
  io::ColmapModel from_txt;
  ASSERT_TRUE(io::read_colmap_model(path("txt"), &from_txt, &format, &error)) << error;
  EXPECT_EQ(format, io::ColmapFormat::kText);
  EXPECT_TRUE(io::format_colmap(sorted(from_txt), io::ColmapFormat::kBinary).points3D ==
              io::format_colmap(sorted(out), io::ColmapFormat::kBinary).points3D);
  t = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--sim3", sim, "--out", path("astxt"), "--out-format", "txt"});
  ASSERT_EQ(t.status, 0) << t.err;
  io::ColmapModel as_txt;
  ASSERT_TRUE(io::read_colmap_model(path("astxt"), &as_txt, &format, &error)) << error;
  EXPECT_EQ(format, io::ColmapFormat::kText);
  EXPECT_TRUE(io::format_colmap(as_txt, io::ColmapFormat::kBinary).images ==
              io::format_colmap(out, io::ColmapFormat::kBinary).images);
}

TEST_F(SparsifyMaps, WholeModeWithTheFloorKeepsEveryImageAtTheFloor) {
  const maps_test::Result r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--mode", "whole",
                                        "--min-obs-per-image", "40"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = last_line(r.out);
  EXPECT_GE(json_number(json, "min_obs_per_image"), 40);
  EXPECT_GT(json_number(json, "floor_restored"), 0);
  EXPECT_NE(json.find("\"mode\":\"whole\""), std::string::npos);
  EXPECT_NE(r.out.find("whole: kept "), std::string::npos);
}

// Whole mode with a count: a floor that binds takes its points from within
// the count, so the count stays exact; one that cannot fit keeps what it
// needs and warns.
TEST_F(SparsifyMaps, AWholeCountKeepsItsFloorWithinTheCount) {
  const auto run = [&](const std::string& count, const std::string& floor) {
    return sparsify({"--colmap", fixture("sparse"), "--mode", "whole", "--keep-points", count, "--track-share", "1",
                     "--min-obs-per-image", floor});
  };
  const maps_test::Result free = run("710", "0");
  ASSERT_EQ(free.status, 0) << free.err;
  const double least = json_number(last_line(free.out), "min_obs_per_image");
  ASSERT_GT(least, 0);
  const int floor = static_cast<int>(least) + 15;  // binds on at least one image
  const maps_test::Result r = run("710", std::to_string(floor));
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = last_line(r.out);
  EXPECT_EQ(json_number(json, "points_kept"), 710);
  EXPECT_GE(json_number(json, "min_obs_per_image"), floor);
  EXPECT_GT(json_number(json, "floor_restored"), 0);
  EXPECT_EQ(r.err.find("the floor"), std::string::npos) << r.err;

  const maps_test::Result tight = run("60", "100");
  ASSERT_EQ(tight.status, 0) << tight.err;
  const std::string tight_json = last_line(tight.out);
  EXPECT_GT(json_number(tight_json, "points_kept"), 60);
  EXPECT_EQ(json_number(tight_json, "points_kept"), json_number(tight_json, "floor_restored"));
  EXPECT_GE(json_number(tight_json, "min_obs_per_image"), 100);
  EXPECT_NE(tight.err.find("alone needs more than the count of 60 points"), std::string::npos) << tight.err;
}

// The floor's warning names the count asked for: points never judged (seen
// by one keyframe) are kept on top of it, as by the count.
TEST_F(SparsifyMaps, TheFloorsWarningNamesTheCountWithoutTheSkippedPoints) {
  // Point 7 in all three keyframes, 8 and 9 in two, 10..13 in keyframe 1 only (skipped).
  maps_test::write_all(path("w.txt"), "kf 1 0 0 0\nkf 2 1 0 0\nkf 3 2 0 0\n"
                                      "obs 1 7 10 10\nobs 2 7 12 10\nobs 3 7 14 10\nobs 1 8 100 100\nobs 2 8 100 100\n"
                                      "obs 2 9 300 200\nobs 3 9 300 200\nobs 1 10 1 1\nobs 1 11 2 2\nobs 1 12 3 3\n"
                                      "obs 1 13 4 4\n");
  const maps_test::Result r = sparsify({"--window", path("w.txt"), "--keep-points", "1", "--min-obs-per-image", "3"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = last_line(r.out);
  EXPECT_EQ(json_number(json, "skipped"), 4);
  EXPECT_EQ(json_number(json, "floor_restored"), 3);
  EXPECT_EQ(json_number(json, "points_kept"), 7);
  EXPECT_NE(r.err.find("alone needs more than the count of 1 points: 3 kept for it"), std::string::npos) << r.err;
}

// --use offline is --mode whole --track-share 1 --floor-over-longest 1.1:
// the same decisions and model; its share needs a count, and the other flags
// refine it.
TEST_F(SparsifyMaps, UseOfflineIsTheWholeModeByTrackLength) {
  const maps_test::Result use = sparsify({"--colmap", fixture("sparse"), "--use", "offline", "--keep-points", "710",
                                          "--out", path("use"), "--decisions", path("use.d")});
  ASSERT_EQ(use.status, 0) << use.err;
  const maps_test::Result flags = sparsify({"--colmap", fixture("sparse"), "--mode", "whole", "--track-share", "1",
                                            "--floor-over-longest", "1.1",
                                            "--keep-points", "710", "--out", path("flags"), "--decisions", path("flags.d")});
  ASSERT_EQ(flags.status, 0) << flags.err;
  const std::string json = last_line(use.out);
  EXPECT_NE(json.find("\"mode\":\"whole\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"track_share\":1,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"floor_over_longest\":1.1,"), std::string::npos) << json;
  EXPECT_GT(json_number(json, "obs_floor"), 30);  // R, not the default floor, set it
  EXPECT_NE(json.find("\"budget\":\"points\",\"budget_value\":710}"), std::string::npos) << json;
  EXPECT_EQ(json_number(json, "points_kept"), 710);
  EXPECT_EQ(maps_test::read_all(path("use.d")), maps_test::read_all(path("flags.d")));
  for (const char* f : {"cameras.bin", "images.bin", "points3D.bin"}) {
    EXPECT_EQ(maps_test::read_all(path("use/") + f), maps_test::read_all(path("flags/") + f)) << f;
  }
  const maps_test::Result replay = sparsify({"--colmap", fixture("sparse"), "--mode", "replay", "--use", "offline",
                                             "--keep-fraction", "0.1"});
  ASSERT_EQ(replay.status, 0) << replay.err;
  EXPECT_NE(last_line(replay.out).find("\"mode\":\"replay\""), std::string::npos);
  EXPECT_EQ(json_number(last_line(replay.out), "floor_over_longest"), 0);
  EXPECT_NE(last_line(replay.out).find("\"budget\":\"fraction\",\"budget_value\":0.1}"), std::string::npos)
      << last_line(replay.out);
  // Without a count (its share set to 0) R does not apply, and the JSON says 0.
  const maps_test::Result m_budget =
      sparsify({"--colmap", fixture("sparse"), "--use", "offline", "--track-share", "0", "--M", "200"});
  ASSERT_EQ(m_budget.status, 0) << m_budget.err;
  EXPECT_EQ(json_number(last_line(m_budget.out), "floor_over_longest"), 0) << last_line(m_budget.out);
  EXPECT_EQ(json_number(last_line(m_budget.out), "obs_floor"), 30);
  const maps_test::Result no_count = sparsify({"--colmap", fixture("sparse"), "--use", "offline"});
  EXPECT_EQ(no_count.status, 2);
  EXPECT_NE(no_count.err.find("--use offline sets it to 1"), std::string::npos) << no_count.err;
  const maps_test::Result unknown = sparsify({"--colmap", fixture("sparse"), "--use", "colmap"});
  EXPECT_EQ(unknown.status, 2);
  EXPECT_NE(unknown.err.find("bad value for --use: 'colmap'"), std::string::npos) << unknown.err;
}

// --floor-over-longest R: the floor is R x the poorest image the count's
// longest tracks leave (1,927 points: the fixture's tracks of 10 and more,
// no tie at the cut), rounded up and taken within the count; the offline
// use sets 1.1 unless a floor is given; it needs the whole mode and a count.
TEST_F(SparsifyMaps, AFloorOverTheLongestTracksLiftsThePoorestImage) {
  const auto run = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = {"--colmap", fixture("sparse"), "--mode", "whole", "--keep-points", "1927",
                                     "--track-share", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    return sparsify(args);
  };
  const maps_test::Result longest = run({"--min-obs-per-image", "0"});
  ASSERT_EQ(longest.status, 0) << longest.err;
  const double poorest = json_number(last_line(longest.out), "min_obs_per_image");
  ASSERT_GT(poorest, 0);
  const maps_test::Result lifted = run({"--min-obs-per-image", "0", "--floor-over-longest", "1.1"});
  ASSERT_EQ(lifted.status, 0) << lifted.err;
  const std::string json = last_line(lifted.out);
  const double floor = sparsify::floor_over(1.1, static_cast<std::uint32_t>(poorest));
  EXPECT_GT(floor, poorest);
  EXPECT_EQ(json_number(json, "obs_floor"), floor);
  EXPECT_GE(json_number(json, "min_obs_per_image"), floor);
  EXPECT_EQ(json_number(json, "points_kept"), 1927);
  EXPECT_GT(json_number(json, "floor_restored"), 0);
  const maps_test::Result own_floor = sparsify({"--colmap", fixture("sparse"), "--use", "offline", "--keep-points",
                                                "1927", "--min-obs-per-image", "0"});
  ASSERT_EQ(own_floor.status, 0) << own_floor.err;
  EXPECT_EQ(json_number(last_line(own_floor.out), "floor_over_longest"), 0);
  EXPECT_EQ(json_number(last_line(own_floor.out), "min_obs_per_image"), poorest);
  const maps_test::Result replay = sparsify({"--colmap", fixture("sparse"), "--mode", "replay", "--keep-points",
                                             "1927", "--floor-over-longest", "1.1"});
  EXPECT_EQ(replay.status, 2);
  EXPECT_NE(replay.err.find("--floor-over-longest needs --mode whole and --keep-points or --keep-fraction"),
            std::string::npos)
      << replay.err;
  const maps_test::Result below_one = run({"--floor-over-longest", "0.5"});
  EXPECT_EQ(below_one.status, 2);
  EXPECT_NE(below_one.err.find("(0, or a number in [1, 100])"), std::string::npos) << below_one.err;
}

// --track-share 1: the whole model's count taken entirely by track length
// (COLMAP's: every observation), so no culled point has a longer track than
// a kept one.
TEST_F(SparsifyMaps, AWholeTrackShareKeepsTheLongestTracks) {
  const std::string out = path("share1");
  const maps_test::Result r = sparsify({"--colmap", fixture("sparse"), "--mode", "whole", "--keep-points", "1420",
                                        "--track-share", "1", "--min-obs-per-image", "0", "--out", out});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(json_number(last_line(r.out), "points_kept"), 1420);
  EXPECT_NE(last_line(r.out).find("\"track_share\":1,"), std::string::npos);
  io::ColmapModel original, kept;
  io::ColmapFormat format;
  std::string error;
  ASSERT_TRUE(io::read_colmap_model(fixture("sparse"), &original, &format, &error)) << error;
  ASSERT_TRUE(io::read_colmap_model(out, &kept, &format, &error)) << error;
  ASSERT_EQ(kept.points.size(), 1420u);
  std::set<std::uint64_t> kept_ids;
  std::size_t shortest_kept = SIZE_MAX, longest_culled = 0;
  for (const io::ColmapPoint3D& p : kept.points) {
    kept_ids.insert(p.id);
    shortest_kept = std::min(shortest_kept, p.track.size());
  }
  for (const io::ColmapPoint3D& p : original.points) {
    if (kept_ids.count(p.id) == 0) longest_culled = std::max(longest_culled, p.track.size());
  }
  EXPECT_GE(shortest_kept, longest_culled);
  EXPECT_GT(shortest_kept, 2u);  // the fixture's long tracks, not a degenerate cut
}

TEST_F(SparsifyMaps, BalAndWindowInputsAreWrittenBackInTheirFormat) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  const std::string bal = std::string(KEEPLESS_MAPS_DATA) + "/bal_zenslam/problem-49-7776-pre.txt";
  maps_test::Result r = sparsify({"--bal", bal, "--M", "30", "--out", path("small.bal")});
  ASSERT_EQ(r.status, 0) << r.err;
  io::BalProblem p;
  std::string error;
  ASSERT_TRUE(io::read_bal(path("small.bal"), &p, &error)) << error;
  const std::string json = last_line(r.out);
  EXPECT_EQ(p.num_points, json_number(json, "points_kept"));
  EXPECT_LT(p.num_points, 7776u);
  EXPECT_EQ(p.num_cameras, 49u);
  EXPECT_NE(json.find("\"order\":\"file\""), std::string::npos);

  maps_test::write_all(path("w.txt"), "kf 1 0 0 0\nkf 2 1 0 0\nkf 3 2 0 0\nobs 1 7 10 10\nobs 2 7 12 10\n"
                                      "obs 3 7 14 10\nobs 1 8 100 100\nobs 2 8 100 100\n");
  r = sparsify({"--window", path("w.txt"), "--mode", "replay", "--K", "2", "--M", "1", "--out", path("w_out.txt")});
  ASSERT_EQ(r.status, 0) << r.err;
  core::WindowFile w;
  ASSERT_TRUE(keepless::platform::read_window_file(path("w_out.txt"), &w, &error)) << error;
  EXPECT_EQ(w.keyframes.size(), 3u);
  EXPECT_EQ(json_number(last_line(r.out), "obs_floor"), 0);  // no floor by default for window files
  // Without map flags, --window is today's single-window path.
  r = sparsify({"--window", path("w.txt")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(std::isnan(json_number(last_line(r.out), "mode")));
}

TEST_F(SparsifyMaps, ABadModelExitsTwoWithOneLineAndWritesNothing) {
  fs::create_directories(path("bad"));
  const std::string images = maps_test::read_all(fixture("sparse/images.bin"));
  fs::copy_file(fixture("sparse/cameras.bin"), path("bad/cameras.bin"));
  fs::copy_file(fixture("sparse/points3D.bin"), path("bad/points3D.bin"));
  maps_test::write_all(path("bad/images.bin"), images.substr(0, 100000));  // inside image 1's 2D points
  maps_test::Result r =
      sparsify({"--colmap", path("bad"), "--out", path("out"), "--decisions", path("dec")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1);
  // The first image's count of 2D points (at byte 83: u64 count, u32 id,
  // 7 f64, u32 camera, "000050.png" NUL) promises more than is left.
  EXPECT_EQ(r.err.rfind(path("bad") + "/images.bin:83: num_points2D ", 0), 0u) << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
  EXPECT_FALSE(fs::exists(path("dec")));
  for (const auto& e : fs::directory_iterator(dir_)) EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos);
  // Missing model, bad sim3 file, --order name on BAL.
  r = sparsify({"--colmap", path("nothing")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("nothing") + ": no COLMAP model (cameras/images/points3D .bin or .txt)\n");
  r = sparsify({"--colmap", fixture()});  // the model's parent folder
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, fixture() + ": no COLMAP model (cameras/images/points3D .bin or .txt)\n");
  maps_test::write_all(path("sim3.txt"), "1 0 0\n");
  r = sparsify({"--colmap", fixture("sparse"), "--sim3", path("sim3.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("sim3.txt") + ":2: expected 13 numbers (s, R row-major, t), got 3\n");
  // Review: R was taken as given; a zero matrix put every centre at t.
  maps_test::write_all(path("sim3.txt"), "1\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n");
  r = sparsify({"--colmap", fixture("sparse"), "--sim3", path("sim3.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("sim3.txt") + ":1: R is not a rotation (its columns must be orthonormal)\n");
  maps_test::write_all(path("sim3.txt"), "1 -1 0 0 0 1 0 0 0 1 0 0 0\n");
  r = sparsify({"--colmap", fixture("sparse"), "--sim3", path("sim3.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("sim3.txt") + ":1: R is not a rotation (a reflection: det R = -1)\n");
  maps_test::write_all(path("sim3.txt"), "2 0.866025 -0.5 0 0.5 0.866025 0 0 0 1 0 0 0\n");  // six decimals
  r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--sim3", path("sim3.txt")});
  EXPECT_EQ(r.status, 0) << r.err;
  // Text into a directory holding a binary model: refused before any output,
  // so an earlier decisions file is left as it was.
  fs::create_directories(path("has_bin"));
  maps_test::write_all(path("has_bin/images.bin"), "old");
  maps_test::write_all(path("earlier_decisions.txt"), "earlier run\n");
  r = sparsify({"--colmap", fixture("sparse"), "--out", path("has_bin"), "--out-format", "txt", "--decisions",
                path("earlier_decisions.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("has_bin") + "/images.bin:0: a model in the other format is already there; write to another "
                                     "directory\n");
  EXPECT_FALSE(fs::exists(path("has_bin/images.txt")));
  EXPECT_EQ(maps_test::read_all(path("earlier_decisions.txt")), "earlier run\n");
  r = sparsify({"--bal", path("x"), "--order", "name"});
  EXPECT_EQ(r.status, 2);
  r = sparsify({"--colmap", fixture("sparse"), "--mode", "all"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("; see 'keepless_sparsify --help'"), std::string::npos);
  r = sparsify({"--colmap", fixture("sparse"), "--bal", path("x")});
  EXPECT_EQ(r.status, 2);
}

// The sizes and the one kept figure: "kept" is what the written model holds
// (judged and kept plus never judged); --compact drops the unmatched 2D
// points and COLMAP's own checks still pass (model_analyzer in tests/maps'
// colmap label).
TEST_F(SparsifyMaps, SizesOneKeptFigureAndCompact) {
  maps_test::Result r = sparsify({"--colmap", fixture("sparse"), "--out", path("plain")});
  ASSERT_EQ(r.status, 0) << r.err;
  std::string json = last_line(r.out);
  EXPECT_EQ(json_number(json, "kept"), json_number(json, "points_kept"));
  EXPECT_EQ(json_number(json, "kept") + json_number(json, "culled"), json_number(json, "model_points"));
  EXPECT_NE(r.out.find("kept " + std::to_string(static_cast<long>(json_number(json, "kept"))) + " of 14195 points"),
            std::string::npos) << r.out;
  const auto size_of = [&](const std::string& dir) {
    std::uint64_t n = 0;
    for (const char* f : {"/cameras.bin", "/images.bin", "/points3D.bin"}) n += fs::file_size(dir + f);
    return n;
  };
  EXPECT_EQ(json_number(json, "input_bytes"), size_of(fixture("sparse")));
  EXPECT_EQ(json_number(json, "output_bytes"), size_of(path("plain")));
  EXPECT_EQ(json_number(json, "points2D_dropped"), 0);
  // The default M is below the evidence's: a warning, exit 0.
  EXPECT_NE(r.err.find("warning: M = 100 is below 200"), std::string::npos) << r.err;

  r = sparsify({"--colmap", fixture("sparse"), "--M", "200", "--compact", "--out", path("compact")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");  // M = 200, every image above the floor: no warning
  json = last_line(r.out);
  io::ColmapModel full, small;
  io::ColmapFormat format;
  std::string error;
  ASSERT_TRUE(io::read_colmap_model(fixture("sparse"), &full, &format, &error)) << error;
  ASSERT_TRUE(io::read_colmap_model(path("compact"), &small, &format, &error)) << error;  // cross-checked
  std::uint64_t left = 0, before = 0;
  for (const auto& im : small.images) {
    left += im.points2D.size();
    for (const auto& p : im.points2D) EXPECT_NE(p.point3D_id, io::kNoPoint3D);
  }
  for (const auto& im : full.images) before += im.points2D.size();
  EXPECT_EQ(json_number(json, "points2D_dropped"), before - left);
  EXPECT_EQ(small.points.size(), json_number(json, "kept"));
  EXPECT_EQ(json_number(json, "output_bytes"), size_of(path("compact")));
  EXPECT_LT(json_number(json, "output_bytes"), 0.2 * json_number(json, "input_bytes"));
  // --compact needs a COLMAP model and --out.
  r = sparsify({"--colmap", fixture("sparse"), "--compact"});
  EXPECT_EQ(r.status, 2);
}

// A model that cannot be written after the checks (here a file name the
// file system refuses) exits 2 and leaves an earlier decisions file as it
// was, with no temporary beside it: the decisions are renamed into place
// only once the model is written.
TEST_F(SparsifyMaps, AModelWriteThatFailsLeavesTheDecisionsFileAsItWas) {
  maps_test::write_all(path("w.txt"), "kf 1 0 0 0\nkf 2 1 0 0\nkf 3 2 0 0\nobs 1 7 10 10\nobs 2 7 12 10\n"
                                      "obs 3 7 14 10\nobs 1 8 100 100\nobs 2 8 100 100\n");
  maps_test::write_all(path("d.txt"), "earlier\n");
  const std::string too_long = path(std::string(300, 'a') + ".txt");  // NAME_MAX is 255
  const maps_test::Result r =
      sparsify({"--window", path("w.txt"), "--mode", "replay", "--out", too_long, "--decisions", path("d.txt")});
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.err.find("cannot write"), std::string::npos) << r.err;
  EXPECT_EQ(maps_test::read_all(path("d.txt")), "earlier\n");
  for (const auto& e : fs::directory_iterator(path(""))) {
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  }
  // And it is written when the model is.
  const maps_test::Result ok =
      sparsify({"--window", path("w.txt"), "--mode", "replay", "--out", path("o.txt"), "--decisions", path("d.txt")});
  ASSERT_EQ(ok.status, 0) << ok.err;
  EXPECT_NE(maps_test::read_all(path("d.txt")), "earlier\n");
}

TEST_F(SparsifyMaps, ImagesLeftBelowTheFloorAreWarnedAbout) {
  const maps_test::Result r =
      sparsify({"--colmap", fixture("sparse"), "--M", "1", "--mode", "whole", "--min-obs-per-image", "0"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_LT(json_number(last_line(r.out), "min_obs_per_image"), 30);
  EXPECT_NE(r.err.find("images keep fewer than 30 observations (fewest: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("warning: M = 1 is below 200"), std::string::npos) << r.err;
}

// A map flag that would change nothing is refused (exit 2, one line, nothing
// read or written), not ignored.
TEST_F(SparsifyMaps, FlagsThatWouldChangeNothingAreRefused) {
  maps_test::write_all(path("w.txt"), "kf 1 0 0 0\nkf 2 1 0 0\nobs 1 7 10 10\nobs 2 7 12 10\n");
  maps_test::write_all(path("s.txt"), "2  1 0 0  0 1 0  0 0 1  0 0 0\n");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--colmap", fixture("sparse"), "--out-format", "txt", "--decisions", path("d1")}, "--out-format needs --out"},
      {{"--window", path("w.txt"), "--scale", "3", "--sim3", path("s.txt"), "--decisions", path("d2")},
       "give --scale or --sim3, not both"},
      {{"--colmap", fixture("sparse"), "--mode", "whole", "--K", "5", "--decisions", path("d3")},
       "--K applies to --mode replay"},
      {{"--window", path("w.txt"), "--K", "5", "--decisions", path("d4")}, "--K applies to --mode replay"},
      {{"--colmap", fixture("sparse"), "--use", "offline", "--keep-points", "10", "--K", "5", "--decisions", path("d5")},
       "--K applies to --mode replay"},
  };
  for (const auto& [args, reason] : cases) {
    const maps_test::Result r = sparsify(args);
    EXPECT_EQ(r.status, 2) << reason;
    EXPECT_NE(r.err.find(reason), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  for (const char* d : {"d1", "d2", "d3", "d4", "d5"}) EXPECT_FALSE(fs::exists(path(d))) << d;
  // Each alone, or with what it needs, runs.
  EXPECT_EQ(sparsify({"--window", path("w.txt"), "--mode", "replay", "--K", "5"}).status, 0);
  EXPECT_EQ(sparsify({"--window", path("w.txt"), "--scale", "3"}).status, 0);
  EXPECT_EQ(sparsify({"--window", path("w.txt"), "--sim3", path("s.txt")}).status, 0);
}

// --out may not be the input folder, contain it or lie inside it, however
// it is spelt; the input is left byte for byte as it was.
TEST_F(SparsifyMaps, OutThatIsHoldsOrIsInsideTheInputIsRefused) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  fs::create_directories(path("m"));
  for (const char* f : {"cameras.bin", "images.bin", "points3D.bin"}) fs::copy_file(fixture("sparse/") + f, path("m/") + f);
  fs::create_directory_symlink(path("m"), path("link"));
  const std::string before = maps_test::read_all(path("m/points3D.bin"));
  const std::string cwd_relative = fs::relative(path("m"), fs::current_path()).string();
  const std::pair<std::string, const char*> cases[] = {
      {path("m"), "is"},          {path("m/"), "is"},           {dir_ + "/./m", "is"},
      {path("link"), "is"},       {cwd_relative, "is"},         {dir_, "contains"},
      {path("m/sub"), "lies inside"},
  };
  for (const auto& [out, how] : cases) {
    SCOPED_TRACE(out);
    const maps_test::Result r = sparsify({"--colmap", path("m"), "--out", out});
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.err, out + ": --out " + how + " the input " + path("m") + "; write the sparsified map elsewhere\n");
  }
  EXPECT_EQ(maps_test::read_all(path("m/points3D.bin")), before);
  EXPECT_FALSE(fs::exists(path("m/sub")));
  // A file input (BAL): --out naming the same file.
  const std::string bal = std::string(KEEPLESS_MAPS_DATA) + "/bal_zenslam/problem-49-7776-pre.txt";
  fs::copy_file(bal, path("p.txt"));
  const maps_test::Result r = sparsify({"--bal", path("p.txt"), "--out", path("./p.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(maps_test::read_all(path("p.txt")), maps_test::read_all(bal));
}

// No output may be an input or another output (the same path resolved, or a
// hard link): refused before anything is read, every input left as it was.
TEST_F(SparsifyMaps, AnOutputThatIsAnInputOrAnotherOutputIsRefused) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  fs::create_directories(path("m"));
  for (const char* f : {"cameras.bin", "images.bin", "points3D.bin"}) fs::copy_file(fixture("sparse/") + f, path("m/") + f);
  const std::string bal = std::string(KEEPLESS_MAPS_DATA) + "/bal_zenslam/problem-49-7776-pre.txt";
  fs::copy_file(bal, path("p.bal"));
  fs::create_hard_link(path("p.bal"), path("hard.bal"));
  maps_test::write_all(path("w.txt"), "kf 1 0 0 0\nkf 2 1 0 0\nobs 1 7 10 10\nobs 2 7 12 10\n");
  maps_test::write_all(path("s.txt"), "1 1 0 0 0 1 0 0 0 1 0 0 0\n");
  const std::map<std::string, std::string> before = {
      {"m/points3D.bin", maps_test::read_all(path("m/points3D.bin"))},
      {"p.bal", maps_test::read_all(path("p.bal"))},
      {"w.txt", maps_test::read_all(path("w.txt"))},
      {"s.txt", maps_test::read_all(path("s.txt"))}};
  struct Case {
    std::vector<std::string> args;
    std::string err;
  };
  const std::vector<Case> cases = {
      {{"--colmap", path("m"), "--decisions", path("m/points3D.bin")},
       path("m/points3D.bin") + ": --decisions is the input --colmap " + path("m/points3D.bin") + "; write it elsewhere\n"},
      {{"--bal", path("p.bal"), "--out", path("o.bal"), "--decisions", path("p.bal")},
       path("p.bal") + ": --decisions is the input --bal " + path("p.bal") + "; write it elsewhere\n"},
      {{"--bal", path("p.bal"), "--out", path("hard.bal")},
       path("hard.bal") + ": --out is the input --bal " + path("p.bal") + "; write it elsewhere\n"},
      {{"--bal", path("p.bal"), "--out", path("o.bal"), "--decisions", path("./o.bal")},
       path("o.bal") + ": --out and --decisions name the same file\n"},
      {{"--window", path("w.txt"), "--sim3", path("s.txt"), "--out", path("s.txt")},
       path("s.txt") + ": --out is the input --sim3 " + path("s.txt") + "; write it elsewhere\n"},
      {{"--window", path("w.txt"), "--decisions", path("w.txt")},
       path("w.txt") + ": --decisions is the input --window " + path("w.txt") + "; write it elsewhere\n"},
      // Review: the model's files in the format not read were not protected.
      {{"--colmap", path("m"), "--decisions", path("m/images.txt")},
       path("m/images.txt") + ": --decisions is the input --colmap " + path("m/images.txt") + "; write it elsewhere\n"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args.back());
    const maps_test::Result r = sparsify(c.args);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.err, c.err);
    EXPECT_EQ(r.out, "");
  }
  for (const auto& [name, contents] : before) EXPECT_EQ(maps_test::read_all(path(name)), contents) << name;
  EXPECT_FALSE(fs::exists(path("o.bal")));
  EXPECT_FALSE(fs::exists(path("m/images.txt")));
}

// Outputs' folders are checked before anything is written: a missing --out
// folder leaves no --decisions file behind. A trailing '/' names the folder,
// and a model is written into an existing folder through a staging folder
// inside it (so a mount point works) that does not stay.
TEST_F(SparsifyMaps, OutputFoldersAreCheckedFirstAndAnExistingFolderIsWrittenInPlace) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  const std::string bal = std::string(KEEPLESS_MAPS_DATA) + "/bal_zenslam/problem-49-7776-pre.txt";
  maps_test::Result r = sparsify({"--bal", bal, "--M", "30", "--decisions", path("d.txt"), "--out", path("nodir/o.bal")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("nodir/o.bal") + ":0: cannot write: its folder " + path("nodir") +
                       " does not exist (create it first)\n");
  EXPECT_FALSE(fs::exists(path("d.txt")));

  r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--out", path("new/")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("new/points3D.bin")));
  fs::create_directories(path("existing"));
  r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--out", path("existing")});
  ASSERT_EQ(r.status, 0) << r.err;
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(path("existing"))) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"cameras.bin", "images.bin", "points3D.bin"}));
  EXPECT_EQ(maps_test::read_all(path("existing/points3D.bin")), maps_test::read_all(path("new/points3D.bin")));
  // Review: these three were found only when the model was written, after
  // the decisions file (and, for the folder by a model file's name, after
  // the first file was renamed in): refused before any output now.
  maps_test::write_all(path("file"), "x");
  maps_test::write_all(path("earlier.txt"), "earlier run\n");
  r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--out", path("file"), "--decisions", path("earlier.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("file") + ":0: cannot write model: it is a file, not a folder\n");
  fs::create_directories(path("mixed/images.bin"));
  maps_test::write_all(path("mixed/cameras.bin"), "old");
  r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--out", path("mixed"), "--decisions", path("earlier.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("mixed/images.bin") + ":0: cannot write model: it is there and not a file\n");
  EXPECT_EQ(maps_test::read_all(path("mixed/cameras.bin")), "old");
  fs::create_directories(path("o.bal"));
  r = sparsify({"--bal", bal, "--M", "30", "--out", path("o.bal"), "--decisions", path("earlier.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("o.bal") + ":0: cannot write: it is a folder\n");
  r = sparsify({"--bal", bal, "--M", "30", "--decisions", path("existing")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("existing") + ":0: cannot write: it is a folder\n");
  EXPECT_EQ(maps_test::read_all(path("earlier.txt")), "earlier run\n");
}

// Model inputs are read only from regular files: a FIFO or a device is
// refused at once, never waited on or read without end.
TEST_F(SparsifyMaps, NonRegularModelFilesAreRefusedWithoutBlocking) {
  ASSERT_EQ(::mkfifo(path("fifo.bal").c_str(), 0600), 0);
  maps_test::Result r = sparsify({"--bal", path("fifo.bal")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("fifo.bal") + ":0: not a regular file (refused: it may never end)\n");
  fs::create_symlink("/dev/zero", path("zero.bal"));
  r = sparsify({"--bal", path("zero.bal")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("zero.bal") + ":0: not a regular file (refused: it may never end)\n");
  fs::create_directories(path("m"));
  for (const char* f : {"cameras.bin", "images.bin"}) fs::copy_file(fixture("sparse/") + f, path("m/") + f);
  ASSERT_EQ(::mkfifo(path("m/points3D.bin").c_str(), 0600), 0);
  r = sparsify({"--colmap", path("m")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("m/points3D.bin") + ":0: not a regular file (refused: it may never end)\n");
}

// A camera whose centre or rotation is not finite is refused by its reader
// with the place it is at; a --scale that carries a centre out of range, by
// the run; a huge but finite quaternion is a rotation like any other.
TEST_F(SparsifyMaps, CentresOutOfRangeAreRefusedWhereTheyAre) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  io::ColmapModel m;
  io::ColmapFormat format;
  std::string error;
  ASSERT_TRUE(io::read_colmap_model(fixture("sparse"), &m, &format, &error)) << error;
  io::ColmapModel far = m;
  const double a = 0.39;
  const double q[4] = {std::cos(a), 0, 0, std::sin(a)};
  std::copy(q, q + 4, far.images[0].qvec);
  far.images[0].tvec[0] = far.images[0].tvec[1] = 1.5e308;  // finite, but R^T t is not
  ASSERT_TRUE(io::write_colmap_model(path("far"), far, io::ColmapFormat::kBinary, &error)) << error;
  maps_test::Result r = sparsify({"--colmap", path("far")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err.rfind(path("far/images.bin") + ":", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("image " + std::to_string(far.images[0].id) + "'s camera centre is not finite"),
            std::string::npos) << r.err;

  r = sparsify({"--colmap", fixture("sparse"), "--scale", "1e308", "--mode", "whole"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("centre is not finite in metres (--scale or --sim3 out of range)"), std::string::npos) << r.err;

  io::BalProblem bal;
  ASSERT_TRUE(io::read_bal(maps_test::bal_problem(), &bal, &error)) << error;
  bal.camera_params[0] = 1e308;
  bal.camera_text[0] = "1e308";
  maps_test::write_all(path("spun.bal"), io::format_bal(bal));
  r = sparsify({"--bal", path("spun.bal")});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("camera 0: its rotation or centre is not finite"), std::string::npos) << r.err;

  // Scaled by 1e300, and (review: |q| overflowed to inf, read as the
  // identity) to a largest component of 1.5e308.
  io::ColmapModel huge = m;
  for (std::size_t i = 0; i < huge.images.size(); ++i) {
    double* q = huge.images[i].qvec;
    double largest = 0;
    for (int c = 0; c < 4; ++c) largest = std::max(largest, std::fabs(q[c]));
    for (int c = 0; c < 4; ++c) q[c] *= i % 2 == 0 ? 1e300 : 1.5e308 / largest;
  }
  const io::Keyframes a_kf = io::keyframes_from_colmap(m, io::KeyframeOrder::kName, io::Similarity{});
  const io::Keyframes b_kf = io::keyframes_from_colmap(huge, io::KeyframeOrder::kName, io::Similarity{});
  ASSERT_EQ(a_kf.file.keyframes.size(), b_kf.file.keyframes.size());
  for (std::size_t k = 0; k < a_kf.file.keyframes.size(); ++k) {
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(a_kf.file.keyframes[k].centre[i], b_kf.file.keyframes[k].centre[i], 1e-9);
    for (int i = 0; i < 4; ++i)
      EXPECT_NEAR(a_kf.file.keyframes[k].orientation[i], b_kf.file.keyframes[k].orientation[i], 1e-12);
  }
}

// --max-pair-arcs bounds the whole mode's one window of a model (replay's
// windows of K images hold fewer): refused before deciding, with the count.
TEST_F(SparsifyMaps, MaxPairArcsBoundsTheWholeModesWindow) {
  maps_test::Result r = sparsify({"--colmap", fixture("sparse"), "--mode", "whole", "--max-pair-arcs", "1000"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err.rfind(fixture("sparse") + ":0: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(" pair arcs in the whole mode's window exceed --max-pair-arcs 1000"), std::string::npos) << r.err;
  r = sparsify({"--colmap", fixture("sparse"), "--mode", "whole", "--max-pair-arcs", "50000000"});
  EXPECT_EQ(r.status, 0) << r.err;
}

// --max-memory-mb is estimated before allocating, on every input path:
// "FILE: reason" with the figure needed.
TEST_F(SparsifyMaps, MaxMemoryIsHonouredOnEveryInputPath) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  const std::string bal = std::string(KEEPLESS_MAPS_DATA) + "/bal_zenslam/problem-49-7776-pre.txt";
  struct Case {
    std::vector<std::string> args;
    std::string start;
  };
  maps_test::write_all(path("w.txt"), [] {
    std::string w;
    for (int k = 1; k <= 60; ++k) w += "kf " + std::to_string(k) + " " + std::to_string(k) + " 0 0\n";
    for (int k = 1; k <= 60; ++k) {
      for (int p = 0; p < 400; ++p) w += "obs " + std::to_string(k) + " " + std::to_string(p) + " " +
                                         std::to_string(p % 600) + " " + std::to_string((p * 7) % 400) + "\n";
    }
    return w;
  }());
  {
    std::string values = "1 1 1\n";
    for (int i = 0; i < 500000; ++i) values += "0\n";
    maps_test::write_all(path("short_values.txt"), values);
  }
  const Case cases[] = {
      {{"--colmap", fixture("sparse"), "--max-memory-mb", "10"}, fixture("sparse") + ": reading this model needs about "},
      {{"--colmap", fixture("sparse"), "--max-memory-mb", "50"}, fixture("sparse") + ": deciding needs about "},
      {{"--colmap", fixture("sparse"), "--mode", "whole", "--max-memory-mb", "50"},
       fixture("sparse") + ": deciding needs about "},
      {{"--bal", bal, "--max-memory-mb", "1"}, bal + ": reading this model needs about "},
      // 1 MB of one-digit values: 6 MB by its bytes, 51 MB (49 MiB) with 90 bytes a token.
      {{"--bal", path("short_values.txt"), "--max-memory-mb", "20"},
       path("short_values.txt") + ": reading this model needs about 49 MiB (its 1,000,006 bytes of files, 500,003 numbers and names on 500,001 lines)"},
      // A window file's reader checks record by record (with the whole-mode
      // decision's memory); replay's windows are checked once it is read.
      // (Both fit in 100 MiB: replay needs about 98 MiB.)
      {{"--window", path("w.txt"), "--mode", "whole", "--max-memory-mb", "60"}, path("w.txt") + ":"},
      {{"--window", path("w.txt"), "--mode", "replay", "--K", "60", "--max-memory-mb", "60"},
       path("w.txt") + ": deciding needs about "},
      {{"--window", path("w.txt"), "--max-memory-mb", "60"}, path("w.txt") + ":"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args[0] + " " + c.args[c.args.size() - 1]);
    const maps_test::Result r = sparsify(c.args);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.err.rfind(c.start, 0), 0u) << r.err;
    EXPECT_NE(r.err.find(" MiB"), std::string::npos) << r.err;
    const bool window_reader = r.err.find("memory limit exceeded") != std::string::npos;
    EXPECT_TRUE(window_reader || r.err.find("--max-memory-mb") != std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

// Under an address-space limit below the need, the failure names the model
// and the figure, and points at the limit.
TEST_F(SparsifyMaps, AnAllocationFailureNamesTheFileAndTheLimit) {
#if defined(__SANITIZE_ADDRESS__) || defined(KEEPLESS_TEST_LAUNCHER)
  GTEST_SKIP() << "ulimit -v cannot hold a sanitizer's or an emulator's reservations";
#else
  const maps_test::Result r = run(
      "/bin/sh", {"-c", "ulimit -v 50000 && exec \"$0\" \"$@\"", KEEPLESS_SPARSIFY_BIN, "--colmap", fixture("sparse"),
                  "--mode", "whole"},
      false);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.err.rfind(fixture("sparse") + ": out of memory while ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("MiB needed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ulimit -v"), std::string::npos) << r.err;
#endif
}

}  // namespace
}  // namespace keepless
