// The window-file reader and writer, in process.

#include "keepless/core/window_file.hpp"
#include "keepless/platform/window_file_io.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

namespace keepless::core {
namespace {

WindowFile parse_ok(const std::string& text, const WindowFileLimits& limits = {}) {
  WindowFile file;
  std::string error;
  EXPECT_TRUE(parse_window_text("w.txt", text, &file, &error, limits)) << error;
  return file;
}

std::string parse_error(const std::string& text, const WindowFileLimits& limits = {}) {
  WindowFile file;
  std::string error;
  EXPECT_FALSE(parse_window_text("w.txt", text, &file, &error, limits));
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  return error;
}

// "w.txt:LINE: ..." -> LINE, or -1.
long error_line(const std::string& error) {
  const std::string prefix = "w.txt:";
  if (error.compare(0, prefix.size(), prefix) != 0) return -1;
  char* end = nullptr;
  const long line = std::strtol(error.c_str() + prefix.size(), &end, 10);
  if (end == nullptr || std::strncmp(end, ": ", 2) != 0) return -1;
  return line;
}

std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

TEST(WindowFileTest, ParsesRecordsCommentsAndBlankLines) {
  const WindowFile f = parse_ok(
      "# a window\n"
      "\n"
      "kf 7 1.5 -2 3e-1   # trailing comment\n"
      "\tobs 7 100 10.25 20\r\n"
      "kf 9 0 0 0 0.5 0.5 -0.5 0.5\n"
      "obs 9 100 11 21\n"
      "obs 7 18446744073709551615 1 2  # obs of kf 7 after kf 9's line\n"
      "   \n"
      "obs 9 5 0 0");  // no final newline
  ASSERT_EQ(f.keyframes.size(), 2u);
  EXPECT_EQ(f.keyframes[0].id, 7u);
  EXPECT_EQ(f.keyframes[0].centre[0], 1.5);
  EXPECT_EQ(f.keyframes[0].centre[1], -2.0);
  EXPECT_EQ(f.keyframes[0].centre[2], 0.3);
  EXPECT_EQ(f.keyframes[0].orientation[0], 1.0);  // default orientation
  EXPECT_EQ(f.keyframes[0].orientation[3], 0.0);
  EXPECT_EQ(f.keyframes[1].orientation[2], -0.5);
  EXPECT_EQ(f.keyframe_lines[0], 3u);
  EXPECT_EQ(f.keyframe_lines[1], 5u);
  ASSERT_EQ(f.observations[0].size(), 2u);
  EXPECT_EQ(f.observations[0][0].point, 100u);
  EXPECT_EQ(f.observations[0][0].u, 10.25);
  EXPECT_EQ(f.observations[0][1].point, 18446744073709551615ULL);
  ASSERT_EQ(f.observations[1].size(), 2u);
  EXPECT_EQ(f.observations[1][1].point, 5u);  // file order kept
  EXPECT_EQ(f.needs.max_keyframes, 2u);
  EXPECT_EQ(f.needs.max_points, 3u);
  EXPECT_EQ(f.needs.max_observations, 4u);
  EXPECT_EQ(f.needs.max_pair_arcs, 1u);  // point 100 seen twice
}

TEST(WindowFileTest, EmptyInputIsAnEmptyWindow) {
  const WindowFile f = parse_ok("# nothing\n\n");
  EXPECT_TRUE(f.keyframes.empty());
  EXPECT_EQ(f.needs.max_points, 0u);
  EXPECT_EQ(f.needs.max_pair_arcs, 0u);
}

TEST(WindowFileTest, PairArcsAreSumOfNChooseTwo) {
  // Point 1 seen by 4 keyframes (6 pairs), point 2 by 3 (3), point 3 by 1 (0).
  std::string text;
  for (int k = 0; k < 4; ++k) text += "kf " + std::to_string(k) + " 0 0 0\n";
  for (int k = 0; k < 4; ++k) text += "obs " + std::to_string(k) + " 1 0 0\n";
  for (int k = 0; k < 3; ++k) text += "obs " + std::to_string(k) + " 2 0 0\n";
  text += "obs 3 3 0 0\n";
  const WindowFile f = parse_ok(text);
  EXPECT_EQ(f.needs.max_pair_arcs, 9u);
  EXPECT_EQ(f.needs.max_points, 3u);
  EXPECT_EQ(f.needs.max_observations, 8u);
  const Capacities c = compute_needs(f);
  EXPECT_EQ(c.max_pair_arcs, 9u);
  EXPECT_EQ(c.max_points, 3u);
  EXPECT_EQ(c.max_observations, 8u);
  EXPECT_EQ(c.max_keyframes, 4u);
}

TEST(WindowFileTest, ErrorsNameTheOffendingLine) {
  const std::string head = "kf 1 0 0 0\nobs 1 5 1 1\n";  // lines 1-2
  struct Case {
    std::string line3;
    const char* reason;  // a substring of the message
  };
  const Case cases[] = {
      {"obs 2 5 1 1", "unknown keyframe 2"},
      {"kf 1 1 1 1", "duplicate keyframe id 1 (first declared on line 1)"},
      {"obs 1 5 3 3", "duplicate observation of point 5 by keyframe 1 (first on line 2)"},
      {"obs 1 6 nan 1", "non-finite u"},
      {"obs 1 6 1 inf", "non-finite v"},
      {"obs 1 6 1 -infinity", "non-finite v"},
      {"kf 2 0 NAN 0", "non-finite cy"},
      {"obs 1 6 1.0abc 1", "malformed u"},
      {"obs 1 6 0x1p3 1", "malformed u"},
      {"obs 1 6 1e999 1", "out of double range"},
      {"obs 1 6 1e-400 1", "out of double range"},
      {"kf 2 0 0 0 1 0 0 0 junk", "kf needs 4 or 8 values"},
      {"kf 2 0 0", "kf needs 4 or 8 values"},
      {"kf 2 0 0 0 1 0 0", "kf needs 4 or 8 values"},
      {"obs 1 6 1", "obs needs 4 values"},
      {"obs 1 6 1 2 3", "obs needs 4 values"},
      {"obs 1 18446744073709551616 1 1", "point id '18446744073709551616' exceeds 2^64-1"},
      {"kf 99999999999999999999999 0 0 0", "exceeds 2^64-1"},
      {"obs 1 -6 1 1", "negative point id '-6'"},
      {"obs -1 6 1 1", "negative keyframe id '-1'"},
      {"obs 1 +6 1 1", "malformed point id '+6'"},
      {"obs 1 6.0 1 1", "malformed point id"},
      {"obs 1 0x6 1 1", "malformed point id"},
      {"point 1 6 1 1", "unknown record 'point'"},
      {"KF 2 0 0 0", "unknown record 'KF'"},
      {std::string("obs 1 6 1 1\0 junk", 17), "NUL byte"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.line3);
    const std::string error = parse_error(head + c.line3 + "\nkf 50 0 0 0\n");
    EXPECT_EQ(error_line(error), 3) << error;
    EXPECT_NE(error.find(c.reason), std::string::npos) << error;
  }
}

TEST(WindowFileTest, LongTokensAreTruncatedInMessages) {
  const std::string error = parse_error("kf 1 0 0 " + std::string(500, '9') + "x\n");
  EXPECT_EQ(error_line(error), 1);
  EXPECT_LT(error.size(), 120u) << error;
}

TEST(WindowFileTest, ObservationBeforeItsKeyframeIsUnknown) {
  const std::string error = parse_error("kf 1 0 0 0\nobs 2 5 0 0\nkf 2 0 0 0\n");
  EXPECT_EQ(error_line(error), 2);
  EXPECT_NE(error.find("unknown keyframe 2"), std::string::npos);
}

TEST(WindowFileTest, DuplicateObservationAcrossInterleavedLines) {
  const std::string error =
      parse_error("kf 1 0 0 0\nobs 1 5 0 0\nkf 2 0 0 0\nobs 2 5 0 0\nobs 1 5 9 9\n");
  EXPECT_EQ(error_line(error), 5);
  EXPECT_NE(error.find("(first on line 2)"), std::string::npos) << error;
}

TEST(WindowFileTest, EachLimitFailsOnTheLineThatCrossesIt) {
  // Lines: 1-3 kf 1..3; 4-6 point 10 by kf 1,2,3; 7 point 11 by kf 1; 8 point 11 by kf 2.
  const std::string text =
      "kf 1 0 0 0\nkf 2 0 0 0\nkf 3 0 0 0\n"
      "obs 1 10 0 0\nobs 2 10 0 0\nobs 3 10 0 0\n"
      "obs 1 11 0 0\nobs 2 11 0 0\n";
  const WindowFile all = parse_ok(text);
  EXPECT_EQ(all.needs.max_pair_arcs, 4u);  // 3 + 1
  EXPECT_EQ(all.needs.max_observations, 5u);

  // Limits equal to the needs pass.
  WindowFileLimits exact;
  exact.max_keyframes = 3, exact.max_points = 2, exact.max_observations = 5;
  exact.max_pair_arcs = 4;
  parse_ok(text, exact);

  struct Case {
    WindowFileLimits limits;
    long line;
    const char* what;
  };
  Case cases[4] = {{exact, 3, "more than 2 keyframes"},
                   {exact, 7, "more than 1 distinct points"},
                   {exact, 8, "more than 4 observations"},
                   {exact, 6, "more than 2 pair arcs"}};  // kf 3's view of point 10 adds 2
  cases[0].limits.max_keyframes = 2;
  cases[1].limits.max_points = 1;
  cases[2].limits.max_observations = 4;
  cases[3].limits.max_pair_arcs = 2;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string error = parse_error(text, c.limits);
    EXPECT_EQ(error_line(error), c.line) << error;
    EXPECT_NE(error.find("capacity exceeded"), std::string::npos) << error;
    EXPECT_NE(error.find(c.what), std::string::npos) << error;
  }
}

TEST(WindowFileTest, UnreadableFileIsLineZero) {
  WindowFile f;
  std::string error;
  EXPECT_FALSE(platform::read_window_file("/nonexistent/keepless/w.txt", &f, &error));
  EXPECT_EQ(error.rfind("/nonexistent/keepless/w.txt:0: ", 0), 0u) << error;
  EXPECT_FALSE(platform::read_window_file("/", &f, &error));  // a directory
  EXPECT_EQ(error.rfind("/:0: ", 0), 0u) << error;
}

TEST(WindowFileTest, WriteThenReadIsBitIdentical) {
  WindowFile f;
  std::uint64_t state = 12345;
  const auto next = [&state] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return state;
  };
  const auto any_finite = [&] {
    for (;;) {
      const std::uint64_t b = next();
      double x;
      std::memcpy(&x, &b, sizeof x);
      if (std::isfinite(x)) return x;
    }
  };
  for (std::uint64_t k = 0; k < 5; ++k) {
    Keyframe kf;
    kf.id = k == 0 ? 18446744073709551615ULL : k * 1000;
    for (double& c : kf.centre) c = any_finite();
    if (k % 2 == 1) {  // any bits, then made unit (the reader refuses others)
      double n2 = 0;
      for (double& q : kf.orientation) {
        int exponent = 0;
        q = std::frexp(any_finite(), &exponent);  // mantissa bits, magnitude in [0.5, 1)
        n2 += q * q;
      }
      for (double& q : kf.orientation) q /= std::sqrt(n2);
      kf.orientation[1] = -kf.orientation[1];
    }
    f.keyframes.push_back(kf);
    f.observations.emplace_back();
    for (std::uint64_t i = 0; i < 20; ++i) {
      f.observations.back().push_back({next() % 50, any_finite(), k == 2 ? -0.0 : 0.1 * i});
    }
    // A point seen twice by one keyframe would be rejected: keep ids unique.
    auto& obs = f.observations.back();
    for (std::size_t i = 0; i < obs.size(); ++i) obs[i].point = obs[i].point * 100 + i;
  }
  const std::string text = format_window_file(f);
  const WindowFile g = parse_ok(text);
  ASSERT_EQ(g.keyframes.size(), f.keyframes.size());
  for (std::size_t k = 0; k < f.keyframes.size(); ++k) {
    EXPECT_EQ(g.keyframes[k].id, f.keyframes[k].id);
    for (int i = 0; i < 3; ++i)
      EXPECT_EQ(bits(g.keyframes[k].centre[i]), bits(f.keyframes[k].centre[i]));
    for (int i = 0; i < 4; ++i) {
      EXPECT_EQ(bits(g.keyframes[k].orientation[i]), bits(f.keyframes[k].orientation[i]));
    }
    ASSERT_EQ(g.observations[k].size(), f.observations[k].size());
    for (std::size_t i = 0; i < f.observations[k].size(); ++i) {
      EXPECT_EQ(g.observations[k][i].point, f.observations[k][i].point);
      EXPECT_EQ(bits(g.observations[k][i].u), bits(f.observations[k][i].u));
      EXPECT_EQ(bits(g.observations[k][i].v), bits(f.observations[k][i].v));
    }
  }
  const Capacities c = compute_needs(f);
  EXPECT_EQ(g.needs.max_points, c.max_points);
  EXPECT_EQ(g.needs.max_pair_arcs, c.max_pair_arcs);

