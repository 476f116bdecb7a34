#include "run_record.hpp"

#include <cstdio>
#include <sstream>
#include <tuple>
#include <utility>

namespace keepless::eval {
namespace {

double pct(double a, double b) { return b > 0 ? 100.0 * a / b : NAN; }

template <typename F>
Stat stat_over(const std::vector<RunRecord>& v, F f) {
  std::vector<double> x;
  for (const RunRecord& r : v) x.push_back(f(r));
  return stat_of(x);
}

// Per seed on which the original ran without failure: f(variant record, original record).
// Every comparison with the original goes through here: a lost original's ATE is that of its
// few tracked frames held still, its map and BA those of a few frames, and would make every
// method look better than the original.
// The record of `seed` in v, or null: runs are paired by seed, never by
// position (--report may merge directories holding different seeds).
const RunRecord* of_seed(const std::vector<RunRecord>& v, std::uint64_t seed) {
  for (const RunRecord& r : v)
    if (r.seed == seed) return &r;
  return nullptr;
}

template <typename F>
Stat paired(const std::vector<RunRecord>& v, const std::vector<RunRecord>& original, F f) {
  std::vector<double> x;
  for (const RunRecord& a : v)
    if (const RunRecord* o = of_seed(original, a.seed); o && !o->failed()) x.push_back(f(a, *o));
  return stat_of(x);
}

// Seeds on which a's ATE is below b's; with the original as `reference`, only those it did not fail.
int count_below(const std::vector<RunRecord>& a, const std::vector<RunRecord>& b,
                const std::vector<RunRecord>* reference = nullptr) {
  int n = 0;
  for (const RunRecord& x : a) {
    const RunRecord* y = of_seed(b, x.seed);
    const RunRecord* o = reference ? of_seed(*reference, x.seed) : nullptr;
    if (y && (!reference || (o && !o->failed()))) n += x.ate_m < y->ate_m ? 1 : 0;
  }
  return n;
}

// a's ATE minus b's, seed by seed.
Stat ate_differences(const std::vector<RunRecord>& a, const std::vector<RunRecord>& b) {
  std::vector<double> d;
  for (const RunRecord& x : a)
    if (const RunRecord* y = of_seed(b, x.seed)) d.push_back(x.ate_m - y->ate_m);
  return stat_of(d);
}

// Mean ATE of v and of the original over the same (paired) seeds.
std::pair<double, double> paired_ate(const std::vector<RunRecord>& v, const std::vector<RunRecord>& original) {
  return {paired(v, original, [](const RunRecord& a, const RunRecord&) { return a.ate_m; }).mean,
          paired(v, original, [](const RunRecord&, const RunRecord& o) { return o.ate_m; }).mean};
}
double ratio_to_original(const std::vector<RunRecord>& v, const std::vector<RunRecord>& original) {
  const auto [a, o] = paired_ate(v, original);
  return o > 0 ? a / o : NAN;
}

void field(std::ostringstream& o, const char* key, const std::string& value) { o << ",\"" << key << "\":" << value; }
void stat_fields(std::ostringstream& o, const char* key, const char* sd_key, const Stat& s, int precision = 6) {
  field(o, key, json_number(s.mean, precision));
  field(o, sd_key, json_number(s.sd, precision));
}

}  // namespace

Stat stat_of(const std::vector<double>& v) {
  Stat s;
  s.n = static_cast<int>(v.size());
  if (v.empty()) return s;
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / double(v.size());
  double ss = 0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.sd = v.size() > 1 ? std::sqrt(ss / double(v.size() - 1)) : 0.0;
  return s;
}

ContractRun summarize(const Comparison& c) {
  ContractRun r;
  r.info = c.info;
  r.variant = c.variant;
  r.seeds = static_cast<int>(c.ours.size());
  r.M = c.M;
  r.target_fraction = c.target_fraction;
  const auto& g = c.original;
  r.mp_percent = paired(c.ours, g, [](const RunRecord& a, const RunRecord& o) { return pct(double(a.mps), double(o.mps)); });
  r.kf_percent = paired(c.ours, g, [](const RunRecord& a, const RunRecord& o) { return pct(double(a.kfs), double(o.kfs)); });
  // The local BAs' thread CPU time where both runs measured it (the wall clock moves with the machine's load).
  r.ba_time_percent = paired(c.ours, g, [](const RunRecord& a, const RunRecord& o) {
    return std::isfinite(a.ba_cpu_s) && std::isfinite(o.ba_cpu_s) && o.ba_cpu_s > 0 ? pct(a.ba_cpu_s, o.ba_cpu_s)
                                                                                   : pct(a.ba_s, o.ba_s);
  });
  auto mp_of = [&](const std::vector<RunRecord>& v) {
    return paired(v, g, [](const RunRecord& a, const RunRecord& o) { return pct(double(a.mps), double(o.mps)); });
  };
  auto kf_of = [&](const std::vector<RunRecord>& v) {
    return paired(v, g, [](const RunRecord& a, const RunRecord& o) { return pct(double(a.kfs), double(o.kfs)); });
  };
  r.mp_percent_random = mp_of(c.random);
  r.mp_percent_longest_track = mp_of(c.longest_track);
  r.mp_percent_anms = mp_of(c.anms);
  r.kf_percent_random = kf_of(c.random);
  r.kf_percent_longest_track = kf_of(c.longest_track);
  r.kf_percent_anms = kf_of(c.anms);
  auto ate = [](const RunRecord& a) { return a.ate_m; };
  r.ate_original = stat_over(g, ate);
  r.ate_ours = stat_over(c.ours, ate);
  r.ate_random = stat_over(c.random, ate);
  r.ate_longest_track = stat_over(c.longest_track, ate);
  r.ate_anms = stat_over(c.anms, ate);
  r.ate_r_original = stat_over(g, [](const RunRecord& a) { return a.ate_r_deg; });
  r.ate_r_ours = stat_over(c.ours, [](const RunRecord& a) { return a.ate_r_deg; });
  r.ratio_seeds = paired(c.ours, g, [](const RunRecord&, const RunRecord&) { return 0.0; }).n;
  r.better_seeds = count_below(c.ours, g, &g);
  r.worse_seeds = count_below(g, c.ours, &g);
  r.below_random_seeds = count_below(c.ours, c.random);
  r.below_longest_track_seeds = count_below(c.ours, c.longest_track);
  r.below_anms_seeds = count_below(c.ours, c.anms);
  r.ate_diff_random = ate_differences(c.ours, c.random);
  r.ate_diff_longest_track = ate_differences(c.ours, c.longest_track);
  r.ate_diff_anms = ate_differences(c.ours, c.anms);
  const auto [an, ao] = paired_ate(c.ours, g);
  r.ate_ratio = ao > 0 ? an / ao : NAN;
  r.ate_ratio_random = ratio_to_original(c.random, g);
  r.ate_ratio_longest_track = ratio_to_original(c.longest_track, g);
  r.ate_ratio_anms = ratio_to_original(c.anms, g);
  auto sqrt_obs = [&](const std::vector<RunRecord>& v) {  // sqrt(mean original observations / mean v's)
    const double n = paired(v, g, [](const RunRecord& a, const RunRecord&) { return double(a.observations); }).mean;
    const double o = paired(v, g, [](const RunRecord&, const RunRecord& o) { return double(o.observations); }).mean;
    return n > 0 ? std::sqrt(o / n) : NAN;
  };
  r.sqrt_obs_ratio = sqrt_obs(c.ours);
  r.sqrt_obs_ratio_random = sqrt_obs(c.random);
  r.sqrt_obs_ratio_longest_track = sqrt_obs(c.longest_track);
  r.sqrt_obs_ratio_anms = sqrt_obs(c.anms);
  const double f2 = c.info.error_floor_m * c.info.error_floor_m;
  if (c.info.error_floor_m > 0) r.ate_ratio_floored = std::sqrt(an * an + f2) / std::sqrt(ao * ao + f2);
  auto failures = [](const std::vector<RunRecord>& v) {
    int n = 0;
    for (const RunRecord& x : v) n += x.failed() ? 1 : 0;
    return n;
  };
  r.failed = {failures(g), failures(c.ours), failures(c.random), failures(c.longest_track), failures(c.anms)};
  r.frames = g.empty() ? 0 : g.front().frames;
  auto tracked = [](const RunRecord& a) { return double(a.frames_tracked); };
  r.frames_tracked = stat_over(c.ours, tracked);
  r.frames_tracked_original = stat_over(g, tracked);
  r.frames_tracked_random = stat_over(c.random, tracked);
  r.frames_tracked_longest_track = stat_over(c.longest_track, tracked);
  r.frames_tracked_anms = stat_over(c.anms, tracked);
  r.floor_keyframes = stat_over(c.ours, [](const RunRecord& a) { return double(a.selector.floor_keyframes); });
  r.floor_promoted = stat_over(c.ours, [](const RunRecord& a) { return double(a.selector.floor_promoted); });
  r.floor_short = stat_over(c.ours, [](const RunRecord& a) { return double(a.selector.floor_short); });
  r.windows = stat_over(c.ours, [](const RunRecord& a) { return double(a.selector.windows); }).mean;
  return r;
}

std::string json_number(double v, int precision) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", precision, v);
  return buf;
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    o += c;
  }
  return o + "\"";
}

