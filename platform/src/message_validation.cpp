#include "keepless/platform/message_validation.hpp"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstring>
#include <iterator>

#include "keepless/core/window_file.hpp"
#include "keepless/map_event_ack_t.hpp"
#include "keepless/platform/recent_ids.hpp"
#include "keepless/status_t.hpp"

namespace keepless::platform {

using S = keepless::status_t;
static_assert(static_cast<int>(RejectReason::kOversizeCount) == S::REJECT_OVERSIZE_COUNT);
static_assert(static_cast<int>(RejectReason::kTruncated) == S::REJECT_TRUNCATED);
static_assert(static_cast<int>(RejectReason::kFingerprint) == S::REJECT_FINGERPRINT);
static_assert(static_cast<int>(RejectReason::kNonFinite) == S::REJECT_NON_FINITE);
static_assert(static_cast<int>(RejectReason::kInvalidField) == S::REJECT_INVALID_FIELD);
static_assert(static_cast<int>(RejectReason::kUnknownKeyframe) == S::REJECT_UNKNOWN_KEYFRAME);
static_assert(static_cast<int>(RejectReason::kDuplicateKeyframe) == S::REJECT_DUPLICATE_KEYFRAME);
static_assert(static_cast<int>(RejectReason::kDuplicateObservation) == S::REJECT_DUPLICATE_OBSERVATION);
static_assert(static_cast<int>(RejectReason::kOutOfOrder) == S::REJECT_OUT_OF_ORDER);
static_assert(static_cast<int>(RejectReason::kUtimeBackwards) == S::REJECT_UTIME_BACKWARDS);
static_assert(static_cast<int>(RejectReason::kWindowCapacity) == S::REJECT_WINDOW_CAPACITY);
static_assert(static_cast<int>(RejectReason::kSequenceJump) == S::REJECT_SEQUENCE_JUMP);
static_assert(static_cast<int>(RejectReason::kUtimeJump) == S::REJECT_UTIME_JUMP);
static_assert(static_cast<int>(RejectReason::kNotOwner) == S::REJECT_NOT_OWNER);
static_assert(kRejectReasonCount == S::NUM_REJECT_REASONS);
static_assert(kRejectReasonCount <= 16, "status_t.rejected has 16 entries");

const char* to_string(RejectReason r) {
  switch (r) {
    case RejectReason::kOversizeCount: return "declared count above capacity";
    case RejectReason::kTruncated: return "byte length does not match the declared counts";
    case RejectReason::kFingerprint: return "wrong LCM fingerprint";
    case RejectReason::kNonFinite: return "non-finite number";
    case RejectReason::kInvalidField: return "invalid field";
    case RejectReason::kUnknownKeyframe: return "unknown keyframe";
    case RejectReason::kDuplicateKeyframe: return "duplicate keyframe";
    case RejectReason::kDuplicateObservation: return "duplicate observation";
    case RejectReason::kOutOfOrder: return "sequence out of order";
    case RejectReason::kUtimeBackwards: return "utime went backwards";
    case RejectReason::kWindowCapacity: return "window capacity exceeded";
    case RejectReason::kSequenceJump: return "sequence jumped beyond the bound";
    case RejectReason::kUtimeJump: return "utime jumped beyond the bound";
    case RejectReason::kNotOwner: return "another publisher owns the window";
    case RejectReason::kNone: return "accepted";
  }
  return "?";
}

namespace {

std::int64_t read_be64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return static_cast<std::int64_t>(v);
}

std::int32_t read_be32(const std::uint8_t* p) {
  const std::uint32_t v = (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
                          (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
  return static_cast<std::int32_t>(v);
}

// Fingerprint first: a message of another type says nothing about our layout.
bool fingerprint_ok(const std::uint8_t* p, std::size_t size, std::int64_t hash) {
  return size >= wire::kFingerprintBytes && read_be64(p) == hash;
}

bool finite(double x) { return std::isfinite(x); }

// The point quality arrays' counts and track lengths (finiteness is checked
// as kNonFinite): the field at fault, or null.
const char* quality_field(const keepless::keyframe_t& m) {
  const auto q = static_cast<std::size_t>(m.num_quality);
  if ((m.num_quality != 0 && m.num_quality != m.num_observations) || m.track_length.size() != q ||
      m.age.size() != q || m.reprojection_error.size() != q || m.triangulation_angle.size() != q) {
    return "num_quality (must be 0 or num_observations)";
  }
  for (std::int32_t t : m.track_length) {
    if (t < 0) return "track_length (must be >= 0)";
  }
  return nullptr;
}

bool has_adjacent_equal(const std::uint64_t* sorted, std::size_t n) {
  for (std::size_t i = 1; i < n; ++i) {
    if (sorted[i] == sorted[i - 1]) return true;
  }
  return false;
}

}  // namespace

RejectReason check_keyframe_bytes(const void* data, std::size_t size, const MessageLimits& limits) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  if (size < wire::kFingerprintBytes) return RejectReason::kTruncated;
  if (!fingerprint_ok(p, size, keepless::keyframe_t::getHash())) return RejectReason::kFingerprint;
  if (size < wire::kKeyframeHeaderBytes) return RejectReason::kTruncated;
  const std::int32_t n = read_be32(p + wire::kKeyframeCountOffset);
  if (n < 0) return RejectReason::kInvalidField;
  if (static_cast<std::uint32_t>(n) > limits.max_observations) return RejectReason::kOversizeCount;
  std::size_t at = wire::kKeyframeHeaderBytes + wire::kKeyframeBytesPerObservation * static_cast<std::size_t>(n);
  // The optional arrays: each count read only once the bytes before it are known to be there.
  const auto count = [&](std::int32_t* c) {
    if (size < at + 4) return false;
    *c = read_be32(p + at);
    at += 4;
    return true;
  };
  std::int32_t depths = 0, intrinsics = 0, unmapped = 0;
  if (!count(&depths)) return RejectReason::kTruncated;
  if (depths != 0 && depths != n) return RejectReason::kInvalidField;
  at += 4 * static_cast<std::size_t>(depths);
  if (!count(&intrinsics)) return RejectReason::kTruncated;
  if (intrinsics != 0 && intrinsics != 4) return RejectReason::kInvalidField;
  at += 8 * static_cast<std::size_t>(intrinsics);
  if (!count(&unmapped)) return RejectReason::kTruncated;
  if (unmapped < 0) return RejectReason::kInvalidField;
  if (static_cast<std::uint32_t>(unmapped) > limits.max_unmapped) return RejectReason::kOversizeCount;
  at += 8 * static_cast<std::size_t>(unmapped);
  // Tracked flags, after publisher_id: 0 or one per observation.
  if (size < at + wire::kKeyframeTrailerBytes) return RejectReason::kTruncated;
  const std::int32_t tracked = read_be32(p + at + wire::kKeyframeTrailerBytes - 4);
  if (tracked != 0 && tracked != n) return RejectReason::kInvalidField;
  at += wire::kKeyframeTrailerBytes + static_cast<std::size_t>(tracked);
  // Point quality, after the flags: 0 or one per observation.
  std::int32_t quality = 0;
  if (!count(&quality)) return RejectReason::kTruncated;
  if (quality != 0 && quality != n) return RejectReason::kInvalidField;
  if (size != at + wire::kKeyframeBytesPerQuality * static_cast<std::size_t>(quality)) return RejectReason::kTruncated;
  return RejectReason::kNone;
}

RejectReason check_map_event_bytes(const void* data, std::size_t size, const MessageLimits& limits) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  if (size < wire::kFingerprintBytes) return RejectReason::kTruncated;
  if (!fingerprint_ok(p, size, keepless::map_event_t::getHash())) return RejectReason::kFingerprint;
  if (size < wire::kMapEventHeaderBytes) return RejectReason::kTruncated;
  std::size_t ids = 0;
  for (int i = 0; i < 3; ++i) {
    const std::int32_t n = read_be32(p + wire::kMapEventCountOffset + 4 * static_cast<std::size_t>(i));
    if (n < 0) return RejectReason::kInvalidField;
    if (static_cast<std::uint32_t>(n) > limits.max_event_ids) return RejectReason::kOversizeCount;
    ids += static_cast<std::size_t>(n) * (i == 1 ? 2 : 1);  // merges carry two ids
  }
  if (size != wire::kMapEventHeaderBytes + 8 * ids + wire::kMapEventTrailerBytes) return RejectReason::kTruncated;
  return RejectReason::kNone;
}

