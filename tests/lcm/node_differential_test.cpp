// The node's state across long random streams, checked differentially after
// every message: keyframes with overlapping (and re-observed) point ids,
// map events (deletions, merges, removals, resets, bad items), sliding past
// K, duplicates, stale and out-of-order messages, invalid keyframes and
// another publisher's traffic. After each message:
//  1. the node's window (keyframe ids, observations, tracked flags) and its
//     cull memory equal a plain reference model (std containers, the rules
//     of docs/reference/lcm-messages.md and node.md);
//  2. each decision of the node's incremental path (Sparsifier::update)
//     equals a from-scratch Sparsifier::run() on a Window rebuilt from the
//     reference model;
//  3. a refused message changes nothing (window, cull memory, order).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "case_count.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/platform/recent_ids.hpp"
#include "node_memq_fixture.hpp"

namespace {

namespace kt = keepless::testing;
namespace core = keepless::core;
using keepless::platform::NodeConfig;
using keepless::platform::RejectReason;
using A = keepless::map_event_ack_t;

constexpr std::int64_t kOwner = 42;
constexpr std::int64_t kStranger = 7;

// --- the reference model -----------------------------------------------------

struct RefObs {
  std::uint64_t point;
  double u, v;
  std::uint8_t tracked;
  double depth;
  core::PointQuality quality;
};
struct RefFrame {
  std::uint64_t id;
  double centre[3];
  double fx = 0, fy = 0, cx = 0, cy = 0;
  bool has_tracked;
  bool has_quality = false;
  std::vector<RefObs> obs;
};

struct Model {
  std::deque<RefFrame> frames;
  std::deque<std::uint64_t> cull_fifo;  // FIFO of distinct culled ids
  std::set<std::uint64_t> culls;
  std::uint32_t cull_capacity = 0;
  std::uint32_t k = 0;
  std::uint32_t max_points = 0, max_observations = 0;
  bool owned = false;
  std::int64_t last_sequence = 0, last_utime = 0;
  std::uint64_t stale = 0;

  bool has_keyframe(std::uint64_t id) const {
    return std::any_of(frames.begin(), frames.end(), [id](const RefFrame& f) { return f.id == id; });
  }
  std::set<std::uint64_t> points() const {
    std::set<std::uint64_t> p;
    for (const RefFrame& f : frames)
      for (const RefObs& o : f.obs) p.insert(o.point);
    return p;
  }
  std::size_t observations() const {
    std::size_t n = 0;
    for (const RefFrame& f : frames) n += f.obs.size();
    return n;
  }
  void remember_cull(std::uint64_t id) {
    if (culls.count(id) > 0) return;
    if (cull_fifo.size() == cull_capacity) {
      culls.erase(cull_fifo.front());
      cull_fifo.pop_front();
    }
    cull_fifo.push_back(id);
    culls.insert(id);
  }
  void clear() {
    frames.clear();
    cull_fifo.clear();
    culls.clear();
  }
  bool follows(std::int64_t sequence, std::int64_t utime, RejectReason* why) const {
    if (sequence <= last_sequence) {
      *why = RejectReason::kOutOfOrder;
      return false;
    }
    if (utime < last_utime) {
      *why = RejectReason::kUtimeBackwards;
      return false;
    }
    return true;
  }
};

// The window a from-scratch run sees, rebuilt from the model.
std::unique_ptr<core::Window> rebuild(const Model& m, const core::Capacities& caps) {
  auto w = std::make_unique<core::Window>(caps);
  for (const RefFrame& f : m.frames) {
    core::Keyframe kf;
    kf.id = f.id;
    std::copy(f.centre, f.centre + 3, kf.centre);
    std::vector<core::Observation> obs;
    std::vector<std::uint8_t> tracked;
    std::vector<core::PointQuality> quality;
    kf.fx = f.fx;
    kf.fy = f.fy;
    kf.cx = f.cx;
    kf.cy = f.cy;
    for (const RefObs& o : f.obs) {
      core::Observation x;
      x.point = o.point;
      x.u = o.u;
      x.v = o.v;
      x.depth = o.depth;
      obs.push_back(x);
      tracked.push_back(o.tracked);
      quality.push_back(o.quality);
    }
    kf.tracked = f.has_tracked && !tracked.empty() ? tracked.data() : nullptr;
    kf.quality = f.has_quality && caps.hold_quality && !quality.empty() ? quality.data() : nullptr;
    const core::Status s = w->add_keyframe(kf, obs.data(), static_cast<std::uint32_t>(obs.size()));
    EXPECT_EQ(s, core::Status::kOk) << "reference window refused keyframe " << f.id;
  }
  return w;
}

// --- the stream generator -----------------------------------------------------

class Stream {
 public:
  explicit Stream(std::uint64_t seed) : rng_(seed) {
    // Point ids: small ones and ids with the top bit set (negative as int64).
    for (std::uint64_t i = 0; i < 90; ++i) universe_.push_back(i);
    for (std::uint64_t i = 0; i < 10; ++i) universe_.push_back(0xFFFFFFFFFFFFFF00ull + i * 7);
    for (std::uint64_t i = 0; i < 6; ++i) universe_.push_back(0x8000000000000000ull + i);
    sequence_ = 100 + static_cast<std::int64_t>(pick(50));
    utime_ = 5000000;
  }
  std::uint64_t pick(std::uint64_t n) { return n == 0 ? 0 : rng_() % n; }
  bool chance(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }
  std::uint64_t any_point() { return universe_[pick(universe_.size())]; }
  std::uint64_t local_point() {
    // Overlapping neighbourhoods drifting through the universe.
    const std::uint64_t span = 30;
    const std::uint64_t at = (drift_ / 3 + pick(span)) % 90;
    return chance(0.08) ? universe_[90 + pick(16)] : at;
  }
  std::uint64_t fresh_keyframe_id(const Model& m) {
    for (;;) {
      std::uint64_t id = chance(0.1) ? 0xF000000000000000ull + pick(12) : pick(24);
      if (!m.has_keyframe(id)) return id;
    }
  }
  // The next sequence and utime of the owner's stream.
  void advance() {
    sequence_ += 1 + (chance(0.1) ? static_cast<std::int64_t>(pick(3)) : 0);
    if (!chance(0.2)) utime_ += 1000 * (1 + static_cast<std::int64_t>(pick(50)));
  }

