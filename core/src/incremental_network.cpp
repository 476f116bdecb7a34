#include "keepless/core/incremental_network.hpp"

#include <algorithm>
#include <cstring>
#include <vector>

#include "cost_model.hpp"
#include "id_table.hpp"
#include "keepless/core/costs.hpp"
#include "keepless/core/network.hpp"
#include "solver_status.hpp"

namespace keepless::core {

namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

std::uint64_t pairs_of(std::uint64_t n) { return n >= 2 ? n * (n - 1) / 2 : 0; }

// A point's block in the arena: owner slot (kNone once replaced), n, n
// entries (frame slot, N) by frame slot, then the ids of its n(n-1)/2 pair
// arcs in PairWalk order.
std::uint64_t block_words(std::uint64_t n) { return 2 + 2 * n + pairs_of(n); }

// c_s of counts below this is looked up (N is mostly small).
constexpr std::uint32_t kSpatialMemo = 128;

// A cache hint for the scattered loads of an update (points, blocks, ids).
inline void prefetch(const void* p) {
#if defined(__GNUC__)
  __builtin_prefetch(p);
#else
  (void)p;
#endif
}

// Index of the lowest set bit of x != 0.
inline std::size_t lowest_bit(std::uint64_t x) {
#if defined(__GNUC__)
  return static_cast<std::size_t>(__builtin_ctzll(x));
#else
  std::size_t i = 0;
  for (; (x & 1) == 0; x >>= 1) ++i;
  return i;
#endif
}

// How far ahead the loops over points prefetch.
constexpr std::uint32_t kAhead = 16;

// The block ring's size in windows' worth of blocks: the live blocks and an
// update's new ones (a whole window at most) must fit, with room to spare so
// that the tail finds dead blocks (a window sized to its capacities slides
// with a few moves per update at 3, none at 4).
constexpr std::uint64_t kArenaWindows = 3;

}  // namespace

// An update touches only the points of the keyframes that came or went
// (about two keyframes' observations in a slide), never every point or arc:
// per point slot it keeps the views and the source arc in small arrays, the
// rest in a Point, and its (frame slot, N) list with the ids of its pair arcs
// in a block of the arena, replaced by a new block when the list changes.
struct IncrementalNetwork::Impl {
  struct Frame {
    KeyframeId id = 0;
    double centre[3] = {0, 0, 0};
    double intrinsics[4] = {0, 0, 0, 0};  // fx, fy, cx, cy
    std::uint32_t unmapped = 0;           // its unmapped keypoints (not kept: see same_content)
    std::uint32_t window_slot = 0;        // in the window of the last update
    std::uint64_t stamp = 0;  // Window::keyframe_stamp when last matched or added
    std::uint32_t begin = 0, count = 0;
    bool live = false;
    bool gone = false;  // retired by this update: its slot waits for the next one
  };
  struct Point {
    PointId id = 0;
    solver::NodeId node = -1;
    std::uint32_t block = kNone;      // its (frame slot, N) list and arcs
    std::uint32_t listed = 0;         // entries in `block`
    std::uint32_t old_block = kNone;  // during an update: the list before it
    bool live = false;
  };
  struct Newcomer {
    PointId id;
    std::uint32_t slot;
  };
  struct Added {  // a new (frame slot, N) of a point, linked per point
    std::uint32_t frame, n, next;
  };
  // Points by ascending id, as parallel arrays.
  struct Ranks {
    std::vector<PointId> id;
    std::vector<std::uint32_t> slot;
  };
  // The pairs (x < y) of a point's entry list in lexicographic order of
  // their frame slots (entries are sorted by frame slot).
  struct PairWalk {
    const std::uint32_t* e;  // frame slot, N, frame slot, N, ...
    std::uint32_t n, x = 0, y = 1, k = 0;
    bool done() const { return n < 2 || x + 1 >= n; }
    std::uint64_t key() const { return (std::uint64_t{e[2 * x]} << 32) | e[2 * y]; }
    void next() {
      ++k;
      if (++y >= n) {
        ++x;
        y = x + 1;
      }
    }
  };

  Capacities caps;
  solver::Capacity room;
  Params params;
  bool built = false;
  std::uint32_t frame_slots = 0;

  std::vector<Frame> frames;
  std::vector<std::int32_t> frame_of;     // window slot -> frame slot
  std::vector<std::uint8_t> matched;      // frame slot
  std::vector<std::uint32_t> by_begin;    // frame slots, for compaction
  std::vector<Observation> pool;          // keyframes' observations, [2 * max_observations]
  std::vector<std::uint32_t> pool_point;  // point slot of each
  std::uint32_t pool_top = 0;
  ObservationScorer scorer;
  // N (or information level) of the keyframe being added, [keyframe_observation_limit].
  std::vector<std::uint32_t> counts;

  IdTable slot_of;  // point id -> slot
  std::vector<Point> points;
  std::vector<std::uint32_t> views;      // by slot: live keyframes observing it
  std::vector<solver::ArcId> source_of;  // by slot: its source arc, -1 unless n >= 2
  // By arc id: n of its point if a source arc (else 0), and a bitset of the
  // source arcs, to re-cost them all in id order when m changes.
  std::vector<std::uint32_t> source_views;
  std::vector<std::uint64_t> source_bits;
  // Free slots, reused first in first out: points leave and arrive roughly
  // in id order, so slots stay roughly in id order too and the passes in id
  // order (ranking) or keyframe order walk the slot arrays nearly in order.
  std::vector<std::uint32_t> free_points;
  std::uint32_t free_point_head = 0, free_point_count = 0, point_high = 0;
  std::vector<std::uint32_t> views_count;  // live points by views, [max_keyframes + 1]
  std::uint64_t pair_total = 0;  // sum of n(n-1)/2 over live points: the window's pair arcs

