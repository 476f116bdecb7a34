// keepless_node's flags and derived capacities, and the latency histogram
// behind its status percentiles.

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "keepless/core/sparsifier.hpp"
#include "keepless/platform/latency_histogram.hpp"
#include "keepless/platform/node.hpp"
#include "keepless/platform/node_config.hpp"

#include <lcm/lcm-cpp.hpp>
#include <utility>

using keepless::platform::LatencyHistogram;
using keepless::platform::NodeConfig;
using keepless::platform::ParseResult;

namespace {

ParseResult parse(std::vector<std::string> args, NodeConfig& c, std::string& error) {
  args.insert(args.begin(), "keepless_node");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return keepless::platform::parse_node_arguments(static_cast<int>(argv.size()), argv.data(), c, error);
}

// Every field a flag sets, as text: two configurations compare equal.
std::string fields(const NodeConfig& c) {
  const keepless::core::Params& p = c.params;
  std::ostringstream s;
  s << c.url << '|' << c.keyframe_channel << '|' << c.event_channel << '|' << c.decision_channel << '|'
    << c.timing_channel << '|' << c.status_channel << '|' << c.event_ack_channel << '|' << c.window << '|'
    << c.max_observations << '|' << c.max_event_ids << '|' << c.max_unmapped << '|' << c.max_points << '|'
    << c.max_window_observations << '|' << c.max_pair_arcs << '|' << c.max_memory_mb << '|'
    << c.max_sequence_jump << '|' << c.max_utime_jump_s << '|' << c.restart_confirm << '|'
    << c.owner_timeout_s << '|' << c.cull_memory << '|' << c.defer_memory << '|' << c.budget_work_units << '|'
    << c.latency_target_ms << '|' << c.cpus << '|' << c.mlock << '|' << c.queue_capacity << '|'
    << c.status_period_ms << '|' << c.max_keyframes << '|' << c.quiet << '|' << p.pair_capacity << '|'
    << p.theta << '|' << p.box_width << 'x' << p.box_height << '|' << int{p.cost_terms} << '|'
    << p.spatial_weight << '|' << static_cast<int>(p.scope) << '|' << p.coverage_floor << '|'
    << static_cast<int>(p.cost_model) << '|' << p.image_width << 'x' << p.image_height << '|'
    << static_cast<int>(p.budget.kind) << '|' << p.budget.count << '|' << p.budget.fraction << '|'
    << p.budget.track_share << '|' << p.budget.track_share_from << '|' << p.budget.track_share_to << '|'
    << p.maturity_keyframes << '|'
    << p.defer_keyframes << '|' << int{p.track_terms};
  return s.str();
}

// Every "(default X)" of --help, given as the flag's value, leaves the
// configuration as no flag does: the help and NodeConfig say the same.
// Defaults that are not a value ("unlimited", "all four") are skipped.
TEST(NodeConfig, EveryDefaultTheHelpNamesIsTheDefault) {
  NodeConfig base;
  std::string error;
  ASSERT_EQ(parse({}, base, error), ParseResult::kOk) << error;
  std::istringstream usage(keepless::platform::node_usage());
  std::string line, flag;
  int checked = 0;
  while (std::getline(usage, line)) {
    if (line.rfind("  --", 0) == 0) flag = line.substr(2, line.find(' ', 2) - 2);
    const std::size_t at = line.find("(default ");
    if (at == std::string::npos) continue;
    const std::size_t from = at + 9;
    std::string value = line.substr(from, line.find_first_of(" ;,)", from) - from);
    if (!value.empty() && value.back() == ':') value.pop_back();  // "(default 0: off)"
    if (value == "unlimited" || value == "all") continue;
    SCOPED_TRACE(flag + " " + value);
    NodeConfig c;
    EXPECT_EQ(parse({flag, value}, c, error), ParseResult::kOk) << error;
    EXPECT_EQ(fields(c), fields(base));
    ++checked;
  }
  EXPECT_GE(checked, 30);  // the help's value defaults were found
}

TEST(NodeConfig, DefaultsMatchTheDocumentedOnes) {
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({}, c, error), ParseResult::kOk);
  EXPECT_EQ(c.url, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(c.keyframe_channel, "KEEPLESS_KEYFRAME");
  EXPECT_EQ(c.decision_channel, "KEEPLESS_DECISION");
  EXPECT_EQ(c.window, 20u);
  EXPECT_EQ(c.params.pair_capacity, 100);
  EXPECT_EQ(c.params.theta, 0.5);
}

TEST(NodeConfig, ParsesEveryFlag) {
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({"--url", "memq://", "--keyframe-channel=KF", "--event-channel", "EV", "--decision-channel", "DE",
                   "--timing-channel", "TI", "--status-channel", "ST", "--window", "7", "--max-observations", "300",
                   "--max-event-ids", "9", "--max-pair-arcs", "5000", "--M", "50", "--theta", "0.25", "--box",
                   "32x16", "--budget-work", "1000", "--latency-target-ms", "2.5", "--cpus", "0,1", "--mlock", "--queue", "64",
                   "--status-period-ms", "250", "--max-keyframes", "12", "--quiet"},
                  c, error),
            ParseResult::kOk)
      << error;
  EXPECT_EQ(c.url, "memq://");
  EXPECT_EQ(c.keyframe_channel, "KF");
  EXPECT_EQ(c.event_channel, "EV");
  EXPECT_EQ(c.decision_channel, "DE");
  EXPECT_EQ(c.timing_channel, "TI");
  EXPECT_EQ(c.status_channel, "ST");
  EXPECT_EQ(c.window, 7u);
  EXPECT_EQ(c.max_observations, 300u);
  EXPECT_EQ(c.max_event_ids, 9u);
  EXPECT_EQ(c.max_pair_arcs, 5000u);
  EXPECT_EQ(c.latency_target_ms, 2.5);
  EXPECT_EQ(c.params.pair_capacity, 50);
  EXPECT_EQ(c.params.theta, 0.25);
  EXPECT_EQ(c.params.box_width, 32);
  EXPECT_EQ(c.params.box_height, 16);
  EXPECT_EQ(c.budget_work_units, 1000u);
  EXPECT_EQ(c.cpus, "0,1");
  EXPECT_TRUE(c.mlock);
  EXPECT_EQ(c.queue_capacity, 64u);
  EXPECT_EQ(c.status_period_ms, 250u);
  EXPECT_EQ(c.max_keyframes, 12u);
  EXPECT_TRUE(c.quiet);
}