  keepless::keyframe_t keyframe(const Model& m) {
    ++drift_;
    advance();
    keepless::keyframe_t k = kt::make_keyframe(sequence_, 0, {});
    k.utime = utime_;
    k.publisher_id = kOwner;
    k.keyframe_id = static_cast<std::int64_t>(fresh_keyframe_id(m));
    k.centre[0] = static_cast<double>(pick(1000)) * 0.01;
    k.centre[1] = static_cast<double>(pick(100)) * 0.01;
    k.centre[2] = static_cast<double>(pick(100)) * 0.01;
    const std::size_t n = 2 + pick(24);
    std::set<std::uint64_t> ids;
    while (ids.size() < n) ids.insert(chance(0.1) ? any_point() : local_point());
    std::vector<std::uint64_t> order(ids.begin(), ids.end());
    std::shuffle(order.begin(), order.end(), rng_);
    for (std::uint64_t id : order) {
      k.point_id.push_back(static_cast<std::int64_t>(id));
      k.u.push_back(static_cast<float>(pick(640)) + 0.5f);
      k.v.push_back(static_cast<float>(pick(480)) + 0.25f);
    }
    k.num_observations = static_cast<std::int32_t>(n);
    if (chance(0.4)) {
      for (std::size_t i = 0; i < n; ++i) k.tracked.push_back(static_cast<std::int8_t>(chance(0.5)));
      k.num_tracked = static_cast<std::int32_t>(n);
    }
    // Optional arrays for the other cost models: depths and intrinsics, point quality.
    if (chance(0.7)) {
      for (std::size_t i = 0; i < n; ++i) k.depth.push_back(static_cast<float>(pick(40)) * 0.25f);
      k.num_depths = static_cast<std::int32_t>(n);
    }
    if (chance(0.7)) {
      k.intrinsics = {500.0 + static_cast<double>(pick(10)), 500.0, 320.0, 240.0};
      k.num_intrinsics = 4;
    }
    if (chance(0.7)) {
      for (std::size_t i = 0; i < n; ++i) {
        k.track_length.push_back(static_cast<std::int32_t>(pick(30)));
        k.age.push_back(static_cast<std::int32_t>(pick(12)) - 1);
        k.reprojection_error.push_back(static_cast<float>(pick(20)) * 0.125f - 0.25f);
        k.triangulation_angle.push_back(static_cast<float>(pick(30)) * 0.5f);
      }
      k.num_quality = static_cast<std::int32_t>(n);
    }
    return k;
  }

  keepless::map_event_t event(const Model& m) {
    advance();
    keepless::map_event_t e = kt::make_event(sequence_);
    e.utime = utime_;
    e.publisher_id = kOwner;
    if (chance(0.06)) {
      e.reset = true;
      // Lists are ignored on a reset.
      if (chance(0.5)) e.deleted_point_id.push_back(static_cast<std::int64_t>(any_point()));
      return e;
    }
    const std::vector<std::uint64_t> window_points = [&] {
      const std::set<std::uint64_t> p = m.points();
      return std::vector<std::uint64_t>(p.begin(), p.end());
    }();
    const auto a_window_point = [&]() {
      return window_points.empty() || chance(0.2) ? any_point() : window_points[pick(window_points.size())];
    };
    const std::size_t nd = chance(0.5) ? pick(5) : 0;
    for (std::size_t i = 0; i < nd; ++i) e.deleted_point_id.push_back(static_cast<std::int64_t>(a_window_point()));
    const std::size_t nm = chance(0.6) ? pick(6) : 0;
    for (std::size_t i = 0; i < nm; ++i) {
      const std::uint64_t from = chance(0.15) && !e.merged_from_id.empty()
                                     ? static_cast<std::uint64_t>(e.merged_from_id[pick(e.merged_from_id.size())])
                                     : a_window_point();
      std::uint64_t into;
      const std::uint64_t kind = pick(10);
      if (kind == 0) {
        into = from;  // self
      } else if (kind == 1 && !e.merged_from_id.empty()) {
        into = static_cast<std::uint64_t>(e.merged_from_id[pick(e.merged_from_id.size())]);  // chain
      } else if (kind == 2 && !e.deleted_point_id.empty()) {
        into = static_cast<std::uint64_t>(e.deleted_point_id[pick(e.deleted_point_id.size())]);  // deleted
      } else if (kind == 3 && !m.culls.empty()) {
        auto it = m.culls.begin();
        std::advance(it, static_cast<long>(pick(m.culls.size())));
        into = *it;  // culled
      } else {
        into = a_window_point();
      }
      e.merged_from_id.push_back(static_cast<std::int64_t>(from));
      e.merged_into_id.push_back(static_cast<std::int64_t>(into));
    }
    const std::size_t nr = chance(0.4) ? pick(3) : 0;
    for (std::size_t i = 0; i < nr; ++i) {
      if (!m.frames.empty() && !chance(0.2)) {
        e.removed_keyframe_id.push_back(static_cast<std::int64_t>(m.frames[pick(m.frames.size())].id));
      } else {
        e.removed_keyframe_id.push_back(static_cast<std::int64_t>(pick(40)));
      }
    }
    return e;
  }