namespace {

// (sequence, utime) strictly after (last_sequence, last_utime) within the
// bounds. Differences in uint64: both operands are int64, so they cannot wrap.
RejectReason follows(std::int64_t last_sequence, std::int64_t last_utime, std::int64_t sequence,
                     std::int64_t utime, std::uint64_t max_sequence_jump, std::uint64_t max_utime_jump_us) {
  if (sequence <= last_sequence) return RejectReason::kOutOfOrder;
  if (utime < last_utime) return RejectReason::kUtimeBackwards;
  if (static_cast<std::uint64_t>(sequence) - static_cast<std::uint64_t>(last_sequence) > max_sequence_jump) {
    return RejectReason::kSequenceJump;
  }
  if (static_cast<std::uint64_t>(utime) - static_cast<std::uint64_t>(last_utime) > max_utime_jump_us) {
    return RejectReason::kUtimeJump;
  }
  return RejectReason::kNone;
}

// A sequence a restarted stream may start at (0 .. kRestartMaxFirstSequence).
bool at_stream_start(std::int64_t sequence) { return sequence >= 0 && sequence <= kRestartMaxFirstSequence; }

}  // namespace

std::uint64_t message_hash(const void* data, std::size_t size) {
  // Four independent lanes of (h ^ word) * odd, h ^= h >> 29: each step is a
  // bijection of h and of the word, so two messages of one length that
  // differ in a single word never collide; the lanes keep the multiplies
  // apart (a few microseconds for the largest keyframe_t).
  constexpr std::uint64_t kMul = 0x9E3779B97F4A7C15ull;
  const auto mix = [](std::uint64_t h, std::uint64_t w) {
    h = (h ^ w) * kMul;
    return h ^ (h >> 29);
  };
  const auto* p = static_cast<const unsigned char*>(data);
  std::uint64_t lane[4] = {size, size + 1, size + 2, size + 3};
  std::size_t at = 0;
  for (; at + 32 <= size; at += 32) {
    for (std::size_t l = 0; l < 4; ++l) {
      std::uint64_t w;
      std::memcpy(&w, p + at + 8 * l, 8);
      lane[l] = mix(lane[l], w);
    }
  }
  for (std::size_t l = 0; at < size; ++l, at += 8) {
    std::uint64_t w = 0;
    std::memcpy(&w, p + at, std::min<std::size_t>(8, size - at));
    lane[l] = mix(lane[l], w);
  }
  return mix(mix(mix(mix(0, lane[0]), lane[1]), lane[2]), lane[3]);
}