  // Points touched by this update (a keyframe of theirs came or went), and
  // those of them left with no keyframe.
  std::vector<std::uint32_t> touched;
  std::vector<std::uint8_t> is_touched;
  std::uint32_t touched_count = 0;
  std::uint64_t touched_words = 0;  // their new blocks' size (a bound: gone points count 2)
  std::vector<std::uint32_t> doomed;
  std::uint32_t doomed_count = 0;
  std::vector<std::uint8_t> is_removed;  // by slot: its point was removed by this update
  std::vector<Added> added;              // [max_observations]
  std::vector<std::uint32_t> add_head;   // by slot: its first Added, kNone between updates
  std::uint32_t added_count = 0;
  std::vector<std::uint32_t> merge;  // one point's new entries, [2 * max_keyframes]

  // Blocks, in a ring: an update writes its new blocks at the head, in one
  // sequential run; before that the tail passes over the blocks replaced or
  // freed since and moves any still live to the head, until the new blocks
  // fit. A slide replaces a point's block within about K updates, and the
  // ring holds many updates' blocks beyond the live ones, so the tail meets
  // few live blocks: the work is spread evenly, with no compaction pauses.
  std::vector<std::uint32_t> arena;
  std::uint32_t head = 0, tail = 0, wrap = kNone;  // wrap: where the head last jumped to 0
  std::uint64_t used = 0;  // words from the tail to the head (a wrap's unused end included)

  // Pairs, by (frame slot, frame slot).
  std::vector<solver::NodeId> pair_node;
  std::vector<solver::ArcId> pair_sink;
  std::vector<std::uint32_t> pair_arcs;
  std::vector<std::uint32_t> idle;  // pairs whose last arc went this update
  std::uint32_t idle_count = 0, live_pairs = 0, live_pair_arcs = 0;

  // Points by ascending id (the canonical order) in ranks[cur], entries
  // [rank_begin, rank_end) of 2 * max_points. A slide usually drops old
  // points and brings higher ids: then the entries are edited in place
  // (dropped ones closed up from the front, newcomers appended at the end).
  // Otherwise, or once the end is reached, they are merged into the other
  // buffer from its start.
  Ranks ranks[2];
  int cur = 0;
  std::uint32_t rank_begin = 0, rank_end = 0, rank_room = 0;
  std::vector<Newcomer> newcomers;
  std::uint32_t newcomer_count = 0;
  // Source arcs of the evaluated points in rank order: order[order_begin..
  // + evaluated), built backwards (from the end of 2 * max_points) when the
  // ranks are edited in place.
  std::vector<solver::ArcId> order;
  std::uint32_t order_begin = 0, evaluated = 0;

  // Retired arc ids. An id retired and reused within one update is simply
  // replaced; ids still free at its end (at or above free_arc_low) are then
  // emptied, so the solver sees one call per id and update.
  std::vector<solver::ArcId> free_arcs;
  std::uint32_t free_arc_count = 0, free_arc_low = 0;
  std::vector<solver::NodeId> free_nodes;
  std::uint32_t free_node_count = 0;
  solver::NodeId next_node = 2;

  std::vector<std::int64_t> cm;  // c_m(n), [max_keyframes + 1]
  std::uint32_t m = 0;
  std::vector<std::uint8_t> spatial_memo;  // c_s(a, b), a, b < kSpatialMemo
  Changes changes;

  explicit Impl(const Capacities& c)
      : caps(c),
        room(IncrementalNetwork::solver_capacity(c)),
        scorer(keyframe_observation_limit(c)),
        slot_of(c.max_points) {
    frame_slots = std::max<std::uint32_t>(2, 2 * c.max_keyframes);
    const std::size_t s = frame_slots;
    const std::size_t kmax = std::size_t{c.max_keyframes} + 1;
    frames.resize(s);
    frame_of.resize(c.max_keyframes);
    matched.resize(s);
    by_begin.resize(s);
    pool.resize(2 * std::size_t{c.max_observations});
    pool_point.resize(pool.size());
    counts.resize(keyframe_observation_limit(c));
    points.resize(c.max_points);
    views.assign(c.max_points, 0);
    source_of.assign(c.max_points, -1);
    source_views.assign(static_cast<std::size_t>(std::max(room.max_arcs, 0)), 0);
    source_bits.assign(source_views.size() / 64 + 1, 0);
    free_points.resize(c.max_points);
    views_count.assign(kmax, 0);
    touched.resize(c.max_points);
    is_touched.assign(c.max_points, 0);
    doomed.resize(c.max_points);
    is_removed.assign(c.max_points, 0);
    added.resize(c.max_observations);
    add_head.assign(c.max_points, kNone);
    merge.resize(2 * kmax);
    const std::uint64_t live_words =
        2ULL * c.max_points + 2ULL * c.max_observations + c.max_pair_arcs;
    arena.resize(static_cast<std::size_t>(std::min<std::uint64_t>(
        kArenaWindows * live_words + block_words(c.max_keyframes), kNone - 1)));
    pair_node.assign(s * s, -1);
    pair_sink.assign(s * s, -1);
    pair_arcs.assign(s * s, 0);
    idle.resize(s * s);
    rank_room = std::max<std::uint32_t>(1, 2 * c.max_points);
    for (Ranks& r : ranks) {
      r.id.resize(rank_room);
      r.slot.resize(rank_room);
    }
    newcomers.resize(c.max_points);
    order.resize(rank_room);
    free_arcs.resize(static_cast<std::size_t>(std::max(room.max_arcs, 0)));
    free_nodes.resize(static_cast<std::size_t>(std::max(room.max_nodes, 0)));
    cm.resize(kmax);
    spatial_memo.resize(std::size_t{kSpatialMemo} * kSpatialMemo);
  }

  // The point -> pair costs of small scores under `params` before
  // spatial_weight (all < 256); spatial() applies the weight.
  void memoise_arc_costs() {
    Params unweighted = params;
    unweighted.spatial_weight = 1;
    for (std::uint32_t a = 0; a < kSpatialMemo; ++a) {
      for (std::uint32_t b = 0; b < kSpatialMemo; ++b) {
        spatial_memo[a * kSpatialMemo + b] = static_cast<std::uint8_t>(pair_arc_cost(unweighted, a, b));
      }
    }
  }

