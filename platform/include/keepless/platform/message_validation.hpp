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
  kNonFinite,             // NaN/inf in any number
  kInvalidField,          // negative count, bad image size, non-unit quaternion, bad optional count
  kUnknownKeyframe,       // names a keyframe not in the window
  kDuplicateKeyframe,     // keyframe id already in the window
  kDuplicateObservation,  // one point twice in one keyframe
  kOutOfOrder,            // sequence not above the last accepted one
  kUtimeBackwards,        // utime below the last accepted one
  kWindowCapacity,        // valid, but the window cannot hold it
  kSequenceJump,          // sequence implausibly far above the last accepted one
  kUtimeJump,             // utime implausibly far above the last accepted one
  kNotOwner,              // another publisher owns the window
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
// After the flags: int32 num_quality, then per observation int32
// track_length, int32 age, float reprojection_error, float
// triangulation_angle (four arrays of num_quality each).
constexpr std::size_t kKeyframeQualityCountBytes = 4;
constexpr std::size_t kKeyframeBytesPerQuality = 16;
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

// The stream-order policy (README: "Stream-order policy"), in five rules:
// 1. The window belongs to one stream, its owner (a publisher_id; 0 for an
//    anonymous VO): the first valid keyframe's publisher. Another publisher's
//    messages are refused (kNotOwner) unless the owner has been silent for
//    OrderBounds::owner_timeout_ns (0: never); then that publisher's next
//    valid keyframe takes the window over (cleared first). Map events never
//    take over; before the first keyframe there is no order to refuse them
//    by, so they are applied to the empty window and set nothing.
// 2. The owner's order: sequence strictly increasing, utime never
//    decreasing, neither jumping further than the bounds; the utime bound
//    grows by the time since the order last accepted a message (a VO that
//    makes keyframes on motion may pause for longer than the bound).
// 3. A refused or invalid message changes nothing. The one exception is the
//    candidate runs (kCandidateRuns of them): owner keyframes valid against
//    the window but refused by the order, each in order with its run's
//    last one. A keyframe extends the longest run it continues; one that
//    continues none starts a run in place of the shortest (the least
//    recently extended of equals); a duplicate does neither: a copy of the
//    last accepted message or of one of the last recent_keyframes accepted
//    keyframes (same sequence and content hash: a retransmission), or a
//    keyframe with the sequence of a run's last one. A keyframe whose id is
//    in the window counts only if it is no such copy and is later than the
//    last accepted message (reissues()): a VO restarted within its first
//    keyframes sends its sequences and ids again, with other content and
//    later utimes; a second process behind the owner, or late copies of a
//    dead process's keyframes, are earlier. Every accepted message clears
//    the runs. A restart run starts at a sequence in
//    0..kRestartMaxFirstSequence that does not follow the order as it was
//    before the last accepted message, and is continued only in steps of at
//    most kRestartMaxFirstSequence (stragglers of an old run never break or
//    complete it): `restart_confirm` keyframes are a restart (the last one
//    is accepted, the window and the cull memory are cleared), if its last
//    is later than the last accepted message or the order has accepted
//    nothing for the resync's silence (late copies of a start the order never
//    accepted are earlier, into a live order). Every other run is a resync
//    run: `restart_confirm` keyframes, once the order has accepted nothing
//    for kResyncSilenceNs (or owner_timeout_ns if shorter and not 0), are a
//    resync: the last one is accepted and becomes the order, the window
//    kept; a run behind the order in both fields (behind_the_stream) only
//    once it has been heard for that silence too (a flush of the stream's
//    past arrives at once). A resync undoes an order set by messages the
//    stream does not continue (a corrupted sequence, a clock step, a first
//    message heard mid-run), early in a stream too; without it such a
//    message locked the owner out.
// 4. A reset is honoured only from the owner, in order.
// 5. Only a newer accepted keyframe of the owner supersedes a queued one
//    (Node's drain).
struct OrderBounds {
  std::uint64_t max_sequence_jump = 1000000;          // messages
  std::uint64_t max_utime_jump_us = 600ull * 1000000;  // 10 minutes
  std::uint32_t restart_confirm = 3;                   // keyframes
  std::uint64_t owner_timeout_ns = 1000000000ull;      // 1 s; 0: the owner is never replaced
  // Accepted keyframes whose sequence and content hash are remembered, to
  // tell a retransmission from a restarted VO's keyframe (rule 3); the node
  // remembers its window's (--window). Allocated once, at construction.
  std::uint32_t recent_keyframes = 20;
};
// A restart candidate starts at a sequence no larger than this.
constexpr std::int64_t kRestartMaxFirstSequence = 16;
// Candidate runs held at once: a duplicate or straggler starts its own run
// instead of replacing the stream's (kCandidateRuns or more out-of-order
// keyframes after each of the stream's would still displace it).
constexpr std::size_t kCandidateRuns = 4;
// The longest silence of the order a resync waits for (rule 3).
constexpr std::uint64_t kResyncSilenceNs = 1000000000ull;

