// An allocation that fails while a Window, Sparsifier or DeferredCulls is
// being built reaches the caller as std::bad_alloc, which keepless_node and
// keepless_sparsify answer "cannot allocate ...", exit 2. The embedded
// profile compiles keepless::core without exceptions; on 32-bit ARM such
// code gets no unwind tables unless asked (-funwind-tables), and the
// unwinder calls std::terminate at its first frame instead.
//
// Its own binary: it replaces the global operator new with one that fails
// on demand.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>

#include "keepless/core/config.hpp"
#include "keepless/core/deferred_culls.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"

namespace {
// Allocations left before the next one fails (negative: never fails).
std::atomic<std::int64_t> g_allocations_left{-1};
std::atomic<std::int64_t> g_allocations{0};

void* allocate(std::size_t size) {
  g_allocations.fetch_add(1);
  if (g_allocations_left.load() >= 0 && g_allocations_left.fetch_sub(1) == 0) throw std::bad_alloc();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace keepless::core {
namespace {

// Fails the allocation number `n` (0: the first) inside `make`; true if
// std::bad_alloc reached this frame.
template <typename Make>
bool fails_with_bad_alloc(std::int64_t n, Make make) {
  g_allocations_left.store(n);
  bool caught = false;
  try {
    make();
  } catch (const std::bad_alloc&) {
    caught = true;
  }
  g_allocations_left.store(-1);
  return caught;
}

// Fails each of the first allocations of `make` in turn.
template <typename Make>
void expect_each_failure_reaches_the_caller(const char* what, Make make) {
  const std::int64_t before = g_allocations.load();
  make();
  const std::int64_t count = g_allocations.load() - before;
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