  std::size_t bytes() const {
    const auto b = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
    return sizeof(Impl) + b(frames) + b(frame_of) + b(matched) + b(by_begin) + b(pool) +
           b(pool_point) + scorer.memory_bytes() + b(counts) + slot_of.memory_bytes() + b(points) +
           b(views) + b(source_of) + b(source_views) + b(source_bits) + b(free_points) +
           b(views_count) + b(touched) + b(is_touched) + b(doomed) + b(is_removed) + b(added) +
           b(add_head) + b(merge) + b(arena) + b(pair_node) + b(pair_sink) + b(pair_arcs) +
           b(idle) + 2 * (b(ranks[0].id) + b(ranks[0].slot)) + b(newcomers) + b(order) +
           b(free_arcs) + b(free_nodes) + b(cm) + b(spatial_memo);
  }

  // --- costs --------------------------------------------------------------

  std::int64_t spatial(std::uint32_t a, std::uint32_t b) const {
    if (a < kSpatialMemo && b < kSpatialMemo) return std::int64_t{spatial_memo[a * kSpatialMemo + b]} * params.spatial_weight;
    return pair_arc_cost(params, a, b);
  }
  std::int64_t baseline(std::uint32_t fa, std::uint32_t fb) const {
    return pair_sink_cost(params, frames[fa].centre, frames[fb].centre);
  }

  // --- blocks ---------------------------------------------------------------

  std::uint32_t* entries(std::uint32_t b) { return arena.data() + b + 2; }
  std::uint32_t* arc_ids(std::uint32_t b) { return arena.data() + b + 2 + 2 * arena[b + 1]; }

  // The caller has made room (see make_room).
  std::uint32_t alloc_block(std::uint32_t owner, std::uint32_t n) {
    const auto words = static_cast<std::uint32_t>(block_words(n));
    if (head + words > arena.size()) {
      used += arena.size() - head;
      wrap = head;
      head = 0;
    }
    const std::uint32_t b = head;
    head += words;
    used += words;
    arena[b] = owner;
    arena[b + 1] = n;
    return b;
  }

  void free_block(std::uint32_t b) { arena[b] = kNone; }

  // Advances the tail until `words` more (and a wrap's waste) fit, moving the
  // live blocks it passes to the head. False if they cannot fit (the tail
  // went once round the ring).
  bool make_room(std::uint64_t words) {
    const std::uint64_t need = words + block_words(caps.max_keyframes);
    for (std::uint64_t passed = 0; arena.size() - used < need;) {
      if (used == 0 || passed > arena.size()) return false;
      if (tail == wrap) {
        used -= arena.size() - tail;
        passed += arena.size() - tail;
        tail = 0;
        wrap = kNone;
        continue;
      }
      const std::uint32_t at = tail, owner = arena[at], n = arena[at + 1];
      const auto words_at = static_cast<std::uint32_t>(block_words(n));
      tail += words_at;
      used -= words_at;
      passed += words_at;
      if (owner == kNone) continue;
      const std::uint32_t b = alloc_block(owner, n);  // may land on the words just passed
      if (b != at)
        std::memmove(arena.data() + b + 2, arena.data() + at + 2,
                     (words_at - 2) * sizeof(std::uint32_t));
      points[owner].block = b;
    }
    return true;
  }

  // --- points ---------------------------------------------------------------

  // A point's views change only once it is touched: the totals follow.
  void touch(std::uint32_t slot) {
    if (is_touched[slot]) return;
    is_touched[slot] = 1;
    touched[touched_count++] = slot;
    touched_words += block_words(views[slot]);
  }
  void add_view(std::uint32_t slot) {
    const std::uint32_t n = views[slot]++;
    if (n > 0) --views_count[n];
    ++views_count[n + 1];
    pair_total += n;
    touched_words += 2 + n;  // block_words(n + 1) - block_words(n)
  }
  void drop_view(std::uint32_t slot) {
    const std::uint32_t n = views[slot]--;
    --views_count[n];
    if (n > 1) ++views_count[n - 1];
    pair_total -= n - 1;
    touched_words -= 1 + n;
  }

  // Slot of a new point, or kNone when every slot is taken.
  std::uint32_t insert(PointId id) {
    std::uint32_t slot = 0;
    if (free_point_count > 0) {
      slot = free_points[free_point_head];
      free_point_head = free_point_head + 1 == caps.max_points ? 0 : free_point_head + 1;
      --free_point_count;
    } else if (point_high < caps.max_points) {
      slot = point_high++;
    } else {
      return kNone;
    }
    if (slot_of.insert(id, slot) == nullptr) return kNone;
    Point& pt = points[slot];
    pt = Point{};
    pt.id = id;
    pt.live = true;
    views[slot] = 0;
    source_of[slot] = -1;
    newcomers[newcomer_count++] = Newcomer{id, slot};
    ++changes.points_added;
    return slot;
  }

  // A point that lost its last view: every arc it had goes, and its slot.
  void remove(std::uint32_t slot) {
    Point& pt = points[slot];
    const std::uint32_t b = pt.block;
    PairWalk walk{entries(b), pt.listed};
    const std::uint32_t* ids = arc_ids(b);
    for (; !walk.done(); walk.next()) {
      retire_arc(static_cast<solver::ArcId>(ids[walk.k]));
      pair_loses_arc(walk.key());
    }
    if (pt.node >= 0) {
      retire_arc(source_of[slot]);
      mark_source(source_of[slot], 0);
      free_node(pt.node);
      source_of[slot] = -1;
    }
    free_block(b);
    slot_of.erase(pt.id);
    pt = Point{};
    is_removed[slot] = 1;
    const std::uint32_t tail = free_point_head + free_point_count++;
    free_points[tail >= caps.max_points ? tail - caps.max_points : tail] = slot;
    ++changes.points_removed;
  }

  // --- solver ids -------------------------------------------------------------

