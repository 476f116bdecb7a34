#pragma once
// The two ways keepless_sparsify decides a whole map, over keyframes in a
// given order (keepless::io::Keyframes):
//   replay: the onboard node's decisions. Keyframes enter a sliding window of
//     K one at a time (the oldest leaves when K are held); after each one the
//     window is decided (Sparsifier::update, incremental, as the node does)
//     and every point culled there is removed from the map for good, as the
//     VO deletes it; a point never culled is kept.
//   whole: the whole map as one window (Sparsifier::run), today's
//     keepless_sparsify on a window file.
// Then, optionally, a floor: every image keeps at least F observations.

#include <cstdint>
#include <string>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window_file.hpp"

namespace keepless::sparsify {

enum class Mode { kReplay, kWhole };
const char* to_string(Mode mode);

// A keep budget's value for the JSON summaries: K or B, or F (shortest
// exact); "0" without a budget.
std::string budget_value(const core::KeepBudget& budget);

struct ModeResult {
  // One per distinct point of the keyframes, ascending id: the final verdict
  // (cull if any slide culled it; keep if evaluated and never culled; skip
  // if never seen twice in one window) with the flow and capacity of the
  // slide that culled it, else of its last evaluation.
  std::vector<core::PointDecision> decisions;
  core::Summary totals;  // replay: pairs, arcs, max_flow, total_cost summed over slides
  std::uint32_t slides = 0;
  core::Capacities capacities{0, 0, 0, 0};  // what the windows were sized to
  std::size_t memory_bytes = 0;
  // kWhole with a keep budget: each decision's keep threshold M*
  // (core::Sparsifier::keep_thresholds()), indexed like `decisions`.
  std::vector<std::uint32_t> thresholds;
};

// Decides `keyframes` (in their order). kOk, or the first failing status.
[[nodiscard]] core::Status decide(const core::WindowFile& keyframes, Mode mode, const core::Params& params,
                                  std::uint32_t K, ModeResult* out);

// The per-image floor. `images[i]` lists image i's observations by point id
// (duplicates included: what COLMAP counts). Every image left with fewer
// than `floor` observations of points not culled gets culled points back,
// images in the order given, each image's candidates by most observations
// in the whole map first, then lowest id, until it reaches the floor or has
// none left. Restored points become kKeep. Returns how many were restored.
std::uint32_t apply_floor(const std::vector<std::vector<core::PointId>>& images, std::uint32_t floor,
                          std::vector<core::PointDecision>* decisions);

// Observations per image of points not culled, as apply_floor counts them.
std::vector<std::uint32_t> kept_observations(const std::vector<std::vector<core::PointId>>& images,
                                             const std::vector<core::PointDecision>& decisions);

// What decide() sizes its windows to: the whole map (kWhole), or the
// largest K consecutive keyframes (kReplay).
core::Capacities decision_capacities(const core::WindowFile& keyframes, Mode mode, std::uint32_t K);

// The bytes decide() will allocate for its windows and sparsifier, before
// allocating them (platform::MemoryModel).
double decision_bytes(const core::WindowFile& keyframes, Mode mode, const core::Params& params, std::uint32_t K);

// Whole mode's one window holds every image: with c_c on, a point seen by
// more than core::kMaxPointViews of them cannot be priced (its c_m(2) would
// pass the solver's cost bound). The refusal naming the limit, or "".
std::string point_views_refusal(const core::WindowFile& keyframes, const core::Params& params,
                                const std::string& name);

// The index of `point` in decisions (ascending ids), or -1.
std::int64_t find_decision(const std::vector<core::PointDecision>& decisions, core::PointId point);

}  // namespace keepless::sparsify
