#include "keepless/platform/regular_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace keepless::platform {

// Inputs may exceed 2 GiB: 32-bit builds define _FILE_OFFSET_BITS=64
// (top-level CMakeLists.txt), or open/fstat would fail with EOVERFLOW.
static_assert(sizeof(off_t) == 8, "64-bit file offsets needed (_FILE_OFFSET_BITS=64 on 32-bit targets)");

RegularFile::~RegularFile() {
  if (fd >= 0) ::close(fd);
}

bool open_regular_file(const std::string& path, RegularFile* file, std::string* problem) {
  const auto fail = [&](const char* what, int err) {
    *problem = std::string(what) + (err != 0 ? std::string(": ") + std::strerror(err) : std::string());
    if (file->fd >= 0) ::close(file->fd);
    file->fd = -1;
    return false;
  };
  // O_NONBLOCK: opening a FIFO without a writer would otherwise wait forever.
  file->fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (file->fd < 0) return fail("cannot open", errno);
  struct stat st {};
  if (::fstat(file->fd, &st) != 0) return fail("cannot open", errno);
  if (S_ISDIR(st.st_mode)) return fail("is a directory, not a file", 0);
  if (!S_ISREG(st.st_mode)) return fail("not a regular file (refused: it may never end)", 0);
  const int flags = ::fcntl(file->fd, F_GETFL);
  if (flags < 0 || ::fcntl(file->fd, F_SETFL, flags & ~O_NONBLOCK) != 0) return fail("cannot open", errno);
  file->size = static_cast<std::uint64_t>(st.st_size);
  return true;
}

}  // namespace keepless::platform