TEST(NodeConfig, RejectsBadValues) {
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--window", "1"}, {"--window", "x"}, {"--theta", "1.5"}, {"--theta", "nan"},
        {"--M", "0"}, {"--box", "64"}, {"--max-observations", "-3"}, {"--bogus"}, {"--url"},
        {"--window", "256", "--max-observations", "1000000"}}) {
    NodeConfig c;
    std::string error;
    EXPECT_EQ(parse(bad, c, error), ParseResult::kError) << bad[0];
    EXPECT_FALSE(error.empty());
  }
  NodeConfig c;
  std::string error;
  EXPECT_EQ(parse({"--help"}, c, error), ParseResult::kHelp);
}

TEST(NodeConfig, CapacitiesCoverTheWorstCaseWindow) {
  NodeConfig c;
  c.window = 10;
  c.max_observations = 100;
  const keepless::core::Capacities caps = keepless::platform::window_capacities(c);
  EXPECT_EQ(caps.max_keyframes, 10u);
  EXPECT_EQ(caps.max_observations, 1000u);
  EXPECT_EQ(caps.max_points, 1000u);
  EXPECT_EQ(caps.max_pair_arcs, 100u * 10u * 9u / 2u);  // 100 points each in all 10 keyframes
  c.max_pair_arcs = 77;
  EXPECT_EQ(keepless::platform::window_capacities(c).max_pair_arcs, 77u);
}

// The defaults are the "default" profile, and their fixed memory, predicted
// before allocating, is within 16 MB.
TEST(NodeConfig, DefaultsFitSixteenMegabytes) {
  const NodeConfig defaults;
  EXPECT_LE(keepless::platform::estimate_node_bytes(defaults), 16e6);
  const keepless::core::Capacities caps = keepless::platform::window_capacities(defaults);
  EXPECT_EQ(caps.max_keyframes, 20u);
  EXPECT_EQ(caps.max_points, 6600u);
  EXPECT_EQ(caps.max_observations, 19100u);
  EXPECT_EQ(caps.max_pair_arcs, 51000u);
  EXPECT_EQ(caps.max_keyframe_observations, defaults.max_observations);
  NodeConfig profiled;
  std::string error;
  ASSERT_EQ(parse({"--profile", "default"}, profiled, error), ParseResult::kOk) << error;
  const keepless::core::Capacities same = keepless::platform::window_capacities(profiled);
  EXPECT_EQ(same.max_points, caps.max_points);
  EXPECT_EQ(same.max_observations, caps.max_observations);
  EXPECT_EQ(same.max_pair_arcs, caps.max_pair_arcs);
  EXPECT_EQ(profiled.max_observations, defaults.max_observations);
}