  // The file writer produces the same bytes as the formatter.
  const std::string path = ::testing::TempDir() + "keepless_window_file_test.txt";
  std::string error;
  ASSERT_TRUE(platform::write_window_file(path, f, &error)) << error;
  WindowFile h;
  ASSERT_TRUE(platform::read_window_file(path, &h, &error)) << error;
  EXPECT_EQ(format_window_file(h), text);
  std::remove(path.c_str());
}

// The writer goes through a temporary name: a write that cannot land (here
// PATH is a folder) leaves PATH as it was and no temporary behind.
TEST(WindowFileTest, AFailedWriteLeavesNoPartialFile) {
  const std::string dir = ::testing::TempDir() + "keepless_window_file_dir";
  std::filesystem::create_directories(dir);
  WindowFile f;
  Keyframe kf;
  kf.id = 1;
  f.keyframes.push_back(kf);
  f.observations.push_back({{7, 1, 2}});
  std::string error;
  EXPECT_FALSE(platform::write_window_file(dir, f, &error));
  EXPECT_EQ(error.rfind(dir + ": write failed: ", 0), 0u) << error;
  EXPECT_TRUE(std::filesystem::is_directory(dir));
  for (const auto& e : std::filesystem::directory_iterator(::testing::TempDir())) {
    EXPECT_EQ(e.path().filename().string().find("keepless_window_file_dir.tmp-"), std::string::npos) << e.path();
  }
  std::filesystem::remove_all(dir);
}

