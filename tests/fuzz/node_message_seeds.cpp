// Writes the seed corpus of node_message_fuzzer into argv[1]: op streams
// (node_message_input.hpp) for a sliding, culling stream; map events with
// good and bad items; a reset; a restart; absurd sequence and utime; two
// publishers; bit flips and raw bytes.

#include <cstdio>
#include <string>
#include <vector>

#include "node_message_input.hpp"

namespace fz = keepless::fuzz;

namespace {

using Bytes = std::vector<unsigned char>;

// op kKeyframe: flags, [i64 sequence], [i64 utime], id, n, base, stride.
void keyframe(Bytes& b, unsigned char flags, unsigned char id, unsigned char n, unsigned char base) {
  b.insert(b.end(), {fz::kKeyframe, flags});
  if (flags & 0x40) b.push_back(1);
  if (flags & 1) b.insert(b.end(), {0x7f, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff});
  if (flags & 2) b.insert(b.end(), {0x7f, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff});
  b.insert(b.end(), {id, n, base, 0});
}

void stream(Bytes& b, int count) {
  for (int i = 0; i < count; ++i) keyframe(b, 0, static_cast<unsigned char>(i), 19, static_cast<unsigned char>(i * 4));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  std::vector<Bytes> seeds(9);
  stream(seeds[0], 8);
  stream(seeds[1], 5);  // + a map event: delete 2, merge 2 (one into a culled id), remove 1 known + 1 unknown
  seeds[1].insert(seeds[1].end(), {fz::kMapEvent, 0, 2, 2, 2, 3, 4, 5, 6, 7, 8, 2, 31});
  stream(seeds[2], 3);
  seeds[2].insert(seeds[2].end(), {fz::kMapEvent, 1, 0, 0, 0});  // reset
  stream(seeds[2], 3);
  stream(seeds[3], 4);
  for (int i = 0; i < 4; ++i) keyframe(seeds[3], 0x40, static_cast<unsigned char>(20 + i), 10, 0);  // steps back: a restart
  stream(seeds[4], 3);
  keyframe(seeds[4], 1, 9, 5, 0);  // absurd sequence
  keyframe(seeds[4], 2, 10, 5, 0);  // absurd utime
  stream(seeds[4], 2);
  for (int i = 0; i < 6; ++i) keyframe(seeds[5], static_cast<unsigned char>((i % 2) << 2), static_cast<unsigned char>(i), 12, static_cast<unsigned char>(i * 3));
  stream(seeds[6], 3);
  seeds[6].insert(seeds[6].end(), {fz::kFlippedKeyframe, 0, 4, 10, 0, 0, 97, 3});
  seeds[6].insert(seeds[6].end(), {fz::kFlippedMapEvent, 0, 1, 0, 0, 3, 30, 5});
  stream(seeds[7], 2);
  keyframe(seeds[7], 0x10, 5, 4, 0);  // non-unit quaternion
  keyframe(seeds[7], 0x20, 6, 4, 0);  // NaN keypoint
  seeds[7].insert(seeds[7].end(), {fz::kRawKeyframe, 0x01, 0x02, 0x03});
  stream(seeds[8], 2);
  seeds[8].insert(seeds[8].end(), {fz::kMapEvent, 2, 1, 0, 0, 5});  // stale sequence
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    const std::string path = std::string(argv[1]) + "/seed_" + std::to_string(i);
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) return 1;
    std::fwrite(seeds[i].data(), 1, seeds[i].size(), f);
    std::fclose(f);
  }
  return 0;
}