TEST(NodeConfig, ProfilesParseAndSizeAsDocumented) {
  struct Expected {
    const char* name;
    std::uint32_t window, per_keyframe, points, observations, pair_arcs;
    double max_bytes;
  };
  for (const Expected& e : {Expected{"small", 10, 1000, 2000, 4500, 7000, 3.6e6},
                            Expected{"default", 20, 2000, 6600, 19100, 51000, 16e6},
                            Expected{"large", 40, 2000, 8100, 37000, 117000, 30e6}}) {
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"--profile", e.name}, {std::string("--profile=") + e.name}}) {
      NodeConfig c;
      std::string error;
      ASSERT_EQ(parse(args, c, error), ParseResult::kOk) << error;
      EXPECT_EQ(c.window, e.window) << e.name;
      EXPECT_EQ(c.max_observations, e.per_keyframe) << e.name;
      const keepless::core::Capacities caps = keepless::platform::window_capacities(c);
      EXPECT_EQ(caps.max_keyframes, e.window);
      EXPECT_EQ(caps.max_points, e.points) << e.name;
      EXPECT_EQ(caps.max_observations, e.observations) << e.name;
      EXPECT_EQ(caps.max_pair_arcs, e.pair_arcs) << e.name;
      const double bytes = keepless::platform::estimate_node_bytes(c);
      EXPECT_LE(bytes, e.max_bytes) << e.name;
    }
  }
  // The other flags refine a profile wherever it stands.
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({"--max-pair-arcs", "9000", "--profile", "small", "--max-points", "3000"}, c, error), ParseResult::kOk)
      << error;
  EXPECT_EQ(c.window, 10u);
  EXPECT_EQ(c.max_pair_arcs, 9000u);
  EXPECT_EQ(c.max_points, 3000u);
  EXPECT_EQ(c.max_window_observations, 4500u);
  // A larger profile costs more, as predicted.
  NodeConfig small, large;
  ASSERT_TRUE(keepless::platform::apply_profile("small", small));
  ASSERT_TRUE(keepless::platform::apply_profile("large", large));
  EXPECT_LT(keepless::platform::estimate_node_bytes(small), keepless::platform::estimate_node_bytes(NodeConfig{}));
  EXPECT_LT(keepless::platform::estimate_node_bytes(NodeConfig{}), keepless::platform::estimate_node_bytes(large));
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--profile", "tiny"}, {"--profile"}, {"--profile="},
        {"--max-points", "100"},  // below one keyframe's 2000 observations
        {"--profile", "small", "--max-window-observations", "999"}, {"--max-points", "-1"}}) {
    NodeConfig b;
    std::string why;
    EXPECT_EQ(parse(bad, b, why), ParseResult::kError) << bad[0];
    EXPECT_FALSE(why.empty());
  }
}

TEST(LatencyHistogram, QuantilesWithinOneSixteenth) {
  LatencyHistogram h;
  EXPECT_EQ(h.quantile(0.5), 0u);
  for (std::uint64_t v = 1; v <= 10000; ++v) h.record(v * 1000);  // 1 us .. 10 ms
  EXPECT_EQ(h.count(), 10000u);
  EXPECT_EQ(h.max(), 10000000u);
  const double p50 = static_cast<double>(h.quantile(0.5)), p99 = static_cast<double>(h.quantile(0.99));
  EXPECT_GE(p50, 5000000.0);
  EXPECT_LE(p50, 5000000.0 * (1 + 1.0 / 16));
  EXPECT_GE(p99, 9900000.0);
  EXPECT_LE(p99, 9900000.0 * (1 + 1.0 / 16));
  EXPECT_EQ(h.quantile(1.0), 10000000u);
  h.record(3);
  EXPECT_EQ(h.quantile(0.0), 3u);  // small values are exact
  h.clear();
  EXPECT_EQ(h.count(), 0u);
}

}  // namespace