TEST(WindowFileTest, IdentityOrientationIsOmitted) {
  WindowFile f;
  Keyframe kf;
  kf.id = 3;
  kf.centre[0] = 0.5;
  f.keyframes.push_back(kf);
  f.observations.push_back({{42, 1.25, 2}});
  EXPECT_EQ(format_window_file(f), "kf 3 0.5 0 0\nobs 3 42 1.25 2\n");
}

TEST(WindowFileTest, ParseUint64) {
  std::uint64_t v = 0;
  EXPECT_TRUE(parse_uint64("0", &v));
  EXPECT_EQ(v, 0u);
  EXPECT_TRUE(parse_uint64("00042", &v));
  EXPECT_EQ(v, 42u);
  EXPECT_TRUE(parse_uint64("18446744073709551615", &v));
  EXPECT_EQ(v, 18446744073709551615ULL);
  for (const char* bad :
       {"18446744073709551616", "-1", "-0", "+1", " 1", "1 ", "", "1e3", "0x10", "1.0", "abc"}) {
    EXPECT_FALSE(parse_uint64(bad, &v)) << bad;
  }
  EXPECT_FALSE(parse_uint64(nullptr, &v));
}

TEST(WindowFileTest, ParseFiniteDouble) {
  double x = 0;
  EXPECT_TRUE(parse_finite_double("1.5", &x));
  EXPECT_EQ(x, 1.5);
  EXPECT_TRUE(parse_finite_double("-2e3", &x));
  EXPECT_EQ(x, -2000.0);
  EXPECT_TRUE(parse_finite_double(".5", &x));
  EXPECT_TRUE(parse_finite_double("5.", &x));
  EXPECT_TRUE(parse_finite_double("1.7976931348623157e308", &x));
  for (const char* bad : {"nan", "NaN", "inf", "-inf", "infinity", "1e309", "-1e309", "1e-400",
                          "0x1p3", "1.0abc", "", " 1", "1 ", "1,5", "--1", "e5"}) {
    EXPECT_FALSE(parse_finite_double(bad, &x)) << bad;
  }
}