  void mark_source(solver::ArcId a, std::uint32_t n) {
    const auto i = static_cast<std::size_t>(a);
    source_views[i] = n;
    if (n > 0) {
      source_bits[i >> 6] |= 1ULL << (i & 63);
    } else {
      source_bits[i >> 6] &= ~(1ULL << (i & 63));
    }
  }

  Status new_arc(solver::MinCostFlow& solver, solver::NodeId from, solver::NodeId to,
                 std::int64_t cap, std::int64_t cost, solver::ArcId* id) {
    solver::Status s;
    if (free_arc_count > 0) {
      *id = free_arcs[--free_arc_count];
      free_arc_low = std::min(free_arc_low, free_arc_count);
      s = solver.replace_arc(*id, from, to, cap, cost);
    } else {
      *id = solver.arc_count();
      s = solver.add_arc(from, to, cap, cost);
    }
    ++changes.arcs_added;
    return from_solver(s);
  }

  void retire_arc(solver::ArcId id) {
    free_arcs[free_arc_count++] = id;
    ++changes.arcs_retired;
  }

  // Empties the arcs retired by this update and not reused.
  void empty_retired_arcs(solver::MinCostFlow& solver) {
    for (std::uint32_t i = free_arc_low; i < free_arc_count; ++i) {
      (void)solver.set_arc(free_arcs[i], 0, solver.cost(free_arcs[i]));  // a live id: cannot fail
    }
    free_arc_low = free_arc_count;
  }

  Status new_node(solver::MinCostFlow& solver, solver::NodeId* v) {
    if (free_node_count > 0) {
      *v = free_nodes[--free_node_count];
    } else if (next_node < solver.node_count()) {
      *v = next_node++;
    } else {
      return Status::kCapacityExceeded;
    }
    return from_solver(solver.renew_node(*v));
  }

  void free_node(solver::NodeId v) { free_nodes[free_node_count++] = v; }

  // --- pairs -------------------------------------------------------------------

  std::size_t pair_index(std::uint64_t key) const {
    return static_cast<std::size_t>(key >> 32) * frame_slots + static_cast<std::uint32_t>(key);
  }

  Status pair_gains_arc(solver::MinCostFlow& solver, std::uint64_t key, solver::NodeId* node) {
    const std::size_t q = pair_index(key);
    if (pair_node[q] < 0) {
      const auto fa = static_cast<std::uint32_t>(key >> 32), fb = static_cast<std::uint32_t>(key);
      if (Status s = new_node(solver, &pair_node[q]); s != Status::kOk) return s;
      if (Status s = new_arc(solver, pair_node[q], 1, params.pair_capacity, baseline(fa, fb),
                             &pair_sink[q]);
          s != Status::kOk) {
        return s;
      }
      ++live_pairs;
    }
    ++pair_arcs[q];
    ++live_pair_arcs;
    *node = pair_node[q];
    return Status::kOk;
  }

  void pair_loses_arc(std::uint64_t key) {
    const std::size_t q = pair_index(key);
    --live_pair_arcs;
    if (--pair_arcs[q] == 0) idle[idle_count++] = static_cast<std::uint32_t>(q);
  }

  // Retires pairs left without arcs: with `only_gone`, just those of
  // retired frames (they cannot come back, and their ids are needed now).
  void retire_idle_pairs(bool only_gone) {
    std::uint32_t kept = 0;
    for (std::uint32_t k = 0; k < idle_count; ++k) {
      const std::uint32_t q = idle[k];
      if (pair_arcs[q] != 0 || pair_node[q] < 0) continue;
      const bool gone = frames[q / frame_slots].gone || frames[q % frame_slots].gone;
      if (only_gone && !gone) {
        idle[kept++] = q;
        continue;
      }
      retire_arc(pair_sink[q]);
      free_node(pair_node[q]);
      pair_node[q] = -1;
      pair_sink[q] = -1;
      --live_pairs;
    }
    idle_count = kept;
  }

  // --- frames -------------------------------------------------------------------

  bool pool_free(std::uint32_t at, std::uint32_t count) const {
    if (at + std::uint64_t{count} > pool.size()) return false;
    for (const Frame& f : frames) {
      if (f.live && f.count > 0 && f.begin < at + count && at < f.begin + f.count) return false;
    }
    return true;
  }

  // Where `count` more observations go: after the last frame stored, or
  // else from the start of the pool (a sliding window frees the pool in the
  // order it was filled, and the pool holds two windows' worth, so it is
  // used as a ring); or else, after the live frames are slid down in pool
  // order, after them. kNone if there is no room.
  std::uint32_t pool_room(std::uint32_t count) {
    if (pool_free(pool_top, count)) return pool_top;
    if (pool_free(0, count)) return 0;
    std::uint32_t n = 0;
    for (std::uint32_t f = 0; f < frame_slots; ++f) {
      if (!frames[f].live) continue;
      std::uint32_t j = n++;
      for (; j > 0 && frames[by_begin[j - 1]].begin > frames[f].begin; --j)
        by_begin[j] = by_begin[j - 1];
      by_begin[j] = f;
    }
    std::uint32_t top = 0;
    for (std::uint32_t j = 0; j < n; ++j) {
      Frame& fr = frames[by_begin[j]];
      if (fr.begin != top && fr.count > 0) {
        std::memmove(pool.data() + top, pool.data() + fr.begin, fr.count * sizeof(Observation));
        std::memmove(pool_point.data() + top, pool_point.data() + fr.begin,
                     fr.count * sizeof(std::uint32_t));
      }
      fr.begin = top;
      top += fr.count;
    }
    pool_top = top;
    return pool_top + std::uint64_t{count} <= pool.size() ? pool_top : kNone;
  }