namespace {

TEST(NodeConfig, ParsesThePolicyFlags) {
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({}, c, error), ParseResult::kOk);
  EXPECT_EQ(c.params.scope, keepless::core::Scope::kWindow);  // the library's defaults
  EXPECT_EQ(c.params.coverage_floor, 0u);
  EXPECT_EQ(c.params.cost_model, keepless::core::CostModel::kPaper);
  ASSERT_EQ(parse({"--scope", "newest", "--floor=30", "--cost", "information", "--image", "1241x376",
                   "--max-unmapped", "1500", "--window", "10"},
                  c, error),
            ParseResult::kOk)
      << error;
  EXPECT_EQ(c.max_unmapped, 1500u);
  EXPECT_EQ(keepless::platform::window_capacities(c).max_unmapped_keypoints, 15000u);
  EXPECT_EQ(c.params.scope, keepless::core::Scope::kNewest);
  EXPECT_EQ(c.params.coverage_floor, 30u);
  EXPECT_EQ(c.params.cost_model, keepless::core::CostModel::kInformation);
  EXPECT_EQ(c.params.image_width, 1241);
  EXPECT_EQ(c.params.image_height, 376);
  NodeConfig automatic;
  ASSERT_EQ(parse({"--scope", "auto"}, automatic, error), ParseResult::kOk) << error;
  EXPECT_EQ(automatic.params.scope, keepless::core::Scope::kAuto);
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--scope", "all"}, {"--floor", "-1"}, {"--floor", "4294967296"},
        {"--cost", "Paper"}, {"--image", "0x480"}, {"--image", "640"}, {"--max-unmapped", "-1"},
        {"--track-terms", "length,length"}, {"--track-terms", ""}, {"--track-terms", "size"},
        {"--cost-terms", "c_s,c_s"}, {"--cost-terms", ""}, {"--cost-terms", "c_d"}}) {
    NodeConfig d;
    EXPECT_EQ(parse(bad, d, error), ParseResult::kError) << bad[0] << " " << bad[1];
  }
  // --cost track and the terms it sums (default all four).
  NodeConfig t;
  ASSERT_EQ(parse({"--cost", "track"}, t, error), ParseResult::kOk) << error;
  EXPECT_EQ(t.params.cost_model, keepless::core::CostModel::kTrack);
  EXPECT_EQ(t.params.track_terms, 15);
  ASSERT_EQ(parse({"--cost", "track", "--track-terms", "length,error"}, t, error), ParseResult::kOk) << error;
  EXPECT_EQ(t.params.track_terms, keepless::core::kTrackLength | keepless::core::kTrackError);
  // The paper's cost terms (default all three).
  EXPECT_EQ(t.params.cost_terms, 7);
  ASSERT_EQ(parse({"--cost-terms", "c_s,c_b"}, t, error), ParseResult::kOk) << error;
  EXPECT_EQ(t.params.cost_terms, keepless::core::kSpatialCost | keepless::core::kBaselineCost);
}

TEST(NodeConfig, ParsesTheKeepBudgets) {
  using keepless::core::BudgetKind;
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({}, c, error), ParseResult::kOk);
  EXPECT_EQ(c.params.budget.kind, BudgetKind::kNone);
  ASSERT_EQ(parse({"--keep-fraction", "0.3"}, c, error), ParseResult::kOk) << error;
  EXPECT_EQ(c.params.budget.kind, BudgetKind::kFraction);
  EXPECT_EQ(c.params.budget.fraction, 0.3);
  NodeConfig p;
  ASSERT_EQ(parse({"--keep-points=250"}, p, error), ParseResult::kOk) << error;
  EXPECT_EQ(p.params.budget.kind, BudgetKind::kPoints);
  EXPECT_EQ(p.params.budget.count, 250u);
  NodeConfig o;
  ASSERT_EQ(parse({"--keep-observations", "4000"}, o, error), ParseResult::kOk) << error;
  EXPECT_EQ(o.params.budget.kind, BudgetKind::kObservations);
  EXPECT_EQ(o.params.budget.count, 4000u);
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--keep-fraction", "1.2"}, {"--keep-fraction", "nan"},
        {"--keep-points", "-3"}, {"--keep-observations", "x"},
        {"--M", "10", "--keep-points", "5"}, {"--keep-fraction", "0.2", "--M", "10"},
        {"--keep-points", "5", "--keep-observations", "9"}}) {
    NodeConfig d;
    EXPECT_EQ(parse(bad, d, error), ParseResult::kError) << bad[0] << " " << bad[1];
    EXPECT_FALSE(error.empty());
  }
  NodeConfig d;
  ASSERT_EQ(parse({"--M", "10", "--keep-points", "5"}, d, error), ParseResult::kError);
  EXPECT_NE(error.find("exclude each other"), std::string::npos) << error;
}