TEST(WindowFileTest, ParseBox) {
  int w = 0, h = 0;
  EXPECT_TRUE(parse_box("64x48", &w, &h));
  EXPECT_EQ(w, 64);
  EXPECT_EQ(h, 48);
  EXPECT_TRUE(parse_box("0x0", &w, &h));
  EXPECT_EQ(w, 0);
  EXPECT_TRUE(parse_box("2147483647x1", &w, &h));
  EXPECT_EQ(w, 2147483647);
  for (const char* bad : {"64", "64x", "x48", "64x48x2", "-64x48", "64x-48", "64X48", "64 x48",
                          "2147483648x1", "6.4x48", ""}) {
    EXPECT_FALSE(parse_box(bad, &w, &h)) << bad;
  }
}

// Chunk boundaries anywhere give the same window as one piece.
TEST(WindowFileTest, StreamingInChunksGivesTheSameWindow) {
  const std::string text =
      "# w\nkf 1 0.5 0 0\nobs 1 7 1.25 2\n\nkf 2 1 0 0 1 0 0 0 # c\nobs 2 7 3 4\nobs 1 8 5 6";  // no final newline
  const std::string whole = format_window_file(parse_ok(text));
  for (std::size_t step : {1u, 2u, 3u, 7u, 64u}) {
    WindowFileParser parser("w.txt");
    for (std::size_t i = 0; i < text.size(); i += step) {
      ASSERT_TRUE(parser.feed(text.data() + i, std::min(step, text.size() - i))) << parser.error();
    }
    WindowFile f;
    ASSERT_TRUE(parser.finish(&f)) << parser.error();
    EXPECT_EQ(format_window_file(f), whole) << "chunks of " << step;
    EXPECT_EQ(f.needs.max_observations, 3u);
  }
}

