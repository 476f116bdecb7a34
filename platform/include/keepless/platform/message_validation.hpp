#pragma once
// Checks every incoming keepless message passes before it can touch the
// window: first on the raw bytes (fingerprint, declared counts against the
// configured limits, exact length), so an oversize or malformed message is
// refused before decoding costs anything; then on the decoded content
// (ordering, finite numbers, field ranges, known/duplicate ids). Nothing here
// allocates; scratch buffers are supplied by the caller.

#include <cstddef>
#include <cstdint>

#include "keepless/core/window.hpp"
#include "keepless/keyframe_t.hpp"
#include "keepless/map_event_t.hpp"

namespace keepless::platform {

// Same order and values as status_t.REJECT_* (checked at compile time).
enum class [[nodiscard]] RejectReason : std::uint8_t {
  kOversizeCount = 0,     // a declared count above the configured limit
  kTruncated,             // byte length differs from what the counts need
  kFingerprint,           // not this message type
  kNonFinite,             // NaN/inf in a pose or keypoint
  kInvalidField,          // negative count, bad image size, non-unit quaternion, bad merge list
  kUnknownKeyframe,       // names a keyframe not in the window
  kDuplicateKeyframe,     // keyframe id already in the window
  kDuplicateObservation,  // one point twice in one keyframe
  kOutOfOrder,            // sequence not above the last accepted one
  kUtimeBackwards,        // utime below the last accepted one
  kWindowCapacity,        // valid, but the window cannot hold it
  kNone,                  // accepted
};
constexpr std::size_t kRejectReasonCount = static_cast<std::size_t>(RejectReason::kNone);

const char* to_string(RejectReason r);

struct MessageLimits {
  std::uint32_t max_observations = 2000;  // per keyframe_t
  std::uint32_t max_unmapped = 0;         // unmapped keypoints per keyframe_t
  std::uint32_t max_event_ids = 1024;     // per list of a map_event_t
};

// Wire layout (LCM encodes big-endian; the 8-byte fingerprint comes first).
namespace wire {
constexpr std::size_t kFingerprintBytes = 8;
constexpr std::size_t kKeyframeCountOffset = 96;  // int32 num_observations
constexpr std::size_t kKeyframeHeaderBytes = 100;
constexpr std::size_t kKeyframeBytesPerObservation = 16;  // int64 id + 2 float
// After the observations: int32 num_depths, its floats, int32
// num_intrinsics, its doubles, int32 num_unmapped, its 2 floats each.
constexpr std::size_t kKeyframeOptionalCountBytes = 12;
constexpr std::size_t kMapEventCountOffset = 25;          // 3 x int32: deleted, merged, removed
constexpr std::size_t kMapEventHeaderBytes = 37;
}  // namespace wire

// Raw-byte checks: fingerprint, then counts, then exact length.
RejectReason check_keyframe_bytes(const void* data, std::size_t size, const MessageLimits& limits);
RejectReason check_map_event_bytes(const void* data, std::size_t size, const MessageLimits& limits);

// The last accepted (sequence, utime) of the VO stream, shared by keyframe_t
// and map_event_t.
struct StreamOrder {
  bool started = false;
  std::int64_t last_sequence = -1;
  std::int64_t last_utime = 0;
};
// kOutOfOrder unless sequence > last; kUtimeBackwards if utime < last.
RejectReason check_order(const StreamOrder& order, std::int64_t sequence, std::int64_t utime);

// Decoded keyframe against the window (not the order: see check_order).
// `scratch` must hold msg.num_observations ids.
RejectReason check_keyframe(const keepless::keyframe_t& msg, const core::Window& window,
                            std::uint64_t* scratch);

// Decoded map event against the window. `scratch` must hold
// num_deleted_points + num_merged_points ids. A reset event's lists are not
// checked (they are ignored).
RejectReason check_map_event(const keepless::map_event_t& msg, const core::Window& window,
                             std::uint64_t* scratch);

}  // namespace keepless::platform
