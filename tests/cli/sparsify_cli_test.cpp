// keepless_sparsify (and keepless_make_window) run as child processes on files
// written to a temp dir: the exit status, the one-line stderr contract, the
// decisions file and the JSON summary, checked against hand-computed values
// and against the independent reference implementation.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <set>
#include <string>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "keepless/core/window_file.hpp"
#include "child_run.hpp"
#include "keepless/platform/window_file_io.hpp"
#include "reference_policies.hpp"
#include "reference_sparsifier.hpp"


namespace keepless {
namespace {

namespace fs = std::filesystem;

using Result = test::ChildResult;
using test::read_all;

std::size_t count_lines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

// The last line, without its newline.
std::string last_line(std::string s) {
  if (!s.empty() && s.back() == '\n') s.pop_back();
  const std::size_t nl = s.rfind('\n');
  return nl == std::string::npos ? s : s.substr(nl + 1);
}

// The number after "key": in a one-line JSON object; fails the test if absent.
double json_number(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const std::size_t at = json.find(needle);
  EXPECT_NE(at, std::string::npos) << key << " missing in " << json;
  if (at == std::string::npos) return -1;
  return std::strtod(json.c_str() + at + needle.size(), nullptr);
}

std::int64_t json_int(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const std::size_t at = json.find(needle);
  EXPECT_NE(at, std::string::npos) << key << " missing in " << json;
  if (at == std::string::npos) return -1;
  return std::strtoll(json.c_str() + at + needle.size(), nullptr, 10);
}

class SparsifyCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = ::testing::TempDir() + "keepless_cli_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string path(const std::string& name) const { return dir_ + "/" + name; }

  std::string write(const std::string& name, const std::string& content) const {
    const std::string p = path(name);
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }

  Result run(const char* binary, const std::vector<std::string>& args) const {
    return test::run_child(binary, args, path("stdout.txt"), path("stderr.txt"));
  }

  Result sparsify(const std::vector<std::string>& args) const {
    return run(KEEPLESS_SPARSIFY_BIN, args);
  }

  // Bad input: exit 2, exactly one stderr line "WINDOW:LINE: ..." containing
  // `reason`, no stdout, no decisions file and no temp file left.
  void expect_input_error(const std::string& text, long line, const std::string& reason,
                          std::vector<std::string> extra = {}) const {
    const std::string window = write("bad.txt", text);
    const std::string out = path("decisions.txt");
    std::vector<std::string> args{"--window", window, "--decisions", out};
    args.insert(args.end(), extra.begin(), extra.end());
    expect_error_result(sparsify(args), window, line, reason);
  }

  void expect_error_result(const Result& r, const std::string& window, long line,
                           const std::string& reason) const {
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    const std::string prefix = window + ":" + std::to_string(line) + ": ";
    EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << "expected prefix '" << prefix << "', got " << r.err;
    EXPECT_NE(r.err.find(reason), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_FALSE(fs::exists(path("decisions.txt")));
    EXPECT_EQ(temporaries(), 0u);
  }

  // Files left under a temporary name (NAME.tmp-PID) in the test's folder.
  std::size_t temporaries() const {
    std::size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir_)) {
      n += e.path().filename().string().find(".tmp") != std::string::npos;
    }
    return n;
  }

  std::string dir_;
};

// A valid 2-keyframe window, lines 1-4, for tests that append a bad line 5.
const char* const kGoodHead =
    "# two keyframes\n"
    "kf 10 0 0 0\n"
    "kf 20 1 0 0 1 0 0 0\n"
    "obs 10 1 100 100\n";

TEST_F(SparsifyCliTest, UnreadableWindowFileIsLineZero) {
  const std::string missing = path("no_such_file.txt");
  expect_error_result(sparsify({"--window", missing, "--decisions", path("decisions.txt")}),
                      missing, 0, "cannot open");
  // A directory is refused by name, not read.
  expect_error_result(sparsify({"--window", dir_, "--decisions", path("decisions.txt")}), dir_, 0,
                      "is a directory, not a file");
}

TEST_F(SparsifyCliTest, UnknownKeyframe) {
  expect_input_error(std::string(kGoodHead) + "obs 30 1 5 5\n", 5, "unknown keyframe 30");
  // Declared only after the observation: still unknown on the obs line.
  expect_input_error(std::string(kGoodHead) + "obs 30 1 5 5\nkf 30 0 0 0\n", 5,
                     "unknown keyframe 30");
}