std::string run_json(const ContractRun& r) {
  std::ostringstream o;
  o << "{\"input\":" << json_string(r.info.input);
  field(o, "name", json_string(r.info.name));
  field(o, "group", json_string(r.info.group));
  field(o, "kind", json_string(r.info.kind));
  field(o, "variant", json_string(r.variant));
  field(o, "alignment", json_string(r.info.sim3 ? "sim3" : "se3"));
  field(o, "seeds", std::to_string(r.seeds));
  field(o, "M", std::to_string(r.M));
  field(o, "target_fraction", json_number(r.target_fraction, 4));
  stat_fields(o, "mp_percent", "mp_percent_sd", r.mp_percent, 3);
  stat_fields(o, "kf_percent", "kf_percent_sd", r.kf_percent, 3);
  stat_fields(o, "ba_time_percent", "ba_time_percent_sd", r.ba_time_percent, 3);
  stat_fields(o, "ate_original_m", "ate_original_sd_m", r.ate_original);
  stat_fields(o, "ate_ours_m", "ate_ours_sd_m", r.ate_ours);
  stat_fields(o, "ate_random_m", "ate_random_sd_m", r.ate_random);
  stat_fields(o, "ate_longest_track_m", "ate_longest_track_sd_m", r.ate_longest_track);
  stat_fields(o, "ate_anms_m", "ate_anms_sd_m", r.ate_anms);
  field(o, "ate_r_original_deg", json_number(r.ate_r_original.mean));
  field(o, "ate_r_ours_deg", json_number(r.ate_r_ours.mean));
  field(o, "mp_percent_random", json_number(r.mp_percent_random.mean, 3));
  field(o, "mp_percent_longest_track", json_number(r.mp_percent_longest_track.mean, 3));
  field(o, "mp_percent_anms", json_number(r.mp_percent_anms.mean, 3));
  field(o, "kf_percent_random", json_number(r.kf_percent_random.mean, 3));
  field(o, "kf_percent_longest_track", json_number(r.kf_percent_longest_track.mean, 3));
  field(o, "kf_percent_anms", json_number(r.kf_percent_anms.mean, 3));
  field(o, "better_seeds", std::to_string(r.better_seeds));
  field(o, "worse_seeds", std::to_string(r.worse_seeds));
  field(o, "below_random_seeds", std::to_string(r.below_random_seeds));
  field(o, "below_longest_track_seeds", std::to_string(r.below_longest_track_seeds));
  field(o, "below_anms_seeds", std::to_string(r.below_anms_seeds));
  for (auto [key, se_key, d] : {std::tuple{"ate_diff_random_m", "ate_diff_random_se_m", &r.ate_diff_random},
                                std::tuple{"ate_diff_longest_track_m", "ate_diff_longest_track_se_m", &r.ate_diff_longest_track},
                                std::tuple{"ate_diff_anms_m", "ate_diff_anms_se_m", &r.ate_diff_anms}}) {
    field(o, key, json_number(d->mean));
    field(o, se_key, json_number(d->se()));
  }
  field(o, "ate_ratio", json_number(r.ate_ratio, 4));
  field(o, "ate_ratio_random", json_number(r.ate_ratio_random, 4));
  field(o, "ate_ratio_longest_track", json_number(r.ate_ratio_longest_track, 4));
  field(o, "ate_ratio_anms", json_number(r.ate_ratio_anms, 4));
  field(o, "ratio_seeds", std::to_string(r.ratio_seeds));
  field(o, "sqrt_obs_ratio", json_number(r.sqrt_obs_ratio, 4));
  field(o, "sqrt_obs_ratio_random", json_number(r.sqrt_obs_ratio_random, 4));
  field(o, "sqrt_obs_ratio_longest_track", json_number(r.sqrt_obs_ratio_longest_track, 4));
  field(o, "sqrt_obs_ratio_anms", json_number(r.sqrt_obs_ratio_anms, 4));
  field(o, "error_floor_m", json_number(r.info.error_floor_m, 4));
  field(o, "ate_ratio_floored", json_number(r.ate_ratio_floored, 4));
  field(o, "windows", json_number(r.windows, 1));
  field(o, "floor_keyframes", json_number(r.floor_keyframes.mean, 1));
  field(o, "floor_promoted", json_number(r.floor_promoted.mean, 1));
  field(o, "floor_short", json_number(r.floor_short.mean, 1));
  o << ",\"failed_seeds\":{\"original\":" << r.failed.original << ",\"ours\":" << r.failed.ours
    << ",\"random\":" << r.failed.random << ",\"longest_track\":" << r.failed.longest_track
    << ",\"anms\":" << r.failed.anms << "}";
  field(o, "frames", std::to_string(r.frames));
  field(o, "frames_tracked", r.frames > 0 ? json_number(r.frames_tracked.mean, 2) : "0");
  if (r.frames > 0) {
    field(o, "frames_tracked_original", json_number(r.frames_tracked_original.mean, 2));
    field(o, "frames_tracked_random", json_number(r.frames_tracked_random.mean, 2));
    field(o, "frames_tracked_longest_track", json_number(r.frames_tracked_longest_track.mean, 2));
    field(o, "frames_tracked_anms", json_number(r.frames_tracked_anms.mean, 2));
  }
  o << "}";
  return o.str();
}

std::string contract_json(const std::vector<ContractRun>& runs, const std::string& extra) {
  std::string o = "{\"runs\":[";
  for (std::size_t i = 0; i < runs.size(); ++i) o += (i ? "," : "") + run_json(runs[i]);
  return o + "]" + extra + "}";
}

}  // namespace keepless::eval