OrderTracker::OrderTracker(const OrderBounds& bounds) : bounds_(bounds), recent_(bounds.recent_keyframes) {}

bool OrderTracker::continues(const Run& run, std::int64_t sequence, std::int64_t utime) const {
  if (run.length == 0 || follows(run.sequence, run.utime, sequence, utime, bounds_.max_sequence_jump,
                                 bounds_.max_utime_jump_us) != RejectReason::kNone) {
    return false;
  }
  // A restarted VO counts up from near 0 in small steps: a straggler of the
  // old run, far above, neither extends nor completes the restart.
  return !run.restart ||
         static_cast<std::uint64_t>(sequence) - static_cast<std::uint64_t>(run.sequence) <=
             static_cast<std::uint64_t>(kRestartMaxFirstSequence);
}

bool OrderTracker::retransmits(std::int64_t sequence, std::uint64_t hash) const {
  if (!owned_) return false;
  if (sequence == last_sequence_ && hash == last_hash_) return true;
  if (at_stream_start(sequence) && start_hash_[sequence] == hash) return true;
  for (std::size_t i = 0; i < recent_used_; ++i) {
    if (recent_[i].sequence == sequence && recent_[i].hash == hash) return true;
  }
  return false;
}

bool OrderTracker::reissues(std::int64_t sequence, std::int64_t utime, std::uint64_t hash) const {
  return utime > last_utime_ && !retransmits(sequence, hash);
}

bool OrderTracker::repeats(std::int64_t sequence, std::uint64_t hash) const {
  if (retransmits(sequence, hash)) return true;
  for (const Run& r : runs_) {
    if (r.length != 0 && r.sequence == sequence) return true;
  }
  return false;
}

bool OrderTracker::behind_the_stream(std::int64_t sequence, std::int64_t utime) const {
  return has_previous_ && sequence < last_sequence_ && utime < last_utime_ &&
         (sequence <= previous_sequence_ || utime < previous_utime_);
}

