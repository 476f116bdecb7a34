#pragma once
// Whole-file reads and writes. A write never leaves a partial file: the
// contents go to a temporary name, renamed over the target once complete.

#include <cstdint>
#include <string>

namespace keepless::io {

// False with *error "PATH:0: reason" when the file cannot be read, is not
// a regular file (a FIFO or a device is refused, never waited on) or holds
// more than max_bytes (refused before it is read).
[[nodiscard]] bool read_file(const std::string& path, std::string* out, std::string* error,
                             std::uint64_t max_bytes = UINT64_MAX);

// Writes `contents` to `path` (created or truncated); 0 or an errno value.
[[nodiscard]] int write_whole_file(const std::string& path, const std::string& contents);

// Writes PATH.tmp-<pid>, then renames it over PATH (platform::AtomicFileWriter);
// false with *error "PATH:0: reason" (and nothing at PATH changed) on failure.
[[nodiscard]] bool write_file_atomically(const std::string& path, const std::string& contents, std::string* error);

}  // namespace keepless::io