TEST_F(SparsifyCliTest, DuplicateKeyframeId) {
  expect_input_error(std::string(kGoodHead) + "kf 10 5 5 5\n", 5,
                     "duplicate keyframe id 10 (first declared on line 2)");
}

TEST_F(SparsifyCliTest, DuplicateObservation) {
  // The repeat comes after another keyframe's records.
  expect_input_error(std::string(kGoodHead) + "obs 20 1 7 7\nobs 10 1 101 101 # again\n", 6,
                     "duplicate observation of point 1 by keyframe 10 (first on line 4)");
}

TEST_F(SparsifyCliTest, NonFiniteNumbers) {
  const std::pair<const char*, const char*> cases[] = {
      {"obs 20 2 nan 5", "non-finite u 'nan'"},
      {"obs 20 2 5 inf", "non-finite v 'inf'"},
      {"obs 20 2 -inf 5", "non-finite u '-inf'"},
      {"kf 30 0 nan 0", "non-finite cy 'nan'"},
      {"kf 30 0 0 0 1 0 0 infinity", "non-finite qz 'infinity'"},
      {"obs 20 2 1e999 5", "u '1e999' out of double range"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.first);
    expect_input_error(std::string(kGoodHead) + c.first + "\n", 5, c.second);
  }
}

TEST_F(SparsifyCliTest, MalformedNumbersAndFieldCounts) {
  const std::pair<const char*, const char*> cases[] = {
      {"obs 20 2 1.5abc 5", "malformed u"},
      {"obs 20 2 5 7,5", "malformed v"},
      {"kf 30 0 0 0x10", "malformed cz"},
      {"obs 20 2 5", "obs needs 4 values"},
      {"obs 20 2 5 5 5", "obs needs 4 values"},
      {"kf 30 0 0", "kf needs 4 or 8 values"},
      {"kf 30 0 0 0 1 0 0", "kf needs 4 or 8 values"},
      {"kf 30 0 0 0 1 0 0 0 0", "kf needs 4 or 8 values"},
      {"obs 20 2.0 5 5", "malformed point id"},
      {"obs 20 abc 5 5", "malformed point id"},
      {"frame 30 0 0 0", "unknown record 'frame'"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.first);
    expect_input_error(std::string(kGoodHead) + c.first + "  # comment\n", 5, c.second);
  }
}

TEST_F(SparsifyCliTest, IdOverflowAndNegativeIds) {
  const std::pair<const char*, const char*> cases[] = {
      {"obs 20 18446744073709551616 5 5", "exceeds 2^64-1"},
      {"kf 18446744073709551616 0 0 0", "exceeds 2^64-1"},
      {"obs 20 -3 5 5", "negative point id"},
      {"obs -20 3 5 5", "negative keyframe id"},
      {"kf -1 0 0 0", "negative keyframe id"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.first);
    expect_input_error(std::string(kGoodHead) + c.first + "\n", 5, c.second);
  }
  // The largest id is fine.
  const std::string ok =
      write("ok.txt", std::string(kGoodHead) + "obs 20 18446744073709551615 5 5\n");
  EXPECT_EQ(sparsify({"--window", ok}).status, 0);
}

TEST_F(SparsifyCliTest, CapacityExceededOnTheLineThatCrossesIt) {
  // Lines 1-3: kf; 4-6: point 7 by all three (3 pair arcs); 7-8: point 8 by two (1).
  const std::string text =
      "kf 1 0 0 0\nkf 2 1 0 0\nkf 3 2 0 0\n"
      "obs 1 7 10 10\nobs 2 7 10 10\nobs 3 7 10 10\n"
      "obs 1 8 200 200\nobs 2 8 200 200\n";
  expect_input_error(text, 3, "capacity exceeded", {"--max-keyframes", "2"});
  expect_input_error(text, 7, "capacity exceeded", {"--max-points", "1"});
  expect_input_error(text, 8, "capacity exceeded", {"--max-observations", "4"});
  expect_input_error(text, 6, "capacity exceeded", {"--max-pair-arcs", "2"});
  expect_input_error(text, 8, "capacity exceeded", {"--max-pair-arcs", "3"});
  // Exactly at the limits: accepted.
  const std::string ok = write("ok.txt", text);
  const Result r = sparsify({"--window", ok, "--max-keyframes", "3", "--max-points", "2",
                             "--max-observations", "5", "--max-pair-arcs", "4"});
  EXPECT_EQ(r.status, 0) << r.err;
}