int OrderTracker::extended_run(std::int64_t sequence, std::int64_t utime) const {
  int best = -1;
  for (std::size_t i = 0; i < kCandidateRuns; ++i) {
    const Run& r = runs_[i];
    if (!continues(r, sequence, utime)) continue;
    if (best < 0 || r.length > runs_[best].length ||
        (r.length == runs_[best].length && r.touched > runs_[best].touched)) {
      best = static_cast<int>(i);
    }
  }
  return best;
}

OrderTracker::Verdict OrderTracker::check(std::int64_t publisher, std::int64_t sequence, std::int64_t utime,
                                          std::uint64_t hash, std::uint64_t now_ns, bool keyframe) const {
  Verdict v;
  if (!owned_ || publisher != owner_) {
    // Before the first keyframe no order can refuse a map event (a VO's
    // start-up reset); it sets no owner and conflicts with none.
    if (!owned_ && !keyframe) return v;
    const bool silent = owned_ && bounds_.owner_timeout_ns > 0 && now_ns >= last_heard_ns_ &&
                        now_ns - last_heard_ns_ >= bounds_.owner_timeout_ns;
    if (keyframe && (!owned_ || silent)) {
      v.takeover = true;
    } else {
      v.reason = RejectReason::kNotOwner;
    }
    return v;
  }
  const std::uint64_t quiet_ns = now_ns >= last_heard_ns_ ? now_ns - last_heard_ns_ : 0;
  // The utime may advance by the bound plus the node's time since the order
  // last accepted anything: a VO that keyframes on motion pauses while parked.
  const std::uint64_t quiet_us = quiet_ns / 1000;
  const std::uint64_t utime_bound = bounds_.max_utime_jump_us > UINT64_MAX - quiet_us
                                        ? UINT64_MAX
                                        : bounds_.max_utime_jump_us + quiet_us;
  v.reason = follows(last_sequence_, last_utime_, sequence, utime, bounds_.max_sequence_jump, utime_bound);
  if (v.reason == RejectReason::kNone || !keyframe || repeats(sequence, hash)) return v;
  const int r = extended_run(sequence, utime);
  if (r < 0 || runs_[r].length + 1 < bounds_.restart_confirm) return v;
  // A resync only of an order that has accepted nothing for a while: a live
  // stream's late or retransmitted keyframes never take the order back. Its
  // own short bound, so a long --owner-timeout-s does not lock the owner out.
  const std::uint64_t silence = bounds_.owner_timeout_ns > 0 ? std::min(bounds_.owner_timeout_ns, kResyncSilenceNs)
                                                             : kResyncSilenceNs;
  if (runs_[r].restart) {
    // A restarted VO clocks on, or its old process fell silent; late copies
    // of a start the order never accepted (a node started after its VO, lost
    // datagrams, a dead process) are earlier, into a live order.
    v.restart = utime > last_utime_ || quiet_ns >= silence;
  } else {
    // The stream's past is a flush, heard at once; a live stream behind an
    // order set by a burst ahead in both fields is heard for the silence.
    const bool heard = now_ns >= runs_[r].first_ns && now_ns - runs_[r].first_ns >= silence;
    v.resync = quiet_ns >= silence && (!behind_the_stream(sequence, utime) || heard);
  }
  if (v.restart || v.resync) v.reason = RejectReason::kNone;
  return v;
}

