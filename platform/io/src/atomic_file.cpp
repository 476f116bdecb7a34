#include "keepless/io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace keepless::io {

// COLMAP models, BAL problems and keyframe files may exceed 2 GiB: 32-bit
// builds define _FILE_OFFSET_BITS=64 (top-level CMakeLists.txt), or open/fstat
// would fail with EOVERFLOW.
static_assert(sizeof(off_t) == 8, "64-bit file offsets needed (_FILE_OFFSET_BITS=64 on 32-bit targets)");

bool read_file(const std::string& path, std::string* out, std::string* error) {
  const auto fail = [&](const std::string& what) {
    *error = path + ":0: " + what;
    return false;
  };
  // O_NONBLOCK: opening a FIFO without a writer would otherwise wait forever;
  // only regular files are read (a FIFO or a device may never end).
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) return fail(std::string("cannot read: ") + std::strerror(errno));
  struct stat st {};
  std::string problem;
  if (::fstat(fd, &st) != 0) {
    problem = std::string("cannot read: ") + std::strerror(errno);
  } else if (!S_ISREG(st.st_mode)) {
    problem = S_ISDIR(st.st_mode) ? "is a directory, not a file" : "not a regular file (refused: it may never end)";
  } else {
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
      problem = std::string("cannot read: ") + std::strerror(errno);
    }
  }
  if (problem.empty()) {
    out->clear();
    out->reserve(static_cast<std::size_t>(st.st_size));
    char buffer[1 << 16];
    for (;;) {
      const ssize_t n = ::read(fd, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) problem = std::string("cannot read: ") + std::strerror(errno);
      if (n <= 0) break;
      out->append(buffer, static_cast<std::size_t>(n));
    }
  }
  ::close(fd);
  return problem.empty() || fail(problem);
}

int write_whole_file(const std::string& path, const std::string& contents) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return errno;
  int err = std::fwrite(contents.data(), 1, contents.size(), f) == contents.size() ? 0 : (errno ? errno : EIO);
  if (std::fclose(f) != 0 && err == 0) err = errno ? errno : EIO;
  return err;
}

bool write_file_atomically(const std::string& path, const std::string& contents, std::string* error) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  int err = write_whole_file(tmp, contents);
  if (err == 0 && std::rename(tmp.c_str(), path.c_str()) != 0) err = errno;
  if (err != 0) {
    std::remove(tmp.c_str());
    *error = path + ":0: cannot write: " + std::strerror(err);
  }
  return err == 0;
}

}  // namespace keepless::io
