#pragma once
// Shared by the map tests: a temp dir per test, child processes (our
// binaries through the cross build's emulator, host tools such as colmap
// directly), the fixture's path and JSON fields of a summary line.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace keepless::maps_test {

namespace fs = std::filesystem;

inline std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_all(const std::string& path, const std::string& contents) {
  std::ofstream(path, std::ios::binary) << contents;
}

inline std::string fixture(const std::string& sub = "") {
  return std::string(KEEPLESS_MAPS_DATA) + "/colmap_kitti06_first51" + (sub.empty() ? "" : "/" + sub);
}

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

struct Result {
  int status = -1;
  std::string out, err;
};

class MapsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(fixture("sparse/images.bin")))
        << "the shared COLMAP fixture is missing: " << fixture() << " (set KEEPLESS_MAPS_DATA_DIR)";
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
    const std::string out_path = path("stdout.txt"), err_path = path("stderr.txt");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<std::string> all;
#ifdef KEEPLESS_TEST_LAUNCHER
    if (ours) {
      std::istringstream launcher(KEEPLESS_TEST_LAUNCHER);
      for (std::string word; launcher >> word;) all.push_back(word);
    }
#else
    (void)ours;
#endif
    all.push_back(binary);
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    Result r;
    const int spawned = posix_spawnp(&pid, all[0].c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    EXPECT_EQ(spawned, 0) << "cannot run " << binary;
    if (spawned != 0) return r;
    int wstatus = 0;
    EXPECT_EQ(waitpid(pid, &wstatus, 0), pid);
    r.status = WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : -1;
    r.out = read_all(out_path);
    r.err = read_all(err_path);
    return r;
  }
  Result sparsify(const std::vector<std::string>& args) const { return run(KEEPLESS_SPARSIFY_BIN, args); }

  std::string dir_;
};

}  // namespace keepless::maps_test
