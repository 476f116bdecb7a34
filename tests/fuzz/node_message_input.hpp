#pragma once
// The byte language node_message_fuzzer reads (and its seed writer writes):
// a sequence of ops, each a few bytes, that build keyframe_t / map_event_t
// messages close enough to valid that the fuzzer reaches the window, the
// order policy and the decision path, plus raw and bit-flipped encodings
// for the byte-level checks.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "keepless/keyframe_t.hpp"
#include "keepless/map_event_t.hpp"
#include "message_builders.hpp"

namespace keepless::fuzz {

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
  bool done() const { return p_ >= end_; }
  std::uint8_t u8() { return p_ < end_ ? *p_++ : 0; }
  std::int64_t i64() {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v = (v << 8) | u8();
    return static_cast<std::int64_t>(v);
  }
  const std::uint8_t* rest(std::size_t* n) {
    *n = static_cast<std::size_t>(end_ - p_);
    const std::uint8_t* r = p_;
    p_ = end_;
    return r;
  }

 private:
  const std::uint8_t* p_;
  const std::uint8_t* end_;
};

// kAdvanceClock: the node's clock moves past the owner timeout (the owner
// falls silent, another publisher id may take the window over).
enum Op : std::uint8_t {
  kKeyframe = 0,
  kMapEvent,
  kFlippedKeyframe,
  kFlippedMapEvent,
  kRawKeyframe,
  kAdvanceClock,
  kOpCount
};

// The stream state the builders advance (sequence and utime of the publishers).
struct Stream {
  std::int64_t sequence = 0;
  std::int64_t utime = 1000000;
  std::int64_t publisher_base = 0;  // publisher ids are base + 0..3
};

// flags: bit0 absurd sequence, bit1 absurd utime, bits2-3 publisher,
// bit4 non-unit quaternion, bit5 NaN keypoint, bit6 step back.
inline keepless::keyframe_t build_keyframe(Reader& r, Stream& s) {
  const std::uint8_t flags = r.u8();
  keepless::keyframe_t m{};
  s.sequence += (flags & 0x40) ? -static_cast<std::int64_t>(r.u8() % 4) : 1 + r.u8() % 3;
  s.utime += 100000;
  m.sequence = (flags & 1) ? r.i64() : s.sequence;
  m.utime = (flags & 2) ? r.i64() : s.utime;
  m.publisher_id = s.publisher_base + ((flags >> 2) & 3);
  m.keyframe_id = r.u8() % 32;
  m.centre[0] = static_cast<double>(m.keyframe_id) * 0.5;
  m.orientation[0] = (flags & 0x10) ? 2.0 : 1.0;
  m.image_width = 640;
  m.image_height = 480;
  const int n = r.u8() % 20;
  const std::int64_t base = r.u8() % 48;
  const std::int64_t stride = 1 + r.u8() % 3;
  for (int i = 0; i < n; ++i) {
    const std::int64_t id = (base + i * stride) % 64;
    m.point_id.push_back(id);
    m.u.push_back(static_cast<float>((id * 37 + m.keyframe_id * 11) % 600 + 20));
    m.v.push_back(static_cast<float>((id * 53) % 440 + 20));
  }
  if ((flags & 0x20) && n > 0) m.u[0] = std::numeric_limits<float>::quiet_NaN();
  m.num_observations = n;
  return m;
}

// flags: bit0 reset, bit1 stale sequence, bits2-3 publisher.
inline keepless::map_event_t build_map_event(Reader& r, Stream& s) {
  const std::uint8_t flags = r.u8();
  keepless::map_event_t e{};
  s.sequence += 1;
  s.utime += 1000;
  e.sequence = (flags & 2) ? s.sequence - 1 - r.u8() % 8 : s.sequence;
  e.utime = s.utime;
  e.reset = flags & 1;
  e.publisher_id = s.publisher_base + ((flags >> 2) & 3);
  const int nd = r.u8() % 6, nm = r.u8() % 6, nr = r.u8() % 4;
  for (int i = 0; i < nd; ++i) e.deleted_point_id.push_back(r.u8() % 64);
  for (int i = 0; i < nm; ++i) {
    e.merged_from_id.push_back(r.u8() % 64);
    e.merged_into_id.push_back(r.u8() % 64);
  }
  for (int i = 0; i < nr; ++i) e.removed_keyframe_id.push_back(r.u8() % 32);
  e.num_deleted_points = nd;
  e.num_merged_points = nm;
  e.num_removed_keyframes = nr;
  return e;
}

// One op read as what it sends: a clock advance (in owner timeouts), or a
// keyframe's or map event's bytes, with the message as built before a flip
// (raw bytes build none).
struct Message {
  std::uint8_t op = kAdvanceClock;
  int timeouts = 0;  // kAdvanceClock: 1 or 2
  std::vector<std::uint8_t> bytes;
  keepless::keyframe_t keyframe{};
  keepless::map_event_t event{};
  bool is_keyframe() const { return op == kKeyframe || op == kFlippedKeyframe || op == kRawKeyframe; }
};

inline Message next_message(Reader& r, Stream& s) {
  Message m;
  m.op = r.u8() % kOpCount;
  const auto flip = [&](bool flipped) {
    if (flipped && !m.bytes.empty()) m.bytes[r.u8() % m.bytes.size()] ^= static_cast<std::uint8_t>(1u << (r.u8() % 8));
  };
  if (m.op == kAdvanceClock) {
    m.timeouts = 1 + r.u8() % 2;
  } else if (m.op == kRawKeyframe) {
    std::size_t n = 0;
    const std::uint8_t* raw = r.rest(&n);
    m.bytes.assign(raw, raw + n);
  } else if (m.is_keyframe()) {
    m.keyframe = build_keyframe(r, s);
    m.bytes = keepless::testing::encode(m.keyframe);
    flip(m.op == kFlippedKeyframe);
  } else {
    m.event = build_map_event(r, s);
    m.bytes = keepless::testing::encode(m.event);
    flip(m.op == kFlippedMapEvent);
  }
  return m;
}

}  // namespace keepless::fuzz