TEST(NodeConfig, ParsesTheTrackShareOfACountBudget) {
  using keepless::core::BudgetKind;
  std::string error;
  NodeConfig c;
  ASSERT_EQ(parse({}, c, error), ParseResult::kOk);
  EXPECT_EQ(c.params.budget.track_share, 0.0);
  // Before or after its budget: the share ends on the budget.
  for (const std::vector<std::string>& flags :
       {std::vector<std::string>{"--track-share", "0.5", "--keep-fraction", "0.2"},
        {"--keep-fraction", "0.2", "--track-share=0.5"}}) {
    NodeConfig f;
    ASSERT_EQ(parse(flags, f, error), ParseResult::kOk) << error;
    EXPECT_EQ(f.params.budget.kind, BudgetKind::kFraction);
    EXPECT_EQ(f.params.budget.track_share, 0.5);
    EXPECT_EQ(keepless::core::Sparsifier::validate(f.params), keepless::core::Status::kOk);
  }
  NodeConfig p;
  ASSERT_EQ(parse({"--keep-points", "300", "--track-share", "1"}, p, error), ParseResult::kOk) << error;
  EXPECT_EQ(p.params.budget.track_share, 1.0);
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--keep-fraction", "0.2", "--track-share", "1.5"},
        {"--keep-fraction", "0.2", "--track-share", "-0.1"}, {"--keep-fraction", "0.2", "--track-share", "nan"},
        {"--keep-points", "5", "--track-share", "x"}}) {
    NodeConfig d;
    EXPECT_EQ(parse(bad, d, error), ParseResult::kError) << bad[2] << " " << bad[3];
    EXPECT_FALSE(error.empty());
  }
  // A share of a count: not of an observation budget, nor without a budget.
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--track-share", "0.5"}, {"--keep-observations", "900", "--track-share", "0.5"},
        {"--M", "50", "--track-share", "0.5"}}) {
    NodeConfig d;
    ASSERT_EQ(parse(bad, d, error), ParseResult::kError) << bad[0];
    EXPECT_NE(error.find("--track-share needs --keep-points or --keep-fraction"), std::string::npos) << error;
  }
}

