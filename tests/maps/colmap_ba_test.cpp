// Checked by a tool nobody here wrote: the shared COLMAP fixture through
// keepless_sparsify (replay, K = 20, M = 30, the fixture's metric scale),
// then COLMAP 3.8 itself. Asserts: the written model loads in COLMAP
// (model_analyzer, binary and text) with the points we kept; every image
// keeps the documented floor (30); decisions are identical across runs;
// `colmap bundle_adjuster` (fixed intrinsics, SOURCES.md's flags) converges
// on the original and the sparsified model; and the sparsified solution's
// camera centres, aligned onto the full solution's (metres, through the
// fixture's similarity), stay within kMaxCentreDeviation of it.
//
// The bound: keepless_maps_bench measured a largest centre deviation of
// 0.061 m (RMS 0.033 m) for exactly this run on the 2-core dev machine
// (docs/development/tests.md); BA is deterministic, so the bound is that
// figure with a 2.5x margin for other BLAS/Ceres builds. Random selection at
// the same count measured 0.064 +- 0.008 m, so this is not a quality claim.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>

#include "keepless/io/colmap_model.hpp"
#include "keepless/io/keyframes.hpp"
#include "keepless/io/trajectory_alignment.hpp"
#include "maps_support.hpp"

namespace keepless {
namespace {

using maps_test::fixture;
using maps_test::json_number;
using maps_test::last_line;
namespace fs = std::filesystem;

constexpr double kMaxCentreDeviation = 0.15;  // metres, see above
constexpr int kFloor = 30;                    // keepless_sparsify's default for COLMAP models

class ColmapCheck : public maps_test::MapsTest {
 protected:
  void SetUp() override {
    maps_test::MapsTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    if (const char* why = std::getenv("KEEPLESS_SKIP_COLMAP")) GTEST_SKIP() << "KEEPLESS_SKIP_COLMAP: " << why;
    colmap_ = KEEPLESS_COLMAP;
    ASSERT_FALSE(colmap_.empty()) << "colmap not found at configure time: install Debian's colmap "
                                     "(scripts/keepless.sh installs it), or set KEEPLESS_SKIP_COLMAP=<reason> "
                                     "where it cannot be installed";
    setenv("QT_QPA_PLATFORM", "offscreen", 1);
  }
  maps_test::Result colmap(const std::vector<std::string>& args) const { return run(colmap_, args, false); }

  // Runs bundle_adjuster; returns the adjusted model.
  io::ColmapModel bundle_adjust(const std::string& in, const std::string& name) {
    const std::string out = path(name);
    fs::create_directories(out);
    const maps_test::Result r = colmap({"bundle_adjuster", "--input_path", in, "--output_path", out,
                                        "--BundleAdjustment.refine_focal_length", "0",
                                        "--BundleAdjustment.refine_principal_point", "0",
                                        "--BundleAdjustment.refine_extra_params", "0"});
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE((r.out + r.err).find("Termination : Convergence"), std::string::npos)
        << "bundle_adjuster did not converge on " << in << ":\n"
        << r.out.substr(r.out.size() > 2000 ? r.out.size() - 2000 : 0);
    io::ColmapModel m;
    io::ColmapFormat format;
    std::string error;
    EXPECT_TRUE(io::read_colmap_model(out, &m, &format, &error)) << error;
    return m;
  }

