#include "keepless/core/incremental_network.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <vector>

#include "box_neighbours.hpp"
#include "keepless/core/costs.hpp"
#include "keepless/core/network.hpp"
#include "id_hash.hpp"
#include "solver_status.hpp"

namespace keepless::core {

struct IncrementalNetwork::Impl {
  struct Frame {
    KeyframeId id = 0;
    double centre[3] = {0, 0, 0};
    std::uint32_t begin = 0, count = 0;
    bool live = false;
    bool gone = false;  // retired by this update: its slot waits for the next one
  };
  // One observation of a point: frame slot and N(p, f). No padding, so
  // lists compare with memcmp.
  struct Entry {
    std::uint32_t frame;
    std::uint32_t n;
  };
  struct Point {
    PointId id = 0;
    std::uint32_t views = 0;
    solver::NodeId node = -1;
    solver::ArcId source = -1;
    bool live = false;
    bool fresh = false;  // added by this update: no previous list
  };
  struct Ranked {
    PointId id;
    std::uint32_t slot;
  };
  // The pairs (x < y) of a point's entry list in lexicographic order of
  // their frame slots (entries are sorted by frame slot).
  struct PairWalk {
    const Entry* e;
    std::uint32_t n, x = 0, y = 1, k = 0;
    bool done() const { return n < 2 || x + 1 >= n; }
    std::uint64_t key() const { return (std::uint64_t{e[x].frame} << 32) | e[y].frame; }
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
  std::vector<std::int32_t> frame_of;  // window slot -> frame slot
  std::vector<std::uint8_t> matched;   // frame slot
  std::vector<std::uint32_t> by_begin;  // frame slots, for compaction
  std::vector<Observation> pool;       // keyframes' observations, [2 * max_observations]
  std::vector<std::uint32_t> pool_n;   // N(p, f) of each
  std::vector<std::uint32_t> pool_point;  // point slot of each
  std::uint32_t pool_top = 0;

  std::vector<std::int32_t> table;  // point id -> slot, open addressing, -1 empty
  std::uint64_t mask = 0;
  std::vector<Point> points;
  std::vector<std::uint32_t> free_points;
  std::uint32_t free_point_count = 0, point_high = 0;

  // Per point slot, double-buffered (this update / the previous one): its
  // entry list and its pair arcs in PairWalk order.
  std::vector<Entry> group[2];
  std::vector<std::uint32_t> gbegin[2], glen[2];
  std::vector<solver::ArcId> arcs_of[2];
  std::vector<std::uint32_t> abegin[2];
  std::vector<std::uint32_t> cursor;
  std::vector<std::uint8_t> changed;
  int cur = 0;

  // Pairs, by (frame slot, frame slot).
  std::vector<solver::NodeId> pair_node;
  std::vector<solver::ArcId> pair_sink;
  std::vector<std::uint32_t> pair_arcs;
  std::vector<std::uint32_t> idle;  // pairs whose last arc went this update
  std::uint32_t idle_count = 0, live_pairs = 0, live_pair_arcs = 0;

  // Points by ascending id, double-buffered; the canonical order.
  std::vector<Ranked> ranked[2];
  std::uint32_t ranked_count[2] = {0, 0};
  std::vector<Ranked> newcomers;
  std::uint32_t newcomer_count = 0;
  std::vector<solver::ArcId> order;
  std::uint32_t evaluated = 0;

  std::vector<solver::ArcId> free_arcs;
  std::uint32_t free_arc_count = 0;
  std::vector<solver::NodeId> free_nodes;
  std::uint32_t free_node_count = 0;
  solver::NodeId next_node = 2;

  std::vector<std::int64_t> cm;  // c_m(n), [max_keyframes + 1]
  std::uint32_t m = 0;
  std::vector<std::uint32_t> box_scratch;
  Changes changes;