// --use sets the policy flags of its use before the other flags, wherever it
// stands, so they refine it; the paper's is the default.
TEST(NodeConfig, ParsesTheUses) {
  using keepless::core::Scope;
  std::string error;
  NodeConfig defaults;
  ASSERT_EQ(parse({}, defaults, error), ParseResult::kOk);
  NodeConfig paper;
  ASSERT_EQ(parse({"--maturity", "3", "--use", "paper"}, paper, error), ParseResult::kOk) << error;
  EXPECT_EQ(paper.params.maturity_keyframes, 3u);  // the flag refines the use
  EXPECT_EQ(paper.params.scope, defaults.params.scope);
  for (const std::vector<std::string>& flags :
       {std::vector<std::string>{"--use", "monocular", "--keep-fraction", "0.2"},
        {"--keep-fraction", "0.2", "--use=monocular"}}) {
    NodeConfig m;
    ASSERT_EQ(parse(flags, m, error), ParseResult::kOk) << error;
    EXPECT_EQ(m.params.scope, Scope::kNewest);
    EXPECT_EQ(m.params.maturity_keyframes, 2u);
    EXPECT_EQ(m.params.defer_keyframes, 0u);
    EXPECT_EQ(m.params.budget.fraction, 0.2);
    EXPECT_EQ(m.params.budget.track_share, 0.5);  // from F = 0.3 on
    EXPECT_EQ(m.params.budget.track_share_from, 0.3);
  }
  // Monocular's share needs no count (without one it never applies); a given one applies at every budget.
  NodeConfig by_m;
  ASSERT_EQ(parse({"--use", "monocular", "--M", "50"}, by_m, error), ParseResult::kOk) << error;
  EXPECT_EQ(keepless::core::Sparsifier::validate(by_m.params), keepless::core::Status::kOk);
  NodeConfig given;
  ASSERT_EQ(parse({"--track-share", "0.5", "--use", "monocular", "--keep-fraction", "0.2"}, given, error),
            ParseResult::kOk) << error;
  EXPECT_EQ(given.params.budget.track_share, 0.5);
  EXPECT_EQ(given.params.budget.track_share_from, 0.0);
  EXPECT_EQ(given.params.budget.track_share_to, 1.0);
  NodeConfig off;
  ASSERT_EQ(parse({"--use", "monocular", "--keep-fraction", "0.4", "--track-share", "0"}, off, error), ParseResult::kOk);
  EXPECT_EQ(off.params.budget.track_share, 0.0);
  NodeConfig refined;
  ASSERT_EQ(parse({"--scope", "window", "--use", "monocular", "--maturity", "1"}, refined, error), ParseResult::kOk);
  EXPECT_EQ(refined.params.scope, Scope::kWindow);
  EXPECT_EQ(refined.params.maturity_keyframes, 1u);
  NodeConfig deferred;
  ASSERT_EQ(parse({"--use", "monocular-deferred"}, deferred, error), ParseResult::kOk) << error;
  EXPECT_EQ(deferred.params.defer_keyframes, 2u);
  EXPECT_EQ(deferred.params.scope, Scope::kAuto);
  EXPECT_EQ(deferred.params.budget.track_share, 0.5);  // up to F = 0.15, which needs no count
  EXPECT_EQ(deferred.params.budget.track_share_to, 0.15);
  NodeConfig deferred_given;  // a given share applies at every budget
  ASSERT_EQ(parse({"--use", "monocular-deferred", "--keep-fraction", "0.2", "--track-share", "0.25"}, deferred_given,
                  error), ParseResult::kOk) << error;
  EXPECT_EQ(deferred_given.params.budget.track_share, 0.25);
  EXPECT_EQ(deferred_given.params.budget.track_share_to, 1.0);
  NodeConfig rgbd;
  ASSERT_EQ(parse({"--use", "rgbd"}, rgbd, error), ParseResult::kOk) << error;
  EXPECT_EQ(rgbd.params.scope, Scope::kNewest);  // the monocular use's settings
  EXPECT_EQ(rgbd.params.maturity_keyframes, 2u);
  EXPECT_EQ(rgbd.params.defer_keyframes, 0u);
  EXPECT_EQ(rgbd.params.budget.track_share, 0.0);
  // --profile and --use together, each applied first.
  NodeConfig both;
  ASSERT_EQ(parse({"--use", "offline", "--profile", "small", "--keep-points", "300"}, both, error),
            ParseResult::kOk) << error;
  EXPECT_EQ(both.params.budget.track_share, 1.0);
  EXPECT_EQ(both.window, 10u);
  NodeConfig share;
  ASSERT_EQ(parse({"--track-share", "0.5", "--use", "offline", "--keep-points", "300"}, share, error), ParseResult::kOk);
  EXPECT_EQ(share.params.budget.track_share, 0.5);
  // Offline's share is of a count.
  NodeConfig no_count;
  ASSERT_EQ(parse({"--use", "offline"}, no_count, error), ParseResult::kError);
  EXPECT_NE(error.find("--use offline sets it to 1"), std::string::npos) << error;
  // A share given without a count is refused for itself, whatever the use: the
  // note on offline's share would point at a use not given.
  for (const char* use : {"monocular", "rgbd", "paper"}) {
    NodeConfig given;
    ASSERT_EQ(parse({"--use", use, "--track-share", "0.5"}, given, error), ParseResult::kError) << use;
    EXPECT_NE(error.find("--track-share needs --keep-points or --keep-fraction"), std::string::npos) << error;
    EXPECT_EQ(error.find("offline"), std::string::npos) << use << ": " << error;
  }
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--use", "mono"}, {"--use"}, {"--use="}, {"--use", ""}}) {
    NodeConfig d;
    EXPECT_EQ(parse(bad, d, error), ParseResult::kError) << bad[0];
    EXPECT_FALSE(error.empty());
  }
}

TEST(NodeConfig, ParsesTheMaturityGuard) {
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({}, c, error), ParseResult::kOk);
  EXPECT_EQ(c.params.maturity_keyframes, 0u);  // off by default
  ASSERT_EQ(parse({"--maturity", "2"}, c, error), ParseResult::kOk) << error;
  EXPECT_EQ(c.params.maturity_keyframes, 2u);
  for (const char* bad : {"-1", "x", "4294967296"}) {
    NodeConfig d;
    EXPECT_EQ(parse({"--maturity", bad}, d, error), ParseResult::kError) << bad;
  }
}