  std::string colmap_;
};

TEST_F(ColmapCheck, SparsifiedFixtureLoadsAndBundleAdjustsCloseToTheFullSolution) {
  const std::string sim3 = fixture("sim3_to_kitti_gt.txt");
  std::string json;
  for (int run = 0; run < 2; ++run) {
    const std::string n = std::to_string(run);
    const maps_test::Result r = sparsify({"--colmap", fixture("sparse"), "--M", "30", "--K", "20", "--sim3", sim3,
                                          "--out", path("small" + n), "--decisions", path("decisions" + n)});
    ASSERT_EQ(r.status, 0) << r.err;
    json = last_line(r.out);
  }
  ASSERT_EQ(maps_test::read_all(path("decisions0")), maps_test::read_all(path("decisions1")));
  const double kept = json_number(json, "points_kept");
  ASSERT_GT(kept, 0);
  ASSERT_LT(kept, 14195 * 0.25) << json;

  // COLMAP loads it, binary and as text, with exactly the points we kept.
  ASSERT_EQ(sparsify({"--colmap", fixture("sparse"), "--M", "30", "--sim3", sim3, "--out", path("small_txt"),
                      "--out-format", "txt"})
                .status,
            0);
  for (const char* dir : {"small0", "small_txt"}) {
    const maps_test::Result a = colmap({"model_analyzer", "--path", path(dir)});
    ASSERT_EQ(a.status, 0) << a.err;
    const std::string text = a.out + a.err;
    const std::size_t at = text.find("Points: ");  // no std::regex: GCC 12 warns in it under ASan
    ASSERT_NE(at, std::string::npos) << text;
    EXPECT_EQ(std::strtod(text.c_str() + at + 8, nullptr), kept) << dir;
    EXPECT_NE(text.find("Registered images: 51"), std::string::npos) << text;
  }

  // Every image keeps the floor.
  io::ColmapModel small;
  io::ColmapFormat format;
  std::string error;
  ASSERT_TRUE(io::read_colmap_model(path("small0"), &small, &format, &error)) << error;
  const std::vector<std::uint32_t> per_image = io::observations_per_image(small);
  ASSERT_EQ(per_image.size(), 51u);
  EXPECT_GE(*std::min_element(per_image.begin(), per_image.end()), static_cast<std::uint32_t>(kFloor));

  // Bundle adjustment converges on both; centres stay close to the full solution.
  const io::ColmapModel full = bundle_adjust(fixture("sparse"), "full_ba");
  const io::ColmapModel sparse = bundle_adjust(path("small0"), "small_ba");
  io::Similarity sim;
  ASSERT_TRUE(io::read_similarity(sim3, &sim, &error)) << error;
  std::vector<std::array<double, 3>> ref, est;
  io::matched_centres(full, sparse, &ref, &est);
  ASSERT_EQ(ref.size(), 51u);
  for (auto& c : ref) {
    const std::array<double, 3> u = c;
    io::to_metric(sim, u.data(), c.data());
  }
  const io::AlignedDeviation d = io::aligned_deviation(ref, est);
  std::printf("kept %.0f of 14195 points; centre deviation from the full solution: max %.4f m, rms %.4f m\n", kept,
              d.max, d.rms);
  EXPECT_LT(d.max, kMaxCentreDeviation);
}

// --compact drops the 2D points no kept 3D point references: COLMAP loads
// the result (binary and text) with the same points and observations as
// the plain output, and bundle_adjuster converges on it.
TEST_F(ColmapCheck, CompactModelLoadsAndBundleAdjusts) {
  const auto analyse = [&](const std::string& dir, double* points, double* observations) {
    const maps_test::Result a = colmap({"model_analyzer", "--path", dir});
    ASSERT_EQ(a.status, 0) << a.err;
    const std::string text = a.out + a.err;
    const std::size_t p = text.find("Points: "), o = text.find("Observations: ");
    ASSERT_NE(p, std::string::npos) << text;
    ASSERT_NE(o, std::string::npos) << text;
    *points = std::strtod(text.c_str() + p + 8, nullptr);
    *observations = std::strtod(text.c_str() + o + 14, nullptr);
    EXPECT_NE(text.find("Registered images: 51"), std::string::npos) << text;
  };
  ASSERT_EQ(sparsify({"--colmap", fixture("sparse"), "--M", "200", "--out", path("plain")}).status, 0);
  double points = 0, observations = 0;
  analyse(path("plain"), &points, &observations);
  for (const char* format : {"bin", "txt"}) {
    const std::string dir = path(std::string("compact_") + format);
    const maps_test::Result r =
        sparsify({"--colmap", fixture("sparse"), "--M", "200", "--compact", "--out", dir, "--out-format", format});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_GT(json_number(last_line(r.out), "points2D_dropped"), 0);
    double p = 0, o = 0;
    analyse(dir, &p, &o);
    EXPECT_EQ(p, points) << format;
    EXPECT_EQ(o, observations) << format;
  }
  bundle_adjust(path("compact_bin"), "compact_ba");
}

}  // namespace
}  // namespace keepless
