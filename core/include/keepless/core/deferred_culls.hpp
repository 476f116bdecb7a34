#pragma once
// Deferred culling: the points a decision culled, held between "excluded
// from local BA" and "deleted from the map" (Params::defer_keyframes = T).
//
// The rule. Each call to begin_keyframe() is one tick of a keyframe clock
// (never utime, so time going backwards cannot confuse it). A point excluded
// at tick c is deleted by the first expire() at a tick c' with c' - m >= T,
// where m is the last tick at which a keyframe matched it (observe() with
// matched = true), or c if none has: it is deleted once T keyframes in a row
// have not matched it. T = 1 deletes it at the first keyframe that does not
// match it; T = 0 at once (immediate culling).
//
// Capacity is fixed at construction; nothing allocates afterwards. A point
// that does not fit is refused (counted in refused()) and the caller deletes
// it at once, as without deferral. expire() lists ids ascending, so the
// output is a function of the calls made, not of the table's layout.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/config.hpp"
#include "keepless/core/status.hpp"

namespace keepless::core {

class DeferredCulls {
 public:
  // Room for `capacity` excluded points at once; `defer_keyframes` is T.
  DeferredCulls(std::uint32_t capacity, std::uint32_t defer_keyframes);
  ~DeferredCulls();
  DeferredCulls(const DeferredCulls&) = delete;
  DeferredCulls& operator=(const DeferredCulls&) = delete;

  // A new keyframe arrives: the clock ticks once.
  void begin_keyframe();
  // One observation of the new keyframe. True if `point` is excluded: the
  // caller keeps the observation out of the window (the point stays out of
  // BA and out of later decisions). `matched` (its tracked flag, or true when
  // the keyframe carries none) makes this tick the point's last match.
  bool observe(PointId point, bool matched);
  // A point the decision culled becomes excluded, matched at this tick. A
  // point already excluded is left as it is (kOk). kCapacityExceeded: not
  // held (refused() counts it); the caller deletes it at once.
  [[nodiscard]] Status exclude(PointId point);
  // The excluded points the rule deletes at this tick, ascending, into
  // `out` (room for capacity() ids); returns how many. They are forgotten.
  std::uint32_t expire(PointId* out);
  // A decision's whole step: each of the `n` culled points is excluded
  // (copied to `excluded` in the order given; *excluded_count set) or, when
  // refused, deleted at once; the points expire() deletes at this tick join
  // those in `deleted` (room for n + capacity() ids), ascending. Returns how
  // many are deleted. A point held already, or repeated in `culled`, is
  // listed (and refused) once.
  std::uint32_t defer(const PointId* culled, std::uint32_t n, PointId* excluded, std::uint32_t* excluded_count,
                      PointId* deleted);
  // The map merged `from` into the held `into`: the source's observations
  // are now its, so `into` keeps the later of their last matches and a held
  // `from` is forgotten; `from_in_window` (the source had observations in
  // the window, whose ticks are not kept) counts as a match at this tick:
  // never early, at most T keyframes late. False if `into` is not held.
  bool merge(PointId from, PointId into, bool from_in_window);
  // The map deleted or merged `point` itself: forgotten without a deletion
  // to report. False if it was not held.
  bool forget(PointId point);
  bool contains(PointId point) const;
  // A reset: nothing held, the clock and the refusal count kept.
  void clear();

  std::uint32_t size() const;
  std::uint32_t capacity() const;
  std::uint32_t defer_keyframes() const;
  std::uint64_t refused() const;
  std::uint64_t tick() const;
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
