#include "modes.hpp"

#include <algorithm>
#include <charconv>
#include <numeric>
#include <unordered_map>

#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "keepless/platform/memory_estimate.hpp"

namespace keepless::sparsify {

std::string budget_value(const core::KeepBudget& budget) {
  char text[32];
  const auto end = budget.kind == core::BudgetKind::kFraction
                       ? std::to_chars(text, text + sizeof text, budget.fraction).ptr
                       : std::to_chars(text, text + sizeof text, budget.count).ptr;
  return std::string(text, end);
}

namespace {

core::Capacities at_least_one(core::Capacities c) {
  c.max_keyframes = std::max<std::uint32_t>(c.max_keyframes, 1);
  c.max_points = std::max<std::uint32_t>(c.max_points, 1);
  c.max_observations = std::max<std::uint32_t>(c.max_observations, 1);
  c.max_pair_arcs = std::max<std::uint32_t>(c.max_pair_arcs, 1);
  return c;
}

// The largest window of K consecutive keyframes, before any cull (culls
// only shrink a window): observations, distinct points, pair arcs, unmapped
// keypoints.
core::Capacities replay_capacities(const core::WindowFile& f, std::uint32_t K) {
  core::Capacities c{std::min<std::uint32_t>(K, static_cast<std::uint32_t>(f.keyframes.size())), 0, 0, 0};
  std::unordered_map<core::PointId, std::uint32_t> count;
  std::uint64_t obs = 0, arcs = 0, unmapped = 0;
  for (std::size_t i = 0; i < f.keyframes.size(); ++i) {
    for (const core::Observation& o : f.observations[i]) arcs += count[o.point]++;
    obs += f.observations[i].size();
    unmapped += f.keyframes[i].unmapped_count;
    if (i >= K) {
      for (const core::Observation& o : f.observations[i - K]) {
        auto it = count.find(o.point);
        arcs -= --it->second;
        if (it->second == 0) count.erase(it);
      }
      obs -= f.observations[i - K].size();
      unmapped -= f.keyframes[i - K].unmapped_count;
    }
    c.max_unmapped_keypoints = std::max<std::uint32_t>(c.max_unmapped_keypoints, static_cast<std::uint32_t>(unmapped));
    c.max_observations = std::max<std::uint32_t>(c.max_observations, static_cast<std::uint32_t>(obs));
    c.max_points = std::max<std::uint32_t>(c.max_points, static_cast<std::uint32_t>(count.size()));
    c.max_pair_arcs = std::max<std::uint32_t>(c.max_pair_arcs, static_cast<std::uint32_t>(arcs));
  }
  return at_least_one(c);
}

void add_totals(const core::Summary& s, core::Summary* t) {
  t->pairs += s.pairs;
  t->arcs += s.arcs;
  t->max_flow += s.max_flow;
  t->total_cost += s.total_cost;
  t->out_of_scope += s.out_of_scope;  // the scope and floor counts: summed over the slides
  t->floor_keyframes += s.floor_keyframes;
  t->floor_promoted += s.floor_promoted;
  t->floor_short += s.floor_short;
  t->guarded += s.guarded;  // tracking-safe culling's counts, likewise
  t->tracked += s.tracked;
  t->track_fallback += s.track_fallback;  // keyframes without point quality, per slide
}

// Final counts over the decisions.
void count_verdicts(ModeResult* r, std::uint32_t keyframes) {
  core::Summary& t = r->totals;
  t.keyframes = keyframes;
  t.points = static_cast<std::uint32_t>(r->decisions.size());
  t.kept = t.culled = t.skipped = 0;
  for (const core::PointDecision& d : r->decisions) {
    t.kept += d.verdict == core::Verdict::kKeep;
    t.culled += d.verdict == core::Verdict::kCull;
    t.skipped += d.verdict == core::Verdict::kSkip;
  }
  t.evaluated = t.kept + t.culled;
}

core::Status whole(const core::WindowFile& f, const core::Params& params, ModeResult* out) {
  const core::Capacities caps = at_least_one(f.needs);
  core::Window window(caps);
  core::Sparsifier sparsifier(caps, params);
  for (std::size_t k = 0; k < f.keyframes.size(); ++k) {
    const core::Status s = window.add_keyframe(f.keyframes[k], f.observations[k].data(),
                                               static_cast<std::uint32_t>(f.observations[k].size()));
    if (s != core::Status::kOk) return s;
  }
  const core::Status s = sparsifier.run(window);
  if (s != core::Status::kOk) return s;
  out->decisions.assign(sparsifier.decisions(), sparsifier.decisions() + sparsifier.decision_count());
  if (const std::uint32_t* t = sparsifier.keep_thresholds()) out->thresholds.assign(t, t + sparsifier.decision_count());
  out->totals = sparsifier.summary();
  out->slides = 1;
  out->capacities = caps;
  out->memory_bytes = window.memory_bytes() + sparsifier.memory_bytes();
  return core::Status::kOk;
}

core::Status replay(const core::WindowFile& f, const core::Params& params, std::uint32_t K, ModeResult* out) {
  // Every point once, ascending id; slots index decisions.
  std::vector<core::PointDecision>& decisions = out->decisions;
  for (const auto& obs : f.observations) {
    for (const core::Observation& o : obs) decisions.push_back({o.point, core::Verdict::kSkip, 0, 0});
  }
  std::sort(decisions.begin(), decisions.end(),
            [](const core::PointDecision& a, const core::PointDecision& b) { return a.point < b.point; });
  decisions.erase(std::unique(decisions.begin(), decisions.end(),
                              [](const core::PointDecision& a, const core::PointDecision& b) { return a.point == b.point; }),
                  decisions.end());
  const auto slot_of = [&](core::PointId p) { return static_cast<std::uint32_t>(find_decision(decisions, p)); };

  const core::Capacities caps = replay_capacities(f, K);
  // One window, slid and edited in place as the node's is: a keyframe enters
  // without the points culled before it, and culled points leave at once.
  core::Window window(caps);
  core::Sparsifier sparsifier(caps, params, core::SolveMode::kIncremental);
  std::vector<bool> culled(decisions.size(), false);
  std::vector<core::Observation> entering;
  std::vector<std::uint8_t> entering_tracked;  // flags and quality follow the observations
  std::vector<core::PointQuality> entering_quality;
  std::vector<core::PointId> culled_now;
  for (std::size_t i = 0; i < f.keyframes.size(); ++i) {
    core::Keyframe kf = f.keyframes[i];
    entering.clear();
    entering_tracked.clear();
    entering_quality.clear();
    for (std::size_t k = 0; k < f.observations[i].size(); ++k) {
      const core::Observation& o = f.observations[i][k];
      if (culled[slot_of(o.point)]) continue;
      entering.push_back(o);
      if (kf.tracked != nullptr) entering_tracked.push_back(kf.tracked[k]);
      if (kf.quality != nullptr) entering_quality.push_back(kf.quality[k]);
    }
    if (kf.tracked != nullptr) kf.tracked = entering_tracked.data();
    if (kf.quality != nullptr) kf.quality = entering_quality.data();
    const auto count = static_cast<std::uint32_t>(entering.size());
    core::Status s = window.keyframe_count() == caps.max_keyframes ? window.slide(kf, entering.data(), count)
                                                                  : window.add_keyframe(kf, entering.data(), count);
    if (s != core::Status::kOk) return s;
    s = sparsifier.update(window);
    if (s != core::Status::kOk) return s;
    ++out->slides;
    add_totals(sparsifier.summary(), &out->totals);
    culled_now.clear();
    const core::PointDecision* d = sparsifier.decisions();
    for (std::uint32_t k = 0; k < sparsifier.decision_count(); ++k) {
      if (d[k].verdict == core::Verdict::kSkip) continue;
      const std::uint32_t slot = slot_of(d[k].point);
      decisions[slot] = d[k];
      if (d[k].verdict == core::Verdict::kCull) {
        culled[slot] = true;
        culled_now.push_back(d[k].point);
      }
    }
    std::sort(culled_now.begin(), culled_now.end());
    s = window.remove_points(culled_now.data(), static_cast<std::uint32_t>(culled_now.size()));
    if (s != core::Status::kOk) return s;
  }
  out->capacities = caps;
  out->memory_bytes = window.memory_bytes() + sparsifier.memory_bytes();
  return core::Status::kOk;
}

}  // namespace

const char* to_string(Mode mode) { return mode == Mode::kReplay ? "replay" : "whole"; }

std::string point_views_refusal(const core::WindowFile& keyframes, const core::Params& params,
                                const std::string& name) {
  if (!(params.cost_terms & core::kConnectivityCost) || keyframes.keyframes.size() <= core::kMaxPointViews) return "";
  std::vector<core::PointId> ids;
  ids.reserve(keyframes.needs.max_observations);
  for (const auto& obs : keyframes.observations) {
    for (const core::Observation& o : obs) ids.push_back(o.point);
  }
  std::sort(ids.begin(), ids.end());
  std::size_t most = 0;
  core::PointId point = 0;
  for (std::size_t i = 0, j = 0; i < ids.size(); i = j) {
    while (j < ids.size() && ids[j] == ids[i]) ++j;
    if (j - i > most) {
      most = j - i;
      point = ids[i];
    }
  }
  if (most <= core::kMaxPointViews) return "";
  return name + ":0: point " + std::to_string(point) + " is seen by " + std::to_string(most) +
         " images, above the " + std::to_string(core::kMaxPointViews) +
         " one window can price (core::kMaxPointViews: its connectivity cost c_m(2) would pass the solver's cost "
         "bound 2^30); --mode replay decides windows of --K images, or --cost-terms without c_c";
}

core::Capacities decision_capacities(const core::WindowFile& keyframes, Mode mode, std::uint32_t K) {
  return mode == Mode::kWhole ? at_least_one(keyframes.needs) : replay_capacities(keyframes, K);
}

double decision_bytes(const core::WindowFile& keyframes, Mode mode, const core::Params& params, std::uint32_t K) {
  const platform::MemoryModel model =
      mode == Mode::kWhole ? platform::probe_memory_model(params, core::SolveMode::kFromScratch, 1)
                           : platform::probe_memory_model(params, core::SolveMode::kIncremental, 1);
  // Replay also keeps one decision per distinct point of the map.
  const double decisions =
      mode == Mode::kReplay ? static_cast<double>(sizeof(core::PointDecision)) * keyframes.needs.max_points : 0.0;
  return model.bytes(decision_capacities(keyframes, mode, K)) + decisions;
}

std::int64_t find_decision(const std::vector<core::PointDecision>& decisions, core::PointId point) {
  const auto it = std::lower_bound(decisions.begin(), decisions.end(), point,
                                   [](const core::PointDecision& d, core::PointId p) { return d.point < p; });
  return it != decisions.end() && it->point == point ? it - decisions.begin() : -1;
}

core::Status decide(const core::WindowFile& keyframes, Mode mode, const core::Params& params, std::uint32_t K,
                    ModeResult* out) {
  *out = ModeResult{};
  const core::Status s = mode == Mode::kWhole ? whole(keyframes, params, out) : replay(keyframes, params, K, out);
  if (s == core::Status::kOk) count_verdicts(out, static_cast<std::uint32_t>(keyframes.keyframes.size()));
  return s;
}

std::vector<std::uint32_t> kept_observations(const std::vector<std::vector<core::PointId>>& images,
                                             const std::vector<core::PointDecision>& decisions) {
  std::vector<std::uint32_t> n(images.size(), 0);
  for (std::size_t i = 0; i < images.size(); ++i) {
    for (const core::PointId p : images[i]) {
      const std::int64_t s = find_decision(decisions, p);
      n[i] += s < 0 || decisions[s].verdict != core::Verdict::kCull;
    }
  }
  return n;
}

std::uint32_t apply_floor(const std::vector<std::vector<core::PointId>>& images, std::uint32_t floor,
                          std::vector<core::PointDecision>* decisions) {
  if (floor == 0) return 0;
  // Slots of each image's observations, and each point's image list and size.
  std::vector<std::vector<std::int64_t>> slots(images.size());
  std::vector<std::uint32_t> track(decisions->size(), 0);
  std::vector<std::vector<std::uint32_t>> seen_in(decisions->size());
  for (std::size_t i = 0; i < images.size(); ++i) {
    for (const core::PointId p : images[i]) {
      const std::int64_t s = find_decision(*decisions, p);
      slots[i].push_back(s);
      if (s < 0) continue;
      ++track[s];
      seen_in[s].push_back(static_cast<std::uint32_t>(i));  // once per observation
    }
  }
  std::vector<std::uint32_t> kept = kept_observations(images, *decisions);
  std::uint32_t restored = 0;
  std::vector<std::int64_t> candidates;
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (kept[i] >= floor) continue;
    candidates.clear();
    for (const std::int64_t s : slots[i]) {
      if (s >= 0 && (*decisions)[s].verdict == core::Verdict::kCull) candidates.push_back(s);
    }
    std::sort(candidates.begin(), candidates.end(), [&](std::int64_t a, std::int64_t b) {
      return track[a] != track[b] ? track[a] > track[b] : (*decisions)[a].point < (*decisions)[b].point;
    });
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    for (const std::int64_t s : candidates) {
      if (kept[i] >= floor) break;
      (*decisions)[s].verdict = core::Verdict::kKeep;
      ++restored;
      for (const std::uint32_t j : seen_in[s]) ++kept[j];
    }
  }
  return restored;
}

}  // namespace keepless::sparsify
