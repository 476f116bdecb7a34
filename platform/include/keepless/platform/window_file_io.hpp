#pragma once
// Window files on disk (the format: keepless/core/window_file.hpp). Reading
// streams the file through core::WindowFileParser in fixed chunks, so memory
// follows the records, not the file size; only regular files are read, and
// the open never blocks (a FIFO without a writer, a device, a directory are
// refused on line 0).

#include <string>

#include "keepless/core/window_file.hpp"

namespace keepless::platform {

// On failure returns false and sets *error to one line "PATH:LINE: reason"
// (LINE 0 when the file cannot be opened or is not a regular file).
[[nodiscard]] bool read_window_file(const std::string& path, core::WindowFile* out, std::string* error,
                                    const core::WindowFileLimits& limits = {});

// Writes `file` to `path` keyframe by keyframe, under a temporary name
// renamed over it; false + *error on I/O failure or a file that would not
// read back (core::window_file_problem), nothing at PATH changed.
[[nodiscard]] bool write_window_file(const std::string& path, const core::WindowFile& file, std::string* error);

}  // namespace keepless::platform
