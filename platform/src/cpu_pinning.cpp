#include "keepless/platform/cpu_pinning.hpp"

#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace keepless::platform {
namespace {
constexpr int kMaxCpu = 1024;
}

bool parse_cpu_list(const std::string& text, std::uint64_t mask[16]) {
  for (int i = 0; i < 16; ++i) mask[i] = 0;
  if (text.empty()) return false;
  const char* p = text.c_str();
  while (*p) {
    char* end = nullptr;
    const long lo = std::strtol(p, &end, 10);
    if (end == p || lo < 0 || lo >= kMaxCpu) return false;
    long hi = lo;
    p = end;
    if (*p == '-') {
      hi = std::strtol(p + 1, &end, 10);
      if (end == p + 1 || hi < lo || hi >= kMaxCpu) return false;
      p = end;
    }
    for (long c = lo; c <= hi; ++c) mask[c / 64] |= 1ull << (c % 64);
    if (*p == ',') {
      ++p;
      if (*p == '\0') return false;
    } else if (*p != '\0') {
      return false;
    }
  }
  return true;
}

std::string current_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return "";
  std::string out;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (!CPU_ISSET(c, &set)) continue;
    if (!out.empty()) out += ',';
    out += std::to_string(c);
  }
  return out;
}

PinResult pin_to_cpus(const std::string& cpu_list) {
  PinResult r;
  std::uint64_t mask[16];
  if (!parse_cpu_list(cpu_list, mask)) {
    r.error = "malformed CPU list '" + cpu_list + "'";
    r.granted = current_cpus();
    return r;
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  for (int c = 0; c < kMaxCpu && c < CPU_SETSIZE; ++c) {
    if (mask[c / 64] & (1ull << (c % 64))) CPU_SET(c, &set);
  }
  cpu_set_t got;
  CPU_ZERO(&got);
  if (sched_setaffinity(0, sizeof(set), &set) != 0) {
    r.error = std::strerror(errno);
  } else if (sched_getaffinity(0, sizeof(got), &got) == 0 && !CPU_EQUAL(&got, &set)) {
    // The kernel takes a list holding one usable CPU and drops the rest.
    r.error = "only some of them exist or are allowed";
  } else {
    r.ok = true;
  }
  r.granted = current_cpus();
  return r;
}

LockResult lock_memory() {
  LockResult r;
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    r.error = std::strerror(errno);
  } else {
    r.ok = true;
  }
  return r;
}

}  // namespace keepless::platform
