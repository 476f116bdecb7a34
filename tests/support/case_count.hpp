#pragma once
// How many random cases a property test runs. Under the sanitizers (the asan
// preset's KEEPLESS_SANITIZE) a case costs about ten times a release one, and
// the release and cross builds run every case: there a third of them, which
// still passes every path the test is for under the sanitizers' checks.

#include <cstdint>

namespace keepless::test {

#ifdef KEEPLESS_TEST_SANITIZED
constexpr std::uint64_t kCaseDivisor = 3;
#else
constexpr std::uint64_t kCaseDivisor = 1;
#endif

// n, or n / kCaseDivisor under the sanitizers: for a test's case count and
// for the counts it expects those cases to reach.
constexpr std::uint64_t cases(std::uint64_t n) { return n / kCaseDivisor; }

}  // namespace keepless::test
