#include "keepless/platform/window_file_io.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "keepless/platform/atomic_file_writer.hpp"
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
  if (const std::string problem = core::window_file_problem(file); !problem.empty()) {
    *error = path + ": " + problem + " (nothing written)";
    return false;
  }
  AtomicFileWriter out(path);
  if (out.open_error() != 0) {
    *error = path + ": cannot open for writing: " + std::strerror(out.open_error());
    return false;
  }
  // One keyframe at a time keeps the buffer small for a whole map.
  std::string chunk;
  for (std::size_t k = 0; k < file.keyframes.size(); ++k) {
    chunk.clear();
    core::append_window_keyframe(&chunk, file.keyframes[k], file.observations[k]);
    if (!out.write(chunk)) break;
  }
  if (const int err = out.commit(); err != 0) {
    *error = path + ": write failed: " + std::strerror(err);
    return false;
  }
  return true;
}

}  // namespace keepless::platform