// Found by window_file_fuzzer: a NUL early in a line that is also too long
// was "NUL byte" when the line came in pieces and "line longer" when whole.
TEST(WindowFileTest, ChunkingDoesNotChangeTheVerdictOnABadLine) {
  WindowFileLimits limits;
  limits.max_line_bytes = 64;
  std::string line = "kf 1 " + std::string(100, ' ');
  line[20] = '\0';
  const std::string whole = parse_error(line + "\n", limits);
  WindowFileParser parser("w.txt", limits);
  EXPECT_TRUE(parser.feed(line.data(), 10));
  EXPECT_FALSE(parser.feed(line.data() + 10, line.size() - 10));
  EXPECT_EQ(parser.error(), whole);
  EXPECT_EQ(whole, "w.txt:1: NUL byte in line");
}

// Issue 15, defect 5: memory followed the file, not the records. A line
// without end is refused at max_line_bytes, a NUL at once, whatever follows.
TEST(WindowFileTest, MemoryIsBoundedByTheLineNotTheInput) {
  WindowFileParser parser("w.txt");
  const std::string chunk(1 << 16, '1');
  bool ok = true;
  int fed = 0;
  for (; fed < 1000 && ok; ++fed) ok = parser.feed(chunk.data(), chunk.size());
  EXPECT_FALSE(ok);
  EXPECT_EQ(fed, 1) << "refused in the first chunk";
  EXPECT_EQ(parser.error(), "w.txt:1: line longer than 4096 bytes");
  EXPECT_LT(parser.bytes(), 8192.0);
  WindowFileParser nul("w.txt");
  const std::string zeros(100, '\0');
  EXPECT_FALSE(nul.feed(zeros.data(), zeros.size()));
  EXPECT_EQ(nul.error(), "w.txt:1: NUL byte in line");
}

