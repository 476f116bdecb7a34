#include "random_networks.hpp"

#include <algorithm>

namespace keepless::solver::test {
namespace {

constexpr Flow kLargeCapacity = 1'000'000;
constexpr Cost kLargeCost = 1'000'000;

// floor(log10(x)) for x >= 1, in integers so no float rounding is involved.
Cost floor_log10(std::int64_t x) {
  Cost digits = 0;
  while (x >= 10) {
    x /= 10;
    ++digits;
  }
  return digits;
}

}  // namespace

TestNetwork random_general_network(std::uint64_t seed, CostShape shape) {
  SplitMix64 rng(seed * 0x100000001B3ull + static_cast<std::uint64_t>(shape));
  TestNetwork net;
  net.label = "general(shape=" + std::to_string(static_cast<int>(shape)) +
              ", seed=" + std::to_string(seed) + ")";
  const auto n = static_cast<std::int32_t>(rng.range(2, 60));
  net.node_count = n;
  net.source = static_cast<NodeId>(rng.range(0, n - 1));
  net.sink = static_cast<NodeId>(rng.range(0, n - 2));
  if (net.sink >= net.source) ++net.sink;

  // One instance in ten is sparse, so "no path" and tiny flows show up too.
  const std::int64_t max_arcs = rng.chance(10) ? n : 4 * static_cast<std::int64_t>(n);
  const auto m = rng.range(0, max_arcs);
  const Cost equal_cost = rng.range(0, 50);
  const int large_capacity_percent = shape == CostShape::kLarge ? 25 : 5;

  auto random_node = [&] { return static_cast<NodeId>(rng.range(0, n - 1)); };
  for (std::int64_t i = 0; i < m; ++i) {
    TestArc arc{random_node(), random_node(), 0, 0};
    const auto kind = rng.range(0, 99);
    if (kind < 15) {
      arc.from = net.source;
    } else if (kind < 30) {
      arc.to = net.sink;
    } else if (kind < 33) {
      arc.to = net.source;  // into the source
    } else if (kind < 36) {
      arc.from = net.sink;  // out of the sink
    } else if (kind < 41) {
      arc.to = arc.from;  // self-loop
    } else if (kind < 51 && !net.arcs.empty()) {
      arc.from = net.arcs.back().from;  // parallel to the previous arc
      arc.to = net.arcs.back().to;
    }

    if (rng.chance(10)) {
      arc.capacity = 0;
    } else if (rng.chance(large_capacity_percent)) {
      arc.capacity = kLargeCapacity - rng.range(0, 1000);
    } else {
      arc.capacity = rng.range(1, 20);
    }

    switch (shape) {
      case CostShape::kSmall:
        arc.cost = rng.range(0, 50);
        break;
      case CostShape::kAllEqual:
        arc.cost = equal_cost;
        break;
      case CostShape::kLarge:
        arc.cost = rng.chance(50) ? rng.range(0, kLargeCost) : rng.range(0, 50);
        break;
    }
    net.arcs.push_back(arc);
  }
  return net;
}

TestNetwork random_layered_network(std::uint64_t seed) {
  SplitMix64 rng(seed ^ 0xA5A5A5A55A5A5A5Aull);
  TestNetwork net;
  net.label = "layered(seed=" + std::to_string(seed) + ")";

  const auto frames = static_cast<std::int32_t>(rng.range(3, 7));
  const std::int32_t pairs = frames * (frames - 1) / 2;
  const auto points = static_cast<std::int32_t>(
      rng.range(1, std::min<std::int32_t>(40, kMaxTestNodes - 2 - pairs)));
  net.node_count = 2 + points + pairs;
  net.source = 0;
  net.sink = 1;
  const NodeId first_point = 2;
  const NodeId first_pair = first_point + points;
  // Index of the frame-pair node for frames j < k.
  auto pair_node = [&](std::int32_t j, std::int32_t k) {
    std::int32_t index = 0;
    for (std::int32_t a = 0; a < j; ++a) index += frames - 1 - a;
    return first_pair + index + (k - j - 1);
  };

  // Which frames see each point (at least two), and the keypoint density
  // N(p, f) around it in each frame.
  std::vector<std::vector<std::int32_t>> seen_by(static_cast<std::size_t>(points));
  std::vector<std::vector<std::int64_t>> nearby(static_cast<std::size_t>(points));
  std::int32_t max_views = 2;
  for (std::int32_t p = 0; p < points; ++p) {
    auto& frames_of_p = seen_by[static_cast<std::size_t>(p)];
    for (std::int32_t f = 0; f < frames; ++f) {
      if (rng.chance(50)) frames_of_p.push_back(f);
    }
    for (std::int32_t f = 0; f < frames && frames_of_p.size() < 2; ++f) {
      if (std::find(frames_of_p.begin(), frames_of_p.end(), f) == frames_of_p.end()) {
        frames_of_p.push_back(f);
      }
    }
    std::sort(frames_of_p.begin(), frames_of_p.end());
    for (std::int32_t f = 0; f < frames; ++f)
      nearby[static_cast<std::size_t>(p)].push_back(rng.range(0, 40));
    max_views = std::max(max_views, static_cast<std::int32_t>(frames_of_p.size()));
  }

  // c_m(m) = 1, c_m(n) = ceil((n + 1) / (n - 1) * c_m(n + 1)).
  std::vector<Cost> connectivity_cost(static_cast<std::size_t>(max_views) + 1, 1);
  for (std::int32_t v = max_views - 1; v >= 2; --v) {
    const Cost next = connectivity_cost[static_cast<std::size_t>(v) + 1];
    connectivity_cost[static_cast<std::size_t>(v)] = ((v + 1) * next + (v - 2)) / (v - 1);
  }

  for (std::int32_t p = 0; p < points; ++p) {
    const auto views = static_cast<Flow>(seen_by[static_cast<std::size_t>(p)].size());
    net.arcs.push_back({net.source, first_point + p, views * (views - 1) / 2,
                        connectivity_cost[static_cast<std::size_t>(views)]});
  }
  for (std::int32_t p = 0; p < points; ++p) {
    const auto& frames_of_p = seen_by[static_cast<std::size_t>(p)];
    const auto& density = nearby[static_cast<std::size_t>(p)];
    for (std::size_t a = 0; a < frames_of_p.size(); ++a) {
      for (std::size_t b = a + 1; b < frames_of_p.size(); ++b) {
        const std::int32_t j = frames_of_p[a];
        const std::int32_t k = frames_of_p[b];
        const Cost spatial = floor_log10(
            density[static_cast<std::size_t>(j)] * density[static_cast<std::size_t>(k)] + 1);
        net.arcs.push_back({first_point + p, pair_node(j, k), 1, spatial});
      }
    }
  }
  const Flow per_pair_limit = rng.range(1, 10);  // M
  for (std::int32_t j = 0; j < frames; ++j) {
    for (std::int32_t k = j + 1; k < frames; ++k) {
      const std::int64_t baseline = rng.range(0, 100);  // d(f_j, f_k), decimetres
      // ceil(10 / (0.1 d + 1)) = ceil(100 / (d + 10)).
      const Cost baseline_cost = (100 + baseline + 9) / (baseline + 10);
      net.arcs.push_back({pair_node(j, k), net.sink, per_pair_limit, baseline_cost});
    }
  }
  return net;
}

Status load(MinCostFlow& solver, const TestNetwork& net) {
  Status status = solver.reset(net.node_count);
  if (status != Status::kOptimal) return status;
  for (const TestArc& arc : net.arcs) {
    status = solver.add_arc(arc.from, arc.to, arc.capacity, arc.cost);
    if (status != Status::kOptimal) return status;
  }
  return Status::kOptimal;
}

}  // namespace keepless::solver::test