  // Unmapped keypoints are not kept here, so a keyframe with any is the
  // same only by its stamp (a different one is re-added: correct, slower).
  bool same_content(const Frame& f, const Keyframe& kf, const Observation* obs,
                    std::uint32_t count) const {
    const double intrinsics[4] = {kf.fx, kf.fy, kf.cx, kf.cy};
    return f.count == count && f.unmapped == 0 && kf.unmapped_count == 0 &&
           std::memcmp(f.centre, kf.centre, sizeof(f.centre)) == 0 &&
           std::memcmp(f.intrinsics, intrinsics, sizeof(intrinsics)) == 0 &&
           (count == 0 ||
            std::memcmp(pool.data() + f.begin, obs, count * sizeof(Observation)) == 0);
  }

  // Under the track cost a keyframe's N values come from its quality, which
  // is not kept here (a VO re-sends a keyframe with older, longer tracks):
  // the same keyframe must also give the N its points' entries hold.
  bool same_levels(std::uint32_t f, const Keyframe& kf, const Observation* obs, std::uint32_t count) {
    if (params.cost_model != CostModel::kTrack) return true;
    scorer.score(kf, obs, count, params, counts.data());
    const std::uint32_t* slots = pool_point.data() + frames[f].begin;
    for (std::uint32_t i = 0; i < count; ++i) {
      const Point& pt = points[slots[i]];
      const std::uint32_t* e = entries(pt.block);
      std::uint32_t j = 0;
      while (j < pt.listed && e[2 * j] != f) ++j;
      if (j == pt.listed || e[2 * j + 1] != counts[i]) return false;
    }
    return true;
  }

  // Forgets everything (an update may have stopped half-way).
  void reset_state() {
    for (Frame& f : frames) f = Frame{};
    pool_top = 0;
    slot_of.clear();
    free_point_head = free_point_count = 0;
    point_high = 0;
    std::fill(views_count.begin(), views_count.end(), 0u);
    std::fill(source_views.begin(), source_views.end(), 0u);
    std::fill(source_bits.begin(), source_bits.end(), 0ULL);
    pair_total = 0;
    std::fill(is_touched.begin(), is_touched.end(), 0);
    std::fill(is_removed.begin(), is_removed.end(), 0);
    std::fill(add_head.begin(), add_head.end(), kNone);
    touched_count = doomed_count = added_count = 0;
    head = tail = 0;
    wrap = kNone;
    used = 0;
    std::fill(pair_node.begin(), pair_node.end(), -1);
    std::fill(pair_sink.begin(), pair_sink.end(), -1);
    std::fill(pair_arcs.begin(), pair_arcs.end(), 0u);
    idle_count = live_pairs = live_pair_arcs = 0;
    rank_begin = rank_end = 0;
    order_begin = 0;
    cur = 0;
    newcomer_count = 0;
    evaluated = 0;
    free_arc_count = free_arc_low = free_node_count = 0;
    next_node = 2;
    m = 0;
    built = false;
  }

  Status update(const Window& window, const Params& p, solver::MinCostFlow& solver);
  void match_frames(const Window& window);
  void remove_frames();
  Status add_frames(const Window& window);
  Status relist();
  Status connect(solver::MinCostFlow& solver);
  void rank();
  Status fail(Status s) {
    built = false;
    return s;
  }
};

// Keyframes kept bit for bit keep their slot, counts and points. The
// window's stamp proves that without comparing the contents; ids are unique,
// so at most one live frame can match.
void IncrementalNetwork::Impl::match_frames(const Window& window) {
  std::fill(matched.begin(), matched.end(), 0);
  for (std::uint32_t s = 0; s < window.keyframe_count(); ++s) {
    frame_of[s] = -1;
    const Keyframe& kf = window.keyframe(s);
    const std::uint64_t stamp = window.keyframe_stamp(s);
    for (std::uint32_t f = 0; f < frame_slots; ++f) {
      Frame& fr = frames[f];
      if (!fr.live || fr.id != kf.id) continue;
      const Observation* obs = window.observations(s);
      const std::uint32_t count = window.observation_count(s);
      if (fr.stamp == stamp || (same_content(fr, kf, obs, count) && same_levels(f, kf, obs, count))) {
        fr.stamp = stamp;
        frame_of[s] = static_cast<std::int32_t>(f);
        matched[f] = 1;
      }
      break;
    }
  }
}

// Keyframes that left: their points lose a view; points left with none go,
// with their arcs, before anything is added (so ids recycle within capacity).
void IncrementalNetwork::Impl::remove_frames() {
  for (std::uint32_t f = 0; f < frame_slots; ++f) {
    Frame& fr = frames[f];
    if (!fr.live || matched[f]) continue;
    fr.live = false;
    fr.gone = true;
    ++changes.frames_removed;
    const std::uint32_t end = fr.begin + fr.count;
    for (std::uint32_t i = fr.begin; i < end; ++i) {
      if (i + kAhead < end) {
        prefetch(&views[pool_point[i + kAhead]]);
        prefetch(&is_touched[pool_point[i + kAhead]]);
      }
      const std::uint32_t slot = pool_point[i];
      touch(slot);
      drop_view(slot);
      if (views[slot] == 0) doomed[doomed_count++] = slot;
    }
  }
  for (std::uint32_t t = 0; t < doomed_count; ++t) {
    if (t + kAhead < doomed_count) prefetch(&points[doomed[t + kAhead]]);
    if (t + kAhead / 2 < doomed_count) {
      const Point& ahead = points[doomed[t + kAhead / 2]];  // prefetched above
      prefetch(arena.data() + ahead.block);
      slot_of.prefetch(ahead.id);
    }
    remove(doomed[t]);
  }
}