// One window prices a point's views up to core::kMaxPointViews (c_m(2) would
// pass the solver's cost bound): a point seen by more is refused by name
// before any network is built (the boundary values: ConnectivityCost tests).
TEST_F(SparsifyCliTest, APointSeenByMoreImagesThanOneWindowCanPriceIsRefusedByName) {
  const std::uint32_t k = core::kMaxPointViews + 1;
  std::string text;
  for (std::uint32_t i = 1; i <= k; ++i) text += "kf " + std::to_string(i) + " " + std::to_string(i) + " 0 0\n";
  for (std::uint32_t i = 1; i <= k; ++i) text += "obs " + std::to_string(i) + " 7 10 10\n";
  text += "obs 1 8 200 200\nobs 2 8 200 200\n";
  const std::string path = write("views.txt", text);
  // The whole mode's one window, and replay windows of --K 2201 images.
  for (const std::vector<std::string>& mode : {std::vector<std::string>{}, {"--mode", "replay", "--K", "2201"}}) {
    std::vector<std::string> args = {"--window", path};
    args.insert(args.end(), mode.begin(), mode.end());
    const Result r = sparsify(args);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find(path + ":0: point 7 is seen by 2201 images, above the 2200"), std::string::npos) << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  }
}

TEST_F(SparsifyCliTest, FlagErrorsPrintOneUsageLine) {
  const std::string window = write("w.txt", kGoodHead);
  const std::string out = path("decisions.txt");
  const std::vector<std::vector<std::string>> cases = {
      {},
      {"--decisions", out},
      {"--window"},
      {"--window", window, "--M"},
      {"--window", window, "--bogus", "1"},
      {"--window", window, "--M", "0"},
      {"--window", window, "--M", "-5"},
      {"--window", window, "--M", "1.5"},
      {"--window", window, "--M", "99999999999999999999"},
      {"--window", window, "--M", "2147483648"},  // above the solver's int32 (issue 15: was exit 1)
      {"--window", window, "--theta", "1.5"},
      {"--window", window, "--theta", "-0.1"},
      {"--window", window, "--theta", "nan"},
      {"--window", window, "--theta", "0.5x"},
      {"--window", window, "--box", "64"},
      {"--window", window, "--box", "64x"},
      {"--window", window, "--box", "ax48"},
      {"--window", window, "--box", "-64x48"},
      {"--window", window, "--max-keyframes", "0"},
      {"--window", window, "--max-points", "4294967296"},
      {"--window", window, "--max-observations", "many"},
      {"--window", window, "--max-pair-arcs", ""},
      {"--window", "", "--decisions", out},
      {"--window", window, "--scope", "all"},
      {"--window", window, "--floor", "-1"},
      {"--window", window, "--floor", "4294967296"},
      {"--window", window, "--cost", "Paper"},
      {"--window", window, "--image", "0x480"},
      {"--window", window, "--M", "5", "--keep-points", "10"},
      {"--window", window, "--keep-fraction", "0.3", "--M", "5"},
      {"--window", window, "--keep-fraction", "1.5"},
      {"--window", window, "--keep-fraction", "nan"},
      {"--window", window, "--keep-points", "-1"},
      {"--window", window, "--keep-observations", "x"},
      {"--window", window, "--keep-points", "3", "--keep-fraction", "0.3"},
      {"--window", window, "--keep-points", "3", "--track-share", "1.5"},
      {"--window", window, "--keep-points", "3", "--track-share", "nan"},
      {"--window", window, "--track-share", "0.5"},  // a share of a count: needs one
      {"--window", window, "--keep-observations", "20", "--track-share", "0.5"},
      {"--window", window, "--bal", window},  // two inputs
  };
  for (const auto& args : cases) {
    std::string shown;
    for (const auto& a : args) shown += a + " ";
    SCOPED_TRACE(shown);
    const Result r = sparsify(args);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("; see 'keepless_sparsify --help'"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_FALSE(fs::exists(out));
    EXPECT_EQ(temporaries(), 0u);
  }
  const Result help = sparsify({"--help"});
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.out.find("usage: keepless_sparsify"), std::string::npos);
}

TEST_F(SparsifyCliTest, FailureKeepsAnEarlierDecisionsFileUntouched) {
  const std::string out = write("decisions.txt", "earlier run\n");
  const std::string window = write("bad.txt", std::string(kGoodHead) + "obs 99 1 1 1\n");
  const Result r = sparsify({"--window", window, "--decisions", out});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(read_all(out), "earlier run\n");
  EXPECT_EQ(temporaries(), 0u);
}

