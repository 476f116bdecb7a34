#pragma once
// Counting replacement of the global operator new/delete, for the binaries
// that prove a path allocates nothing after initialisation.
//
// Include this header in EXACTLY ONE translation unit per binary: it defines
// the replaceable global operators (which may not be inline), so a second
// inclusion is a multiple-definition link error, and a binary without it
// keeps the normal allocator.
//
// Every allocating form (plain, array, nothrow, aligned, aligned nothrow)
// goes through one counter, and every delete form through free(), so any
// pairing of new and delete stays valid.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace keepless::test {

// Counts allocations only while armed, so gtest's bookkeeping and the test's
// own set-up outside the measured region do not register. Constructing one
// resets the count and arms it; pause()/resume() bracket several measured
// regions into one count; the destructor disarms.
class AllocationCounter {
 public:
  AllocationCounter() {
    count_.store(0, std::memory_order_relaxed);
    bytes_.store(0, std::memory_order_relaxed);
    resume();
  }
  ~AllocationCounter() { pause(); }
  AllocationCounter(const AllocationCounter&) = delete;
  AllocationCounter& operator=(const AllocationCounter&) = delete;

  void pause() { armed_.store(false, std::memory_order_relaxed); }
  void resume() { armed_.store(true, std::memory_order_relaxed); }
  // Allocations seen while armed since construction.
  std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }
  // Disarms and returns the count.
  std::uint64_t stop() {
    pause();
    return count();
  }

  // Bytes requested by those allocations (to check a memory_bytes() report).
  std::uint64_t bytes() const { return bytes_.load(std::memory_order_relaxed); }

  // Makes the n-th allocation from now (0: the next) throw std::bad_alloc,
  // armed or not; -1: none. For the tests that an allocation failure reaches
  // the caller.
  static void fail_allocation(std::int64_t n) { fail_in_.store(n, std::memory_order_relaxed); }

  // For the replacement operators below only.
  static void note_allocation(std::size_t size) {
    if (fail_in_.load(std::memory_order_relaxed) >= 0 && fail_in_.fetch_sub(1, std::memory_order_relaxed) == 0) {
      throw std::bad_alloc();
    }
    if (armed_.load(std::memory_order_relaxed)) {
      count_.fetch_add(1, std::memory_order_relaxed);
      bytes_.fetch_add(size, std::memory_order_relaxed);
    }
  }

 private:
  // Atomic: allocations may come from other threads (LCM, the node).
  static inline std::atomic<bool> armed_{false};
  static inline std::atomic<std::uint64_t> count_{0};
  static inline std::atomic<std::uint64_t> bytes_{0};
  static inline std::atomic<std::int64_t> fail_in_{-1};
};

namespace counting_new_detail {

inline void* allocate(std::size_t size) {
  AllocationCounter::note_allocation(size);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

// posix_memalign rather than aligned_alloc: it needs no size rounding and
// accepts any power-of-two alignment once raised to sizeof(void*).
inline void* allocate_aligned(std::size_t size, std::align_val_t align) {
  AllocationCounter::note_allocation(size);
  const auto alignment = static_cast<std::size_t>(align);
  void* p = nullptr;
  if (posix_memalign(&p, alignment < sizeof(void*) ? sizeof(void*) : alignment,
                     size == 0 ? 1 : size) == 0) {
    return p;
  }
  throw std::bad_alloc();
}

template <typename Allocate>
void* allocate_nothrow(Allocate allocate) noexcept {
  try {
    return allocate();
  } catch (...) {
    return nullptr;
  }
}

}  // namespace counting_new_detail
}  // namespace keepless::test

void* operator new(std::size_t size) { return keepless::test::counting_new_detail::allocate(size); }
void* operator new[](std::size_t size) {
  return keepless::test::counting_new_detail::allocate(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return keepless::test::counting_new_detail::allocate_nothrow(
      [size] { return keepless::test::counting_new_detail::allocate(size); });
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return keepless::test::counting_new_detail::allocate_nothrow(
      [size] { return keepless::test::counting_new_detail::allocate(size); });
}
void* operator new(std::size_t size, std::align_val_t align) {
  return keepless::test::counting_new_detail::allocate_aligned(size, align);
}
void* operator new[](std::size_t size, std::align_val_t align) {
  return keepless::test::counting_new_detail::allocate_aligned(size, align);
}
void* operator new(std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  return keepless::test::counting_new_detail::allocate_nothrow(
      [size, align] { return keepless::test::counting_new_detail::allocate_aligned(size, align); });
}
void* operator new[](std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  return keepless::test::counting_new_detail::allocate_nothrow(
      [size, align] { return keepless::test::counting_new_detail::allocate_aligned(size, align); });
}

// GCC at -O1 (the asan preset) inlines these into a caller of ::operator
// new and warns that free() meets new's pointer: here new is malloc.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11
#pragma GCC diagnostic pop
#endif