// A message's bytes, hashed (64 bits; not cryptographic, the same within one
// process): a retransmission repeats them, so it repeats the hash.
std::uint64_t message_hash(const void* data, std::size_t size);

// The owner and its order (rules 1-3 above). check() is pure; the node
// calls accept() for a message it accepted, extend_restart() for a valid
// keyframe the order refused, and nothing for any other refusal. `hash` is
// the message's message_hash().
class OrderTracker {
 public:
  explicit OrderTracker(const OrderBounds& bounds);

  struct Verdict {
    RejectReason reason = RejectReason::kNone;  // kNone: accept (possibly by takeover or restart)
    bool takeover = false;  // a new owner: clear the window and the culls first
    bool restart = false;   // the owner restarted: clear the window and the culls first
    bool resync = false;    // the owner's stream replaces an order it does not continue; window kept
  };
  [[nodiscard]] Verdict check(std::int64_t publisher, std::int64_t sequence, std::int64_t utime,
                              std::uint64_t hash, std::uint64_t now_ns, bool keyframe) const;
  // The message passed every check. A map event accepted before any owner
  // (rule 1) sets nothing. An accepted keyframe is remembered (rule 3).
  void accept(const Verdict& v, std::int64_t publisher, std::int64_t sequence, std::int64_t utime,
              std::uint64_t hash, std::uint64_t now_ns, bool keyframe);
  // An owner keyframe, valid against the window (or valid but for an id in
  // it), refused by the order: extends (or starts) a candidate run. Returns
  // true if it did.
  bool extend_restart(std::int64_t publisher, std::int64_t sequence, std::int64_t utime, std::uint64_t hash,
                      std::uint64_t now_ns);
  // A keyframe later than the last accepted message and no retransmission:
  // one that may belong to a restart though its id is in the window (rule 3).
  bool reissues(std::int64_t sequence, std::int64_t utime, std::uint64_t hash) const;

  bool owned() const { return owned_; }
  std::int64_t owner() const { return owner_; }
  std::int64_t last_sequence() const { return owned_ ? last_sequence_ : -1; }
  std::int64_t last_utime() const { return last_utime_; }
  std::uint64_t last_heard_ns() const { return last_heard_ns_; }
  std::uint64_t sequence_gaps() const { return gaps_; }
  std::uint64_t restarts() const { return restarts_; }
  std::uint64_t resyncs() const { return resyncs_; }
  std::uint64_t takeovers() const { return takeovers_; }
  std::uint64_t owners_seen() const { return owners_seen_; }
  std::uint32_t recent_capacity() const { return static_cast<std::uint32_t>(recent_.size()); }
  std::size_t memory_bytes() const { return sizeof(*this) + recent_.capacity() * sizeof(Recent); }

