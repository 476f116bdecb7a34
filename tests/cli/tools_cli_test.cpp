// Every tool's command line behaves like the field's tools: --help on stdout
// with exit 0, a usage line and one described line per flag; --version prints
// "<tool> <project version>"; an unknown option or a flag without its value
// is named on stderr, exit 2. Each flag the help documents is known to the
// parser (a value flag alone "needs a value"; a switch followed by an unknown
// option gets past the switch).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "child_run.hpp"

namespace {

namespace fs = std::filesystem;

struct Tool {
  std::string name, path;
};
void PrintTo(const Tool& t, std::ostream* os) { *os << t.name; }

// KEEPLESS_TOOLS: "name=path|name=path|...".
std::vector<Tool> tools() {
  std::vector<Tool> out;
  std::stringstream list(KEEPLESS_TOOLS);
  for (std::string item; std::getline(list, item, '|');) {
    const std::size_t eq = item.find('=');
    if (eq != std::string::npos) out.push_back({item.substr(0, eq), item.substr(eq + 1)});
  }
  return out;
}

// A built tool's path (the test is compiled only where the build has it).
std::string tool_path(const std::string& name) {
  for (const Tool& t : tools()) {
    if (t.name == name) return t.path;
  }
  return "";
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream s(text);
  for (std::string line; std::getline(s, line);) lines.push_back(line);
  return lines;
}

// A documented flag: its name, whether it takes a value, whether it is described.
struct Documented {
  std::string name;
  bool value = false;
  bool described = false;
};

std::vector<Documented> documented_flags(const std::vector<std::string>& lines) {
  std::vector<Documented> flags;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& l = lines[i];
    if (l.rfind("  --", 0) != 0) continue;
    Documented d;
    std::size_t end = l.find_first_of(" ,", 2);
    if (end == std::string::npos) end = l.size();
    d.name = l.substr(2, end - 2);
    // "--name VALUE ...": one blank then a word; "--name   text": a switch.
    d.value = end + 1 < l.size() && l[end] == ' ' && l[end + 1] != ' ';
    std::size_t rest = end;
    if (d.value) rest = l.find(' ', end + 1);
    const bool text_after = rest != std::string::npos && l.find_first_not_of(' ', rest) != std::string::npos;
    const bool continued = i + 1 < lines.size() && lines[i + 1].rfind("    ", 0) == 0 &&
                           lines[i + 1].find_first_not_of(' ') != std::string::npos;
    d.described = text_after || continued;
    flags.push_back(d);
  }
  return flags;
}

class ToolCli : public ::testing::TestWithParam<Tool> {
 protected:
  void SetUp() override {
    std::string pattern = ::testing::TempDir() + "keepless_tools_cli_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    ASSERT_TRUE(fs::exists(GetParam().path)) << GetParam().path << " is missing: build target " << GetParam().name;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  keepless::test::ChildResult run(const std::vector<std::string>& args) const {
    return keepless::test::run_child(GetParam().path, args, dir_ + "/out.txt", dir_ + "/err.txt");
  }
  std::string dir_;
};

TEST_P(ToolCli, HelpPrintsAUsageLineAndOneDescribedLinePerFlag) {
  const auto r = run({"--help"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0].rfind("usage: " + GetParam().name, 0), 0u) << lines[0];
  const std::vector<Documented> flags = documented_flags(lines);
  bool help = false, version = false;
  for (const Documented& d : flags) {
    EXPECT_TRUE(d.described) << d.name << " has no description";
    help = help || d.name == "--help";
    version = version || d.name == "--version";
  }
  EXPECT_TRUE(help);
  EXPECT_TRUE(version);
  EXPECT_EQ(run({"-h"}).out, r.out);
}

TEST_P(ToolCli, EveryDocumentedFlagIsKnownToTheParser) {
  const auto help = run({"--help"});
  ASSERT_EQ(help.status, 0);
  for (const Documented& d : documented_flags(lines_of(help.out))) {
    if (d.name == "--help" || d.name == "--version") continue;
    SCOPED_TRACE(d.name);
    if (d.value) {
      const auto r = run({d.name});
      EXPECT_EQ(r.status, 2);
      EXPECT_NE(r.err.find("option '" + d.name + "' needs a value"), std::string::npos) << r.err;
      // The value check above is the shared table's; given a value, the
      // tool's own parser must take the flag: it refuses the value by the
      // flag's name or reaches the unknown option after it.
      const auto given = run({d.name, "x", "--not-an-option"});
      EXPECT_EQ(given.status, 2);
      EXPECT_EQ(given.err.find("unknown option '" + d.name + "'"), std::string::npos) << given.err;
      EXPECT_TRUE(given.err.find(d.name) != std::string::npos ||
                  given.err.find("unknown option '--not-an-option'") != std::string::npos)
          << given.err;
    } else {
      const auto r = run({d.name, "--not-an-option"});
      EXPECT_EQ(r.status, 2);
      EXPECT_NE(r.err.find("unknown option '--not-an-option'"), std::string::npos) << r.err;
    }
  }
}

