// keepless::io's BAL reader and writer, and the model-to-keyframes bridge:
// the real Ladybug problem round-trips byte for byte; cut or spoilt files
// fail on the right line; centres and duplicate observations as documented.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "keepless/io/bal_problem.hpp"
#include "keepless/io/keyframes.hpp"
#include "maps_support.hpp"

namespace keepless {
namespace {

const std::string kBal = std::string(KEEPLESS_MAPS_DATA) + "/bal_zenslam/problem-49-7776-pre.txt";

TEST(BalFixture, RoundTripsByteForByte) {
  KEEPLESS_MAPS_NEED(maps_test::bal_problem());
  const std::string text = maps_test::read_all(kBal);
  ASSERT_FALSE(text.empty()) << kBal;
  io::BalProblem p;
  std::string error;
  ASSERT_TRUE(io::parse_bal("bal", text, &p, &error)) << error;
  EXPECT_EQ(p.num_cameras, 49u);
  EXPECT_EQ(p.num_points, 7776u);
  EXPECT_EQ(p.observations.size(), 31843u);
  EXPECT_TRUE(io::format_bal(p) == text);
  // Removing points renumbers the rest and drops their observations.
  std::vector<bool> culled(p.num_points, false);
  for (std::uint32_t i = 0; i < p.num_points; i += 2) culled[i] = true;
  const io::BalProblem q = io::remove_points(p, culled);
  EXPECT_EQ(q.num_points, 3888u);
  std::size_t expected = 0;
  for (const auto& o : p.observations) expected += o.point % 2;
  EXPECT_EQ(q.observations.size(), expected);
  io::BalProblem back;
  ASSERT_TRUE(io::parse_bal("q", io::format_bal(q), &back, &error)) << error;
  EXPECT_EQ(back.point_text[0], p.point_text[3]);  // old point 1 is new point 0
}

const char* kSmall =
    "2 2 3\n"
    "0 0     -1.5e+01 2.0e+00\n"
    "1 0     3.0e+00 -4.0e+00\n"
    "1 1     5.0e+00 6.0e+00\n"
    "0\n0\n0\n1\n2\n3\n500\n0\n0\n"
    "0\n0\n1.5707963267948966\n-1\n0\n0\n500\n0\n0\n"
    "1\n2\n3\n4\n5\n6\n";

TEST(BalErrors, CutAtEveryLineOrSpoiltAtEveryValueFailsOnThatLine) {
  io::BalProblem p;
  std::string error;
  ASSERT_TRUE(io::parse_bal("s", kSmall, &p, &error)) << error;
  EXPECT_EQ(io::format_bal(p), kSmall);
  const std::string text = kSmall;
  int line = 1;
  for (std::size_t at = 0; at < text.size(); at = text.find('\n', at) + 1, ++line) {
    // Cut before this line: the counts promise more.
    if (at > 0) {
      EXPECT_FALSE(io::parse_bal("s", text.substr(0, at), &p, &error));
      EXPECT_EQ(error.rfind("s:" + std::to_string(line - 1) + ": truncated", 0), 0u) << error;
    }
    // Every value on this line spoilt.
    const std::size_t end = text.find('\n', at);
    for (std::size_t c = at; c < end; ++c) {
      if (text[c] == ' ' || (c > at && text[c - 1] != ' ')) continue;
      std::string bad = text;
      bad.insert(c, "x");
      EXPECT_FALSE(io::parse_bal("s", bad, &p, &error));
      EXPECT_EQ(error.rfind("s:" + std::to_string(line) + ": bad", 0), 0u) << error;
    }
  }
  EXPECT_FALSE(io::parse_bal("s", text + "7\n", &p, &error));
  EXPECT_EQ(error, "s:29: values after the last point");
  std::string out_of_range = text;
  out_of_range.replace(out_of_range.find("1 1 "), 4, "1 2 ");
  EXPECT_FALSE(io::parse_bal("s", out_of_range, &p, &error));
  EXPECT_EQ(error, "s:4: bad point index '2' (an integer below 2)");
  EXPECT_FALSE(io::parse_bal("s", "3 1000000 4000000000\n", &p, &error));  // cannot allocate first
  EXPECT_EQ(error.rfind("s:1: truncated: the counts need", 0), 0u) << error;
}

// A C-string parse stops at a NUL: "1\07" was camera 1 and "5.0e+00\0junk"
// was 5 (its text, NUL and junk, written back), without a word.
TEST(BalErrors, ANumberFollowedByANulIsRefused) {
  io::BalProblem p;
  std::string error;
  std::string index = kSmall;
  index.insert(index.find("1 1 ") + 1, std::string(1, '\0') + "7");  // line 4's camera index "1" -> "1\07"
  EXPECT_FALSE(io::parse_bal("s", index, &p, &error));
  EXPECT_EQ(error, "s:4: bad camera index '1\\07' (an integer below 2)");
  std::string value = kSmall;
  value.insert(value.find("5.0e+00") + 7, std::string(1, '\0') + "junk");  // line 4's x
  EXPECT_FALSE(io::parse_bal("s", value, &p, &error));
  EXPECT_EQ(error, "s:4: bad observation x '5.0e+00\\0junk' (a finite number)");
}

TEST(BalKeyframes, CentresAreMinusRTransposeT) {
  io::BalProblem p;
  std::string error;
  ASSERT_TRUE(io::parse_bal("s", kSmall, &p, &error)) << error;
  double c[3];
  io::bal_camera_centre(p, 0, c);  // r = 0: C = -t
  EXPECT_DOUBLE_EQ(c[0], -1);
  EXPECT_DOUBLE_EQ(c[1], -2);
  EXPECT_DOUBLE_EQ(c[2], -3);
  io::bal_camera_centre(p, 1, c);  // 90 deg about z, t = (-1, 0, 0): R^T t = (0, 1, 0)
  EXPECT_NEAR(c[0], 0, 1e-12);
  EXPECT_NEAR(c[1], -1, 1e-12);
  EXPECT_NEAR(c[2], 0, 1e-12);
  io::Similarity twice;
  twice.scale = 2;
  const io::Keyframes k = io::keyframes_from_bal(p, io::KeyframeOrder::kFile, twice);
  ASSERT_EQ(k.file.keyframes.size(), 2u);
  EXPECT_NEAR(k.file.keyframes[1].centre[1], -2, 1e-12);
  EXPECT_EQ(k.file.observations[1].size(), 2u);
  EXPECT_EQ(k.duplicates, 0u);
}

// --sim3: a number followed by a NUL byte was read up to the NUL ("4.5\0junk"
// as the scale 4.5), without a word.
TEST(Similarity, ANumberFollowedByANulIsRefused) {
  std::string dir = ::testing::TempDir() + "keepless_sim3_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  const std::string path = dir + "/s.txt";
  maps_test::write_all(path, std::string("4.5") + std::string(1, '\0') + "junk\n1 0 0\n0 1 0\n0 0 1\n0 0 0\n");
  io::Similarity s;
  std::string error;
  EXPECT_FALSE(io::read_similarity(path, &s, &error));
  EXPECT_EQ(error, path + ":1: bad number '4.5\\0junk'");
  std::filesystem::remove_all(dir);
}

TEST(ColmapKeyframes, DuplicatesMergeIntoTheFirstAndOrderIsByNameOrId) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  io::ColmapModel m;
  io::ColmapFormat format;
  std::string error;
  ASSERT_TRUE(io::read_colmap_model(maps_test::fixture("sparse"), &m, &format, &error)) << error;
  const io::Keyframes by_name = io::keyframes_from_colmap(m, io::KeyframeOrder::kName, {});
  EXPECT_EQ(by_name.duplicates, 1154u);  // the count
  std::size_t obs = 0;
  for (const auto& o : by_name.file.observations) obs += o.size();
  EXPECT_EQ(obs + by_name.duplicates, 83883u);
  // Names 000000.png ... 000050.png in order; ids do not follow them.
  std::vector<std::string> names;
  for (const auto& kf : by_name.file.keyframes) {
    for (const auto& im : m.images) {
      if (im.id == kf.id) names.push_back(im.name);
    }
  }
  ASSERT_EQ(names.size(), 51u);
  for (int i = 0; i < 51; ++i) {
    char want[16];
    std::snprintf(want, sizeof want, "%06d.png", i);
    EXPECT_EQ(names[i], want);
  }
  const io::Keyframes by_id = io::keyframes_from_colmap(m, io::KeyframeOrder::kId, {});
  bool ids_follow_names = true;
  for (std::size_t i = 1; i < 51; ++i) {
    EXPECT_LT(by_id.file.keyframes[i - 1].id, by_id.file.keyframes[i].id);
    ids_follow_names &= by_id.file.keyframes[i].id == by_name.file.keyframes[i].id;
  }
  EXPECT_FALSE(ids_follow_names);  // SOURCES.md: ids follow extraction order
  // The first of a duplicated pair is the one kept, at its (x, y).
  for (const auto& im : m.images) {
    std::unordered_map<std::uint64_t, const io::ColmapPoint2D*> first;
    for (const auto& p : im.points2D) {
      if (p.point3D_id != io::kNoPoint3D) first.emplace(p.point3D_id, &p);
    }
    for (std::size_t k = 0; k < by_name.file.keyframes.size(); ++k) {
      if (by_name.file.keyframes[k].id != im.id) continue;
      EXPECT_EQ(by_name.file.observations[k].size(), first.size());
      for (const auto& o : by_name.file.observations[k]) {
        EXPECT_EQ(o.u, first[o.point]->x);
        EXPECT_EQ(o.v, first[o.point]->y);
      }
    }
  }
}

// --sim3 is 13 numbers; a huge file (here 13 numbers, then 64 MiB of NULs)
// was read whole and its tail copied as one "number", beyond any
// --max-memory-mb, before the error.
TEST(Similarity, AHugeFileIsRefusedBeforeItIsRead) {
  std::string dir = ::testing::TempDir() + "keepless_sim3_big_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  const std::string path = dir + "/s.txt";
  maps_test::write_all(path, "2\n1 0 0\n0 1 0\n0 0 1\n0 0 0\n");
  std::filesystem::resize_file(path, std::uintmax_t{64} << 20);
  io::Similarity s;
  std::string error;
  EXPECT_FALSE(io::read_similarity(path, &s, &error));
  EXPECT_EQ(error, path + ":0: 67108864 bytes, more than the 65536 expected");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace keepless