TEST(NodeConfig, ParsesTrackedFirst) {
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({}, c, error), ParseResult::kOk);
  EXPECT_FALSE(c.params.tracked_first);  // off by default
  ASSERT_EQ(parse({"--tracked-first", "--keep-fraction", "0.2"}, c, error), ParseResult::kOk) << error;
  EXPECT_TRUE(c.params.tracked_first);
  NodeConfig d;
  EXPECT_EQ(parse({"--tracked-first"}, d, error), ParseResult::kError);
  EXPECT_NE(error.find("--tracked-first needs a keep budget"), std::string::npos) << error;
}

// Review: a switch's inline value was dropped, so --tracked-first=0 turned it on.
TEST(NodeConfig, ASwitchRefusesAValue) {
  for (const char* arg : {"--tracked-first=0", "--mlock=false", "--quiet=off", "--tracked-first="}) {
    NodeConfig c;
    std::string error;
    EXPECT_EQ(parse({arg, "--keep-fraction", "0.2"}, c, error), ParseResult::kError) << arg;
    EXPECT_NE(error.find("takes no value"), std::string::npos) << arg << ": " << error;
    EXPECT_FALSE(c.params.tracked_first || c.mlock || c.quiet) << arg;
  }
}

// strtoull skips leading blanks and negates a '-' after them: " -1" was
// accepted as 2^64 - 1 where a bound did not catch it (--max-keyframes,
// --budget-work), " 5" as 5.
TEST(NodeConfig, AnIntegerWithBlanksOrASignIsRefused) {
  std::string error;
  for (const char* flag : {"--max-keyframes", "--budget-work", "--window", "--max-sequence-jump"}) {
    for (const char* bad : {" -1", " 5", "\t5", "+5", "-1"}) {
      NodeConfig c;
      EXPECT_EQ(parse({flag, bad}, c, error), ParseResult::kError) << flag << " '" << bad << "'";
    }
  }
}

// strtod takes leading blanks and hex floats: "0x1p-2" was --theta 0.25.
TEST(NodeConfig, ANumberIsPlainDecimal) {
  std::string error;
  for (const char* flag : {"--theta", "--keep-fraction", "--latency-target-ms"}) {
    NodeConfig ok;
    EXPECT_EQ(parse({flag, "0.25"}, ok, error), ParseResult::kOk) << flag << ": " << error;
    for (const char* bad : {"0x1p-2", " 0.25", "\t0.25", "0.25 ", "nan"}) {
      NodeConfig c;
      EXPECT_EQ(parse({flag, bad}, c, error), ParseResult::kError) << flag << " '" << bad << "'";
    }
  }
}

TEST(NodeConfig, ParsesDeferredCulling) {
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({}, c, error), ParseResult::kOk);
  EXPECT_EQ(c.params.defer_keyframes, 0u);  // off by default
  EXPECT_EQ(c.defer_memory, 0u);
  ASSERT_EQ(parse({"--defer", "3", "--defer-memory", "900"}, c, error), ParseResult::kOk) << error;
  EXPECT_EQ(c.params.defer_keyframes, 3u);
  EXPECT_EQ(c.defer_memory, 900u);
  for (const char* bad : {"-1", "x", "2000000000"}) {
    NodeConfig d;
    EXPECT_EQ(parse({"--defer", bad}, d, error), ParseResult::kError) << bad;
    EXPECT_EQ(parse({"--defer-memory", bad}, d, error), ParseResult::kError) << bad;
  }
}

// A flag that would change nothing is refused: --defer-memory without
// deferred culling, --track-terms without the track cost (both were taken
// and ignored).
TEST(NodeConfig, FlagsThatWouldChangeNothingAreRefused) {
  std::string error;
  NodeConfig c;
  EXPECT_EQ(parse({"--defer-memory", "900"}, c, error), ParseResult::kError);
  EXPECT_NE(error.find("--defer-memory needs --defer"), std::string::npos) << error;
  EXPECT_EQ(parse({"--track-terms", "length"}, c, error), ParseResult::kError);
  EXPECT_NE(error.find("--track-terms needs --cost track"), std::string::npos) << error;
  NodeConfig d;
  EXPECT_EQ(parse({"--use", "monocular-deferred", "--defer-memory", "900"}, d, error), ParseResult::kOk) << error;
  EXPECT_EQ(parse({"--defer-memory", "0"}, d, error), ParseResult::kOk) << error;
}