TEST_P(ToolCli, VersionPrintsTheProjectVersion) {
  const auto r = run({"--version"});
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out, GetParam().name + " " + KEEPLESS_PROJECT_VERSION + "\n");
  EXPECT_EQ(r.err, "");
}

TEST_P(ToolCli, UnknownOptionIsNamedOnStderrWithExit2) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--bogus"}, std::vector<std::string>{"--bogus", "1"}}) {
    const auto r = run(args);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find("unknown option '--bogus'"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(GetParam().name + " --help"), std::string::npos) << r.err;
  }
}

INSTANTIATE_TEST_SUITE_P(Tools, ToolCli, ::testing::ValuesIn(tools()),
                         [](const ::testing::TestParamInfo<Tool>& info) { return info.param.name; });

#if KEEPLESS_WITH_LCM
// keepless_vo_sim refuses a flag its source would ignore: --format,
// --kf-distance and --kf-angle without --trajectory, --scene with one.
TEST(VoSimFlags, AFlagOfTheOtherSourceIsRefusedWithExit2) {
  const std::string sim = tool_path("keepless_vo_sim");
  ASSERT_FALSE(sim.empty());
  std::string dir = ::testing::TempDir() + "keepless_vo_sim_flags_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  const std::string trajectory = dir + "/t.txt";
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--format", "kitti"}, {"--kf-distance", "2"}, {"--kf-angle", "5"},
        {"--scene", "room", "--trajectory", trajectory, "--format", "kitti"}}) {
    std::vector<std::string> all = {"--url", "memq://", "--wait-node-ms", "1", "--keyframes", "1"};
    all.insert(all.end(), args.begin(), args.end());
    const auto r = keepless::test::run_child(sim, all, dir + "/out.txt", dir + "/err.txt");
    EXPECT_EQ(r.status, 2) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find(args[0]), std::string::npos) << r.err;
  }
  fs::remove_all(dir);
}

// keepless_vo_sim's integers are digits only: " -1" was --seed 2^64 - 1.
TEST(VoSimFlags, ANegativeIntegerBehindABlankIsRefused) {
  const std::string sim = tool_path("keepless_vo_sim");
  ASSERT_FALSE(sim.empty());
  std::string dir = ::testing::TempDir() + "keepless_vo_sim_numbers_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  for (const char* flag : {"--seed", "--keyframes", "--event-every"}) {
    const auto r = keepless::test::run_child(sim, {"--url", "memq://", "--wait-node-ms", "1", flag, " -1"},
                                             dir + "/out.txt", dir + "/err.txt");
    EXPECT_EQ(r.status, 2) << flag << ": " << r.out << r.err;
  }
  fs::remove_all(dir);
}

// Its decimals too: strtod read "0x1p3" as 8 and " 2" as 2.
TEST(VoSimFlags, AHexOrBlankDecimalIsRefused) {
  const std::string sim = tool_path("keepless_vo_sim");
  ASSERT_FALSE(sim.empty());
  std::string dir = ::testing::TempDir() + "keepless_vo_sim_decimals_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  for (const char* bad : {"0x1p3", " 2"}) {
    const auto r = keepless::test::run_child(sim, {"--url", "memq://", "--wait-node-ms", "1", "--pixel-noise", bad},
                                             dir + "/out.txt", dir + "/err.txt");
    EXPECT_EQ(r.status, 2) << bad << ": " << r.out << r.err;
  }
  fs::remove_all(dir);
}
#endif  // KEEPLESS_WITH_LCM: the simulator is built with LCM only