  std::int64_t sequence() const { return sequence_; }
  std::int64_t utime() const { return utime_; }
  std::mt19937_64& rng() { return rng_; }

 private:
  std::mt19937_64 rng_;
  std::vector<std::uint64_t> universe_;
  std::int64_t sequence_ = 0, utime_ = 0;
  std::uint64_t drift_ = 0;
};

// --- the test ------------------------------------------------------------------
struct Variant {
  const char* name;
  NodeConfig config;
  // With a latency target: messages arrive in bursts of 1..4 and spin_once
  // drains them, so of consecutive accepted keyframes only the newest is
  // decided (the others STATUS_SKIPPED). Checked after each burst.
  bool drain = false;
};

struct Totals {
  std::uint64_t decided = 0, culled = 0, skipped = 0, refused_keyframes = 0, events = 0, refused_events = 0,
                resets = 0, merges = 0, items_refused = 0, removed = 0, stale = 0, capacity = 0, reentered = 0;
};

// What the node must answer to one keyframe.
struct ExpectedDecision {
  std::int64_t sequence = 0, keyframe_id = 0, publisher = 0;
  std::int8_t status = 0, reason = -1;
  std::vector<std::uint64_t> window;
  std::vector<std::uint64_t> culled;
  core::Summary summary{};
  std::string what;
};
struct ExpectedAck {
  std::int64_t sequence = 0, publisher = 0;
  std::int8_t status = 0, reason = -1;
  bool reset = false;
  std::int32_t deleted = 0, merged = 0, removed = 0;
  std::vector<std::pair<std::int64_t, std::int8_t>> refused;
  bool any_status = false;  // an event before the first keyframe: applied or partial
  std::string what;
};

class NodeDifferential : public kt::NodeOnMemq {
 protected:
  struct State {
    kt::WindowSnapshot window;
    std::vector<std::vector<int>> tracked;
    std::int64_t last_sequence;
    std::uint32_t culls;
  };
  State state() const {
    State s;
    s.window = kt::snapshot(node_->window());
    const core::Window& w = node_->window();
    for (std::uint32_t i = 0; i < w.keyframe_count(); ++i) {
      std::vector<int> t;
      if (w.keyframe(i).tracked != nullptr)
        for (std::uint32_t j = 0; j < w.observation_count(i); ++j) t.push_back(w.keyframe(i).tracked[j]);
      s.tracked.push_back(t);
    }
    s.last_sequence = node_->order().last_sequence();
    s.culls = node_->cull_memory().size();
    return s;
  }
  static bool same(const State& a, const State& b) {
    return a.window == b.window && a.tracked == b.tracked && a.last_sequence == b.last_sequence &&
           a.culls == b.culls;
  }

  // (1) window and cull memory against the model.
  ::testing::AssertionResult matches() const {
    const core::Window& w = node_->window();
    if (w.keyframe_count() != m_.frames.size()) {
      return ::testing::AssertionFailure() << "keyframes " << w.keyframe_count() << " vs model " << m_.frames.size();
    }
    for (std::uint32_t i = 0; i < w.keyframe_count(); ++i) {
      const RefFrame& f = m_.frames[i];
      if (w.keyframe(i).id != f.id) {
        return ::testing::AssertionFailure() << "slot " << i << " id " << w.keyframe(i).id << " vs model " << f.id;
      }
      if (w.observation_count(i) != f.obs.size()) {
        return ::testing::AssertionFailure() << "keyframe " << f.id << " observations " << w.observation_count(i)
                                             << " vs model " << f.obs.size();
      }
      if (!f.obs.empty() && (w.keyframe(i).tracked != nullptr) != f.has_tracked) {
        return ::testing::AssertionFailure() << "keyframe " << f.id << " tracked flags present "
                                             << (w.keyframe(i).tracked != nullptr) << " vs model " << f.has_tracked;
      }
      for (std::uint32_t j = 0; j < f.obs.size(); ++j) {
        const core::Observation& o = w.observations(i)[j];
        if (o.point != f.obs[j].point || o.u != f.obs[j].u || o.v != f.obs[j].v) {
          return ::testing::AssertionFailure() << "keyframe " << f.id << " observation " << j << ": point " << o.point
                                               << " (" << o.u << ", " << o.v << ") vs model " << f.obs[j].point << " ("
                                               << f.obs[j].u << ", " << f.obs[j].v << ")";
        }
        if (f.has_tracked && w.keyframe(i).tracked[j] != f.obs[j].tracked) {
          return ::testing::AssertionFailure() << "keyframe " << f.id << " tracked flag of point " << o.point;
        }
      }
    }
    if (node_->cull_memory().size() != m_.culls.size()) {
      return ::testing::AssertionFailure() << "cull memory " << node_->cull_memory().size() << " vs model "
                                           << m_.culls.size();
    }
    for (std::uint64_t id : ids_seen_) {
      if (node_->cull_memory().contains(id) != (m_.culls.count(id) > 0)) {
        return ::testing::AssertionFailure() << "cull memory disagrees on " << id;
      }
    }
    if (node_->counters().stale_observations != m_.stale) {
      return ::testing::AssertionFailure() << "stale observations " << node_->counters().stale_observations
                                           << " vs model " << m_.stale;
    }
    return ::testing::AssertionSuccess();
  }

