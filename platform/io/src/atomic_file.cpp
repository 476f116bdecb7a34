#include "keepless/io/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "keepless/platform/atomic_file_writer.hpp"
#include "keepless/platform/regular_file.hpp"

namespace keepless::io {

bool read_file(const std::string& path, std::string* out, std::string* error, std::uint64_t max_bytes) {
  platform::RegularFile f;
  std::string problem;
  if (platform::open_regular_file(path, &f, &problem) && f.size > max_bytes) {
    problem = std::to_string(f.size) + " bytes, more than the " + std::to_string(max_bytes) + " expected";
  } else if (problem.empty()) {
    out->clear();
    out->reserve(static_cast<std::size_t>(f.size));
    char buffer[1 << 16];
    for (;;) {
      const ssize_t n = ::read(f.fd, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) problem = std::string("cannot read: ") + std::strerror(errno);
      if (n <= 0) break;
      if (out->size() + static_cast<std::size_t>(n) > max_bytes) {  // it grew since
        problem = "more than the " + std::to_string(max_bytes) + " bytes expected";
        break;
      }
      out->append(buffer, static_cast<std::size_t>(n));
    }
  }
  if (problem.empty()) return true;
  *error = path + ":0: " + problem;
  return false;
}

int write_whole_file(const std::string& path, const std::string& contents) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return errno;
  errno = 0;  // so a short write without an errno reads EIO, not an earlier call's error
  int err = std::fwrite(contents.data(), 1, contents.size(), f) == contents.size() ? 0 : (errno ? errno : EIO);
  if (std::fclose(f) != 0 && err == 0) err = errno ? errno : EIO;
  return err;
}

bool write_file_atomically(const std::string& path, const std::string& contents, std::string* error) {
  platform::AtomicFileWriter out(path);
  out.write(contents);
  const int err = out.commit();
  if (err != 0) *error = path + ":0: cannot write: " + std::strerror(err);
  return err == 0;
}

}  // namespace keepless::io