TEST_F(SparsifyCliTest, UnwritableDecisionsFileFailsCleanly) {
  const std::string window = write("w.txt", kGoodHead);
  const std::string out = path("missing_dir/decisions.txt");
  const Result r = sparsify({"--window", window, "--decisions", out});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_EQ(r.err.rfind(out + ":0: ", 0), 0u) << r.err;
  EXPECT_EQ(r.out, "");
}

// Three keyframes A=10 (0,0,0), B=20 (1,0,0), C=30 (10,0,0); points 1 (A,B,C),
// 2 and 3 (A,B), 4 (C only). Keypoints are >= 200 px apart, so no box holds a
// neighbour: N = 0 and c_s = floor(log10(0*0 + 1)) = 0 on every arc.
//   m = 3: c_m(3) = 1, c_m(2) = ceil(3/1 * 1) = 3.
//   c_b: AB d=1: ceil(10/1.1) = 10; AC d=10: ceil(10/2) = 5; BC d=9: ceil(10/1.9) = 6.
//   Capacities: point 1: 3, points 2, 3: 1, point 4: skipped.
//   Pair arcs: 3 (point 1) + 1 + 1 = 5; pairs 3; arcs = 3 source + 5 + 3 sink = 11.
const char* const kHandWindow =
    "kf 10 0 0 0\n"
    "kf 20 1 0 0\n"
    "kf 30 10 0 0\n"
    "obs 10 1 100 100\nobs 10 2 300 100\nobs 10 3 500 100\n"
    "obs 20 3 500 100\nobs 20 2 300 100\nobs 20 1 100 100\n"
    "obs 30 4 100 400\nobs 30 1 100 100\n";

struct HandCase {
  const char* m;
  const char* theta;
  const char* decisions;
  std::int64_t max_flow, total_cost, kept, culled;
};

TEST_F(SparsifyCliTest, HandComputedWindow) {
  const HandCase cases[] = {
      // M=1: each pair carries its cheapest point, point 1 (cost 1) everywhere:
      // AB 1+0+10, AC 1+0+5, BC 1+0+6 = 24; point 1 flow 3 > 0.5*3: keep.
      {"1", "0.5", "1 keep 3 3\n2 cull 0 1\n3 cull 0 1\n4 skip 0 0\n", 3, 24, 1, 2},
      // M=2: AB also carries point 2 (cost 3, tie with 3 -> smaller id): +3+0+10.
      {"2", "0.5", "1 keep 3 3\n2 keep 1 1\n3 cull 0 1\n4 skip 0 0\n", 4, 37, 2, 1},
      // M=100: everything flows: 24 + 13 + 13.
      {"100", "0.5", "1 keep 3 3\n2 keep 1 1\n3 keep 1 1\n4 skip 0 0\n", 5, 50, 3, 0},
      // theta=1: keep iff flow > capacity, never.
      {"100", "1", "1 cull 3 3\n2 cull 1 1\n3 cull 1 1\n4 skip 0 0\n", 5, 50, 0, 3},
  };
  const std::string window = write("hand.txt", kHandWindow);
  const std::string out = path("decisions.txt");
  for (const HandCase& c : cases) {
    SCOPED_TRACE(std::string("M=") + c.m + " theta=" + c.theta);
    const Result r =
        sparsify({"--window", window, "--M", c.m, "--theta", c.theta, "--decisions", out});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_EQ(read_all(out), c.decisions);
    EXPECT_EQ(temporaries(), 0u);
    const std::string json = last_line(r.out);
    ASSERT_EQ(json.front(), '{');
    ASSERT_EQ(json.back(), '}');
    EXPECT_EQ(json_int(json, "keyframes"), 3);
    EXPECT_EQ(json_int(json, "points"), 4);
    EXPECT_EQ(json_int(json, "evaluated"), 3);
    EXPECT_EQ(json_int(json, "kept"), c.kept);
    EXPECT_EQ(json_int(json, "culled"), c.culled);
    EXPECT_EQ(json_int(json, "skipped"), 1);
    EXPECT_EQ(json_int(json, "pairs"), 3);
    EXPECT_EQ(json_int(json, "arcs"), 11);
    EXPECT_EQ(json_int(json, "max_flow"), c.max_flow);
    EXPECT_EQ(json_int(json, "total_cost"), c.total_cost);
    EXPECT_EQ(json_int(json, "M"), std::atoll(c.m));
    EXPECT_EQ(json_number(json, "theta"), std::atof(c.theta));
    EXPECT_GE(json_number(json, "solve_ms"), 0.0);
    EXPECT_GE(json_number(json, "build_ms"), 0.0);
    EXPECT_GT(json_int(json, "memory_bytes"), 0);
  }
}