  explicit Impl(const Capacities& c) : caps(c), room(IncrementalNetwork::solver_capacity(c)) {
    frame_slots = std::max<std::uint32_t>(2, 2 * c.max_keyframes);
    const std::size_t s = frame_slots;
    frames.resize(s);
    frame_of.resize(c.max_keyframes);
    matched.resize(s);
    by_begin.resize(s);
    pool.resize(2 * std::size_t{c.max_observations});
    pool_n.resize(pool.size());
    pool_point.resize(pool.size());
    std::uint64_t size = 2;
    while (size < 2ULL * c.max_points) size <<= 1;
    table.assign(size, -1);
    mask = size - 1;
    points.resize(c.max_points);
    free_points.resize(c.max_points);
    for (int b = 0; b < 2; ++b) {
      group[b].resize(c.max_observations);
      gbegin[b].resize(c.max_points);
      glen[b].resize(c.max_points);
      arcs_of[b].resize(c.max_pair_arcs);
      abegin[b].resize(c.max_points);
      ranked[b].resize(c.max_points);
    }
    cursor.resize(c.max_points);
    changed.resize(c.max_points);
    pair_node.assign(s * s, -1);
    pair_sink.assign(s * s, -1);
    pair_arcs.assign(s * s, 0);
    idle.resize(s * s);
    newcomers.resize(c.max_points);
    order.resize(c.max_points);
    free_arcs.resize(static_cast<std::size_t>(std::max(room.max_arcs, 0)));
    free_nodes.resize(static_cast<std::size_t>(std::max(room.max_nodes, 0)));
    cm.resize(std::size_t{c.max_keyframes} + 1);
    box_scratch.resize(BoxScratch::kWordsPerObservation * std::size_t{c.max_observations} + 1);
  }

  std::size_t bytes() const {
    const auto b = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
    std::size_t total = sizeof(Impl) + b(frames) + b(frame_of) + b(matched) + b(by_begin) + b(pool) + b(pool_n) +
                        b(pool_point) + b(table) + b(points) + b(free_points) + b(cursor) +
                        b(changed) + b(pair_node) + b(pair_sink) + b(pair_arcs) + b(idle) +
                        b(newcomers) + b(order) + b(free_arcs) + b(free_nodes) + b(cm) +
                        b(box_scratch);
    for (int k = 0; k < 2; ++k) {
      total += b(group[k]) + b(gbegin[k]) + b(glen[k]) + b(arcs_of[k]) + b(abegin[k]) + b(ranked[k]);
    }
    return total;
  }

  BoxScratch scratch() {
    const std::size_t n = caps.max_observations;
    return BoxScratch{box_scratch.data(), box_scratch.data() + n, box_scratch.data() + 2 * n,
                      box_scratch.data() + 3 * n};
  }

  // --- costs --------------------------------------------------------------

  std::int64_t spatial(std::uint32_t a, std::uint32_t b) const {
    return (params.cost_terms & kSpatialCost) ? spatial_cost(a, b) : 0;
  }
  std::int64_t baseline(std::uint32_t fa, std::uint32_t fb) const {
    return (params.cost_terms & kBaselineCost) ? baseline_cost(frames[fa].centre, frames[fb].centre)
                                               : 0;
  }
  static std::int64_t source_capacity(std::uint32_t n) {
    return std::int64_t{n} * (std::int64_t{n} - 1) / 2;
  }

  // --- points ---------------------------------------------------------------

  std::int32_t find(PointId id) const {
    for (std::uint64_t i = mix(id) & mask, step = 0; step <= mask; ++step, i = (i + 1) & mask) {
      const std::int32_t s = table[i];
      if (s < 0) return -1;
      if (points[static_cast<std::size_t>(s)].id == id) return s;
    }
    return -1;
  }

  // Slot of a new point, or -1 when every slot is taken.
  std::int32_t insert(PointId id) {
    std::uint32_t slot = 0;
    if (free_point_count > 0) {
      slot = free_points[--free_point_count];
    } else if (point_high < caps.max_points) {
      slot = point_high++;
    } else {
      return -1;
    }
    std::uint64_t i = mix(id) & mask;
    while (table[i] >= 0) i = (i + 1) & mask;  // load <= 1/2: a hole exists
    table[i] = static_cast<std::int32_t>(slot);
    points[slot] = Point{id, 0, -1, -1, true, true};
    newcomers[newcomer_count++] = Ranked{id, slot};
    ++changes.points_added;
    return static_cast<std::int32_t>(slot);
  }

  // Backward-shift deletion, as in Window.
  void erase(PointId id) {
    std::uint64_t hole = mix(id) & mask;
    while (points[static_cast<std::size_t>(table[hole])].id != id) hole = (hole + 1) & mask;
    std::uint64_t j = hole;
    for (std::uint64_t step = 0; step <= mask; ++step) {
      j = (j + 1) & mask;
      if (table[j] < 0) break;
      const std::uint64_t home = mix(points[static_cast<std::size_t>(table[j])].id) & mask;
      const bool home_between = hole <= j ? (hole < home && home <= j) : (hole < home || home <= j);
      if (!home_between) {
        table[hole] = table[j];
        hole = j;
      }
    }
    table[hole] = -1;
  }

