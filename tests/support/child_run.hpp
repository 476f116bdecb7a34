#pragma once
// Runs a program as a child process for a test, its stdout and stderr
// captured in files, and returns its exit status and output. A binary of
// this build goes through the cross build's emulator (KEEPLESS_TEST_LAUNCHER:
// qemu-user does not run a foreign binary on exec); a host tool (colmap) runs
// as it is, found on PATH.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace keepless::test {

struct ChildResult {
  int status = -1;  // exit status, -1 if killed by a signal
  std::string out;
  std::string err;
};

inline std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline ChildResult run_child(const std::string& binary, const std::vector<std::string>& args,
                             const std::string& out_path, const std::string& err_path, bool ours = true) {
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
  ChildResult r;
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

}  // namespace keepless::test