TEST_F(SparsifyCliTest, EmptyWindowIsValid) {
  const std::string window = write("empty.txt", "# nothing here\n\n");
  const std::string out = path("decisions.txt");
  const Result r = sparsify({"--window", window, "--decisions", out});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(read_all(out), "");
  const std::string json = last_line(r.out);
  EXPECT_EQ(json_int(json, "keyframes"), 0);
  EXPECT_EQ(json_int(json, "points"), 0);
  EXPECT_EQ(json_int(json, "max_flow"), 0);
}

// Runs the CLI on `window` and compares decisions and summary with the
// reference implementation on the same file.
void expect_matches_reference(const Result& r, const std::string& window, const std::string& out,
                              const core::Params& params) {
  ASSERT_EQ(r.status, 0) << r.err;
  core::WindowFile file;
  std::string error;
  ASSERT_TRUE(keepless::platform::read_window_file(window, &file, &error)) << error;
  std::vector<test::RefKeyframe> frames;
  for (std::size_t k = 0; k < file.keyframes.size(); ++k) {
    test::RefKeyframe f;
    f.id = file.keyframes[k].id;
    for (int i = 0; i < 3; ++i) f.centre[i] = file.keyframes[k].centre[i];
    for (const core::Observation& o : file.observations[k])
      f.observations.push_back({o.point, o.u, o.v});
    frames.push_back(f);
  }
  const test::RefResult ref = test::reference_decide(frames, params);
  std::string expected;
  std::int64_t kept = 0, culled = 0, skipped = 0;
  for (const test::RefPoint& p : ref.points) {
    expected += std::to_string(p.id) + " " + core::to_string(p.verdict) + " " +
                std::to_string(p.flow) + " " + std::to_string(p.capacity) + "\n";
    kept += p.verdict == core::Verdict::kKeep;
    culled += p.verdict == core::Verdict::kCull;
    skipped += p.verdict == core::Verdict::kSkip;
  }
  EXPECT_EQ(read_all(out), expected);
  EXPECT_GT(kept, 0);  // the case exercises both verdicts
  EXPECT_GT(culled, 0);
  const std::string json = last_line(r.out);
  EXPECT_EQ(json_int(json, "keyframes"), static_cast<std::int64_t>(frames.size()));
  EXPECT_EQ(json_int(json, "points"), static_cast<std::int64_t>(ref.points.size()));
  EXPECT_EQ(json_int(json, "evaluated"), ref.evaluated);
  EXPECT_EQ(json_int(json, "kept"), kept);
  EXPECT_EQ(json_int(json, "culled"), culled);
  EXPECT_EQ(json_int(json, "skipped"), skipped);
  EXPECT_EQ(json_int(json, "pairs"), ref.pairs);
  EXPECT_EQ(json_int(json, "arcs"),
            static_cast<std::int64_t>(ref.evaluated) + ref.pair_arcs + ref.pairs);
  EXPECT_EQ(json_int(json, "max_flow"), ref.max_flow);
  EXPECT_EQ(json_int(json, "total_cost"), ref.total_cost);
  EXPECT_EQ(json_int(json, "floor"), params.coverage_floor);
  EXPECT_EQ(json_int(json, "out_of_scope"), ref.out_of_scope);
  EXPECT_EQ(json_int(json, "floor_keyframes"), ref.floor_keyframes);
  EXPECT_EQ(json_int(json, "floor_promoted"), ref.floor_promoted);
  EXPECT_EQ(json_int(json, "floor_short"), ref.floor_short);
  EXPECT_EQ(json_int(json, "guarded"), ref.guarded);
  EXPECT_NE(json.find(std::string("\"scope\":\"") + core::to_string(params.scope) + "\""),
            std::string::npos);
  EXPECT_NE(json.find(std::string("\"cost\":\"") + core::to_string(params.cost_model) + "\""),
            std::string::npos);
}

