#pragma once
// A Sparsifier's decisions against the reference's, point by point, or two
// Sparsifiers' against each other.

#include <gtest/gtest.h>

#include <cstdint>

#include "keepless/core/sparsifier.hpp"
#include "reference_sparsifier.hpp"

namespace keepless::test {

// Every decision equals the reference point at its index (id, flow,
// capacity, verdict); `verdicts` counts them by core::Verdict.
inline ::testing::AssertionResult decisions_match(const core::Sparsifier& s, const RefResult& ref,
                                                  std::uint32_t verdicts[3]) {
  if (s.decision_count() != ref.points.size()) {
    return ::testing::AssertionFailure() << "decisions " << s.decision_count() << " vs reference "
                                         << ref.points.size();
  }
  verdicts[0] = verdicts[1] = verdicts[2] = 0;
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    const core::PointDecision& d = s.decisions()[i];
    const RefPoint& r = ref.points[i];
    if (d.point != r.id || d.flow != r.flow || d.capacity != r.capacity || d.verdict != r.verdict) {
      return ::testing::AssertionFailure()
             << "point " << d.point << " (ref " << r.id << "): flow " << d.flow << " vs " << r.flow
             << ", capacity " << d.capacity << " vs " << r.capacity << ", verdict "
             << core::to_string(d.verdict) << " vs " << core::to_string(r.verdict);
    }
    ++verdicts[static_cast<int>(d.verdict)];
  }
  return ::testing::AssertionSuccess();
}

// Two Sparsifiers decided alike: every decision (id, verdict, flow,
// capacity) and the summary's counts, flow, cost, scope and floor fields.
inline ::testing::AssertionResult same_decisions(const core::Sparsifier& a, const core::Sparsifier& b) {
  if (a.decision_count() != b.decision_count()) return ::testing::AssertionFailure() << "counts";
  for (std::uint32_t i = 0; i < a.decision_count(); ++i) {
    const core::PointDecision& x = a.decisions()[i];
    const core::PointDecision& y = b.decisions()[i];
    if (x.point != y.point || x.verdict != y.verdict || x.flow != y.flow || x.capacity != y.capacity) {
      return ::testing::AssertionFailure() << "point " << x.point << " differs";
    }
  }
  const core::Summary& s = a.summary();
  const core::Summary& t = b.summary();
  if (s.kept != t.kept || s.culled != t.culled || s.skipped != t.skipped ||
      s.max_flow != t.max_flow || s.total_cost != t.total_cost || s.out_of_scope != t.out_of_scope ||
      s.floor_keyframes != t.floor_keyframes || s.floor_promoted != t.floor_promoted ||
      s.floor_short != t.floor_short) {
    return ::testing::AssertionFailure() << "summaries differ";
  }
  return ::testing::AssertionSuccess();
}

}  // namespace keepless::test
