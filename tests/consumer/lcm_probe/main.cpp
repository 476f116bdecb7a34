#include <cstdio>

#include <lcm/lcm-cpp.hpp>

#include "keepless/decision_t.hpp"

int main() {
  keepless::decision_t d{};
  lcm::LCM bus("memq://");
  std::printf("decision_t: %d bytes, bus %s\n", d.getEncodedSize(), bus.good() ? "good" : "bad");
  return bus.good() ? 0 : 1;
}
