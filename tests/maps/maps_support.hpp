#pragma once
// Shared by the map tests: a temp dir per test, child processes (our
// binaries through the cross build's emulator, host tools such as colmap
// directly), the fixture's path and JSON fields of a summary line.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "child_run.hpp"

namespace keepless::maps_test {

namespace fs = std::filesystem;

using test::read_all;

inline void write_all(const std::string& path, const std::string& contents) {
  std::ofstream(path, std::ios::binary) << contents;
}

inline std::string fixture(const std::string& sub = "") {
  return std::string(KEEPLESS_MAPS_DATA) + "/colmap_kitti06_first51" + (sub.empty() ? "" : "/" + sub);
}

// In a test body: skips the test, naming the path, when that data is missing.
#define KEEPLESS_MAPS_NEED(path)                                                                        \
  do {                                                                                                  \
    if (!std::filesystem::exists(path)) {                                                               \
      GTEST_SKIP() << "no data: " << (path) << " is missing (set KEEPLESS_MAPS_DATA_DIR)";              \
    }                                                                                                   \
  } while (0)

inline std::string bal_problem() { return std::string(KEEPLESS_MAPS_DATA) + "/bal_zenslam/problem-49-7776-pre.txt"; }

inline std::string last_line(std::string s) {
  while (!s.empty() && s.back() == '\n') s.pop_back();
  const std::size_t nl = s.rfind('\n');
  return nl == std::string::npos ? s : s.substr(nl + 1);
}

// The number after "key": in a one-line JSON object (NaN when absent).
inline double json_number(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const std::size_t at = json.find(needle);
  return at == std::string::npos ? std::nan("") : std::strtod(json.c_str() + at + needle.size(), nullptr);
}

using Result = test::ChildResult;

class MapsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Missing data skips, naming the path (never a parse error on a missing file).
    if (!fs::exists(fixture("sparse/images.bin"))) {
      GTEST_SKIP() << "no data: " << fixture("sparse/images.bin") << " is missing (set KEEPLESS_MAPS_DATA_DIR)";
    }
    std::string pattern = ::testing::TempDir() + "keepless_maps_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return dir_ + "/" + name; }

  // `ours`: a binary of this build (run through the cross build's emulator).
  Result run(const std::string& binary, const std::vector<std::string>& args, bool ours = true) const {
    return test::run_child(binary, args, path("stdout.txt"), path("stderr.txt"), ours);
  }
  Result sparsify(const std::vector<std::string>& args) const { return run(KEEPLESS_SPARSIFY_BIN, args); }

  std::string dir_;
};

}  // namespace keepless::maps_test
