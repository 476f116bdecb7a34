// platform::AtomicFileWriter: a file written whole or not at all.

#include "keepless/platform/atomic_file_writer.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace keepless::platform {
namespace {

namespace fs = std::filesystem;

class AtomicFileWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // One folder per test and process: ctest runs the cases in parallel.
    dir_ = fs::path(::testing::TempDir()) /
           ("keepless_atomic_file_writer_test_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string contents(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  // Entries of the folder: the target alone once a write is over.
  std::size_t entries() const {
    std::size_t n = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++n;
    return n;
  }

  fs::path dir_;
};

TEST_F(AtomicFileWriterTest, PiecesLandAtPathOnCommit) {
  const std::string p = path("out.txt");
  {
    std::ofstream(p) << "old";
    AtomicFileWriter w(p);
    ASSERT_EQ(w.open_error(), 0);
    EXPECT_TRUE(w.write("ab", 2));
    EXPECT_TRUE(w.write(std::string("cd")));
    EXPECT_EQ(contents(p), "old");  // not yet
    EXPECT_EQ(w.commit(), 0);
  }
  EXPECT_EQ(contents(p), "abcd");
  EXPECT_EQ(entries(), 1u);
}

TEST_F(AtomicFileWriterTest, AnAbandonedWriteLeavesPathAsItWas) {
  const std::string p = path("out.txt");
  std::ofstream(p) << "old";
  {
    AtomicFileWriter w(p);
    EXPECT_TRUE(w.write("new", 3));
  }
  EXPECT_EQ(contents(p), "old");
  EXPECT_EQ(entries(), 1u);
}

TEST_F(AtomicFileWriterTest, AFailedRenameRemovesTheTemporary) {
  const std::string p = path("folder");
  fs::create_directories(p);
  AtomicFileWriter w(p);
  EXPECT_TRUE(w.write("x", 1));
  EXPECT_EQ(w.commit(), EISDIR);
  EXPECT_TRUE(fs::is_directory(p));
  EXPECT_EQ(entries(), 1u);
}

TEST_F(AtomicFileWriterTest, AFailedOpenIsReportedByEveryCall) {
  AtomicFileWriter w(path("no_such_folder/out.txt"));
  EXPECT_EQ(w.open_error(), ENOENT);
  EXPECT_FALSE(w.write("x", 1));
  EXPECT_EQ(w.commit(), ENOENT);
  EXPECT_EQ(entries(), 0u);
}

}  // namespace
}  // namespace keepless::platform