  // (2) a decision the model makes now: a from-scratch run on its window.
  void decide(ExpectedDecision d, bool evicted) {
    d.window.clear();
    for (const RefFrame& f : m_.frames) d.window.push_back(f.id);
    if (evicted) {
      ++totals_->capacity;
      d.status = keepless::decision_t::STATUS_CAPACITY_EXCEEDED;
      reference_->note_undecided();
      expected_.push_back(d);
      return;
    }
    const std::unique_ptr<core::Window> w = rebuild(m_, caps_);
    const core::Status st = reference_->run(*w);
    if (st != core::Status::kOk) {
      ++totals_->capacity;
      EXPECT_EQ(st, core::Status::kCapacityExceeded) << d.what;
      d.status = keepless::decision_t::STATUS_CAPACITY_EXCEEDED;
      expected_.push_back(d);
      return;
    }
    d.status = keepless::decision_t::STATUS_OPTIMAL;
    d.summary = reference_->summary();
    for (std::uint32_t i = 0; i < reference_->decision_count(); ++i) {
      if (reference_->decisions()[i].verdict == core::Verdict::kCull) d.culled.push_back(reference_->decisions()[i].point);
    }
    ++totals_->decided;
    totals_->culled += d.culled.size();
    // The node drops its culls from the window and remembers them.
    const std::set<std::uint64_t> gone(d.culled.begin(), d.culled.end());
    for (RefFrame& fr : m_.frames) {
      fr.obs.erase(std::remove_if(fr.obs.begin(), fr.obs.end(), [&](const RefObs& o) { return gone.count(o.point) > 0; }),
                   fr.obs.end());
    }
    for (std::uint64_t p : d.culled) {
      m_.remember_cull(p);
      ever_culled_.insert(p);
    }
    expected_.push_back(d);
  }
  void decide_pending() {
    if (!has_pending_) return;
    has_pending_ = false;
    decide(pending_, pending_evicted_);
  }
  void skip_pending() {
    if (!has_pending_) return;
    has_pending_ = false;
    ++totals_->skipped;
    pending_.status = keepless::decision_t::STATUS_SKIPPED;
    reference_->note_undecided();
    expected_.push_back(pending_);
  }

  // The model's answer to a keyframe the generator made; `expect` the
  // refusal the stream rules give (kNone: accepted).
  void model_keyframe(const keepless::keyframe_t& k, const std::vector<std::uint8_t>& bytes, RejectReason expect,
                      const std::string& what) {
    ExpectedDecision d;
    d.sequence = k.sequence;
    d.keyframe_id = k.keyframe_id;
    d.publisher = k.publisher_id;
    d.what = what;
    if (expect != RejectReason::kNone) {
      ++totals_->refused_keyframes;
      decide_pending();  // answers stay in arrival order
      d.status = keepless::decision_t::STATUS_REJECTED_INPUT;
      d.reason = static_cast<std::int8_t>(expect);
      for (const RefFrame& f : m_.frames) d.window.push_back(f.id);
      expected_.push_back(d);
      return;
    }
    if (!m_.owned) {  // a takeover: window and cull memory cleared first
      decide_pending();
      m_.clear();
      ever_culled_.clear();
      reference_->forget_history();
      m_.owned = true;
    }
    m_.last_sequence = k.sequence;
    m_.last_utime = k.utime;
    accepted_.push_back(bytes);
    RefFrame f;
    f.id = static_cast<std::uint64_t>(k.keyframe_id);
    std::copy(k.centre, k.centre + 3, f.centre);
    f.has_tracked = k.num_tracked != 0;
    f.has_quality = k.num_quality != 0;
    if (k.num_intrinsics == 4) {
      f.fx = k.intrinsics[0];
      f.fy = k.intrinsics[1];
      f.cx = k.intrinsics[2];
      f.cy = k.intrinsics[3];
    }
    for (int i = 0; i < k.num_observations; ++i) {
      const auto p = static_cast<std::uint64_t>(k.point_id[i]);
      if (m_.culls.count(p) > 0) {  // culled recently: dropped (in-flight culls)
        ++m_.stale;
        continue;
      }
      if (ever_culled_.count(p) > 0) ++totals_->reentered;  // culled once, forgotten, observed again
      const auto q = static_cast<std::size_t>(i);
      core::PointQuality quality;
      if (f.has_quality) {
        quality = {static_cast<std::uint32_t>(k.track_length[q]), k.age[q], k.reprojection_error[q],
                   k.triangulation_angle[q]};
      }
      f.obs.push_back({p, static_cast<double>(k.u[i]), static_cast<double>(k.v[i]),
                       static_cast<std::uint8_t>(f.has_tracked ? k.tracked[i] : 0),
                       k.num_depths != 0 ? static_cast<double>(k.depth[q]) : 0.0, quality});
    }
    if (m_.frames.size() == m_.k) m_.frames.pop_front();
    m_.frames.push_back(f);
    // Beyond the window's points or observations: older keyframes leave first.
    bool evicted = false;
    while (m_.frames.size() > 1 && (m_.points().size() > m_.max_points || m_.observations() > m_.max_observations)) {
      m_.frames.pop_front();
      evicted = true;
    }
    skip_pending();  // superseded by this accepted keyframe
    if (drain_) {
      has_pending_ = true;
      pending_ = d;
      pending_.window.clear();
      for (const RefFrame& fr : m_.frames) pending_.window.push_back(fr.id);
      pending_evicted_ = evicted;
      return;
    }
    decide(d, evicted);
  }

