#pragma once
// decision_t from the core library's answer: the one place that maps a
// Sparsifier's result onto the wire message (keepless_node and the latency
// benchmark both publish through it). The message's arrays are reserved once
// from the capacities; filling it afterwards only resizes within them, so it
// allocates nothing.

#include <cstddef>
#include <cstdint>

#include "keepless/core/config.hpp"
#include "keepless/core/deferred_culls.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"
#include "keepless/decision_t.hpp"
#include "keepless/platform/message_validation.hpp"

namespace keepless::platform {

// The keyframe a decision answers, echoed in it.
struct DecisionRequest {
  std::int64_t sequence = 0;
  std::int64_t keyframe_id = 0;
  std::int64_t utime = 0;
  std::int64_t publisher_id = 0;
};

// Reserves `msg`'s arrays for a window within `capacities` and, for
// deferred culling, `deferred_capacity` excluded points held (the only
// allocation here), and returns the largest encoded decision, in bytes.
std::size_t reserve_decision(keepless::decision_t& msg, const core::Capacities& capacities,
                             std::uint32_t deferred_capacity = 0);

// The answer to `request` after Sparsifier::run() or update() returned
// `result` on `window` (the window as it is now, before culled points are
// dropped). kOk: STATUS_OPTIMAL; kBudgetExhausted: STATUS_BUDGET_EXHAUSTED
// (the sparsifier then culls nothing); both carry the sparsifier's counts and
// culled ids (ascending). kCapacityExceeded: STATUS_CAPACITY_EXCEEDED; any
// other status: STATUS_REJECTED_INPUT; both with zero counts and no ids.
// Returns the number of culled ids in `msg.culled_point_id`.
std::uint32_t fill_decision(keepless::decision_t& msg, const DecisionRequest& request,
                            const core::Window& window, const core::Sparsifier& sparsifier,
                            core::Status result);

// Deferred culling, after fill_decision: the decision's culled ids become
// excluded (`excluded_point_id`; culled_point_id is emptied), those
// `deferred` cannot hold are deleted at once, and the excluded points its
// rule deletes at this tick join them (`deleted_point_id`, ascending).
// Returns the number deleted.
std::uint32_t defer_culls(keepless::decision_t& msg, core::DeferredCulls& deferred);

// The answer to a keyframe refused before the sparsifier ran (`reason` not
// kNone): STATUS_CAPACITY_EXCEEDED for kWindowCapacity, else
// STATUS_REJECTED_INPUT; the reason, zero counts, no culls, and `window`
// (unchanged by the refusal).
void fill_rejected_decision(keepless::decision_t& msg, const DecisionRequest& request,
                            const core::Window& window, RejectReason reason);

}  // namespace keepless::platform
