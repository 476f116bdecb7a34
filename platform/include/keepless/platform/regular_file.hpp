#pragma once
// Opening an input file that will be read to its end. Only regular files are
// read: a FIFO or a device may never end, and a FIFO without a writer would
// block the open itself.

#include <cstdint>
#include <string>

namespace keepless::platform {

// Closes the descriptor it holds; -1 when the open was refused.
struct RegularFile {
  RegularFile() = default;
  RegularFile(const RegularFile&) = delete;
  RegularFile& operator=(const RegularFile&) = delete;
  ~RegularFile();

  int fd = -1;
  std::uint64_t size = 0;  // bytes at open time
};

// Opens `path` for reading without blocking, refuses anything but a regular
// file, then restores blocking reads. False with *problem, one phrase
// without the path: "cannot open: <strerror>", "is a directory, not a file",
// "not a regular file (refused: it may never end)".
bool open_regular_file(const std::string& path, RegularFile* file, std::string* problem);

}  // namespace keepless::platform
