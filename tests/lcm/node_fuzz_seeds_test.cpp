// node_message_fuzzer's seed corpus (tests/fuzz/node_message_seed_corpus.hpp)
// replayed through its op language into a node configured as the fuzzer's:
// each seed builds the traffic its comment names, so the fuzzer starts from
// the paths it is meant to reach (a misaligned seed is parsed as other ops).

#include <gtest/gtest.h>

#include "node_memq_fixture.hpp"
#include "node_message_input.hpp"
#include "node_message_seed_corpus.hpp"

namespace {

using namespace keepless::testing;
namespace fz = keepless::fuzz;
using A = keepless::map_event_ack_t;
using D = keepless::decision_t;

class FuzzSeeds : public NodeOnMemq {
 protected:
  void SetUp() override {
    NodeConfig c = default_config();  // node_message_fuzzer's config()
    c.window = 4;
    c.max_observations = 16;
    c.max_event_ids = 8;
    c.params.pair_capacity = 3;
    c.cull_memory = 2048;
    make_node(c);
  }

  // The fuzzer's interpretation of one input (publisher base 0, a fresh node).
  void replay(const std::vector<unsigned char>& seed) {
    fz::Reader r(seed.data(), seed.size());
    fz::Stream stream;
    for (int step = 0; step < 64 && !r.done(); ++step) {
      const fz::Message m = fz::next_message(r, stream);
      if (m.op == fz::kAdvanceClock) {
        clock_.advance(static_cast<std::uint64_t>(config_.owner_timeout_s * 1e9) * static_cast<std::uint64_t>(m.timeouts));
      } else {
        send_bytes(m.is_keyframe() ? config_.keyframe_channel : config_.event_channel, m.bytes);
      }
    }
  }

  std::vector<std::uint64_t> window_ids() const { return snapshot(node_->window()).ids; }
  std::int64_t culled_total() const {
    std::int64_t n = 0;
    for (const D& d : decisions_) n += d.num_culled;
    return n;
  }
};

const std::vector<std::vector<unsigned char>>& corpus() {
  static const std::vector<std::vector<unsigned char>> seeds = fz::node_message_seed_corpus();
  return seeds;
}

TEST_F(FuzzSeeds, SeedZeroIsASlidingCullingStream) {
  replay(corpus()[0]);
  ASSERT_EQ(decisions_.size(), 8u) << node_->counters().keyframes_received << " received, " << node_->counters().messages_rejected << " rejected, seed bytes " << corpus()[0].size();
  for (const D& d : decisions_) EXPECT_EQ(d.status, D::STATUS_OPTIMAL) << "seq " << d.sequence;
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  EXPECT_EQ(window_ids(), (std::vector<std::uint64_t>{4, 5, 6, 7}));
  EXPECT_GT(culled_total(), 0);
}

TEST_F(FuzzSeeds, SeedOneEndsInAMapEventWithGoodAndBadItems) {
  replay(corpus()[1]);
  EXPECT_EQ(decisions_.size(), 5u);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_[0].status, A::STATUS_PARTIAL);
  EXPECT_EQ(acks_[0].removed_applied, 1);  // keyframe 2; 31 is unknown
  EXPECT_EQ(acks_[0].refused[A::ITEM_REMOVE_UNKNOWN_KEYFRAME], 1);
  EXPECT_EQ(acks_[0].deleted_applied, 2);
}

TEST_F(FuzzSeeds, SeedTwoResetsBetweenStreams) {
  replay(corpus()[2]);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_TRUE(acks_[0].reset);
  EXPECT_EQ(decisions_.size(), 6u);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  EXPECT_EQ(window_ids(), (std::vector<std::uint64_t>{0, 1, 2}));
}

TEST_F(FuzzSeeds, SeedFourRefusesTheAbsurdSequenceAndUtime) {
  replay(corpus()[4]);
  EXPECT_EQ(rejected(RejectReason::kSequenceJump), 1u);
  EXPECT_EQ(rejected(RejectReason::kUtimeJump), 1u);
  EXPECT_EQ(node_->counters().messages_rejected, 2u);
  EXPECT_EQ(decisions_.size(), 7u);
}

TEST_F(FuzzSeeds, SeedSevenRefusesTheBadQuaternionTheNanAndTheRawBytes) {
  replay(corpus()[7]);
  EXPECT_EQ(rejected(RejectReason::kInvalidField), 1u);
  EXPECT_EQ(rejected(RejectReason::kNonFinite), 1u);
  EXPECT_EQ(rejected(RejectReason::kTruncated), 1u);  // 3 raw bytes
  EXPECT_EQ(decisions_.size(), 4u);
}

TEST_F(FuzzSeeds, SeedEightRefusesTheStaleMapEvent) {
  replay(corpus()[8]);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_[0].status, A::STATUS_REJECTED);
  EXPECT_EQ(acks_[0].reject_reason, static_cast<std::int8_t>(RejectReason::kOutOfOrder));
}

TEST_F(FuzzSeeds, SeedFifteenRefusesASelfMergeBeforeAValidOne) {
  replay(corpus()[15]);
  EXPECT_EQ(decisions_.size(), 4u);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_[0].refused[A::ITEM_MERGE_SELF], 1);
  EXPECT_EQ(acks_[0].num_refused, 1);
}

}  // namespace