TEST(WindowFileTest, MemoryLimitFailsOnTheLineThatCrossesIt) {
  WindowFileLimits limits;
  limits.solve_bytes = [](const Capacities& c) { return 1000.0 * c.max_observations; };
  limits.max_bytes = 3500;  // the parser's own bytes push the third observation over
  const std::string error = parse_error("kf 1 0 0 0\nobs 1 1 0 0\nobs 1 2 0 0\nobs 1 3 0 0\n", limits);
  EXPECT_EQ(error_line(error), 4) << error;
  EXPECT_NE(error.find("memory limit exceeded"), std::string::npos) << error;
  limits.max_bytes = 0;  // unchecked
  parse_ok("kf 1 0 0 0\nobs 1 1 0 0\nobs 1 2 0 0\nobs 1 3 0 0\n", limits);
}

// Issue 15, defect 7: the identity test with == dropped the sign of -0.
TEST(WindowFileTest, NegativeZeroOrientationRoundTrips) {
  WindowFile f;
  Keyframe kf;
  kf.id = 1;
  kf.orientation[0] = 1.0;
  kf.orientation[2] = -0.0;
  f.keyframes.push_back(kf);
  f.observations.emplace_back();
  const WindowFile g = parse_ok(format_window_file(f));
  ASSERT_EQ(g.keyframes.size(), 1u);
  EXPECT_EQ(bits(g.keyframes[0].orientation[2]), bits(-0.0));
  EXPECT_EQ(format_window_file(g), format_window_file(f));
}

// Issue 15, defect 7: 4e-320 is a finite (subnormal) double.
TEST(WindowFileTest, SubnormalsAreAccepted) {
  const WindowFile f = parse_ok("kf 1 4e-320 0 0\nobs 1 2 1e-310 0\n");
  EXPECT_EQ(f.keyframes[0].centre[0], 4e-320);
  EXPECT_EQ(f.observations[0][0].u, 1e-310);
  EXPECT_NE(parse_error("kf 1 1e309 0 0\n").find("out of double range"), std::string::npos);
}

TEST(WindowFileTest, ZeroOrNonUnitQuaternionIsRefused) {
  EXPECT_NE(parse_error("kf 1 0 0 0 0 0 0 0\n").find("not a unit quaternion"), std::string::npos);
  EXPECT_NE(parse_error("kf 1 0 0 0 1 1 0 0\n").find("not a unit quaternion"), std::string::npos);
  parse_ok("kf 1 0 0 0 0.70710678 0 0.70710678 0\n");
}

// A file beyond 2 GiB is opened and read like any other (64-bit offsets on
// 32-bit targets too: without them open() fails with EOVERFLOW). Sparse: a
// valid keyframe, then a hole of zeros (no disk blocks) up to 2 GiB + 4 KiB;
// reading stops at the first chunk of zeros, which is not a window line.
TEST(WindowFileTest, FilesBeyondTwoGigabytesAreRead) {
  static_assert(sizeof(off_t) == 8, "64-bit file offsets");
  char dir[] = "/tmp/keepless_wf_XXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  const std::string path = std::string(dir) + "/large.txt";
  const std::string head = "kf 1 0 0 0\nobs 1 7 10 20\n";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(std::fwrite(head.data(), 1, head.size(), f), head.size());
  ASSERT_EQ(std::fclose(f), 0);
  const off_t size = (off_t{1} << 31) + 4096;
  ASSERT_EQ(::truncate(path.c_str(), size), 0) << std::strerror(errno);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0) << std::strerror(errno);
  EXPECT_EQ(st.st_size, size);
  WindowFile w;
  std::string error;
  EXPECT_FALSE(platform::read_window_file(path, &w, &error));
  EXPECT_EQ(error.rfind(path + ":3: ", 0), 0u) << error;  // the first line of zeros, not line 0 (open/stat)
  ::unlink(path.c_str());
  ::rmdir(dir);
}