// New (or changed) keyframes: stored, counted, their points found or added,
// and each point's new (frame, N) noted.
Status IncrementalNetwork::Impl::add_frames(const Window& window) {
  for (std::uint32_t s = 0; s < window.keyframe_count(); ++s) {
    if (frame_of[s] >= 0) continue;
    std::uint32_t f = 0;
    while (f < frame_slots && (frames[f].live || frames[f].gone)) ++f;  // 2K slots: one is free
    if (f == frame_slots) return Status::kCapacityExceeded;
    const Observation* obs = window.observations(s);
    const std::uint32_t count = window.observation_count(s);
    const std::uint32_t begin = pool_room(count);
    if (begin == kNone) return Status::kCapacityExceeded;
    Frame& fr = frames[f];
    const Keyframe& kf = window.keyframe(s);
    fr.id = kf.id;
    std::memcpy(fr.centre, kf.centre, sizeof(fr.centre));
    const double intrinsics[4] = {kf.fx, kf.fy, kf.cx, kf.cy};
    std::memcpy(fr.intrinsics, intrinsics, sizeof(intrinsics));
    fr.unmapped = kf.unmapped_count;
    fr.stamp = window.keyframe_stamp(s);
    fr.begin = begin;
    fr.count = count;
    fr.live = true;
    pool_top = begin + count;
    if (count > 0) std::memcpy(pool.data() + fr.begin, obs, count * sizeof(Observation));
    scorer.score(kf, obs, count, params, counts.data());
    std::uint32_t* slots = pool_point.data() + fr.begin;
    for (std::uint32_t i = 0; i < count; ++i) {
      if (i + kAhead < count) slot_of.prefetch(obs[i + kAhead].point);
      const std::uint32_t* known = slot_of.find(obs[i].point);
      slots[i] = known != nullptr ? *known : insert(obs[i].point);
      if (slots[i] == kNone) return Status::kCapacityExceeded;
    }
    for (std::uint32_t i = 0; i < count; ++i) {
      if (i + kAhead < count) {
        prefetch(&views[slots[i + kAhead]]);
        prefetch(&add_head[slots[i + kAhead]]);
        prefetch(&is_touched[slots[i + kAhead]]);
      }
      const std::uint32_t slot = slots[i];
      touch(slot);
      add_view(slot);
      added[added_count] = Added{f, counts[i], add_head[slot]};
      add_head[slot] = added_count++;
    }
    frame_of[s] = static_cast<std::int32_t>(f);
    ++changes.frames_added;
  }
  return Status::kOk;
}

// Every touched point's new list, in a new block: its old entries without
// the retired frames, merged with its new ones. Arcs of pairs it no longer
// has are retired, and the node of a point no longer seen twice.
Status IncrementalNetwork::Impl::relist() {
  // The new window's pair arcs (checked as PaperNetwork checks them), and
  // room for every new block.
  if (pair_total > caps.max_pair_arcs) return Status::kCapacityExceeded;
  if (!make_room(touched_words)) return Status::kCapacityExceeded;

  for (std::uint32_t t = 0; t < touched_count; ++t) {
    if (t + kAhead < touched_count) prefetch(&points[touched[t + kAhead]]);
    if (t + kAhead / 2 < touched_count && points[touched[t + kAhead / 2]].block != kNone) {
      prefetch(arena.data() + points[touched[t + kAhead / 2]].block);  // prefetched above
    }
    const std::uint32_t slot = touched[t];
    Point& pt = points[slot];
    if (!pt.live) continue;
    // The new entries by frame slot (one per new keyframe observing it).
    std::uint32_t fresh_entries = 0;
    for (std::uint32_t a = add_head[slot]; a != kNone; a = added[a].next) {
      std::uint32_t j = fresh_entries++;
      for (; j > 0 && merge[2 * j - 2] > added[a].frame; --j) {
        merge[2 * j] = merge[2 * j - 2];
        merge[2 * j + 1] = merge[2 * j - 1];
      }
      merge[2 * j] = added[a].frame;
      merge[2 * j + 1] = added[a].n;
    }
    add_head[slot] = kNone;
    const std::uint32_t n = views[slot];
    const std::uint32_t old = pt.block;
    const std::uint32_t old_n = pt.listed;
    const std::uint32_t b = alloc_block(slot, n);
    std::uint32_t* e = entries(b);
    const std::uint32_t* o = old != kNone ? entries(old) : nullptr;
    std::uint32_t w = 0, x = 0, y = 0;
    while (x < old_n || y < fresh_entries) {
      if (x < old_n && frames[o[2 * x]].gone) {
        ++x;
      } else if (y >= fresh_entries || (x < old_n && o[2 * x] < merge[2 * y])) {
        e[2 * w] = o[2 * x];
        e[2 * w++ + 1] = o[2 * x++ + 1];
      } else {
        e[2 * w] = merge[2 * y];
        e[2 * w++ + 1] = merge[2 * y++ + 1];
      }
    }
    pt.block = b;
    pt.listed = n;
    pt.old_block = old;
    if (old != kNone) {
      ++changes.points_changed;
      PairWalk before{o, old_n};
      PairWalk now{e, n};
      const std::uint32_t* ids = arc_ids(old);
      while (!before.done()) {
        if (!now.done() && now.key() < before.key()) {
          now.next();
        } else if (!now.done() && now.key() == before.key()) {
          now.next();
          before.next();
        } else {
          retire_arc(static_cast<solver::ArcId>(ids[before.k]));
          pair_loses_arc(before.key());
          before.next();
        }
      }
    }
    if (n < 2 && pt.node >= 0) {
      retire_arc(source_of[slot]);
      mark_source(source_of[slot], 0);
      free_node(pt.node);
      pt.node = -1;
      source_of[slot] = -1;
    }
  }
  retire_idle_pairs(true);
  return Status::kOk;
}