  void model_event(const keepless::map_event_t& e, RejectReason expect, bool early, const std::string& what) {
    decide_pending();  // a map event never supersedes a queued keyframe
    ++totals_->events;
    ExpectedAck a;
    a.sequence = e.sequence;
    a.publisher = e.publisher_id;
    a.what = what;
    if (expect != RejectReason::kNone) {
      ++totals_->refused_events;
      a.status = A::STATUS_REJECTED;
      a.reason = static_cast<std::int8_t>(expect);
      acks_expected_.push_back(a);
      return;
    }
    a.any_status = early;
    if (m_.owned) {  // before the first keyframe there is no order to advance
      m_.last_sequence = e.sequence;
      m_.last_utime = e.utime;
    }
    if (e.reset) {
      ++totals_->resets;
      m_.clear();
      ever_culled_.clear();
      reference_->forget_history();
      a.status = A::STATUS_APPLIED;
      a.reset = true;
      acks_expected_.push_back(a);
      return;
    }
    // Items, as documented: deletions first, then merges (each refused item
    // named), then keyframe removals.
    std::set<std::uint64_t> deleted;
    for (std::int64_t p : e.deleted_point_id) deleted.insert(static_cast<std::uint64_t>(p));
    std::set<std::uint64_t> sources;
    for (std::int64_t f : e.merged_from_id) sources.insert(static_cast<std::uint64_t>(f));
    std::map<std::uint64_t, std::uint64_t> merge;  // applied: from -> into
    for (std::size_t i = 0; i < e.merged_from_id.size(); ++i) {
      const auto f = static_cast<std::uint64_t>(e.merged_from_id[i]);
      const auto t = static_cast<std::uint64_t>(e.merged_into_id[i]);
      std::int8_t why = -1;
      if (f == t) {
        why = A::ITEM_MERGE_SELF;
      } else if (merge.count(f) > 0) {
        why = A::ITEM_MERGE_REPEATED_SOURCE;
      } else if (sources.count(t) > 0) {
        why = A::ITEM_MERGE_CHAIN;
      } else if (deleted.count(t) > 0) {
        why = A::ITEM_MERGE_INTO_DELETED;
      } else if (m_.culls.count(t) > 0) {
        why = A::ITEM_MERGE_INTO_CULLED;
      }
      if (why >= 0) {
        a.refused.emplace_back(e.merged_from_id[i], why);
      } else {
        merge[f] = t;
      }
    }
    std::set<std::uint64_t> removed;
    for (std::int64_t id : e.removed_keyframe_id) {
      const auto k = static_cast<std::uint64_t>(id);
      if (!m_.has_keyframe(k)) {
        a.refused.emplace_back(id, A::ITEM_REMOVE_UNKNOWN_KEYFRAME);
      } else if (!removed.insert(k).second) {
        a.refused.emplace_back(id, A::ITEM_REMOVE_REPEATED);
      }
    }
    // Apply: deletions, merges (a keyframe left with two observations of a
    // point keeps the first), removals.
    std::set<std::uint64_t> merged_used;
    std::deque<RefFrame> next;
    for (const RefFrame& fr : m_.frames) {
      // A merge counts where it changed the window: not in a keyframe the
      // event removes (the node skips those before merging).
      if (removed.count(fr.id) > 0) continue;
      RefFrame out = fr;
      out.obs.clear();
      std::set<std::uint64_t> seen;
      for (RefObs o : fr.obs) {
        if (deleted.count(o.point) > 0) continue;
        const auto it = merge.find(o.point);
        if (it != merge.end()) {
          o.point = it->second;
          merged_used.insert(it->first);
        }
        if (!seen.insert(o.point).second) continue;
        out.obs.push_back(o);
      }
      next.push_back(out);
    }
    m_.frames = next;
    totals_->merges += merged_used.size();
    totals_->items_refused += a.refused.size();
    totals_->removed += removed.size();
    a.status = a.refused.empty() ? A::STATUS_APPLIED : A::STATUS_PARTIAL;
    a.deleted = static_cast<std::int32_t>(e.deleted_point_id.size());
    a.merged = static_cast<std::int32_t>(merged_used.size());
    a.removed = static_cast<std::int32_t>(removed.size());
    acks_expected_.push_back(a);
  }

