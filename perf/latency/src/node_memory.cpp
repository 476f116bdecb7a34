#include "node_memory.hpp"

#include <cstdio>
#include <cstring>

#ifdef KEEPLESS_HAVE_LCM
#include <lcm/lcm-cpp.hpp>

#include "keepless/platform/node.hpp"
#include "keepless/platform/node_config.hpp"
#endif

namespace keepless::perf {

namespace {

std::uint64_t status_kb(const char* key) {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (f == nullptr) return 0;
  char line[256];
  unsigned long long kb = 0;
  const std::size_t n = std::strlen(key);
  while (std::fgets(line, sizeof line, f) != nullptr) {
    if (std::strncmp(line, key, n) == 0 && std::sscanf(line + n, ": %llu", &kb) == 1) break;
  }
  std::fclose(f);
  return kb * 1024;
}

}  // namespace

std::uint64_t resident_bytes() { return status_kb("VmRSS"); }
std::uint64_t peak_resident_bytes() { return status_kb("VmHWM"); }

bool measure_node_memory(const std::string& profile, NodeMemory* out, std::string* error) {
#ifdef KEEPLESS_HAVE_LCM
  platform::NodeConfig config;
  if (!platform::apply_profile(profile, config)) {
    *error = "unknown profile '" + profile + "' (small, default or large)";
    return false;
  }
  config.url = "memq://";
  out->caps = platform::window_capacities(config);
  out->predicted_bytes = platform::estimate_node_bytes(config);
  lcm::LCM bus(config.url);
  if (!bus.good()) {
    *error = "memq:// is not usable";
    return false;
  }
  const std::uint64_t before = resident_bytes();
  const platform::Node node(bus, config);
  out->rss_growth_bytes = static_cast<std::int64_t>(resident_bytes()) - static_cast<std::int64_t>(before);
  out->counted_bytes = node.memory_bytes();
  return true;
#else
  (void)profile;
  (void)out;
  *error = "--profile needs keepless_node (built with LCM)";
  return false;
#endif
}

}  // namespace keepless::perf