// A small window with clustered keypoints (non-zero c_s), repeated baselines
// and shared points, written by hand so it does not depend on the generator.
std::string clustered_window() {
  std::string text = "# clustered\n";
  const double centres[5][3] = {{0, 0, 0}, {0.5, 0, 0}, {0.5, 0.2, 0}, {3, 0, 1}, {12, 1, 0}};
  for (int k = 0; k < 5; ++k) {
    std::ostringstream line;
    line << "kf " << 100 + k << " " << centres[k][0] << " " << centres[k][1] << " " << centres[k][2]
         << " 1 0 0 0\n";
    text += line.str();
  }
  // Point p seen by keyframes [p % 5, p % 5 + 1 + p % 3] (clipped), keypoints
  // on a 20 px lattice so boxes overlap often and exactly at their borders.
  for (int p = 0; p < 60; ++p) {
    const int first = p % 5, last = std::min(4, first + 1 + p % 3);
    for (int k = first; k <= last; ++k) {
      const int u = 20 * ((p * 7 + k) % 12), v = 24 * ((p * 3 + k) % 9);
      text += "obs " + std::to_string(100 + k) + " " + std::to_string(1000 + p * 13) + " " +
              std::to_string(u) + " " + std::to_string(v) + "\n";
    }
  }
  return text;
}

TEST_F(SparsifyCliTest, MatchesReferenceOnAClusteredWindow) {
  const std::string window = write("clustered.txt", clustered_window());
  const std::string out = path("decisions.txt");
  struct P {
    const char *m, *theta, *box;
  };
  for (const P& p : {P{"3", "0.5", "64x48"}, P{"1", "0.2", "40x40"}, P{"5", "0.7", "0x0"}}) {
    SCOPED_TRACE(std::string(p.m) + " " + p.theta + " " + p.box);
    core::Params params;
    params.pair_capacity = std::atoll(p.m);
    params.theta = std::atof(p.theta);
    ASSERT_TRUE(core::parse_box(p.box, &params.box_width, &params.box_height));
    const Result r = sparsify(
        {"--window", window, "--M", p.m, "--theta", p.theta, "--box", p.box, "--decisions", out});
    expect_matches_reference(r, window, out, params);
  }
}

// --scope, --floor, --cost and --image reach the library: the decisions are
// the reference's under the same policies.
TEST_F(SparsifyCliTest, PoliciesMatchReference) {
  const std::string window = write("clustered.txt", clustered_window());
  const std::string out = path("decisions.txt");
  struct P {
    const char *scope, *floor, *cost;
  };
  for (const P& p : {P{"newest", "0", "paper"}, P{"window", "12", "authors"},
                     P{"newest", "8", "information"}}) {
    SCOPED_TRACE(std::string(p.scope) + " " + p.floor + " " + p.cost);
    core::Params params;
    params.pair_capacity = 2;
    ASSERT_TRUE(core::parse_scope(p.scope, &params.scope));
    params.coverage_floor = static_cast<std::uint32_t>(std::atoi(p.floor));
    ASSERT_TRUE(core::parse_cost_model(p.cost, &params.cost_model));
    params.image_width = 320;
    params.image_height = 240;
    const Result r = sparsify({"--window", window, "--M", "2", "--scope", p.scope, "--floor",
                               p.floor, "--cost", p.cost, "--image", "320x240", "--decisions", out});
    expect_matches_reference(r, window, out, params);
  }
}

