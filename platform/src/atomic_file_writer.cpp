#include "keepless/platform/atomic_file_writer.hpp"

#include <unistd.h>

#include <cerrno>

namespace keepless::platform {

AtomicFileWriter::AtomicFileWriter(const std::string& path)
    : path_(path), tmp_(path + ".tmp-" + std::to_string(::getpid())) {
  file_ = std::fopen(tmp_.c_str(), "wb");
  if (file_ == nullptr) open_error_ = error_ = errno ? errno : EIO;
}

AtomicFileWriter::~AtomicFileWriter() {
  if (committed_ || open_error_ != 0) return;
  std::fclose(file_);
  std::remove(tmp_.c_str());
}

bool AtomicFileWriter::write(const char* data, std::size_t size) {
  if (error_ != 0) return false;
  errno = 0;  // fwrite need not set it: a stale value would name the wrong cause
  if (std::fwrite(data, 1, size, file_) != size) error_ = errno ? errno : EIO;
  return error_ == 0;
}

int AtomicFileWriter::commit() {
  committed_ = true;
  if (file_ != nullptr) {
    errno = 0;
    if (std::fclose(file_) != 0 && error_ == 0) error_ = errno ? errno : EIO;
    file_ = nullptr;
  }
  if (error_ == 0 && std::rename(tmp_.c_str(), path_.c_str()) != 0) error_ = errno;
  if (error_ != 0 && open_error_ == 0) std::remove(tmp_.c_str());
  return error_;
}

}  // namespace keepless::platform