void OrderTracker::accept(const Verdict& v, std::int64_t publisher, std::int64_t sequence, std::int64_t utime,
                          std::uint64_t hash, std::uint64_t now_ns, bool keyframe) {
  if (!owned_ && !v.takeover) return;  // a map event before any keyframe (rule 1)
  if (v.takeover || v.restart || v.resync) {
    if (v.takeover) {
      ++owners_seen_;
      if (owned_) ++takeovers_;
    }
    if (v.restart) ++restarts_;
    if (v.resync) ++resyncs_;
  } else if (sequence > last_sequence_) {
    // Saturated: with --max-sequence-jump near 2^63 two gaps would wrap it.
    const std::uint64_t gap = static_cast<std::uint64_t>(sequence) - static_cast<std::uint64_t>(last_sequence_) - 1;
    gaps_ = gap > UINT64_MAX - gaps_ ? UINT64_MAX : gaps_ + gap;
  }
  // A run matters only while the order refuses everything: keyframes refused
  // around accepted ones (late or repeated) never count toward a later run.
  for (Run& run : runs_) run = Run{};
  has_previous_ = owned_ && !v.takeover;
  previous_sequence_ = last_sequence_;
  previous_utime_ = last_utime_;
  owned_ = true;
  owner_ = publisher;
  last_sequence_ = sequence;
  last_utime_ = utime;
  last_hash_ = hash;
  last_heard_ns_ = now_ns;
  if (v.takeover) std::fill(std::begin(start_hash_), std::end(start_hash_), 0);
  if (keyframe && at_stream_start(sequence)) start_hash_[sequence] = hash;
  if (keyframe && !recent_.empty()) {
    recent_[recent_next_] = {sequence, hash};
    recent_next_ = (recent_next_ + 1) % recent_.size();
    recent_used_ = std::min(recent_used_ + 1, recent_.size());
  }
}

bool OrderTracker::extend_restart(std::int64_t publisher, std::int64_t sequence, std::int64_t utime,
                                  std::uint64_t hash, std::uint64_t now_ns) {
  // A duplicate (a datagram delivered twice) changes no run: extending
  // one would let copies confirm it, starting one would displace one.
  if (!owned_ || publisher != owner_ || repeats(sequence, hash)) return false;
  ++run_clock_;
  const int e = extended_run(sequence, utime);
  if (e >= 0) {
    Run& run = runs_[e];
    ++run.length;
    run.sequence = sequence;
    run.utime = utime;
    run.touched = run_clock_;
    return true;
  }
  // A new run replaces the shortest (the least recently extended of equals).
  std::size_t slot = 0;
  for (std::size_t i = 0; i < kCandidateRuns; ++i) {
    const Run& r = runs_[i];
    if (r.length < runs_[slot].length || (r.length == runs_[slot].length && r.touched < runs_[slot].touched)) {
      slot = i;
    }
  }
  // Low, and not continuing the order from before the last accepted message
  // (that message would be the one the stream does not continue): a restart.
  const bool continues_previous =
      has_previous_ && follows(previous_sequence_, previous_utime_, sequence, utime, bounds_.max_sequence_jump,
                               bounds_.max_utime_jump_us) == RejectReason::kNone;
  runs_[slot].length = 1;
  runs_[slot].restart = at_stream_start(sequence) && !continues_previous;
  runs_[slot].sequence = sequence;
  runs_[slot].utime = utime;
  runs_[slot].touched = run_clock_;
  runs_[slot].first_ns = now_ns;
  return true;
}

RejectReason check_keyframe(const keepless::keyframe_t& msg, const core::Window& window,
                            std::uint64_t* scratch) {
  for (double c : msg.centre) {
    if (!finite(c)) return RejectReason::kNonFinite;
  }
  double norm2 = 0;
  for (double q : msg.orientation) {
    if (!finite(q)) return RejectReason::kNonFinite;
    norm2 += q * q;
  }
  const auto n = static_cast<std::size_t>(msg.num_observations);
  if (msg.num_observations < 0 || msg.point_id.size() != n || msg.u.size() != n || msg.v.size() != n) {
    return RejectReason::kInvalidField;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(msg.u[i]) || !std::isfinite(msg.v[i])) return RejectReason::kNonFinite;
  }
  const auto depths = static_cast<std::size_t>(msg.num_depths);
  const auto unmapped = static_cast<std::size_t>(msg.num_unmapped);
  if ((msg.num_depths != 0 && depths != n) || msg.depth.size() != depths ||
      (msg.num_intrinsics != 0 && msg.num_intrinsics != 4) ||
      msg.intrinsics.size() != static_cast<std::size_t>(msg.num_intrinsics) || msg.num_unmapped < 0 ||
      msg.unmapped_u.size() != unmapped || msg.unmapped_v.size() != unmapped) {
    return RejectReason::kInvalidField;
  }
  for (float d : msg.depth) {
    if (!std::isfinite(d)) return RejectReason::kNonFinite;
  }
  for (double k : msg.intrinsics) {
    if (!finite(k)) return RejectReason::kNonFinite;
  }
  for (std::size_t i = 0; i < unmapped; ++i) {
    if (!std::isfinite(msg.unmapped_u[i]) || !std::isfinite(msg.unmapped_v[i])) return RejectReason::kNonFinite;
  }
  // Tracked flags: none, or one 0/1 per observation.
  if ((msg.num_tracked != 0 && msg.num_tracked != msg.num_observations) ||
      msg.tracked.size() != static_cast<std::size_t>(msg.num_tracked)) {
    return RejectReason::kInvalidField;
  }
  for (std::int8_t t : msg.tracked) {
    if (t != 0 && t != 1) return RejectReason::kInvalidField;
  }
  if (quality_field(msg) != nullptr) return RejectReason::kInvalidField;
  for (std::int32_t i = 0; i < msg.num_quality; ++i) {
    const auto q = static_cast<std::size_t>(i);
    if (!std::isfinite(msg.reprojection_error[q]) || !std::isfinite(msg.triangulation_angle[q])) {
      return RejectReason::kNonFinite;
    }
  }
  if (msg.image_width <= 0 || msg.image_height <= 0) return RejectReason::kInvalidField;
  // Float-derived quaternions are off by ~1e-7; anything far from unit is a bug upstream.
  if (std::fabs(norm2 - 1.0) > core::kQuaternionNormTolerance) return RejectReason::kInvalidField;
  if (window.find_keyframe(static_cast<core::KeyframeId>(msg.keyframe_id)) >= 0) {
    return RejectReason::kDuplicateKeyframe;
  }
  for (std::size_t i = 0; i < n; ++i) scratch[i] = static_cast<std::uint64_t>(msg.point_id[i]);
  std::sort(scratch, scratch + n);
  if (has_adjacent_equal(scratch, n)) return RejectReason::kDuplicateObservation;
  return RejectReason::kNone;
}

