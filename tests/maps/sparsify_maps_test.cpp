// keepless_sparsify on maps: replay equals a naive replay built here from
// Sparsifier::run on each window; the floor; and the CLI contract on the
// real fixtures (deterministic decisions, models written in the input's
// format, bad models: exit 2, one FILE:OFFSET line, nothing written).

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <set>
#include <unordered_set>

#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "keepless/io/bal_problem.hpp"
#include "keepless/io/colmap_model.hpp"
#include "keepless/io/keyframes.hpp"
#include "keepless/platform/window_file_io.hpp"
#include "maps_support.hpp"
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

TEST_F(SparsifyMaps, BalAndWindowInputsAreWrittenBackInTheirFormat) {
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
  EXPECT_EQ(r.err.rfind(path("nothing") + "/cameras.txt:0: cannot read", 0), 0u) << r.err;
  maps_test::write_all(path("sim3.txt"), "1 0 0\n");
  r = sparsify({"--colmap", fixture("sparse"), "--sim3", path("sim3.txt")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("sim3.txt") + ":2: expected 13 numbers (s, R row-major, t), got 3\n");
  // Text into a directory holding a binary model: refused, nothing changed.
  fs::create_directories(path("has_bin"));
  maps_test::write_all(path("has_bin/images.bin"), "old");
  r = sparsify({"--colmap", fixture("sparse"), "--out", path("has_bin"), "--out-format", "txt"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, path("has_bin") + "/images.bin:0: a model in the other format is already there; write to another "
                                     "directory\n");
  EXPECT_FALSE(fs::exists(path("has_bin/images.txt")));
  r = sparsify({"--bal", path("x"), "--order", "name"});
  EXPECT_EQ(r.status, 2);
  r = sparsify({"--colmap", fixture("sparse"), "--mode", "all"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("; see 'keepless_sparsify --help'"), std::string::npos);
  r = sparsify({"--colmap", fixture("sparse"), "--bal", path("x")});
  EXPECT_EQ(r.status, 2);
}

}  // namespace
}  // namespace keepless