// Every touched point's arcs: kept pairs keep their arc (a live frame slot's
// N never change, so neither does c_s), new pairs get one. A new m re-costs
// every source arc, in arc id order (the solver's arrays in order).
Status IncrementalNetwork::Impl::connect(solver::MinCostFlow& solver) {
  std::uint32_t new_m = caps.max_keyframes;
  while (new_m > 0 && views_count[new_m] == 0) --new_m;
  // c_m(2) would pass the solver's cost bound (kMaxPointViews); update()'s
  // caller clears the network on any refusal.
  if ((params.cost_terms & kConnectivityCost) && new_m > kMaxPointViews) return Status::kCapacityExceeded;
  const bool cm_changed = new_m != m || changes.rebuilt;
  if (cm_changed) {
    m = new_m;
    std::fill(cm.begin(), cm.end(), 0);
    if (params.cost_terms & kConnectivityCost) connectivity_costs(m, cm.data());
  }
  for (std::uint32_t t = 0; t < touched_count; ++t) {
    if (t + kAhead < touched_count) prefetch(&points[touched[t + kAhead]]);
    const std::uint32_t slot = touched[t];
    Point& pt = points[slot];
    if (!pt.live) continue;
    const std::uint32_t n = views[slot];
    const std::uint32_t old = pt.old_block;
    const std::uint32_t old_n = old != kNone ? arena[old + 1] : 0;
    if (n >= 2) {
      const auto capacity = static_cast<std::int64_t>(pairs_of(n));
      if (pt.node < 0) {
        if (Status s = new_node(solver, &pt.node); s != Status::kOk) return s;
        if (Status s = new_arc(solver, 0, pt.node, capacity, cm[n], &source_of[slot]);
            s != Status::kOk) {
          return s;
        }
      } else if (n != old_n && !cm_changed) {
        if (Status s = from_solver(solver.set_arc(source_of[slot], capacity, cm[n]));
            s != Status::kOk) {
          return s;
        }
      }
      mark_source(source_of[slot], n);
      PairWalk before{old != kNone ? entries(old) : nullptr, old_n};
      const std::uint32_t* old_ids = old != kNone ? arc_ids(old) : nullptr;
      PairWalk now{entries(pt.block), n};
      std::uint32_t* ids = arc_ids(pt.block);
      for (; !now.done(); now.next()) {
        while (!before.done() && before.key() < now.key()) before.next();  // retired already
        if (!before.done() && before.key() == now.key()) {
          ids[now.k] = old_ids[before.k];
          before.next();
          continue;
        }
        solver::NodeId pair = -1;
        if (Status s = pair_gains_arc(solver, now.key(), &pair); s != Status::kOk) return s;
        solver::ArcId id = -1;
        if (Status s = new_arc(solver, pt.node, pair, 1,
                               spatial(now.e[2 * now.x + 1], now.e[2 * now.y + 1]), &id);
            s != Status::kOk) {
          return s;
        }
        ids[now.k] = static_cast<std::uint32_t>(id);
      }
    }
    if (old != kNone) free_block(old);
    pt.old_block = kNone;
  }
  if (cm_changed) {
    for (std::size_t w = 0; w < source_bits.size(); ++w) {
      for (std::uint64_t bits = source_bits[w]; bits != 0; bits &= bits - 1) {
        const auto a = static_cast<solver::ArcId>(64 * w + lowest_bit(bits));
        const std::uint32_t n = source_views[static_cast<std::size_t>(a)];
        if (Status s =
                from_solver(solver.set_arc(a, static_cast<std::int64_t>(pairs_of(n)), cm[n]));
            s != Status::kOk) {
          return s;
        }
      }
    }
  }
  retire_idle_pairs(false);
  empty_retired_arcs(solver);
  return Status::kOk;
}

// Points by ascending id: the kept ones in their old order, without those
// removed by this update, merged with the newcomers; then the canonical order
// of the source arcs.
void IncrementalNetwork::Impl::rank() {
  const auto by_id = [](const Newcomer& a, const Newcomer& b) { return a.id < b.id; };
  if (!std::is_sorted(newcomers.begin(), newcomers.begin() + newcomer_count, by_id)) {
    std::sort(newcomers.begin(), newcomers.begin() + newcomer_count, by_id);
  }
  // Locals: the stores below would otherwise force reloads of every member.
  PointId* id = ranks[cur].id.data();
  std::uint32_t* slot = ranks[cur].slot.data();
  const std::uint8_t* removed = is_removed.data();
  const solver::ArcId* source = source_of.data();
  solver::ArcId* out = order.data();
  std::uint32_t last = rank_end;
  while (last > rank_begin && removed[slot[last - 1]]) --last;
  if (!changes.rebuilt && rank_end + newcomer_count <= rank_room &&
      (newcomer_count == 0 || last == rank_begin || id[last - 1] < newcomers[0].id)) {
    // Every newcomer follows the last kept point: appended in place, and the
    // removed entries closed up from the back (they are mostly old, near the
    // front). The order is written backwards from the end of its buffer.
    std::uint32_t at = rank_room;
    for (std::uint32_t b = newcomer_count; b-- > 0;) {
      id[rank_end + b] = newcomers[b].id;
      slot[rank_end + b] = newcomers[b].slot;
      out[at - 1] = source[newcomers[b].slot];
      at -= source[newcomers[b].slot] >= 0;
    }
    std::uint32_t to = rank_end;
    for (std::uint32_t i = rank_end; i-- > rank_begin;) {
      if (i >= rank_begin + kAhead) prefetch(source + slot[i - kAhead]);
      const std::uint32_t s = slot[i];
      const PointId v = id[i];
      const bool keep = !removed[s];
      id[to - 1] = v;  // to - 1 >= i: free, or entry i itself (read already)
      slot[to - 1] = s;
      to -= keep;
      out[at - 1] = source[s];
      at -= keep && source[s] >= 0;
    }
    rank_begin = to;
    rank_end += newcomer_count;
    order_begin = at;
    evaluated = rank_room - at;
    return;
  }
  PointId* into_id = ranks[cur ^ 1].id.data();
  std::uint32_t* into_slot = ranks[cur ^ 1].slot.data();
  std::uint32_t to = 0, a = rank_begin, b = 0;
  evaluated = 0;
  while (a < rank_end || b < newcomer_count) {
    if (a < rank_end && removed[slot[a]]) {
      ++a;
      continue;
    }
    const bool old = b >= newcomer_count || (a < rank_end && id[a] < newcomers[b].id);
    into_id[to] = old ? id[a] : newcomers[b].id;
    into_slot[to] = old ? slot[a++] : newcomers[b++].slot;
    if (source[into_slot[to]] >= 0) out[evaluated++] = source[into_slot[to]];
    ++to;
  }
  cur ^= 1;
  rank_begin = 0;
  rank_end = to;
  order_begin = 0;
}

