#include "keepless/platform/window_file_io.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "keepless/platform/regular_file.hpp"

namespace keepless::platform {

bool read_window_file(const std::string& path, core::WindowFile* out, std::string* error,
                      const core::WindowFileLimits& limits) {
  *out = core::WindowFile{};
  RegularFile f;
  std::string problem;
  if (!open_regular_file(path, &f, &problem)) {
    *error = path + ":0: " + problem;
    return false;
  }

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
  // A temporary name beside it, renamed over it once whole: a failed write
  // leaves no partial file at PATH (io::write_file_atomically, streamed).
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
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
  int err = errno;
  ok = (std::fclose(f) == 0) && ok;
  if (ok && std::rename(tmp.c_str(), path.c_str()) != 0) {
    err = errno;
    ok = false;
  }
  if (!ok) {
    *error = path + ": write failed: " + std::strerror(err != 0 ? err : EIO);
    std::remove(tmp.c_str());
  }
  return ok;
}

}  // namespace keepless::platform