// --keep-points/--keep-fraction/--keep-observations reach the library: the
// JSON's counts and the decisions file are the library's under that budget,
// and the budget is echoed.
TEST_F(SparsifyCliTest, KeepBudgetsReachTheLibrary) {
  const std::string window = write("clustered.txt", clustered_window());
  const std::string out = path("decisions.txt");
  struct B {
    const char* flag;
    const char* value;
    core::KeepBudget budget;
    const char* kind;
    const char* share;
  };
  for (const B& b : {B{"--keep-points", "7", {core::BudgetKind::kPoints, 7, 0.0}, "points", "0"},
                     B{"--keep-fraction", "0.3", {core::BudgetKind::kFraction, 0, 0.3}, "fraction", "0"},
                     B{"--keep-observations", "20", {core::BudgetKind::kObservations, 20, 0.0},
                       "observations", "0"},
                     B{"--keep-points", "7", {core::BudgetKind::kPoints, 7, 0.0, 0.5}, "points", "0.5"},
                     B{"--keep-fraction", "0.3", {core::BudgetKind::kFraction, 0, 0.3, 1.0}, "fraction", "1"}}) {
    SCOPED_TRACE(std::string(b.flag) + " --track-share " + b.share);
    const Result r =
        sparsify({"--window", window, b.flag, b.value, "--track-share", b.share, "--decisions", out});
    ASSERT_EQ(r.status, 0) << r.err;
    core::Params params;
    params.budget = b.budget;
    core::WindowFile file;
    std::string error;
    ASSERT_TRUE(keepless::platform::read_window_file(window, &file, &error)) << error;
    const core::Capacities caps = core::compute_needs(file);
    core::Window w(caps);
    for (std::size_t k = 0; k < file.keyframes.size(); ++k) {
      ASSERT_EQ(w.add_keyframe(file.keyframes[k], file.observations[k].data(),
                               static_cast<std::uint32_t>(file.observations[k].size())),
                core::Status::kOk);
    }
    core::Sparsifier s(caps, params);
    ASSERT_EQ(s.run(w), core::Status::kOk);
    EXPECT_NE(r.out.find("\"kept\":" + std::to_string(s.summary().kept) + ","), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(std::string("\"budget\":\"") + b.kind + "\",\"budget_value\":" + b.value),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("\"budget_m\":" + std::to_string(s.summary().budget_m) + ","), std::string::npos);
    EXPECT_NE(r.out.find(std::string("\"track_share\":") + b.share + "}"), std::string::npos) << r.out;
    // The very points the library keeps (a share changes which, not how many).
    std::set<core::PointId> library_kept, file_kept;
    for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
      if (s.decisions()[i].verdict == core::Verdict::kKeep) library_kept.insert(s.decisions()[i].point);
    }
    std::ifstream in(out);
    std::uint32_t lines = 0;
    for (std::string line; std::getline(in, line);) {
      ++lines;
      if (line.find(" keep ") != std::string::npos) file_kept.insert(std::stoull(line));
    }
    EXPECT_EQ(file_kept, library_kept);
    EXPECT_GT(lines, file_kept.size());
  }
}

// --maturity reaches the library: the reference's decisions and guarded count.
TEST_F(SparsifyCliTest, MaturityMatchesReference) {
  const std::string window = write("clustered.txt", clustered_window());
  const std::string out = path("decisions.txt");
  for (const char* scope : {"window", "newest"}) {
    SCOPED_TRACE(scope);
    core::Params params;
    params.pair_capacity = 2;
    params.maturity_keyframes = 1;
    ASSERT_TRUE(core::parse_scope(scope, &params.scope));
    const Result r = sparsify({"--window", window, "--M", "2", "--scope", scope, "--maturity", "1", "--decisions", out});
    expect_matches_reference(r, window, out, params);
    EXPECT_EQ(json_int(last_line(r.out), "maturity"), 1);
  }
  const Result bad = sparsify({"--window", window, "--maturity", "-1"});
  EXPECT_EQ(bad.status, 2);
}

