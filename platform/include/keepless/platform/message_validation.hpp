#pragma once
// Checks every incoming keepless message passes before it can touch the
// window: first on the raw bytes (fingerprint, declared counts against the
// configured limits, exact length), so an oversize or malformed message is
// refused before decoding costs anything; then on the decoded content
// (ordering, finite numbers, field ranges, known/duplicate ids). Nothing here
// allocates; scratch buffers are supplied by the caller.

#include <cstddef>
#include <cstdint>
#include <vector>

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
  kSequenceJump,          // sequence implausibly far above the last accepted one
  kUtimeJump,             // utime implausibly far above the last accepted one
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
// After the arrays: int64 publisher_id, int32 num_tracked, then its int8
// flags (0 or num_observations of them).
constexpr std::size_t kKeyframeTrailerBytes = 12;
constexpr std::size_t kMapEventCountOffset = 25;          // 3 x int32: deleted, merged, removed
constexpr std::size_t kMapEventHeaderBytes = 37;
constexpr std::size_t kMapEventTrailerBytes = 8;          // int64 publisher_id
// Fixed-offset header fields of keyframe_t (after the fingerprint).
constexpr std::size_t kKeyframeSequenceOffset = 8;
constexpr std::size_t kKeyframeUtimeOffset = 16;
constexpr std::size_t kKeyframeIdOffset = 24;
}  // namespace wire

// Raw-byte checks: fingerprint, then counts, then exact length.
RejectReason check_keyframe_bytes(const void* data, std::size_t size, const MessageLimits& limits);
RejectReason check_map_event_bytes(const void* data, std::size_t size, const MessageLimits& limits);

// The stream-order policy (README: "Stream-order policy"). Each publisher
// (keyframe_t/map_event_t.publisher_id) has its own order: sequence strictly
// increasing, utime never decreasing, and neither jumping further than the
// bounds. A refused message never moves the order. A run of
// `restart_confirm` consecutive messages of one publisher that the order
// refused but that are in order among themselves (no accepted message of that
// publisher in between) becomes the new order: a restart (sequence back near
// 0) or a poisoned order (one absurd message accepted first) is served again
// from the run's last message. A refused run interleaved with accepted
// traffic is a second stream on one publisher id: counted, never adopted.
struct OrderBounds {
  std::uint64_t max_sequence_jump = 1000000;          // messages
  std::uint64_t max_utime_jump_us = 600ull * 1000000;  // 10 minutes
  std::uint32_t restart_confirm = 3;                   // messages
};

struct StreamOrder {
  std::int64_t publisher = 0;
  bool started = false;
  std::int64_t last_sequence = -1;
  std::int64_t last_utime = 0;
  // The run of consecutive refused messages (see above).
  std::uint32_t run_length = 0;
  std::int64_t run_sequence = 0;
  std::int64_t run_utime = 0;
  bool run_interleaved = false;  // an accepted message since the run began
  bool run_reported = false;     // counted as a conflict already
  std::uint64_t last_used = 0;   // tracker tick, for eviction
};

// kNone, or why (sequence, utime) does not follow `order`: kOutOfOrder,
// kUtimeBackwards, kSequenceJump, kUtimeJump.
RejectReason check_order(const StreamOrder& order, std::int64_t sequence, std::int64_t utime,
                         const OrderBounds& bounds = {});

// The orders of up to `max_publishers` publishers (least recently used one
// evicted for a new one). Allocates only in the constructor.
class OrderTracker {
 public:
  OrderTracker(const OrderBounds& bounds, std::uint32_t max_publishers);

  struct Verdict {
    RejectReason reason = RejectReason::kNone;  // kNone: in order (possibly by adopting a run)
    bool adopted = false;                       // a refused run became the order with this message
    bool went_back = false;                     // ... and its sequence is below the old order's: a restart
  };
  // Checks one message; on a refusal records it in the publisher's run, and
  // when the run is confirmed adopts it (then reason is kNone, adopted set).
  // The caller then calls accept() or, if the message fails other checks,
  // nothing.
  Verdict check(std::int64_t publisher, std::int64_t sequence, std::int64_t utime);
  // The message passed every check: it becomes the publisher's order.
  void accept(std::int64_t publisher, std::int64_t sequence, std::int64_t utime);
  void clear();

  std::uint64_t sequence_gaps() const { return gaps_; }
  std::uint64_t restarts() const { return restarts_; }
  std::uint64_t conflicts() const { return conflicts_; }
  std::uint64_t publishers_seen() const { return seen_; }
  std::uint32_t publishers_active() const { return active_; }
  bool started() const { return last_ != nullptr; }
  std::int64_t last_sequence() const { return last_ != nullptr ? last_->last_sequence : -1; }
  const StreamOrder* find(std::int64_t publisher) const;
  std::size_t memory_bytes() const { return slots_.size() * sizeof(StreamOrder); }

 private:
  StreamOrder& slot(std::int64_t publisher);

  OrderBounds bounds_;
  std::vector<StreamOrder> slots_;
  std::uint32_t active_ = 0;
  std::uint64_t tick_ = 0;
  std::uint64_t gaps_ = 0, restarts_ = 0, conflicts_ = 0, seen_ = 0;
  const StreamOrder* last_ = nullptr;  // the publisher of the last accepted message
};

// Decoded keyframe against the window (not the order: see check_order).
// `scratch` must hold msg.num_observations ids.
RejectReason check_keyframe(const keepless::keyframe_t& msg, const core::Window& window,
                            std::uint64_t* scratch);

// A decoded map event's lists, split into the items to apply and the ones
// refused (per item, map_event_ack_t.ITEM_*): no valid deletion or merge is
// lost because of an unrelated bad id. Merges are refused for a self-merge,
// a repeated source (the first is applied), a chain (the target is a source
// of this event), a target deleted by this event, or a target in `culled`
// (may be null); removals for a keyframe not in the window or removed twice.
struct MapEventItems {
  // Into caller storage: each array holds max_event_ids entries.
  std::int64_t* merged_from = nullptr;
  std::int64_t* merged_into = nullptr;
  std::uint32_t merged = 0;
  std::int64_t* removed = nullptr;
  std::uint32_t removed_count = 0;
  // Refused items (up to 2 * max_event_ids).
  std::int64_t* refused_id = nullptr;
  std::int8_t* refused_reason = nullptr;
  std::uint32_t refused = 0;
};
class RecentIds;
// `scratch` must hold num_deleted_points + num_merged_points ids. The counts
// must already match the arrays (check_map_event).
void split_map_event(const keepless::map_event_t& msg, const core::Window& window, const RecentIds* culled,
                     std::uint64_t* scratch, MapEventItems& out);

// Decoded map event: counts consistent with the arrays (kInvalidField).
RejectReason check_map_event(const keepless::map_event_t& msg);

}  // namespace keepless::platform