  // --- solver ids -------------------------------------------------------------

  Status new_arc(solver::MinCostFlow& solver, solver::NodeId from, solver::NodeId to,
                 std::int64_t cap, std::int64_t cost, solver::ArcId* id) {
    solver::Status s;
    if (free_arc_count > 0) {
      *id = free_arcs[--free_arc_count];
      s = solver.replace_arc(*id, from, to, cap, cost);
    } else {
      *id = solver.arc_count();
      s = solver.add_arc(from, to, cap, cost);
    }
    ++changes.arcs_added;
    return from_solver(s);
  }

  void retire_arc(solver::MinCostFlow& solver, solver::ArcId id) {
    (void)solver.set_arc(id, 0, solver.cost(id));  // a live id: cannot fail
    free_arcs[free_arc_count++] = id;
    ++changes.arcs_retired;
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
  void retire_idle_pairs(solver::MinCostFlow& solver, bool only_gone) {
    std::uint32_t kept = 0;
    for (std::uint32_t k = 0; k < idle_count; ++k) {
      const std::uint32_t q = idle[k];
      if (pair_arcs[q] != 0 || pair_node[q] < 0) continue;
      const bool gone = frames[q / frame_slots].gone || frames[q % frame_slots].gone;
      if (only_gone && !gone) {
        idle[kept++] = q;
        continue;
      }
      retire_arc(solver, pair_sink[q]);
      free_node(pair_node[q]);
      pair_node[q] = -1;
      pair_sink[q] = -1;
      --live_pairs;
    }
    idle_count = kept;
  }

  // --- frames -------------------------------------------------------------------

  // Room for `count` more observations, compacting the pool if needed
  // (live frames slide down in pool order; the pool holds two windows'
  // worth, so a compaction makes room for any frame the window accepts).
  bool pool_room(std::uint32_t count) {
    if (pool_top + count <= pool.size()) return true;
    std::uint32_t n = 0;
    for (std::uint32_t f = 0; f < frame_slots; ++f) {
      if (!frames[f].live) continue;
      std::uint32_t j = n++;
      for (; j > 0 && frames[by_begin[j - 1]].begin > frames[f].begin; --j) by_begin[j] = by_begin[j - 1];
      by_begin[j] = f;
    }
    std::uint32_t top = 0;
    for (std::uint32_t j = 0; j < n; ++j) {
      Frame& fr = frames[by_begin[j]];
      if (fr.begin != top && fr.count > 0) {
        std::memmove(pool.data() + top, pool.data() + fr.begin, fr.count * sizeof(Observation));
        std::memmove(pool_n.data() + top, pool_n.data() + fr.begin, fr.count * sizeof(std::uint32_t));
        std::memmove(pool_point.data() + top, pool_point.data() + fr.begin,
                     fr.count * sizeof(std::uint32_t));
      }
      fr.begin = top;
      top += fr.count;
    }
    pool_top = top;
    return pool_top + count <= pool.size();
  }

  bool same_frame(const Frame& f, const Keyframe& kf, const Observation* obs,
                  std::uint32_t count) const {
    return f.live && f.id == kf.id && f.count == count &&
           std::memcmp(f.centre, kf.centre, sizeof(f.centre)) == 0 &&
           (count == 0 || std::memcmp(pool.data() + f.begin, obs, count * sizeof(Observation)) == 0);
  }

  void reset_state(solver::MinCostFlow& solver) {
    for (Frame& f : frames) f = Frame{};
    pool_top = 0;
    std::fill(table.begin(), table.end(), -1);
    free_point_count = 0;
    point_high = 0;
    std::fill(pair_node.begin(), pair_node.end(), -1);
    std::fill(pair_sink.begin(), pair_sink.end(), -1);
    std::fill(pair_arcs.begin(), pair_arcs.end(), 0u);
    idle_count = live_pairs = live_pair_arcs = 0;
    ranked_count[0] = ranked_count[1] = 0;
    newcomer_count = 0;
    evaluated = 0;
    free_arc_count = free_node_count = 0;
    next_node = 2;
    m = 0;
    cur = 0;
    built = false;
    (void)solver;
  }

  Status update(const Window& window, const Params& p, solver::MinCostFlow& solver);
  Status fail(Status s) {
    built = false;
    return s;
  }
};

Status IncrementalNetwork::Impl::update(const Window& window, const Params& p,
                                        solver::MinCostFlow& solver) {
  if (p.box_width < 0 || p.box_height < 0 || p.pair_capacity < 0) return Status::kInvalidArgument;
  const std::uint32_t k = window.keyframe_count();
  if (k > caps.max_keyframes || window.total_observations() > caps.max_observations ||
      window.distinct_points() > caps.max_points) {
    return Status::kCapacityExceeded;
  }
  changes = Changes{};
  const bool same_params = built && p.pair_capacity == params.pair_capacity &&
                           p.box_width == params.box_width && p.box_height == params.box_height &&
                           p.cost_terms == params.cost_terms;
  if (!same_params) {
    reset_state(solver);
    const std::int32_t nodes = std::min(solver.capacity_limits().max_nodes, room.max_nodes);
    if (nodes < 2) return Status::kCapacityExceeded;
    if (Status s = from_solver(solver.reset(nodes)); s != Status::kOk) return fail(s);
    params = p;
    built = true;
    changes.rebuilt = true;
  }
  const int prev = cur;
  cur ^= 1;
  newcomer_count = 0;
  idle_count = 0;

  // 1. Keyframes kept bit for bit keep their slot, counts and points.
  std::fill(matched.begin(), matched.end(), 0);
  for (std::uint32_t s = 0; s < k; ++s) {
    frame_of[s] = -1;
    const Observation* obs = window.observations(s);
    const std::uint32_t count = window.observation_count(s);
    for (std::uint32_t f = 0; f < frame_slots; ++f) {
      if (!matched[f] && same_frame(frames[f], window.keyframe(s), obs, count)) {
        frame_of[s] = static_cast<std::int32_t>(f);
        matched[f] = 1;
        break;
      }
    }
  }

  // 2. Keyframes that left: their points lose a view; points left with none
  // go, with their arcs (retirements first, so ids recycle within capacity).
  for (std::uint32_t f = 0; f < frame_slots; ++f) {
    Frame& fr = frames[f];
    if (!fr.live || matched[f]) continue;
    fr.live = false;
    fr.gone = true;
    ++changes.frames_removed;
    for (std::uint32_t i = fr.begin; i < fr.begin + fr.count; ++i) --points[pool_point[i]].views;
  }
  for (std::uint32_t f = 0; f < frame_slots; ++f) {
    const Frame& fr = frames[f];
    if (!fr.gone) continue;
    for (std::uint32_t i = fr.begin; i < fr.begin + fr.count; ++i) {
      const std::uint32_t slot = pool_point[i];
      Point& pt = points[slot];
      if (!pt.live || pt.views != 0) continue;
      // Every arc it had, from the previous lists.
      PairWalk walk{group[prev].data() + gbegin[prev][slot], glen[prev][slot]};
      const solver::ArcId* ids = arcs_of[prev].data() + abegin[prev][slot];
      for (; !walk.done(); walk.next()) {
        retire_arc(solver, ids[walk.k]);
        pair_loses_arc(walk.key());
      }
      if (pt.node >= 0) {
        retire_arc(solver, pt.source);
        free_node(pt.node);
      }
      erase(pt.id);
      pt.live = false;
      free_points[free_point_count++] = slot;
      ++changes.points_removed;
    }
  }

  // 3. New (or changed) keyframes: stored, counted, their points found or added.
  for (std::uint32_t s = 0; s < k; ++s) {
    if (frame_of[s] >= 0) continue;
    std::uint32_t f = 0;
    while (f < frame_slots && (frames[f].live || frames[f].gone)) ++f;  // 2K slots: one is free
    if (f == frame_slots) return fail(Status::kCapacityExceeded);
    const Observation* obs = window.observations(s);
    const std::uint32_t count = window.observation_count(s);
    if (!pool_room(count)) return fail(Status::kCapacityExceeded);
    Frame& fr = frames[f];
    fr.id = window.keyframe(s).id;
    std::memcpy(fr.centre, window.keyframe(s).centre, sizeof(fr.centre));
    fr.begin = pool_top;
    fr.count = count;
    fr.live = true;
    pool_top += count;
    if (count > 0) std::memcpy(pool.data() + fr.begin, obs, count * sizeof(Observation));
    count_box_neighbours(obs, count, params.box_width, params.box_height, scratch(),
                         pool_n.data() + fr.begin);
    for (std::uint32_t i = 0; i < count; ++i) {
      std::int32_t slot = find(obs[i].point);
      if (slot < 0) slot = insert(obs[i].point);
      if (slot < 0) return fail(Status::kCapacityExceeded);
      ++points[static_cast<std::size_t>(slot)].views;
      pool_point[fr.begin + i] = static_cast<std::uint32_t>(slot);
    }
    frame_of[s] = static_cast<std::int32_t>(f);
    ++changes.frames_added;
  }

  // 4. Every point's (frame slot, N) list, by a counting sort over the
  // keyframes in slot order, and whether it differs from the previous one.
  std::vector<std::uint32_t>& len = glen[cur];
  std::vector<std::uint32_t>& beg = gbegin[cur];
  std::fill(len.begin(), len.begin() + point_high, 0u);
  for (std::uint32_t f = 0; f < frame_slots; ++f) {
    const Frame& fr = frames[f];
    if (!fr.live) continue;
    for (std::uint32_t i = fr.begin; i < fr.begin + fr.count; ++i) ++len[pool_point[i]];
  }
  std::uint32_t at = 0, new_m = 0;
  for (std::uint32_t slot = 0; slot < point_high; ++slot) {
    beg[slot] = cursor[slot] = at;
    at += len[slot];
    new_m = std::max(new_m, len[slot]);
  }
  for (std::uint32_t f = 0; f < frame_slots; ++f) {
    const Frame& fr = frames[f];
    if (!fr.live) continue;
    for (std::uint32_t i = fr.begin; i < fr.begin + fr.count; ++i) {
      group[cur][cursor[pool_point[i]]++] = Entry{f, pool_n[i]};
    }
  }
  for (std::uint32_t slot = 0; slot < point_high; ++slot) {
    const Point& pt = points[slot];
    if (!pt.live) continue;
    const std::uint32_t n = len[slot];
    changed[slot] = pt.fresh || n != glen[prev][slot] ||
                    std::memcmp(group[cur].data() + beg[slot], group[prev].data() + gbegin[prev][slot],
                                n * sizeof(Entry)) != 0;
  }
  const bool cm_changed = new_m != m || changes.rebuilt;
  if (cm_changed) {
    m = new_m;
    std::fill(cm.begin(), cm.end(), 0);
    if (params.cost_terms & kConnectivityCost) connectivity_costs(m, cm.data());
  }

  // 5. Retirements of kept points that changed: arcs to pairs they no longer
  // have, and the node of a point no longer seen twice.
  for (std::uint32_t slot = 0; slot < point_high; ++slot) {
    Point& pt = points[slot];
    if (!pt.live || pt.fresh || !changed[slot]) continue;
    ++changes.points_changed;
    PairWalk old{group[prev].data() + gbegin[prev][slot], glen[prev][slot]};
    PairWalk now{group[cur].data() + beg[slot], len[slot]};
    const solver::ArcId* ids = arcs_of[prev].data() + abegin[prev][slot];
    while (!old.done()) {
      if (!now.done() && now.key() < old.key()) {
        now.next();
      } else if (!now.done() && now.key() == old.key()) {
        now.next();
        old.next();
      } else {
        retire_arc(solver, ids[old.k]);
        pair_loses_arc(old.key());
        old.next();
      }
    }
    if (len[slot] < 2 && pt.node >= 0) {
      retire_arc(solver, pt.source);
      free_node(pt.node);
      pt.node = -1;
      pt.source = -1;
    }
  }
  retire_idle_pairs(solver, true);

  // 6. Every point's arcs for this update: unchanged lists keep theirs (with
  // a new c_m when m moved); changed ones keep, re-cost or add.
  std::uint32_t out = 0;
  for (std::uint32_t slot = 0; slot < point_high; ++slot) {
    Point& pt = points[slot];
    if (!pt.live) continue;
    const std::uint32_t n = len[slot];
    const std::uint32_t count = n >= 2 ? n * (n - 1) / 2 : 0;
    if (out + std::uint64_t{count} > caps.max_pair_arcs) return fail(Status::kCapacityExceeded);
    abegin[cur][slot] = out;
    solver::ArcId* dst = arcs_of[cur].data() + out;
    out += count;
    if (n < 2) continue;
    if (!changed[slot]) {
      std::memcpy(dst, arcs_of[prev].data() + abegin[prev][slot], count * sizeof(solver::ArcId));
      if (cm_changed) {
        if (Status s = from_solver(solver.set_arc(pt.source, source_capacity(n), cm[n]));
            s != Status::kOk) {
          return fail(s);
        }
      }
      continue;
    }
    if (pt.node < 0) {
      if (Status s = new_node(solver, &pt.node); s != Status::kOk) return fail(s);
      if (Status s = new_arc(solver, 0, pt.node, source_capacity(n), cm[n], &pt.source);
          s != Status::kOk) {
        return fail(s);
      }
    } else if (Status s = from_solver(solver.set_arc(pt.source, source_capacity(n), cm[n]));
               s != Status::kOk) {
      return fail(s);
    }
    const std::uint32_t old_len = pt.fresh ? 0 : glen[prev][slot];
    const Entry* old_entries = group[prev].data() + gbegin[prev][slot];
    PairWalk old{old_entries, old_len};
    PairWalk now{group[cur].data() + beg[slot], n};
    const solver::ArcId* ids = arcs_of[prev].data() + (pt.fresh ? 0 : abegin[prev][slot]);
    for (; !now.done(); now.next()) {
      while (!old.done() && old.key() < now.key()) old.next();  // retired in step 5
      const std::int64_t cost = spatial(now.e[now.x].n, now.e[now.y].n);
      if (!old.done() && old.key() == now.key()) {
        const solver::ArcId id = ids[old.k];
        if (spatial(old.e[old.x].n, old.e[old.y].n) != cost) {
          if (Status s = from_solver(solver.set_arc(id, 1, cost)); s != Status::kOk) return fail(s);
          ++changes.arcs_recosted;
        }
        dst[now.k] = id;
        old.next();
        continue;
      }
      solver::NodeId pair = -1;
      if (Status s = pair_gains_arc(solver, now.key(), &pair); s != Status::kOk) return fail(s);
      if (Status s = new_arc(solver, pt.node, pair, 1, cost, &dst[now.k]); s != Status::kOk) {
        return fail(s);
      }
    }
  }
  retire_idle_pairs(solver, false);

  // 7. Points by ascending id: the kept ones in their old order, merged with
  // the newcomers; then the canonical order of the source arcs.
  std::sort(newcomers.begin(), newcomers.begin() + newcomer_count,
            [](const Ranked& a, const Ranked& b) { return a.id < b.id; });
  const Ranked* old_rank = ranked[prev].data();
  const std::uint32_t old_count = ranked_count[prev];
  Ranked* rank = ranked[cur].data();
  std::uint32_t r = 0, a = 0, b = 0;
  const auto kept = [this](const Ranked& e) {
    const Point& pt = points[e.slot];
    return pt.live && !pt.fresh && pt.id == e.id;
  };
  while (a < old_count || b < newcomer_count) {
    if (a < old_count && !kept(old_rank[a])) {
      ++a;
    } else if (b >= newcomer_count || (a < old_count && old_rank[a].id < newcomers[b].id)) {
      rank[r++] = old_rank[a++];
    } else {
      rank[r++] = newcomers[b++];
    }
  }
  ranked_count[cur] = r;
  evaluated = 0;
  for (std::uint32_t i = 0; i < r; ++i) {
    const Point& pt = points[rank[i].slot];
    if (pt.node >= 0) order[evaluated++] = pt.source;
  }
  for (std::uint32_t i = 0; i < newcomer_count; ++i) points[newcomers[i].slot].fresh = false;
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

std::uint32_t IncrementalNetwork::point_count() const { return impl_->ranked_count[impl_->cur]; }
PointId IncrementalNetwork::point_id(std::uint32_t i) const { return impl_->ranked[impl_->cur][i].id; }
std::uint32_t IncrementalNetwork::point_views(std::uint32_t i) const {
  return impl_->glen[impl_->cur][impl_->ranked[impl_->cur][i].slot];
}
solver::ArcId IncrementalNetwork::point_source_arc(std::uint32_t i) const {
  const Impl::Point& pt = impl_->points[impl_->ranked[impl_->cur][i].slot];
  return pt.node >= 0 ? pt.source : -1;
}
const solver::ArcId* IncrementalNetwork::canonical_order() const { return impl_->order.data(); }
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