// A malformed --cpus list exits 2 at parse; it was taken, reported at start
// ("could not pin ... malformed CPU list") and the node ran unpinned.
TEST(NodeConfig, AMalformedCpuListIsRefused) {
  std::string error;
  for (const char* bad : {"", "abc", "-5", "0,", "3-1", "0.1", "1024"}) {
    NodeConfig c;
    EXPECT_EQ(parse({"--cpus", bad}, c, error), ParseResult::kError) << "'" << bad << "'";
  }
  NodeConfig c;
  ASSERT_EQ(parse({"--cpus", "0-1,3"}, c, error), ParseResult::kOk) << error;
  EXPECT_EQ(c.cpus, "0-1,3");
}

TEST(NodeConfig, ParsesTheReliabilityFlags) {
  NodeConfig c;
  std::string error;
  ASSERT_EQ(parse({"--event-ack-channel", "ACK", "--max-memory-mb", "64", "--max-sequence-jump", "50",
                   "--max-utime-jump-s", "2.5", "--restart-confirm", "5", "--owner-timeout-s", "0.25",
                   "--cull-memory", "100"},
                  c, error),
            ParseResult::kOk)
      << error;
  EXPECT_EQ(c.event_ack_channel, "ACK");
  EXPECT_EQ(c.max_memory_mb, 64u);
  const keepless::platform::OrderBounds b = keepless::platform::order_bounds(c);
  EXPECT_EQ(b.max_sequence_jump, 50u);
  EXPECT_EQ(b.max_utime_jump_us, 2500000u);
  EXPECT_EQ(b.restart_confirm, 5u);
  EXPECT_EQ(b.owner_timeout_ns, 250000000u);
  EXPECT_EQ(c.cull_memory, 100u);
  for (const auto& bad : std::vector<std::vector<std::string>>{{"--restart-confirm", "1"},
                                                               {"--max-sequence-jump", "0"},
                                                               {"--max-utime-jump-s", "-1"},
                                                               {"--owner-timeout-s", "-1"},
                                                               {"--owner-timeout-s", "1e-10"},  // would read as 0: never
                                                               {"--max-publishers", "4"},  // removed: one owner
                                                               {"--max-memory-mb", "0"}}) {
    NodeConfig d;
    EXPECT_EQ(parse(bad, d, error), ParseResult::kError) << bad[0] << " " << bad[1];
  }
}

// The estimate keepless_node checks against --max-memory-mb before
// allocating is the node's own figure, within a few percent.
TEST(NodeConfig, MemoryEstimateMatchesTheNode) {
  for (const auto& [window, obs] : std::vector<std::pair<std::uint32_t, std::uint32_t>>{{8, 256}, {10, 500}, {20, 2000}}) {
    NodeConfig c;
    c.url = "memq://";
    c.window = window;
    c.max_observations = obs;
    lcm::LCM bus("memq://");
    const keepless::platform::Node node(bus, c);
    const double actual = static_cast<double>(node.memory_bytes());
    const double estimate = keepless::platform::estimate_node_bytes(c);
    EXPECT_NEAR(estimate / actual, 1.0, 0.05) << "window " << window << " obs " << obs << ": " << estimate
                                                << " estimated, " << actual << " actual";
  }
  // Deferred culling adds its memory of excluded points and the decision's
  // two lists: the estimate follows, and the node reports it.
  for (const std::uint32_t memory : {0u, 20000u}) {
    NodeConfig c;
    c.url = "memq://";
    lcm::LCM bus("memq://");
    const double off = static_cast<double>(keepless::platform::Node(bus, c).memory_bytes());
    c.params.defer_keyframes = 2;
    c.defer_memory = memory;
    const double on = static_cast<double>(keepless::platform::Node(bus, c).memory_bytes());
    EXPECT_GT(on, off);
    EXPECT_NEAR(keepless::platform::estimate_node_bytes(c) / on, 1.0, 0.05) << "defer memory " << memory;
  }
  // Issue 15, defect 6: passed flag validation, then aborted in bad_alloc.
  NodeConfig huge;
  huge.window = 256;
  huge.max_observations = 4096;
  huge.max_points = huge.max_window_observations = huge.max_pair_arcs = 0;  // the worst case of K full keyframes
  EXPECT_GT(keepless::platform::estimate_node_bytes(huge), 1024.0 * 1048576.0);
}

}  // namespace