TEST(WindowFileTest, NonRegularFilesAreRefusedWithoutBlocking) {
  char dir[] = "/tmp/keepless_wf_XXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  const std::string fifo = std::string(dir) + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  WindowFile f;
  std::string error;
  EXPECT_FALSE(platform::read_window_file(fifo, &f, &error));  // no writer: must not block
  EXPECT_EQ(error.rfind(fifo + ":0: not a regular file", 0), 0u) << error;
  EXPECT_FALSE(platform::read_window_file("/dev/zero", &f, &error));
  EXPECT_EQ(error.rfind("/dev/zero:0: not a regular file", 0), 0u) << error;
  ::unlink(fifo.c_str());
  ::rmdir(dir);
}

// Review: fed after finish() the parser wrote through its old keyframe
// index into the moved-out file (a crash), and a second finish() returned
// an empty file with the first one's needs. Both are refused now.
TEST(WindowFileTest, AParserRefusesInputAfterFinish) {
  WindowFileParser p("w.txt");
  const std::string text = "kf 1 0 0 0\nobs 1 5 1 2\n";
  ASSERT_TRUE(p.feed(text.data(), text.size()));
  WindowFile first;
  ASSERT_TRUE(p.finish(&first));
  ASSERT_EQ(first.observations.size(), 1u);
  const std::string more = "obs 1 6 3 4\n";
  EXPECT_FALSE(p.feed(more.data(), more.size()));
  EXPECT_NE(p.error().find("after the end"), std::string::npos) << p.error();
  EXPECT_FALSE(p.feed_line("kf 2 0 0 0", 10));
  WindowFile second;
  EXPECT_FALSE(p.finish(&second));
  EXPECT_TRUE(second.keyframes.empty());
  WindowFileParser q("w.txt");
  ASSERT_TRUE(q.finish(&second));
  EXPECT_FALSE(q.finish(&second)) << "finish() twice";
}

// Review: a WindowFile built in code was written whatever it held, and the
// reader then refused the file (or, with fewer observation lists than
// keyframes, formatting it read past the end). The writer refuses what
// would not read back, and writes nothing.
TEST(WindowFileTest, TheWriterRefusesWhatWouldNotReadBack) {
  const std::string path = ::testing::TempDir() + "keepless_window_file_refused.txt";
  std::remove(path.c_str());
  const auto base = [] {
    WindowFile f;
    f.keyframes.resize(2);
    f.keyframes[0].id = 3;
    f.keyframes[1].id = 4;
    f.observations.resize(2);
    f.observations[0].push_back({42, 1.25, 2.0, 0.0});
    return f;
  };
  ASSERT_EQ(window_file_problem(base()), "");
  std::vector<std::pair<WindowFile, const char*>> cases(6, {base(), ""});
  cases[0].first.keyframes[0].centre[1] = std::nan("");
  cases[0].second = "non-finite";
  cases[1].first.observations[0][0].u = INFINITY;
  cases[1].second = "non-finite keypoint";
  cases[2].first.keyframes[0].orientation[0] = 2.0;
  cases[2].second = "not a unit quaternion";
  cases[3].first.observations[0].push_back({42, 5, 6, 0});
  cases[3].second = "duplicate observation";
  cases[4].first.keyframes[1].id = 3;
  cases[4].second = "duplicate keyframe id";
  cases[5].first.observations.resize(1);
  cases[5].second = "2 keyframes but 1 observation lists";
  for (const auto& [file, says] : cases) {
    EXPECT_NE(window_file_problem(file).find(says), std::string::npos) << says << ": " << window_file_problem(file);
    std::string error;
    EXPECT_FALSE(platform::write_window_file(path, file, &error)) << says;
    EXPECT_NE(error.find(says), std::string::npos) << error;
    EXPECT_FALSE(std::filesystem::exists(path)) << says << ": nothing written";
  }
  EXPECT_EQ(format_window_file(cases[5].first), "kf 3 0 0 0\nobs 3 42 1.25 2\nkf 4 0 0 0\n") << "no read past the end";
  std::string error;
  ASSERT_TRUE(platform::write_window_file(path, base(), &error)) << error;
  WindowFile back;
  ASSERT_TRUE(platform::read_window_file(path, &back, &error)) << error;
  EXPECT_EQ(back.keyframes.size(), 2u);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace keepless::core