TEST_F(SparsifyCliTest, GeneratorIsDeterministicPerSeed) {
  const std::vector<std::string> common = {"--keyframes",  "6",  "--points", "400",
                                           "--obs-per-kf", "150"};
  const auto make = [&](const char* seed, const std::string& name) {
    std::vector<std::string> args = common;
    args.insert(args.end(), {"--seed", seed, "--out", path(name)});
    const Result r = run(KEEPLESS_MAKE_WINDOW_BIN, args);
    EXPECT_EQ(r.status, 0) << r.err;
    return read_all(path(name));
  };
  const std::string a = make("7", "a.txt");
  const std::string b = make("7", "b.txt");
  const std::string c = make("8", "c.txt");
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST_F(SparsifyCliTest, GeneratorWritesTracksOverConsecutiveKeyframes) {
  const Result r = run(KEEPLESS_MAKE_WINDOW_BIN, {"--workload", "small", "--points", "1500",
                                                  "--seed", "3", "--out", path("small.txt")});
  ASSERT_EQ(r.status, 0) << r.err;
  core::WindowFile file;
  std::string error;
  ASSERT_TRUE(keepless::platform::read_window_file(path("small.txt"), &file, &error)) << error;
  EXPECT_EQ(file.keyframes.size(), 10u);    // the preset
  EXPECT_EQ(file.needs.max_points, 1500u);  // the override
  EXPECT_EQ(json_int(last_line(r.out), "points"), 1500);
  std::map<std::uint64_t, std::vector<std::size_t>> views;
  for (std::size_t k = 0; k < file.keyframes.size(); ++k) {
    for (const core::Observation& o : file.observations[k]) {
      EXPECT_GE(o.u, 0.0);
      EXPECT_LE(o.u, 640.0);
      EXPECT_GE(o.v, 0.0);
      EXPECT_LE(o.v, 480.0);
      views[o.point].push_back(k);
    }
  }
  std::size_t longest = 0, multi = 0;
  for (const auto& entry : views) {
    const auto& kfs = entry.second;
    EXPECT_EQ(kfs.back() - kfs.front() + 1, kfs.size()) << "point " << entry.first;
    longest = std::max(longest, kfs.size());
    multi += kfs.size() >= 2;
  }
  EXPECT_GE(longest, 5u);              // long tracks exist
  EXPECT_GT(multi, views.size() / 2);  // most points are evaluated
}

TEST_F(SparsifyCliTest, MatchesReferenceOnGeneratedWindows) {
  const std::string out = path("decisions.txt");
  for (const char* seed : {"1", "2"}) {
    SCOPED_TRACE(seed);
    const std::string window = path(std::string("gen") + seed + ".txt");
    const Result g =
        run(KEEPLESS_MAKE_WINDOW_BIN, {"--keyframes", "8", "--points", "600", "--obs-per-kf", "200",
                                       "--seed", seed, "--out", window});
    ASSERT_EQ(g.status, 0) << g.err;
    core::Params params;
    params.pair_capacity = 20;
    const Result r = sparsify({"--window", window, "--M", "20", "--decisions", out});
    expect_matches_reference(r, window, out, params);
  }
}



// Issue 15, defect 5: a FIFO with no writer blocked open() forever and
// /dev/zero ended in bad_alloc (exit 1). Neither is a regular file: refused
// on line 0 at once.
TEST_F(SparsifyCliTest, NonRegularFilesAreRefusedWithoutBlocking) {
  const std::string fifo = path("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expect_error_result(sparsify({"--window", fifo, "--decisions", path("decisions.txt")}), fifo, 0,
                      "not a regular file");
  expect_error_result(sparsify({"--window", "/dev/zero", "--decisions", path("decisions.txt")}), "/dev/zero", 0,
                      "not a regular file");
}

// A large file whose first line is bad costs one line, not the whole file.
TEST_F(SparsifyCliTest, ALongFileWithABadFirstLineFailsOnLineOne) {
  std::string text = "kf 1 0 0 0 x\n";
  for (int i = 0; i < 200000; ++i) text += "obs 1 5 0 0\n";
  expect_input_error(text, 1, "kf needs 4 or 8 values");
  expect_input_error(std::string(1 << 20, 'k'), 1, "line longer than 4096 bytes");
}

// Issue 15, defect 6: 317 keyframes x 997 shared points (49.96M pair arcs)
// is inside every default limit and ended in bad_alloc, exit 1. Its memory
// is now checked record by record: the line that crosses --max-memory-mb is
// the error, before anything is allocated for the solve.
TEST_F(SparsifyCliTest, AWindowBeyondTheMemoryLimitFailsOnTheCrossingLine) {
  std::string text;
  for (int k = 0; k < 317; ++k) {
    text += "kf " + std::to_string(k) + " " + std::to_string(k) + " 0 0\n";
    for (int p = 0; p < 997; ++p) text += "obs " + std::to_string(k) + " " + std::to_string(p) + " 1 1\n";
  }
  const std::string window = write("huge.txt", text);
  const Result r = sparsify({"--window", window, "--decisions", path("decisions.txt"), "--max-memory-mb", "64"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("memory limit exceeded"), std::string::npos) << r.err;
  const long line = std::strtol(r.err.c_str() + window.size() + 1, nullptr, 10);
  EXPECT_GT(line, 1000) << r.err;
  EXPECT_LT(line, 317 * 998) << "refused before the end of the file: " << r.err;
  // The default limit refuses it too.
  const Result d = sparsify({"--window", window});
  EXPECT_EQ(d.status, 2) << d.err;
  EXPECT_NE(d.err.find("memory limit exceeded"), std::string::npos) << d.err;
}

// Issue 15, defect 7: the node refuses zero and non-unit quaternions; so
// does the offline tool.
TEST_F(SparsifyCliTest, ZeroOrNonUnitQuaternionIsRefused) {
  expect_input_error(std::string(kGoodHead) + "kf 30 0 0 0 0 0 0 0\n", 5, "not a unit quaternion");
  expect_input_error(std::string(kGoodHead) + "kf 30 0 0 0 2 0 0 0\n", 5, "not a unit quaternion");
}

}  // namespace
}  // namespace keepless
