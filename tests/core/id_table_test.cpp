// IdTable (core/src/id_table.hpp), the fixed-capacity id -> value map of the
// window and the incremental network: it agrees with std::map under seeded
// churn at full load, refuses ids beyond its capacity without changing,
// keeps values through the backward-shift deletions, and allocates nothing
// after construction (this binary counts operator new).

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "counting_new.hpp"  // this binary's only inclusion
#include "id_table.hpp"

namespace keepless::core {
namespace {

// Every id of the model is found with its value; absent probe ids are not.
::testing::AssertionResult agrees(const IdTable& table,
                                  const std::map<std::uint64_t, std::uint32_t>& model,
                                  const std::vector<std::uint64_t>& absent) {
  if (table.size() != model.size()) {
    return ::testing::AssertionFailure() << "size " << table.size() << " vs " << model.size();
  }
  for (const auto& [id, value] : model) {
    const std::uint32_t* v = table.find(id);
    if (v == nullptr || *v != value) return ::testing::AssertionFailure() << "id " << id << " lost";
  }
  for (std::uint64_t id : absent) {
    if (model.count(id) == 0 && table.find(id) != nullptr) {
      return ::testing::AssertionFailure() << "id " << id << " found but absent";
    }
  }
  return ::testing::AssertionSuccess();
}

TEST(IdTable, StartsEmpty) {
  const IdTable table(8);
  EXPECT_EQ(table.size(), 0u);
  EXPECT_EQ(table.capacity(), 8u);
  EXPECT_EQ(table.find(0), nullptr);
  EXPECT_EQ(table.find(~0ULL), nullptr);
}

TEST(IdTable, InsertFindEraseOneId) {
  IdTable table(4);
  std::uint32_t* v = table.insert(42, 7);
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(*v, 7u);
  *v = 9;  // values are the caller's to change
  ASSERT_NE(table.find(42), nullptr);
  EXPECT_EQ(*table.find(42), 9u);
  // Inserting a present id returns its value and changes nothing.
  EXPECT_EQ(*table.insert(42, 1), 9u);
  EXPECT_EQ(table.size(), 1u);
  EXPECT_TRUE(table.erase(42));
  EXPECT_FALSE(table.erase(42));
  EXPECT_EQ(table.find(42), nullptr);
  EXPECT_EQ(table.size(), 0u);
}

TEST(IdTable, RefusesIdsBeyondCapacity) {
  IdTable table(3);
  ASSERT_NE(table.insert(1, 10), nullptr);
  ASSERT_NE(table.insert(2, 20), nullptr);
  ASSERT_NE(table.insert(3, 30), nullptr);
  EXPECT_EQ(table.insert(4, 40), nullptr);
  EXPECT_EQ(table.find(4), nullptr);
  EXPECT_EQ(table.size(), 3u);
  EXPECT_EQ(*table.insert(2, 99), 20u);  // a present id is still found when full
  ASSERT_TRUE(table.erase(1));
  ASSERT_NE(table.insert(4, 40), nullptr);
  EXPECT_EQ(*table.find(4), 40u);

  IdTable none(0);
  EXPECT_EQ(none.insert(5, 1), nullptr);
  EXPECT_EQ(none.size(), 0u);
}

TEST(IdTable, ClearForgetsEverything) {
  IdTable table(16);
  for (std::uint64_t id = 0; id < 16; ++id) ASSERT_NE(table.insert(id * 977, 1), nullptr);
  table.clear();
  EXPECT_EQ(table.size(), 0u);
  for (std::uint64_t id = 0; id < 16; ++id) EXPECT_EQ(table.find(id * 977), nullptr);
  for (std::uint64_t id = 0; id < 16; ++id) EXPECT_NE(table.insert(id + 1, 2), nullptr);
}

// Churn at full load with ids drawn from a small range (many collisions and
// long clusters) and from the whole 64-bit range, checked against std::map
// after every operation; no allocation after construction.
TEST(IdTable, ChurnMatchesModel) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    const std::uint32_t capacity = 64 + static_cast<std::uint32_t>(seed * 37);
    const std::uint64_t range = seed % 2 == 0 ? 3ULL * capacity : ~0ULL;
    const auto draw = [&] { return range == ~0ULL ? rng() : rng() % range; };
    std::vector<std::uint64_t> probes;
    for (int i = 0; i < 64; ++i) probes.push_back(draw());
    std::map<std::uint64_t, std::uint32_t> model;
    IdTable table(capacity);
    const std::size_t bytes = table.memory_bytes();

    // Armed around the table's calls only (the model allocates).
    test::AllocationCounter counter;
    counter.pause();
    for (int step = 0; step < 20000; ++step) {
      const std::uint64_t id = draw();
      const auto value = static_cast<std::uint32_t>(rng());
      if (rng() % 3 != 0) {  // lean to insertions: the table stays near full
        counter.resume();
        std::uint32_t* v = table.insert(id, value);
        counter.pause();
        const bool present = model.count(id) != 0;
        if (!present && model.size() == capacity) {
          ASSERT_EQ(v, nullptr);
        } else {
          ASSERT_NE(v, nullptr);
          if (present) {
            ASSERT_EQ(*v, model[id]);
          } else {
            model[id] = value;
          }
        }
      } else {
        const std::uint64_t victim =
            model.empty() || rng() % 4 == 0
                ? id
                : std::next(model.begin(), static_cast<long>(rng() % model.size()))->first;
        counter.resume();
        const bool erased = table.erase(victim);
        counter.pause();
        ASSERT_EQ(erased, model.erase(victim) == 1);
      }
      if (step % 97 == 0) {
        ASSERT_TRUE(agrees(table, model, probes)) << "step " << step;
      }
    }
    ASSERT_TRUE(agrees(table, model, probes));
    EXPECT_EQ(counter.stop(), 0u);
    EXPECT_EQ(table.memory_bytes(), bytes);
  }
}

// The layout is a function of the calls: two tables given the same calls
// answer alike, and the hash is splitmix64's (whose first output from state
// 0 is the published 0xe220a8397b1dcdaf), the same on every platform.
TEST(IdTable, DeterministicHash) {
  EXPECT_EQ(IdTable::mix(0), 0xe220a8397b1dcdafULL);
  IdTable a(100), b(100);
  std::mt19937_64 rng(7);
  for (int i = 0; i < 1000; ++i) {
    const std::uint64_t id = rng() % 300;
    if (i % 4 == 3) {
      EXPECT_EQ(a.erase(id), b.erase(id));
    } else {
      EXPECT_EQ(a.insert(id, static_cast<std::uint32_t>(i)) == nullptr,
                b.insert(id, static_cast<std::uint32_t>(i)) == nullptr);
    }
  }
  EXPECT_EQ(a.size(), b.size());
  for (std::uint64_t id = 0; id < 300; ++id) {
    ASSERT_EQ(a.find(id) == nullptr, b.find(id) == nullptr);
    if (a.find(id) != nullptr) {
      EXPECT_EQ(*a.find(id), *b.find(id));
    }
  }
}

}  // namespace
}  // namespace keepless::core