RejectReason check_map_event(const keepless::map_event_t& msg) {
  if (msg.num_deleted_points < 0 || msg.num_merged_points < 0 || msg.num_removed_keyframes < 0) {
    return RejectReason::kInvalidField;
  }
  const auto nd = static_cast<std::size_t>(msg.num_deleted_points);
  const auto nm = static_cast<std::size_t>(msg.num_merged_points);
  const auto nr = static_cast<std::size_t>(msg.num_removed_keyframes);
  if (msg.deleted_point_id.size() != nd || msg.merged_from_id.size() != nm ||
      msg.merged_into_id.size() != nm || msg.removed_keyframe_id.size() != nr) {
    return RejectReason::kInvalidField;
  }
  return RejectReason::kNone;
}

const char* invalid_keyframe_field(const keepless::keyframe_t* m) {
  if (m == nullptr) {
    return "an array count (num_observations, num_depths, num_intrinsics, num_unmapped, num_tracked or "
           "num_quality)";
  }
  const auto n = static_cast<std::size_t>(m->num_observations);
  if (m->num_observations < 0 || m->point_id.size() != n || m->u.size() != n || m->v.size() != n) {
    return "num_observations (negative or not the arrays' length)";
  }
  if ((m->num_depths != 0 && m->num_depths != m->num_observations) ||
      m->depth.size() != static_cast<std::size_t>(m->num_depths)) {
    return "num_depths (must be 0 or num_observations)";
  }
  if ((m->num_intrinsics != 0 && m->num_intrinsics != 4) ||
      m->intrinsics.size() != static_cast<std::size_t>(m->num_intrinsics)) {
    return "num_intrinsics (must be 0 or 4)";
  }
  if (m->num_unmapped < 0 || m->unmapped_u.size() != static_cast<std::size_t>(m->num_unmapped) ||
      m->unmapped_v.size() != static_cast<std::size_t>(m->num_unmapped)) {
    return "num_unmapped (negative or not the arrays' length)";
  }
  if ((m->num_tracked != 0 && m->num_tracked != m->num_observations) ||
      m->tracked.size() != static_cast<std::size_t>(m->num_tracked)) {
    return "num_tracked (must be 0 or num_observations)";
  }
  for (std::int8_t t : m->tracked) {
    if (t != 0 && t != 1) return "tracked (a flag is 0 or 1)";
  }
  if (const char* q = quality_field(*m)) return q;
  if (m->image_width <= 0) return "image_width (must be > 0)";
  if (m->image_height <= 0) return "image_height (must be > 0)";
  double norm2 = 0;
  for (double q : m->orientation) norm2 += q * q;
  if (std::fabs(norm2 - 1.0) > core::kQuaternionNormTolerance) return "orientation (not a unit quaternion)";
  return "a field";
}