Status IncrementalNetwork::Impl::update(const Window& window, const Params& p,
                                        solver::MinCostFlow& solver) {
  if (p.box_width < 0 || p.box_height < 0 || p.pair_capacity < 0 ||
      (p.cost_model == CostModel::kAuthors && (p.image_width <= 0 || p.image_height <= 0))) {
    return Status::kInvalidArgument;
  }
  if (window.keyframe_count() > caps.max_keyframes ||
      window.total_observations() > caps.max_observations ||
      window.distinct_points() > caps.max_points || !keyframes_fit(window, caps)) {
    return Status::kCapacityExceeded;
  }
  changes = Changes{};
  const bool same_params = built && same_network(p, params);
  if (!same_params) {
    reset_state();
    const std::int32_t nodes = std::min(solver.capacity_limits().max_nodes, room.max_nodes);
    if (nodes < 2) return Status::kCapacityExceeded;
    if (Status s = from_solver(solver.reset(nodes)); s != Status::kOk) return fail(s);
    params = p;
    memoise_arc_costs();
    built = true;
    changes.rebuilt = true;
  }
  newcomer_count = idle_count = touched_count = doomed_count = added_count = 0;
  touched_words = 0;
  free_arc_low = free_arc_count;

  match_frames(window);
  remove_frames();
  if (Status s = add_frames(window); s != Status::kOk) return fail(s);
  if (Status s = relist(); s != Status::kOk) return fail(s);
  if (Status s = connect(solver); s != Status::kOk) return fail(s);
  if (touched_count > 0 || changes.rebuilt) rank();
  for (std::uint32_t s = 0; s < window.keyframe_count(); ++s) {
    frames[static_cast<std::uint32_t>(frame_of[s])].window_slot = s;
  }

  for (std::uint32_t t = 0; t < touched_count; ++t) is_touched[touched[t]] = 0;
  for (std::uint32_t t = 0; t < doomed_count; ++t) is_removed[doomed[t]] = 0;
  for (Frame& f : frames) f.gone = false;
  return Status::kOk;
}

IncrementalNetwork::IncrementalNetwork(const Capacities& capacities)
    : impl_(std::make_unique<Impl>(capacities)) {}
IncrementalNetwork::~IncrementalNetwork() = default;

solver::Capacity IncrementalNetwork::solver_capacity(const Capacities& c) {
  // Retirements come before additions within an update, so the live ids
  // never exceed what PaperNetwork needs for the larger of two windows.
  return PaperNetwork::solver_capacity(c);
}

Status IncrementalNetwork::update(const Window& window, const Params& params,
                                  solver::MinCostFlow& solver) {
  return impl_->update(window, params, solver);
}

void IncrementalNetwork::clear() { impl_->built = false; }

const IncrementalNetwork::Changes& IncrementalNetwork::changes() const { return impl_->changes; }

std::uint32_t IncrementalNetwork::point_count() const {
  return impl_->rank_end - impl_->rank_begin;
}
PointId IncrementalNetwork::point_id(std::uint32_t i) const {
  return impl_->ranks[impl_->cur].id[impl_->rank_begin + i];
}
std::uint32_t IncrementalNetwork::point_views(std::uint32_t i) const {
  return impl_->views[impl_->ranks[impl_->cur].slot[impl_->rank_begin + i]];
}
solver::ArcId IncrementalNetwork::point_source_arc(std::uint32_t i) const {
  return impl_->source_of[impl_->ranks[impl_->cur].slot[impl_->rank_begin + i]];
}
void IncrementalNetwork::read_points(std::uint32_t begin, std::uint32_t count, PointId* id,
                                     std::uint32_t* views, solver::ArcId* source_arc) const {
  const Impl& n = *impl_;
  const std::uint32_t* slot = n.ranks[n.cur].slot.data() + n.rank_begin + begin;
  const PointId* ids = n.ranks[n.cur].id.data() + n.rank_begin + begin;
  for (std::uint32_t i = 0; i < count; ++i) {
    id[i] = ids[i];
    views[i] = n.views[slot[i]];
    source_arc[i] = n.source_of[slot[i]];
  }
}
const solver::ArcId* IncrementalNetwork::canonical_order() const {
  return impl_->order.data() + impl_->order_begin;
}
void IncrementalNetwork::point_slots(std::uint32_t* at, std::uint32_t* slots) const {
  const Impl& n = *impl_;
  const std::uint32_t* rank_slot = n.ranks[n.cur].slot.data() + n.rank_begin;
  const std::uint32_t count = n.rank_end - n.rank_begin;
  std::uint32_t w = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    if (i + kAhead < count) prefetch(&n.points[rank_slot[i + kAhead]]);
    if (i + kAhead / 2 < count) prefetch(n.arena.data() + n.points[rank_slot[i + kAhead / 2]].block);
    const Impl::Point& pt = n.points[rank_slot[i]];
    const std::uint32_t* e = n.arena.data() + pt.block + 2;
    at[i] = w;
    for (std::uint32_t x = 0; x < pt.listed; ++x) slots[w++] = n.frames[e[2 * x]].window_slot;
  }
  at[count] = w;
}
std::uint32_t IncrementalNetwork::evaluated_count() const { return impl_->evaluated; }
std::uint32_t IncrementalNetwork::pair_count() const { return impl_->live_pairs; }
std::uint32_t IncrementalNetwork::pair_arc_count() const { return impl_->live_pair_arcs; }
std::uint32_t IncrementalNetwork::max_views() const { return impl_->m; }
solver::NodeId IncrementalNetwork::source() const { return 0; }
solver::NodeId IncrementalNetwork::sink() const { return 1; }
std::size_t IncrementalNetwork::memory_bytes() const {
  return sizeof(IncrementalNetwork) + impl_->bytes();
}

}  // namespace keepless::core
