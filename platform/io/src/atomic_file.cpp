#include "keepless/io/atomic_file.hpp"

#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace keepless::io {

// COLMAP models, BAL problems and keyframe files may exceed 2 GiB: 32-bit
// builds define _FILE_OFFSET_BITS=64 (top-level CMakeLists.txt), or fopen
// would fail with EOVERFLOW.
static_assert(sizeof(off_t) == 8, "64-bit file offsets needed (_FILE_OFFSET_BITS=64 on 32-bit targets)");

bool read_file(const std::string& path, std::string* out, std::string* error) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    *error = path + ":0: cannot read: " + std::strerror(errno);
    return false;
  }
  out->clear();
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0) out->append(buffer, n);
  const bool ok = std::ferror(f) == 0;
  const int err = errno;
  std::fclose(f);
  if (!ok) *error = path + ":0: cannot read: " + std::strerror(err);
  return ok;
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
