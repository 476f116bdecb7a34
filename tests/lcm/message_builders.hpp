#pragma once
// Small builders for keepless LCM messages in tests.

#include <cstdint>
#include <vector>

#include "keepless/keyframe_t.hpp"
#include "keepless/map_event_t.hpp"

namespace keepless::testing {

// A keyframe at x = id metres, observing `ids` with keypoints on a grid
// spread over a 640x480 image (so boxes overlap a little).
inline keepless::keyframe_t make_keyframe(std::int64_t sequence, std::int64_t keyframe_id,
                                          const std::vector<std::int64_t>& ids) {
  keepless::keyframe_t m{};
  m.sequence = sequence;
  m.utime = 1000000 + sequence * 100000;
  m.keyframe_id = keyframe_id;
  m.centre[0] = static_cast<double>(keyframe_id) * 0.5;
  m.centre[1] = 0;
  m.centre[2] = 0;
  m.orientation[0] = 1;
  m.orientation[1] = m.orientation[2] = m.orientation[3] = 0;
  m.image_width = 640;
  m.image_height = 480;
  m.num_observations = static_cast<std::int32_t>(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    m.point_id.push_back(ids[i]);
    // Position depends on the point and the keyframe, like a moving camera.
    const auto p = static_cast<std::uint64_t>(ids[i]);
    m.u.push_back(static_cast<float>((p * 37 + static_cast<std::uint64_t>(keyframe_id) * 11) % 600 + 20));
    m.v.push_back(static_cast<float>((p * 53) % 440 + 20));
  }
  return m;
}

// Points [first, first + count).
inline std::vector<std::int64_t> id_range(std::int64_t first, std::int64_t count) {
  std::vector<std::int64_t> v;
  for (std::int64_t i = 0; i < count; ++i) v.push_back(first + i);
  return v;
}

inline keepless::map_event_t make_event(std::int64_t sequence) {
  keepless::map_event_t e{};
  e.sequence = sequence;
  e.utime = 1000000 + sequence * 100000;
  e.reset = false;
  return e;
}

inline void finalize(keepless::map_event_t& e) {
  e.num_deleted_points = static_cast<std::int32_t>(e.deleted_point_id.size());
  e.num_merged_points = static_cast<std::int32_t>(e.merged_from_id.size());
  e.num_removed_keyframes = static_cast<std::int32_t>(e.removed_keyframe_id.size());
}

template <class Message>
std::vector<std::uint8_t> encode(const Message& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  const int n = m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  buf.resize(n < 0 ? 0 : static_cast<std::size_t>(n));
  return buf;
}

}  // namespace keepless::testing
