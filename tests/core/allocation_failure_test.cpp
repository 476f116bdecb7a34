// An allocation that fails while a Window, Sparsifier or DeferredCulls is
// being built reaches the caller as std::bad_alloc, which keepless_node and
// keepless_sparsify answer "cannot allocate ...", exit 2. The embedded
// profile compiles keepless::core without exceptions; on 32-bit ARM such
// code gets no unwind tables unless asked (-funwind-tables), and the
// unwinder calls std::terminate at its first frame instead.
//
// Its own binary: it replaces the global operator new (counting_new.hpp,
// which fails an allocation on demand).

#include <gtest/gtest.h>

#include <cstdint>
#include <new>

#include "counting_new.hpp"  // this binary's only inclusion
#include "keepless/core/config.hpp"
#include "keepless/core/deferred_culls.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"

namespace keepless::core {
namespace {

// Fails the allocation number `n` (0: the first) inside `make`; true if
// std::bad_alloc reached this frame.
template <typename Make>
bool fails_with_bad_alloc(std::int64_t n, Make make) {
  test::AllocationCounter::fail_allocation(n);
  bool caught = false;
  try {
    make();
  } catch (const std::bad_alloc&) {
    caught = true;
  }
  test::AllocationCounter::fail_allocation(-1);
  return caught;
}

// Fails each of the first allocations of `make` in turn.
template <typename Make>
void expect_each_failure_reaches_the_caller(const char* what, Make make) {
  test::AllocationCounter counter;
  make();
  const auto count = static_cast<std::int64_t>(counter.stop());
  ASSERT_GT(count, 0) << what;
  for (std::int64_t n = 0; n < count && n < 8; ++n) {
    EXPECT_TRUE(fails_with_bad_alloc(n, make)) << what << ", allocation " << n << " of " << count;
  }
}

TEST(AllocationFailure, ReachesTheCallerAsBadAlloc) {
  const Capacities caps{8, 512, 2048, 4096, 64};
  expect_each_failure_reaches_the_caller("window", [&] { Window w(caps); });
  expect_each_failure_reaches_the_caller("sparsifier", [&] { Sparsifier s(caps, Params{}); });
  expect_each_failure_reaches_the_caller("incremental sparsifier",
                                         [&] { Sparsifier s(caps, Params{}, SolveMode::kIncremental); });
  expect_each_failure_reaches_the_caller("deferred culls", [&] { DeferredCulls d(512, 2); });
}

}  // namespace
}  // namespace keepless::core
