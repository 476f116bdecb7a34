#pragma once
// The forward-moving stream the monocular uses are tested on, and the rules
// their decisions keep on it. Keyframe i (sequence i + 1) sees points
// 10i .. 10i+59: point p is first seen by keyframe max(0, ceil((p - 59) / 10))
// and last by floor(p / 10). The checks take the decisions as they arrived:
// a late decision (stopped by the latency target) culls nothing and the next
// one catches up, and over UDP some may be missing.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "keepless/core/use.hpp"
#include "keepless/decision_t.hpp"
#include "keepless/keyframe_t.hpp"
#include "message_builders.hpp"

namespace keepless::testing::forward_stream {

constexpr std::int64_t kStride = 10;
constexpr std::int64_t kSeen = 60;

inline keepless::keyframe_t keyframe(std::int64_t i) { return make_keyframe(i + 1, i, id_range(kStride * i, kSeen)); }
inline std::int64_t first_seen(std::int64_t p) { return p < kSeen ? 0 : (p - kSeen + kStride) / kStride; }
inline std::int64_t last_seen(std::int64_t p) { return p / kStride; }

// `monocular` (Scope::kNewest, maturity 2, culls deleted at once): the
// decision on keyframe i decides keyframe i - 2 and, after missed turns,
// every keyframe since the last one decided; it culls only points those
// keyframes see and none first seen after i - 2. Returns the culls.
inline std::size_t expect_monocular_rules(const std::vector<keepless::decision_t>& decisions) {
  std::size_t culls = 0;
  std::int64_t last_solved = -1;  // the newest keyframe whose decision was solved
  for (const keepless::decision_t& d : decisions) {
    EXPECT_EQ(d.num_excluded, 0) << "keyframe " << d.keyframe_id;
    EXPECT_EQ(d.num_deleted, 0) << "keyframe " << d.keyframe_id;
    if (d.status != keepless::decision_t::STATUS_OPTIMAL) {
      EXPECT_EQ(d.num_culled, 0) << "keyframe " << d.keyframe_id << " status " << int{d.status};
      continue;
    }
    const std::int64_t i = d.keyframe_id;
    // The last solved decision decided last_solved - 2; this one decides from the next keyframe on.
    const std::int64_t from = last_solved < 0 ? 0 : last_solved - 1;
    for (const std::int64_t p : d.culled_point_id) {
      EXPECT_TRUE(last_seen(p) >= from && first_seen(p) <= i - 2)
          << "keyframe " << i << " culled " << p << " (keyframes from " << from << " to " << i - 2 << " decided)";
      ++culls;
    }
    last_solved = i;
  }
  return culls;
}

// `monocular-deferred` (defer T): nothing is culled outright; a point is
// excluded once and deleted once, by the decision on the keyframe T after
// the later of its exclusion and its last sighting (T keyframes in a row
// have not seen it). Returns the points excluded.
inline std::size_t expect_deferred_rules(const std::vector<keepless::decision_t>& decisions, std::int64_t t) {
  std::map<std::int64_t, std::int64_t> excluded_at, deleted_at;
  std::set<std::int64_t> answered;
  for (const keepless::decision_t& d : decisions) {
    const std::int64_t i = d.keyframe_id;
    answered.insert(i);
    EXPECT_EQ(d.num_culled, 0) << "keyframe " << i;
    for (const std::int64_t p : d.excluded_point_id) {
      EXPECT_TRUE(excluded_at.emplace(p, i).second) << "excluded twice: " << p;
    }
    for (const std::int64_t p : d.deleted_point_id) {
      EXPECT_TRUE(deleted_at.emplace(p, i).second) << "deleted twice: " << p;
    }
  }
  // With every decision in hand, no point is deleted without its exclusion.
  const bool complete = !answered.empty() && *answered.begin() == 0 &&
                        *answered.rbegin() + 1 == static_cast<std::int64_t>(answered.size());
  if (complete) {
    for (const auto& [p, k] : deleted_at) {
      EXPECT_EQ(excluded_at.count(p), 1u) << "keyframe " << k << " deleted " << p << ", never excluded";
    }
  }
  for (const auto& [p, e] : excluded_at) {
    const std::int64_t due = std::max(e, last_seen(p)) + t;
    const auto deleted = deleted_at.find(p);
    if (deleted != deleted_at.end()) {
      EXPECT_EQ(deleted->second, due) << "point " << p << " excluded at keyframe " << e << ", last seen at "
                                      << last_seen(p);
    } else {
      EXPECT_EQ(answered.count(due), 0u) << "point " << p << " excluded at keyframe " << e << ", never deleted";
    }
  }
  return excluded_at.size();
}

// The monocular uses and kept fractions the node's tests run (monocular
// also at 0.4, where its track share applies).
inline constexpr std::pair<const char*, const char*> kMonocularUses[] = {
    {"monocular", "0.2"}, {"monocular", "0.4"}, {"monocular-deferred", "0.2"}};

// `use`'s rules, by its own settings (core::apply_use: deferred culling's T,
// or culls deleted at once). Returns the points culled or excluded.
inline std::size_t expect_use_rules(const char* use, const std::vector<keepless::decision_t>& decisions) {
  core::Use u{};
  EXPECT_TRUE(core::parse_use(use, &u)) << use;
  core::Params params;
  core::apply_use(u, &params);
  return params.defer_keyframes > 0 ? expect_deferred_rules(decisions, params.defer_keyframes)
                                    : expect_monocular_rules(decisions);
}

}  // namespace keepless::testing::forward_stream