  // Every answer the node published so far against the model's.
  void compare_answers() {
    ASSERT_EQ(decisions_.size(), expected_.size()) << "decisions published vs expected";
    for (; checked_decisions_ < expected_.size(); ++checked_decisions_) {
      const ExpectedDecision& x = expected_[checked_decisions_];
      const keepless::decision_t& d = decisions_[checked_decisions_];
      const std::string& w = x.what;
      EXPECT_EQ(d.sequence, x.sequence) << w;
      EXPECT_EQ(d.keyframe_id, x.keyframe_id) << w;
      EXPECT_EQ(d.publisher_id, x.publisher) << w;
      ASSERT_EQ(d.status, x.status) << w;
      EXPECT_EQ(d.reject_reason, x.reason) << w;
      std::vector<std::uint64_t> window, culled;
      for (std::int64_t id : d.window_keyframe_id) window.push_back(static_cast<std::uint64_t>(id));
      for (std::int64_t id : d.culled_point_id) culled.push_back(static_cast<std::uint64_t>(id));
      EXPECT_EQ(window, x.window) << w;
      ASSERT_EQ(culled, x.culled) << "incremental and from-scratch culls differ: " << w;
      EXPECT_EQ(d.num_culled, static_cast<std::int32_t>(x.culled.size())) << w;
      EXPECT_EQ(d.points, static_cast<std::int32_t>(x.summary.points)) << w;
      EXPECT_EQ(d.evaluated, static_cast<std::int32_t>(x.summary.evaluated)) << w;
      EXPECT_EQ(d.kept, static_cast<std::int32_t>(x.summary.kept)) << w;
      EXPECT_EQ(d.culled, static_cast<std::int32_t>(x.summary.culled)) << w;
      EXPECT_EQ(d.skipped, static_cast<std::int32_t>(x.summary.skipped)) << w;
      EXPECT_EQ(d.pairs, static_cast<std::int32_t>(x.summary.pairs)) << w;
      EXPECT_EQ(d.max_flow, x.summary.max_flow) << w;
      EXPECT_EQ(d.total_cost, x.summary.total_cost) << w;
    }
    ASSERT_EQ(acks_.size(), acks_expected_.size()) << "acknowledgements published vs expected";
    for (; checked_acks_ < acks_expected_.size(); ++checked_acks_) {
      const ExpectedAck& x = acks_expected_[checked_acks_];
      const A& a = acks_[checked_acks_];
      const std::string& w = x.what;
      EXPECT_EQ(a.sequence, x.sequence) << w;
      EXPECT_EQ(a.publisher_id, x.publisher) << w;
      if (x.any_status) {
        EXPECT_NE(a.status, A::STATUS_REJECTED) << w;
        continue;
      }
      EXPECT_EQ(a.status, x.status) << w;
      EXPECT_EQ(a.reject_reason, x.reason) << w;
      EXPECT_EQ(a.reset, x.reset) << w;
      EXPECT_EQ(a.deleted_applied, x.deleted) << w;
      EXPECT_EQ(a.merged_applied, x.merged) << w;
      EXPECT_EQ(a.removed_applied, x.removed) << w;
      ASSERT_EQ(a.num_refused, static_cast<std::int32_t>(x.refused.size())) << w;
      for (std::size_t i = 0; i < x.refused.size(); ++i) {
        EXPECT_EQ(a.refused_id[i], x.refused[i].first) << w << ", refused item " << i;
        EXPECT_EQ(a.refused_reason[i], x.refused[i].second) << w << ", refused item " << i;
      }
    }
  }

  void run_stream(const Variant& variant, std::uint64_t seed, int messages, std::vector<std::string>* log,
                  Totals* totals);