 private:
  struct Run {
    std::uint32_t length = 0;  // 0: the slot is free
    bool restart = false;      // a restart run, else a resync run
    std::int64_t sequence = 0, utime = 0;  // its last keyframe's
    std::uint64_t touched = 0;             // extend_restart() call that last started or extended it
    std::uint64_t first_ns = 0;            // node time of its first keyframe
  };
  bool continues(const Run& run, std::int64_t sequence, std::int64_t utime) const;
  // A copy of the last accepted message or of a remembered keyframe (the
  // last recent_keyframes, and the stream's start): the same sequence and
  // hash (a retransmission).
  bool retransmits(std::int64_t sequence, std::uint64_t hash) const;
  // A retransmission, or the sequence of a run's last keyframe.
  bool repeats(std::int64_t sequence, std::uint64_t hash) const;
  // The run the keyframe would extend, or -1.
  int extended_run(std::int64_t sequence, std::int64_t utime) const;
  // Behind the order in both sequence and utime and not after the order
  // before it: a late copy of the stream's past, which no resync may take.
  bool behind_the_stream(std::int64_t sequence, std::int64_t utime) const;

  OrderBounds bounds_;
  bool owned_ = false;
  std::int64_t owner_ = 0;
  std::int64_t last_sequence_ = -1;
  std::int64_t last_utime_ = 0;
  std::uint64_t last_hash_ = 0;  // the last accepted message's
  std::uint64_t last_heard_ns_ = 0;
  // The order before the last accepted message (none after a takeover):
  // a low run that follows it continues the stream, so it is no restart.
  bool has_previous_ = false;
  std::int64_t previous_sequence_ = 0, previous_utime_ = 0;
  Run runs_[kCandidateRuns];  // the candidates (rule 3)
  // The last recent_keyframes accepted keyframes (a ring; used: recent_used_).
  struct Recent {
    std::int64_t sequence = 0;
    std::uint64_t hash = 0;
  };
  std::vector<Recent> recent_;
  std::size_t recent_next_ = 0, recent_used_ = 0;
  // The hashes of the accepted keyframes with sequence 0 ..
  // kRestartMaxFirstSequence, by sequence (0: none): late copies of a
  // stream's start never start a restart run.
  std::uint64_t start_hash_[kRestartMaxFirstSequence + 1] = {};
  std::uint64_t run_clock_ = 0;
  std::uint64_t gaps_ = 0, restarts_ = 0, resyncs_ = 0, takeovers_ = 0, owners_seen_ = 0;
};

// Decoded keyframe against the window (not the order: see OrderTracker).
// `scratch` must hold msg.num_observations ids.
RejectReason check_keyframe(const keepless::keyframe_t& msg, const core::Window& window,
                            std::uint64_t* scratch);

// A decoded map event's lists, split into the items to apply and the ones
// refused (per item, map_event_ack_t.ITEM_*): no valid deletion or merge is
// lost because of an unrelated bad id. Merges are refused for a self-merge,
// a repeated source (the first valid one is applied), a chain (the target is a source
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
// `scratch` must hold num_deleted_points + 2 * num_merged_points ids. The
// counts must already match the arrays (check_map_event). O(n log n) in the
// lists' lengths.
void split_map_event(const keepless::map_event_t& msg, const core::Window& window, const RecentIds* culled,
                     std::uint64_t* scratch, MapEventItems& out);

// Decoded map event: counts consistent with the arrays (kInvalidField).
RejectReason check_map_event(const keepless::map_event_t& msg);

// For log lines: the field that made a message kInvalidField, e.g.
// "orientation (not a unit quaternion)" or "image_width (must be > 0)".
// Pass the decoded message, or nullptr when its bytes were refused before
// decoding (the array counts are named then).
const char* invalid_keyframe_field(const keepless::keyframe_t* decoded);
const char* invalid_map_event_field(const keepless::map_event_t* decoded);

}  // namespace keepless::platform
