#pragma once
// Writing a file whole or not at all: the bytes go to a temporary name beside
// it, PATH.tmp-<pid>, renamed over PATH once all are written, so a failed or
// abandoned write leaves PATH as it was and no temporary behind. Streamed:
// the caller writes in pieces (a map keyframe by keyframe), so no buffer the
// size of the file is needed.

#include <cstddef>
#include <cstdio>
#include <string>

namespace keepless::platform {

class AtomicFileWriter {
 public:
  // Opens PATH.tmp-<pid> for writing (created or truncated).
  explicit AtomicFileWriter(const std::string& path);
  // Closes and removes the temporary unless commit() was called.
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  // 0 when the temporary is open, else the open's errno value.
  int open_error() const { return open_error_; }

  // Appends `size` bytes. False once the open or any write has failed (a
  // later write does nothing); commit() reports that failure.
  bool write(const char* data, std::size_t size);
  bool write(const std::string& bytes) { return write(bytes.data(), bytes.size()); }

  // Closes the temporary and renames it over PATH; call once. 0, or the
  // errno value of the first failure (open, write, close or rename; EIO when
  // none was set), the temporary then removed and PATH unchanged. (A
  // temporary that could not be opened is not ours: it is left alone.)
  [[nodiscard]] int commit();

 private:
  std::string path_;
  std::string tmp_;
  std::FILE* file_ = nullptr;
  int open_error_ = 0;
  int error_ = 0;  // the first failure's errno value
  bool committed_ = false;
};

}  // namespace keepless::platform