  Model m_;
  core::Capacities caps_;
  std::unique_ptr<core::Sparsifier> reference_;
  Totals* totals_ = nullptr;
  bool drain_ = false;
  std::vector<std::vector<std::uint8_t>> accepted_;  // accepted keyframes' bytes (retransmissions)
  std::set<std::uint64_t> ever_culled_;
  std::vector<std::uint64_t> ids_seen_;
  std::vector<ExpectedDecision> expected_;
  std::vector<ExpectedAck> acks_expected_;
  std::size_t checked_decisions_ = 0, checked_acks_ = 0;
  bool has_pending_ = false, pending_evicted_ = false;
  ExpectedDecision pending_;
};

void NodeDifferential::run_stream(const Variant& variant, std::uint64_t seed, int messages,
                                  std::vector<std::string>* log, Totals* totals) {
  make_node(variant.config);
  caps_ = keepless::platform::window_capacities(config_);
  reference_ = std::make_unique<core::Sparsifier>(caps_, config_.params);  // from scratch: run() only
  m_ = Model{};
  m_.k = config_.window;
  m_.cull_capacity = config_.cull_memory != 0 ? config_.cull_memory : caps_.max_points;
  m_.max_points = caps_.max_points;
  m_.max_observations = caps_.max_observations;
  totals_ = totals;
  drain_ = variant.drain;
  accepted_.clear();
  ever_culled_.clear();
  ids_seen_.clear();
  expected_.clear();
  acks_expected_.clear();
  checked_decisions_ = checked_acks_ = 0;
  has_pending_ = false;
  Stream g(seed);
  int burst = 0;  // messages left in the current burst (drain)

  for (int step = 0; step < messages; ++step) {
    const State before = state();
    const double r = std::uniform_real_distribution<double>(0, 1)(g.rng());
    std::ostringstream what;
    what << "#" << step << " ";
    std::string channel;
    std::vector<std::uint8_t> bytes;
    bool refused = false;

    if (!m_.owned && r < 0.1) {
      // A map event before any keyframe: applied to the empty window, no order.
      keepless::map_event_t e = g.event(m_);
      e.sequence = static_cast<std::int64_t>(g.pick(1000));
      kt::finalize(e);
      what << "early event seq " << e.sequence << (e.reset ? " reset" : "");
      model_event(e, RejectReason::kNone, true, what.str());
      channel = config_.event_channel;
      bytes = kt::encode(e);
    } else if (r < 0.55 || !m_.owned) {
      // --- a keyframe: valid, or one of the kinds that must be refused.
      keepless::keyframe_t k = g.keyframe(m_);
      RejectReason expect = RejectReason::kNone;
      const double kind = std::uniform_real_distribution<double>(0, 1)(g.rng());
      std::string kind_name = "valid";
      if (m_.owned && kind < 0.05 && !m_.frames.empty()) {
        k.keyframe_id = static_cast<std::int64_t>(m_.frames[g.pick(m_.frames.size())].id);
        kind_name = "duplicate keyframe id";
      } else if (kind < 0.08 && k.num_observations >= 2) {
        k.point_id[1] = k.point_id[0];
        expect = RejectReason::kDuplicateObservation;
        kind_name = "duplicate observation";
      } else if (kind < 0.11) {
        k.orientation[0] = 0.9;
        expect = RejectReason::kInvalidField;
        kind_name = "non-unit quaternion";
      } else if (m_.owned && kind < 0.16) {
        // Stale: behind the order (sequences far above the restart range).
        k.sequence = m_.last_sequence - static_cast<std::int64_t>(g.pick(8));
        k.utime = m_.last_utime - static_cast<std::int64_t>(g.pick(3)) * 1000;
        kind_name = "stale";
      } else if (m_.owned && kind < 0.19 && m_.last_utime > 0) {
        k.utime = m_.last_utime - 1 - static_cast<std::int64_t>(g.pick(1000));
        kind_name = "utime backwards";
      } else if (m_.owned && kind < 0.22) {
        k.publisher_id = kStranger;
        expect = RejectReason::kNotOwner;
        kind_name = "another publisher";
      }
      bytes = kt::encode(k);
      if (m_.owned && !accepted_.empty() && kind > 0.22 && kind < 0.25) {
        bytes = accepted_[accepted_.size() - 1 - g.pick(std::min<std::size_t>(accepted_.size(), 6))];
        keepless::keyframe_t copy;
        copy.decode(bytes.data(), 0, static_cast<int>(bytes.size()));
        k = copy;
        kind_name = "retransmission";
      }
      // The rules: the owner's order first, then the content (against the
      // window; a takeover's is empty).
      if (expect != RejectReason::kNotOwner) {
        RejectReason why = RejectReason::kNone;
        if (m_.owned && !m_.follows(k.sequence, k.utime, &why)) {
          expect = why;
        } else if (expect == RejectReason::kNone && m_.owned &&
                   m_.has_keyframe(static_cast<std::uint64_t>(k.keyframe_id))) {
          expect = RejectReason::kDuplicateKeyframe;
        }
      }
      what << "keyframe seq " << k.sequence << " utime " << k.utime << " id "
           << static_cast<std::uint64_t>(k.keyframe_id) << " pub " << k.publisher_id << " (" << kind_name
           << ") points";
      for (std::int64_t p : k.point_id) what << " " << static_cast<std::uint64_t>(p);
      if (k.num_tracked != 0) {
        what << " tracked ";
        for (std::int8_t t : k.tracked) what << static_cast<int>(t);
      }
      for (std::int64_t p : k.point_id) ids_seen_.push_back(static_cast<std::uint64_t>(p));
      refused = expect != RejectReason::kNone;
      model_keyframe(k, bytes, expect, what.str());
      channel = config_.keyframe_channel;
    } else {
      // --- a map event: the owner's, a stale one, or another publisher's.
      keepless::map_event_t e = g.event(m_);
      RejectReason expect = RejectReason::kNone;
      const double kind = std::uniform_real_distribution<double>(0, 1)(g.rng());
      std::string kind_name = "owner";
      if (kind < 0.08) {
        e.sequence = m_.last_sequence - static_cast<std::int64_t>(g.pick(5));
        kind_name = "stale";
      } else if (kind < 0.12) {
        e.publisher_id = kStranger;
        expect = RejectReason::kNotOwner;
        kind_name = "another publisher";
      }
      if (expect == RejectReason::kNone) {
        RejectReason why;
        if (!m_.follows(e.sequence, e.utime, &why)) expect = why;
      }
      kt::finalize(e);
      what << "event seq " << e.sequence << " utime " << e.utime << " pub " << e.publisher_id << " (" << kind_name
           << ")" << (e.reset ? " reset" : "") << " delete";
      for (std::int64_t p : e.deleted_point_id) what << " " << static_cast<std::uint64_t>(p);
      what << " merge";
      for (std::size_t i = 0; i < e.merged_from_id.size(); ++i) {
        what << " " << static_cast<std::uint64_t>(e.merged_from_id[i]) << ">"
             << static_cast<std::uint64_t>(e.merged_into_id[i]);
      }
      what << " remove";
      for (std::int64_t p : e.removed_keyframe_id) what << " " << static_cast<std::uint64_t>(p);
      refused = expect != RejectReason::kNone;
      model_event(e, expect, false, what.str());
      channel = config_.event_channel;
      bytes = kt::encode(e);
    }
    log->push_back(what.str());

    if (!drain_) {
      send_bytes(channel, bytes);  // delivered and handled at once
      compare_answers();
      if (HasFailure()) return;
      // (3) a refused message changes nothing.
      if (refused) {
        ASSERT_TRUE(same(before, state())) << "a refused message changed the node: " << what.str();
      }
      ASSERT_TRUE(matches()) << what.str();
      continue;
    }
    // A burst: queued, then drained by one spin_once.
    bus_->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    if (burst == 0) burst = 1 + static_cast<int>(g.pick(4));
    if (--burst > 0 && step + 1 < messages) continue;
    log->push_back("-- drained");
    node_->spin_once(0);
    decide_pending();
    pump();
    compare_answers();
    if (HasFailure()) return;
    ASSERT_TRUE(matches()) << what.str();
  }
}

std::vector<Variant> variants() {
  const NodeConfig base = [] {
    NodeConfig c;
    c.url = "memq://";
    c.latency_target_ms = 0;  // every keyframe decided at once, no deadline
    c.window = 4;
    c.max_observations = 64;
    c.max_event_ids = 16;
    c.params.pair_capacity = 3;
    c.status_period_ms = 3600 * 1000;
    c.quiet = true;
    return c;
  }();
  std::vector<Variant> v;
  v.push_back({"M3 K4", base});
  {
    NodeConfig c = base;
    c.window = 6;
    c.params.pair_capacity = 2;
    c.cull_memory = 6;  // culled ids forgotten soon: re-observed by id
    v.push_back({"M2 K6 cull-memory 6", c});
  }
  {
    NodeConfig c = base;
    c.window = 2;
    c.params.pair_capacity = 1;
    v.push_back({"M1 K2", c});
  }
  {
    NodeConfig c = base;
    c.window = 5;
    c.params.scope = core::Scope::kNewest;
    c.params.maturity_keyframes = 1;
    v.push_back({"newest, maturity 1", c});
  }
  {
    NodeConfig c = base;
    c.params.budget.kind = core::BudgetKind::kFraction;
    c.params.budget.fraction = 0.5;
    c.params.tracked_first = true;
    v.push_back({"fraction 0.5, tracked first", c});
  }
  {
    NodeConfig c = base;
    c.window = 5;
    c.params.budget.kind = core::BudgetKind::kPoints;
    c.params.budget.count = 8;
    c.params.budget.track_share = 0.5;
    c.params.coverage_floor = 2;
    v.push_back({"8 points, share 0.5, floor 2", c});
  }
  {
    NodeConfig c = base;
    c.window = 5;
    c.params.cost_model = core::CostModel::kInformation;
    v.push_back({"cost information", c});
  }
  {
    NodeConfig c = base;
    c.window = 5;
    c.params.cost_model = core::CostModel::kTrack;
    c.params.budget.kind = core::BudgetKind::kPoints;
    c.params.budget.count = 10;
    v.push_back({"cost track, 10 points", c});
  }
  {
    NodeConfig c = base;
    c.window = 6;
    c.max_observations = 32;
    c.max_points = 36;  // older keyframes leave to make room
    c.max_window_observations = 60;
    c.max_pair_arcs = 40;  // and some windows are beyond the pair arcs
    c.cull_memory = 20;
    v.push_back({"small capacities", c});
  }
  {
    NodeConfig c = base;
    c.window = 5;
    c.latency_target_ms = 1000;  // the drain; the deadline never fires on the test's clock
    c.params.scope = core::Scope::kNewest;
    v.push_back({"drain, newest", c, true});
  }
  {
    NodeConfig c = base;
    c.window = 4;
    c.latency_target_ms = 1000;
    c.cull_memory = 10;
    v.push_back({"drain, window", c, true});
  }
  return v;
}

TEST_F(NodeDifferential, LongRandomStreamsMatchTheModelAndAFromScratchRun) {
  const std::uint64_t seeds = keepless::test::cases(12);
  for (const Variant& variant : variants()) {
    Totals t;
    for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
      std::vector<std::string> log;
      run_stream(variant, seed * 7919 + 13, 500, &log, &t);
      if (HasFailure()) {
        std::ostringstream s;
        const std::size_t from = log.size() > 40 ? log.size() - 40 : 0;
        for (std::size_t i = from; i < log.size(); ++i) s << log[i] << "\n";
        FAIL() << variant.name << ", seed " << seed << ": the stream's last messages:\n" << s.str();
      }
    }
    std::printf("%-30s decided %llu culled %llu skipped %llu capacity %llu refused keyframes %llu events %llu "
                "(refused %llu, resets %llu, merges %llu, items refused %llu, keyframes removed %llu), culled points "
                "re-entering %llu\n",
                variant.name, static_cast<unsigned long long>(t.decided), static_cast<unsigned long long>(t.culled),
                static_cast<unsigned long long>(t.skipped), static_cast<unsigned long long>(t.capacity),
                static_cast<unsigned long long>(t.refused_keyframes), static_cast<unsigned long long>(t.events),
                static_cast<unsigned long long>(t.refused_events), static_cast<unsigned long long>(t.resets),
                static_cast<unsigned long long>(t.merges), static_cast<unsigned long long>(t.items_refused),
                static_cast<unsigned long long>(t.removed), static_cast<unsigned long long>(t.reentered));
    // The streams reach what they are for.
    EXPECT_GT(t.culled, 0u) << variant.name;
    EXPECT_GT(t.merges, 0u) << variant.name;
    EXPECT_GT(t.resets, 0u) << variant.name;
    EXPECT_GT(t.items_refused, 0u) << variant.name;
    EXPECT_GT(t.refused_keyframes, 0u) << variant.name;
    if (variant.drain) {
      EXPECT_GT(t.skipped, 0u) << variant.name;
    }
  }
}

}  // namespace
