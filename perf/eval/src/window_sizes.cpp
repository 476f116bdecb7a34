#include "window_sizes.hpp"

#include <algorithm>
#include <cstddef>
#include <sstream>

#include "run_record.hpp"

namespace keepless::eval {

void WindowSize::max_with(const WindowSize& o) {
  keyframes = std::max(keyframes, o.keyframes);
  points = std::max(points, o.points);
  observations = std::max(observations, o.observations);
  pair_arcs = std::max(pair_arcs, o.pair_arcs);
  unmapped = std::max(unmapped, o.unmapped);
}

void WindowSizes::max_with(const WindowSizes& o) {
  for (std::size_t i = 0; i < kSizes.size(); ++i) {
    local[i].max_with(o.local[i]);
    sliding[i].max_with(o.sliding[i]);
  }
  steps += o.steps;
  replayed += o.replayed;
  refused += o.refused;
}

void WindowMeasure::clear() {
  ids_.clear();
  s_ = WindowSize{};
}

void WindowMeasure::add_keyframe(const std::vector<core::PointId>& points, std::uint64_t unmapped) {
  const std::size_t at = ids_.size();
  ids_.insert(ids_.end(), points.begin(), points.end());
  std::sort(ids_.begin() + static_cast<std::ptrdiff_t>(at), ids_.end());  // a point once per keyframe
  ids_.erase(std::unique(ids_.begin() + static_cast<std::ptrdiff_t>(at), ids_.end()), ids_.end());
  ++s_.keyframes;
  s_.observations += ids_.size() - at;
  s_.unmapped += unmapped;
}

WindowSize WindowMeasure::size() {
  std::sort(ids_.begin(), ids_.end());
  WindowSize s = s_;
  for (std::size_t i = 0; i < ids_.size();) {
    std::size_t j = i;
    while (j < ids_.size() && ids_[j] == ids_[i]) ++j;
    const std::uint64_t n = j - i;
    ++s.points;
    s.pair_arcs += n * (n - 1) / 2;
    i = j;
  }
  return s;
}

namespace {

template <typename F>
void each(const std::vector<std::pair<std::string, WindowSizes>>& rows, F&& f) {
  for (const auto& [name, w] : rows) {
    for (const char* kind : {"local", "sliding"}) {
      for (std::size_t i = 0; i < WindowSizes::kSizes.size(); ++i) {
        const WindowSize& s = kind[0] == 'l' ? w.local[i] : w.sliding[i];
        f(name, kind, WindowSizes::kSizes[i], s, w.steps);
      }
    }
  }
}

}  // namespace

std::string window_sizes_table(const std::vector<std::pair<std::string, WindowSizes>>& rows) {
  std::ostringstream o;
  o << "| input | window | K | keyframes | points | observations | pair arcs | unmapped keypoints | windows |\n"
       "|---|---|---:|---:|---:|---:|---:|---:|---:|\n";
  std::ostringstream replay;
  for (const auto& [name, w] : rows) {
    if (w.replayed > 0) {
      replay << "- " << name << ": " << w.replayed << " K = 20 windows replayed at the node's capacities, " << w.refused
             << " refused for a capacity\n";
    }
  }
  each(rows, [&](const std::string& name, const char* kind, int k, const WindowSize& s, std::uint64_t steps) {
    o << "| " << name << " | " << kind << " | " << k << " | " << s.keyframes << " | " << s.points << " | "
      << s.observations << " | " << s.pair_arcs << " | " << s.unmapped << " | " << steps << " |\n";
  });
  if (!replay.str().empty()) o << "\n" << replay.str();
  return o.str();
}

std::string window_sizes_json(const std::vector<std::pair<std::string, WindowSizes>>& rows) {
  std::ostringstream o;
  o << "{\"window_sizes\":[";
  bool first = true;
  each(rows, [&](const std::string& name, const char* kind, int k, const WindowSize& s, std::uint64_t steps) {
    o << (first ? "" : ",") << "{\"input\":" << json_string(name) << ",\"kind\":\"" << kind << "\",\"K\":" << k
      << ",\"keyframes\":" << s.keyframes << ",\"points\":" << s.points << ",\"observations\":" << s.observations
      << ",\"pair_arcs\":" << s.pair_arcs << ",\"unmapped\":" << s.unmapped << ",\"windows\":" << steps << "}";
    first = false;
  });
  o << "],\"replays\":[";
  first = true;
  for (const auto& [name, w] : rows) {
    if (w.replayed == 0) continue;
    o << (first ? "" : ",") << "{\"input\":" << json_string(name) << ",\"windows\":" << w.replayed
      << ",\"refused\":" << w.refused << "}";
    first = false;
  }
  o << "]}";
  return o.str();
}

}  // namespace keepless::eval
