#pragma once
// Real-time set-up of a process: CPU affinity and locked memory. Both report
// what the OS granted or why it refused; neither is fatal.

#include <cstdint>
#include <string>

namespace keepless::platform {

struct PinResult {
  bool ok = false;
  std::string granted;  // CPUs the kernel reports after the call, e.g. "0,1"
  std::string error;    // strerror text when refused
};

// Parses "0,1" or "0-3"; false on malformed text or CPU >= 1024.
[[nodiscard]] bool parse_cpu_list(const std::string& text, std::uint64_t mask_out[16]);
// ok only when the process now runs on exactly those CPUs (a list the kernel
// grants in part is an error, with `granted` saying what it kept).
[[nodiscard]] PinResult pin_to_cpus(const std::string& cpu_list);
std::string current_cpus();

struct LockResult {
  bool ok = false;
  std::string error;
};
// mlockall(MCL_CURRENT | MCL_FUTURE).
[[nodiscard]] LockResult lock_memory();

}  // namespace keepless::platform
