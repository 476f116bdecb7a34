#pragma once
// The seed corpus of node_message_fuzzer (written by node_message_seeds.cpp,
// replayed by tests/lcm/node_fuzz_seeds_test.cpp): op streams
// (node_message_input.hpp) for a sliding, culling stream; map events with
// good and bad items; a reset; a restart; absurd sequence and utime; two
// publishers; bit flips and raw bytes; and the stray traffic that must
// change nothing: another publisher's reset, retransmissions, a restart run
// ending in an invalid keyframe, stale empty map events, a straggler inside
// a restart, another publisher's far-ahead messages and its takeover after
// the owner's silence, a refused merge before a valid one.

#include <vector>

#include "node_message_input.hpp"

namespace keepless::fuzz {

namespace detail {

namespace fz = keepless::fuzz;
using Bytes = std::vector<unsigned char>;

// op kKeyframe: flags, step (read always: back 1 with flags & 0x40, else on 1),
// [i64 sequence], [i64 utime], id, n, base, stride.
inline void keyframe(Bytes& b, unsigned char flags, unsigned char id, unsigned char n, unsigned char base) {
  b.insert(b.end(), {fz::kKeyframe, flags});
  b.push_back((flags & 0x40) ? 1 : 0);
  if (flags & 1) b.insert(b.end(), {0x7f, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff});
  if (flags & 2) b.insert(b.end(), {0x7f, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff});
  b.insert(b.end(), {id, n, base, 0});
}

// Every field explicit: flags, step (read always), [i64 sequence if flags & 1],
// id, n, base, stride.
inline void keyframe_at(Bytes& b, unsigned char flags, unsigned char step, long long sequence, unsigned char id,
                 unsigned char n, unsigned char base) {
  b.insert(b.end(), {fz::kKeyframe, flags, step});
  if (flags & 1) {
    for (int i = 7; i >= 0; --i) b.push_back(static_cast<unsigned char>((static_cast<unsigned long long>(sequence) >> (8 * i)) & 0xff));
  }
  b.insert(b.end(), {id, n, base, 1});
}

// In order, 16 observations each (the fuzzer's --max-observations; more are refused unread).
// Ids first.., points from 4 * id.
inline void stream(Bytes& b, int count, int first = 0) {
  for (int i = first; i < first + count; ++i) keyframe(b, 0, static_cast<unsigned char>(i), 16, static_cast<unsigned char>(i * 4));
}

}  // namespace detail


inline std::vector<std::vector<unsigned char>> node_message_seed_corpus() {
  using namespace detail;
  std::vector<Bytes> seeds(16);
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
  stream(seeds[4], 2, 3);  // the stream goes on
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
  // Stray traffic (each must leave the owner's state alone).
  for (int i = 0; i < 6; ++i) keyframe_at(seeds[9], 0, 0, 0, static_cast<unsigned char>(i), 12, static_cast<unsigned char>(i * 4));
  seeds[9].insert(seeds[9].end(), {fz::kMapEvent, 1 | (1 << 2), 0, 0, 0});  // a reset from publisher base + 1
  for (int i = 0; i < 6; ++i) keyframe_at(seeds[10], 0, 0, 0, static_cast<unsigned char>(i), 12, static_cast<unsigned char>(i * 4));
  for (int i = 3; i < 6; ++i) keyframe_at(seeds[10], 1, 0, i + 1, static_cast<unsigned char>(i), 12, static_cast<unsigned char>(i * 4));  // retransmitted
  for (int i = 0; i < 6; ++i) keyframe_at(seeds[11], 0, 0, 0, static_cast<unsigned char>(i), 12, static_cast<unsigned char>(i * 4));
  keyframe_at(seeds[11], 1, 0, 1, 20, 8, 40);
  keyframe_at(seeds[11], 1, 0, 2, 21, 8, 40);
  keyframe_at(seeds[11], 1 | 0x20, 0, 3, 22, 8, 40);  // NaN: no restart
  keyframe_at(seeds[11], 1, 0, 4, 23, 8, 40);         // the restart's third valid keyframe
  for (int i = 0; i < 6; ++i) keyframe_at(seeds[12], 0, 0, 0, static_cast<unsigned char>(i), 12, static_cast<unsigned char>(i * 4));
  for (int i = 0; i < 3; ++i) seeds[12].insert(seeds[12].end(), {fz::kMapEvent, 2, 7, 0, 0, 0});  // stale, empty
  for (int i = 0; i < 8; ++i) keyframe_at(seeds[13], 0, 0, 0, static_cast<unsigned char>(i), 12, static_cast<unsigned char>(i * 4));
  keyframe_at(seeds[13], 1, 0, 1, 20, 8, 40);  // the new process
  keyframe_at(seeds[13], 0, 0, 0, 9, 8, 30);   // the old one's straggler
  for (int i = 2; i < 6; ++i) keyframe_at(seeds[13], 1, 0, i, static_cast<unsigned char>(19 + i), 8, 40);
  for (int i = 0; i < 6; ++i) {
    keyframe_at(seeds[14], 0, 0, 0, static_cast<unsigned char>(i), 12, static_cast<unsigned char>(i * 4));
    keyframe_at(seeds[14], 1 | (1 << 2), 0, 5000000, static_cast<unsigned char>(24 + i), 4, 0);  // another id, far ahead
  }
  seeds[14].push_back(fz::kAdvanceClock);
  seeds[14].push_back(0);
  keyframe_at(seeds[14], 1 << 2, 0, 0, 30, 10, 8);  // publisher base + 1 takes over
  stream(seeds[15], 4);
  seeds[15].insert(seeds[15].end(), {fz::kMapEvent, 0, 0, 2, 0, 5, 5, 5, 25});  // 5 -> 5 refused, 5 -> 25 applied
  return seeds;
}

}  // namespace keepless::fuzz