const char* invalid_map_event_field(const keepless::map_event_t* m) {
  if (m == nullptr || m->num_deleted_points < 0 || m->num_merged_points < 0 || m->num_removed_keyframes < 0) {
    return "an array count (num_deleted_points, num_merged_points or num_removed_keyframes)";
  }
  if (m->deleted_point_id.size() != static_cast<std::size_t>(m->num_deleted_points)) return "num_deleted_points";
  if (m->merged_from_id.size() != static_cast<std::size_t>(m->num_merged_points) ||
      m->merged_into_id.size() != static_cast<std::size_t>(m->num_merged_points)) {
    return "num_merged_points";
  }
  if (m->removed_keyframe_id.size() != static_cast<std::size_t>(m->num_removed_keyframes)) {
    return "num_removed_keyframes";
  }
  return "a field";
}

void split_map_event(const keepless::map_event_t& msg, const core::Window& window, const RecentIds* culled,
                     std::uint64_t* scratch, MapEventItems& out) {
  using A = keepless::map_event_ack_t;
  out.merged = out.removed_count = out.refused = 0;
  const auto refuse = [&](std::int64_t id, std::int8_t why) {
    out.refused_id[out.refused] = id;
    out.refused_reason[out.refused] = why;
    ++out.refused;
  };
  const auto nd = static_cast<std::size_t>(msg.num_deleted_points);
  const auto nm = static_cast<std::size_t>(msg.num_merged_points);
  std::uint64_t* deleted = scratch;
  std::uint64_t* from = scratch + nd;
  // Per sorted source, nonzero once a merge from it was applied (at the
  // first position of its run in `from`): a repeat is found in O(log n).
  std::uint64_t* applied = scratch + nd + nm;
  for (std::size_t i = 0; i < nd; ++i) deleted[i] = static_cast<std::uint64_t>(msg.deleted_point_id[i]);
  for (std::size_t i = 0; i < nm; ++i) from[i] = static_cast<std::uint64_t>(msg.merged_from_id[i]);
  std::fill(applied, applied + nm, 0);
  std::sort(deleted, deleted + nd);
  std::sort(from, from + nm);
  for (std::size_t i = 0; i < nm; ++i) {
    const std::int64_t f = msg.merged_from_id[i];
    const std::int64_t t = msg.merged_into_id[i];
    const auto source =
        static_cast<std::size_t>(std::lower_bound(from, from + nm, static_cast<std::uint64_t>(f)) - from);
    // A repeat of a source already applied by this event (a refused earlier
    // item, e.g. 5 -> 5, does not take the source's turn).
    const bool repeated = applied[source] != 0;
    if (f == t) {
      refuse(f, A::ITEM_MERGE_SELF);
    } else if (repeated) {
      refuse(f, A::ITEM_MERGE_REPEATED_SOURCE);
    } else if (std::binary_search(from, from + nm, static_cast<std::uint64_t>(t))) {
      refuse(f, A::ITEM_MERGE_CHAIN);
    } else if (std::binary_search(deleted, deleted + nd, static_cast<std::uint64_t>(t))) {
      refuse(f, A::ITEM_MERGE_INTO_DELETED);
    } else if (culled != nullptr && culled->contains(static_cast<std::uint64_t>(t))) {
      refuse(f, A::ITEM_MERGE_INTO_CULLED);
    } else {
      out.merged_from[out.merged] = f;
      out.merged_into[out.merged] = t;
      ++out.merged;
      applied[source] = 1;
    }
  }
  std::bitset<1024> seen;  // window slots (--window <= 256)
  for (const std::int64_t id : msg.removed_keyframe_id) {
    const std::int32_t slot = window.find_keyframe(static_cast<core::KeyframeId>(id));
    if (slot < 0 || static_cast<std::size_t>(slot) >= seen.size()) {
      refuse(id, A::ITEM_REMOVE_UNKNOWN_KEYFRAME);
    } else if (seen.test(static_cast<std::size_t>(slot))) {
      refuse(id, A::ITEM_REMOVE_REPEATED);
    } else {
      seen.set(static_cast<std::size_t>(slot));
      out.removed[out.removed_count++] = id;
    }
  }
}

}  // namespace keepless::platform
