// libFuzzer harness for keepless::io's BAL reader. Oracle: a problem that
// parses is written and parsed back to the same problem (values and their
// text), and writing it again gives the same bytes; anything else must be a
// clean error "NAME:LINE: reason".

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_check.hpp"
#include "keepless/io/bal_problem.hpp"


extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace io = keepless::io;
  const std::string text(reinterpret_cast<const char*>(data), size);
  io::BalProblem p;
  std::string error;
  if (!io::parse_bal("fuzz", text, &p, &error)) {
    KEEPLESS_FUZZ_CHECK(error.rfind("fuzz:", 0) == 0 && error.find(": ", 5) != std::string::npos);
    return 0;
  }
  const std::string written = io::format_bal(p);
  io::BalProblem q;
  KEEPLESS_FUZZ_CHECK(io::parse_bal("fuzz", written, &q, &error));
  KEEPLESS_FUZZ_CHECK(q.num_cameras == p.num_cameras && q.num_points == p.num_points &&
        q.observations.size() == p.observations.size() && q.camera_params == p.camera_params &&
        q.point_params == p.point_params && q.camera_text == p.camera_text && q.point_text == p.point_text);
  for (std::size_t i = 0; i < p.observations.size(); ++i) {
    const auto& a = p.observations[i];
    const auto& b = q.observations[i];
    KEEPLESS_FUZZ_CHECK(a.camera == b.camera && a.point == b.point && a.x == b.x && a.y == b.y && a.x_text == b.x_text &&
          a.y_text == b.y_text);
  }
  KEEPLESS_FUZZ_CHECK(io::format_bal(q) == written);
  return 0;
}
