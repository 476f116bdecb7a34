#pragma once
// A Sparsifier's decisions against the reference's, point by point.

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

}  // namespace keepless::test
