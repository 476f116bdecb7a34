#include "keepless/platform/window_file_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace keepless::platform {

// Window files may exceed 2 GiB: 32-bit builds define _FILE_OFFSET_BITS=64
// (top-level CMakeLists.txt), or open/fstat would fail with EOVERFLOW.
static_assert(sizeof(off_t) == 8, "64-bit file offsets needed (_FILE_OFFSET_BITS=64 on 32-bit targets)");

namespace {

struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

bool read_window_file(const std::string& path, core::WindowFile* out, std::string* error,
                      const core::WindowFileLimits& limits) {
  *out = core::WindowFile{};
  const auto fail = [&](const char* what, int err) {
    *error = path + ":0: " + what + (err != 0 ? std::string(": ") + std::strerror(err) : std::string());
    return false;
  };
  // O_NONBLOCK: opening a FIFO without a writer would otherwise wait forever.
  Fd f;
  f.fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (f.fd < 0) return fail("cannot open", errno);
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) return fail("cannot stat", errno);
  if (!S_ISREG(st.st_mode)) {
    return fail(S_ISDIR(st.st_mode) ? "is a directory, not a window file" : "not a regular file (refused: it may never end)", 0);
  }
  const int flags = ::fcntl(f.fd, F_GETFL);
  if (flags < 0 || ::fcntl(f.fd, F_SETFL, flags & ~O_NONBLOCK) != 0) return fail("cannot read", errno);

  core::WindowFileParser parser(path, limits);
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(f.fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      parser.fail_at(parser.line() + 1, std::string("cannot read: ") + std::strerror(errno));
      break;
    }
    if (n == 0 || !parser.feed(buf, static_cast<std::size_t>(n))) break;
  }
  if (parser.finish(out)) return true;
  *error = parser.error();
  return false;
}

bool write_window_file(const std::string& path, const core::WindowFile& file, std::string* error) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) {
    *error = path + ": cannot open for writing: " + std::strerror(errno);
    return false;
  }
  // One keyframe at a time keeps the buffer small for a whole map.
  std::string chunk;
  bool ok = true;
  for (std::size_t k = 0; ok && k < file.keyframes.size(); ++k) {
    chunk.clear();
    core::append_window_keyframe(&chunk, file.keyframes[k], file.observations[k]);
    ok = std::fwrite(chunk.data(), 1, chunk.size(), f) == chunk.size();
  }
  const int err = errno;
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) *error = path + ": write failed: " + std::strerror(err != 0 ? err : EIO);
  return ok;
}

}  // namespace keepless::platform