// A malformed number is refused whole, never read as its prefix ("30x" as 30),
// by each tool that takes --M.
TEST(ToolNumbers, AMalformedNumberIsRefusedWithExit2) {
  std::string dir = ::testing::TempDir() + "keepless_tools_numbers_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  int checked = 0;  // keepless_sparsify always; the node with LCM, the bench with perf/
  for (const Tool& tool : tools()) {
    if (tool.name != "keepless_maps_bench" && tool.name != "keepless_sparsify" && tool.name != "keepless_node") {
      continue;
    }
    const auto r = keepless::test::run_child(tool.path, {"--M", "30x"}, dir + "/out.txt", dir + "/err.txt");
    EXPECT_EQ(r.status, 2) << tool.name;
    EXPECT_NE(r.err.find("30x"), std::string::npos) << tool.name << ": " << r.err;
    ++checked;
  }
  fs::remove_all(dir);
  EXPECT_GE(checked, 1);
}

#if KEEPLESS_WITH_PERF
// An empty list, or one with an empty last item, is refused too: "" would
// otherwise run keepless_maps_bench's default --M sweep instead of the fractions.
TEST(ToolNumbers, AnEmptyListIsRefusedWithExit2) {
  const std::string bench = tool_path("keepless_maps_bench");
  ASSERT_FALSE(bench.empty());
  std::string dir = ::testing::TempDir() + "keepless_tools_lists_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--keep-fraction", ""}, {"--keep-fraction", "0.1,"}, {"--track-share", ""},
        {"--track-share", "0.5,"}, {"--M", ""}, {"--M", "30,"}}) {
    const auto r = keepless::test::run_child(bench, args, dir + "/out.txt", dir + "/err.txt");
    EXPECT_EQ(r.status, 2) << args[0] << " '" << args[1] << "': " << r.err;
    EXPECT_NE(r.err.find("bad value for " + args[0]), std::string::npos) << r.err;
  }
  fs::remove_all(dir);
}
#endif  // KEEPLESS_WITH_PERF: the bench is built with perf/ only

#if KEEPLESS_WITH_LCM
// keepless_log_compare's verdicts on hand-made LCM logs: order, one byte and
// count differ (1); a file that is not an LCM log, or is cut or corrupt
// within an event, is unreadable (2), never compared as its readable prefix.
std::string lcm_event(std::int64_t n, const std::string& channel, const std::string& data) {
  std::string e;
  const auto be = [&e](std::uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) e += static_cast<char>((v >> (8 * i)) & 0xff);
  };
  be(0xEDA1DA01u, 4);
  be(static_cast<std::uint64_t>(n), 8);
  be(1000 + static_cast<std::uint64_t>(n), 8);
  be(channel.size(), 4);
  be(data.size(), 4);
  return e + channel + data;
}

TEST(LogCompare, VerdictsOnOrderBytesCountAndDamagedLogs) {
  const std::string compare = tool_path("keepless_log_compare");
  ASSERT_FALSE(compare.empty());
  std::string dir = ::testing::TempDir() + "keepless_log_compare_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  const auto write = [&dir](const std::string& name, const std::string& bytes) {
    std::ofstream(dir + "/" + name, std::ios::binary) << bytes;
    return dir + "/" + name;
  };
  const std::string full = lcm_event(0, "D", "abc") + lcm_event(1, "X", "zz") + lcm_event(2, "D", "def");
  const std::string a = write("a.lcmlog", full);
  std::string corrupt = full;
  corrupt[lcm_event(0, "D", "abc").size() + 20] = 0x10;  // the second event's channel length
  const struct {
    std::string log;
    int status;
  } cases[] = {
      {write("same.lcmlog", full), 0},
      {write("order.lcmlog", lcm_event(0, "D", "def") + lcm_event(1, "D", "abc")), 1},
      {write("byte.lcmlog", lcm_event(0, "D", "abc") + lcm_event(1, "D", "dEf")), 1},
      {write("count.lcmlog", full + lcm_event(3, "D", "ghi")), 1},
      {write("cut.lcmlog", full.substr(0, full.size() - 2)), 2},
      {write("junk_after.lcmlog", full + "junk"), 2},
      {write("text.lcmlog", "not an LCM log\n"), 2},
      {write("corrupt.lcmlog", corrupt), 2},
  };
  for (const auto& c : cases) {
    const auto r = keepless::test::run_child(compare, {a, "D", c.log, "D"}, dir + "/out.txt", dir + "/err.txt");
    EXPECT_EQ(r.status, c.status) << c.log << ": " << r.out << r.err;
  }
  // A corrupt log against itself: not "identical" over the prefix before the damage.
  const std::string bad = dir + "/corrupt.lcmlog";
  EXPECT_EQ(keepless::test::run_child(compare, {bad, "D", bad, "D"}, dir + "/out.txt", dir + "/err.txt").status, 2);
  fs::remove_all(dir);
}
#endif  // KEEPLESS_WITH_LCM

}  // namespace
