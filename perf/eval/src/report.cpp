#include "report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

namespace keepless::eval {
namespace {

constexpr const char* kCsvHeader =
    "input,name,group,kind,alignment,variant,seed,M,target_fraction,compared_M,mps,kfs,observations,ba_s,total_s,"
    "ate_m,ate_r_deg,C,F,S,frames,frames_tracked,windows,floor_keyframes,floor_promoted,floor_short,ba_cpu_s,"
    "diverged,failed,refine_cpu_s";

std::string f(double v, int prec) {
  if (!std::isfinite(v)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", prec, v);
  return buf;
}
// mean ± sd, with significant digits suited to the magnitude.
std::string pm(const Stat& s, int prec) {
  if (s.n == 0 || !std::isfinite(s.mean)) return "–";
  return f(s.mean, prec) + " ± " + f(s.sd, prec);
}
int ate_digits(double v) { return v >= 1 ? 3 : v >= 0.1 ? 4 : v >= 0.01 ? 5 : 6; }
std::string ate_pm(const Stat& s) { return pm(s, ate_digits(s.mean)); }
std::string bold_if(bool b, const std::string& s) { return b ? "**" + s + "**" : s; }
// A mean that includes failed runs says so beside it.
std::string with_failed(const std::string& cell, int failed) {
  return failed > 0 ? cell + " (" + std::to_string(failed) + " failed)" : cell;
}
std::string op_label(const ContractRun& r) {
  return std::isfinite(r.target_fraction) ? "F = " + f(r.target_fraction, 2) : "M = " + std::to_string(r.M);
}
// A selector whose seeds gave the same ATE (to 1e-4 of it: BAL's keepless and
// longest-track-first, the image tracks' keepless): its seeds repeat one run,
// so a comparison between two such selectors is one comparison, not one per seed.
bool repeated(const Stat& s) { return s.n > 1 && s.sd <= 1e-4 * std::fabs(s.mean); }

// A ratio to the original over fewer seeds than the run's (the original failed on the others) says so.
std::string over_ratio_seeds(const std::string& cell, const ContractRun& r) {
  return r.ratio_seeds < r.seeds ? cell + " (" + std::to_string(r.ratio_seeds) + " seeds)" : cell;
}

// The four trajectory groups of the paper's Table V (ours: TUM, EuRoC MH,
// EuRoC V, KITTI), each the mean over its inputs of ATE / original ATE.
struct GroupRow {
  std::string group;
  int inputs = 0;
  double mp = 0, kf = 0, ba = 0;
  double ours = 0, random = 0, longest = 0, anms = 0;                  // ATE / original
  double sq_ours = 0, sq_random = 0, sq_longest = 0, sq_anms = 0;      // sqrt(obs ratio)
};

std::vector<GroupRow> group_rows(const std::vector<ContractRun>& runs, const std::string& label) {
  std::vector<GroupRow> rows;
  for (const ContractRun& r : runs) {
    if (r.info.kind != "trajectory" || op_label(r) != label) continue;
    auto it = std::find_if(rows.begin(), rows.end(), [&](const GroupRow& g) { return g.group == r.info.group; });
    if (it == rows.end()) {
      rows.push_back(GroupRow{r.info.group});
      it = rows.end() - 1;
    }
    ++it->inputs;
    it->mp += r.mp_percent.mean;
    it->kf += r.kf_percent.mean;
    it->ba += r.ba_time_percent.mean;
    it->ours += r.ate_ratio;
    it->random += r.ate_ratio_random;
    it->longest += r.ate_ratio_longest_track;
    it->anms += r.ate_ratio_anms;
    it->sq_ours += r.sqrt_obs_ratio;
    it->sq_random += r.sqrt_obs_ratio_random;
    it->sq_longest += r.sqrt_obs_ratio_longest_track;
    it->sq_anms += r.sqrt_obs_ratio_anms;
  }
  for (GroupRow& g : rows)
    for (double* v : {&g.mp, &g.kf, &g.ba, &g.ours, &g.random, &g.longest, &g.anms, &g.sq_ours, &g.sq_random,
                      &g.sq_longest, &g.sq_anms})
      *v /= g.inputs;
  return rows;
}

std::vector<std::string> labels_of(const std::vector<ContractRun>& runs) {
  std::vector<std::string> out;
  for (const ContractRun& r : runs)
    if (std::find(out.begin(), out.end(), op_label(r)) == out.end()) out.push_back(op_label(r));
  return out;
}

// The cost ablation of one comparison: "all" (ours), then each ablation
// variant, in the order run; every row's records by seed.
std::vector<std::pair<std::string, std::vector<RunRecord>>> ablation_rows(const Comparison& c) {
  std::vector<std::pair<std::string, std::vector<RunRecord>>> rows;
  if (c.ablation.empty()) return rows;
  rows.emplace_back("all", c.ours);
  for (const RunRecord& r : c.ablation) {
    auto it = std::find_if(rows.begin(), rows.end(), [&](const auto& row) { return row.first == r.variant; });
    if (it == rows.end()) rows.emplace_back(r.variant, std::vector<RunRecord>{r});
    else it->second.push_back(r);
  }
  return rows;
}

template <typename F>
Stat stat_by(const std::vector<RunRecord>& v, F fn) {
  std::vector<double> x;
  for (const RunRecord& r : v) x.push_back(fn(r));
  return stat_of(x);
}

// A record's map points as % of the original's of the same seed.
double mp_percent_of(const Comparison& c, const RunRecord& r) {
  for (const RunRecord& g : c.original)
    if (g.seed == r.seed && g.mps > 0) return 100.0 * double(r.mps) / double(g.mps);
  return NAN;
}

// ---- SVG ----
struct Svg {
  std::ostringstream o;
  Svg(int w, int h) {
    o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << w << "\" height=\"" << h
      << "\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  }
  void text(double x, double y, const std::string& t, const char* anchor = "start", int size = 11) {
    o << "<text x=\"" << f(x, 1) << "\" y=\"" << f(y, 1) << "\" text-anchor=\"" << anchor << "\" font-size=\"" << size
      << "\">" << t << "</text>\n";
  }
  void line(double x1, double y1, double x2, double y2, const char* c, double w = 1) {
    o << "<line x1=\"" << f(x1, 1) << "\" y1=\"" << f(y1, 1) << "\" x2=\"" << f(x2, 1) << "\" y2=\"" << f(y2, 1)
      << "\" stroke=\"" << c << "\" stroke-width=\"" << f(w, 1) << "\"/>\n";
  }
  void circle(double x, double y, double r, const char* c) {
    o << "<circle cx=\"" << f(x, 1) << "\" cy=\"" << f(y, 1) << "\" r=\"" << f(r, 1) << "\" fill=\"" << c << "\"/>\n";
  }
  std::string str() { return o.str() + "</svg>\n"; }
};

struct Axes {
  double x0, y0, w, h, xmin, xmax, ymin, ymax;
  double X(double v) const { return x0 + (v - xmin) / (xmax - xmin) * w; }
  double Y(double v) const { return y0 + h - (v - ymin) / (ymax - ymin) * h; }
  void draw(Svg& s, const std::string& xl, const std::string& yl, const std::string& title) const {
    s.line(x0, y0 + h, x0 + w, y0 + h, "black");
    s.line(x0, y0, x0, y0 + h, "black");
    for (int i = 0; i <= 5; ++i) {
      const double xv = xmin + (xmax - xmin) * i / 5, yv = ymin + (ymax - ymin) * i / 5;
      s.line(X(xv), y0 + h, X(xv), y0 + h + 4, "black");
      s.text(X(xv), y0 + h + 16, f(xv, xmax - xmin < 5 ? 2 : 0), "middle");
      s.line(x0 - 4, Y(yv), x0, Y(yv), "black");
      s.line(x0, Y(yv), x0 + w, Y(yv), "#eee");
      s.text(x0 - 6, Y(yv) + 4, f(yv, ymax - ymin < 5 ? 2 : 0), "end");
    }
    s.text(x0 + w / 2, y0 + h + 34, xl, "middle");
    s.o << "<text transform=\"translate(" << f(x0 - 46, 1) << "," << f(y0 + h / 2, 1)
        << ") rotate(-90)\" text-anchor=\"middle\">" << yl << "</text>\n";
    s.text(x0 + w / 2, y0 - 10, title, "middle", 13);
  }
};

std::string svg_ate_vs_kept(const EvalSummary& s) {
  Svg svg(760, 480);
  double ymax = 1.5;
  for (const ContractRun& r : s.runs)
    for (double v : {r.ate_ratio, r.ate_ratio_random, r.ate_ratio_longest_track, r.ate_ratio_anms})
      if (std::isfinite(v)) ymax = std::max(ymax, v);
  ymax = std::min(std::ceil(ymax * 2) / 2, 10.0);
  Axes ax{80, 40, 520, 380, 0, 100, 0, ymax};
  ax.draw(svg, "map points kept (% of original, mean over seeds)", "RMS ATE / original",
          "ATE vs kept points at equal count (each input)");
  svg.line(ax.X(0), ax.Y(1), ax.X(100), ax.Y(1), "#999");
  struct Series { const char* name; const char* colour; double ContractRun::*ratio; Stat ContractRun::*mp; };
  const Series series[] = {{"ours", "#1f77b4", &ContractRun::ate_ratio, &ContractRun::mp_percent},
                           {"random", "#7f7f7f", &ContractRun::ate_ratio_random, &ContractRun::mp_percent_random},
                           {"longest track", "#2ca02c", &ContractRun::ate_ratio_longest_track, &ContractRun::mp_percent_longest_track},
                           {"ANMS (SSC)", "#d62728", &ContractRun::ate_ratio_anms, &ContractRun::mp_percent_anms}};
  double ly = 60;
  for (const Series& se : series) {
    for (const ContractRun& r : s.runs) {
      const double y = r.*se.ratio, x = (r.*se.mp).mean;
      if (std::isfinite(x) && std::isfinite(y)) svg.circle(ax.X(std::min(100.0, x)), ax.Y(std::min(ymax, y)), 4, se.colour);
    }
    svg.circle(620, ly, 4, se.colour);
    svg.text(630, ly + 4, se.name);
    ly += 20;
  }
  return svg.str();
}


// ---- Budget sweep: per input, every kept fraction, every method ----
struct SweepPoint {
  double fraction = NAN;
  Stat ate, observations, ba_cpu_s, mps, kfs, tracked;
  int failed = 0, seeds = 0;
};
struct SweepSeries {
  std::string method;
  std::vector<SweepPoint> points;  // by ascending fraction
};

SweepPoint sweep_point(double fraction, const std::vector<RunRecord>& v) {
  SweepPoint p;
  p.fraction = fraction;
  p.seeds = static_cast<int>(v.size());
  p.ate = stat_by(v, [](const RunRecord& r) { return r.ate_m; });
  p.observations = stat_by(v, [](const RunRecord& r) { return double(r.observations); });
  p.ba_cpu_s = stat_by(v, [](const RunRecord& r) { return r.ba_cpu_s; });
  p.mps = stat_by(v, [](const RunRecord& r) { return double(r.mps); });
  p.kfs = stat_by(v, [](const RunRecord& r) { return double(r.kfs); });
  p.tracked = stat_by(v, [](const RunRecord& r) { return double(r.frames_tracked); });
  for (const RunRecord& r : v) p.failed += r.failed() ? 1 : 0;
  return p;
}

// The inputs run at two or more kept fractions, in the order first run.
std::vector<std::string> swept_inputs(const EvalSummary& s) {
  std::vector<std::string> inputs;
  for (const Comparison& c : s.comparisons) {
    if (!std::isfinite(c.target_fraction)) continue;
    if (std::find(inputs.begin(), inputs.end(), c.info.input) != inputs.end()) continue;
    int n = 0;
    for (const Comparison& d : s.comparisons) n += d.info.input == c.info.input && std::isfinite(d.target_fraction);
    if (n >= 2) inputs.push_back(c.info.input);
  }
  return inputs;
}

// The original (one point: every fraction's original runs are the same
// runs, so the first comparison's) and each method's curve over F.
std::vector<SweepSeries> sweep_of(const EvalSummary& s, const std::string& input, std::string* name) {
  std::vector<const Comparison*> cs;
  for (const Comparison& c : s.comparisons)
    if (c.info.input == input && std::isfinite(c.target_fraction)) cs.push_back(&c);
  std::sort(cs.begin(), cs.end(), [](const Comparison* a, const Comparison* b) { return a->target_fraction < b->target_fraction; });
  std::vector<SweepSeries> out = {{"original", {}}, {"ours", {}}, {"random", {}}, {"longest track", {}}, {"ANMS (SSC)", {}}};
  if (cs.empty()) return out;
  *name = cs.front()->info.name;
  out[0].points.push_back(sweep_point(1.0, cs.front()->original));
  for (const Comparison* c : cs) {
    const std::vector<RunRecord>* v[] = {&c->ours, &c->random, &c->longest_track, &c->anms};
    for (int m = 0; m < 4; ++m)
      if (!v[m]->empty()) out[static_cast<std::size_t>(m + 1)].points.push_back(sweep_point(c->target_fraction, *v[m]));
  }
  return out;
}

std::string sweep_tables(const EvalSummary& s) {
  std::ostringstream o;
  for (const std::string& input : swept_inputs(s)) {
    std::string name;
    const std::vector<SweepSeries> series = sweep_of(s, input, &name);
    o << "\n#### Budget sweep: " << name << " (every method keeps the share F of the points it evaluates: F of "
         "those new to each window plus those it kept before; mean ± sd over seeds, failed runs included and "
         "counted)\n\n"
         "| F | method | failed | frames tracked | ATE (m) | local-BA observations | local-BA CPU (s) | map points | "
         "keyframes |\n|---:|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const SweepSeries& se : series)
      for (const SweepPoint& p : se.points)
        o << "| " << (se.method == "original" ? std::string("–") : f(p.fraction, 2)) << " | " << se.method << " | "
          << p.failed << " / " << p.seeds << " | " << f(p.tracked.mean, 1) << " | " << ate_pm(p.ate) << " | "
          << f(p.observations.mean, 0) << " | " << pm(p.ba_cpu_s, 2) << " | " << f(p.mps.mean, 0) << " | "
          << f(p.kfs.mean, 0) << " |\n";
    o << "\nSmallest F at which every seed ran without failure:";
    for (std::size_t m = 1; m < series.size(); ++m) {
      if (series[m].points.empty()) continue;
      double smallest = NAN;
      for (auto it = series[m].points.rbegin(); it != series[m].points.rend() && it->failed == 0; ++it) smallest = it->fraction;
      o << (m > 1 ? "," : "") << " " << series[m].method << " "
        << (std::isfinite(smallest) ? f(smallest, 2) : std::string("none of those run"));
    }
    o << " (each from the largest F down to its first failure).\n";
  }
  return o.str();
}

// ATE against local-BA observations, one curve per method over F, a failed
// point drawn as a ring with its count of failed seeds.
std::string svg_sweep(const EvalSummary& s, const std::string& input) {
  std::string name;
  const std::vector<SweepSeries> series = sweep_of(s, input, &name);
  // ATE on a log scale: a lost run's error is orders above a tracked one's.
  double xmax = 1, lo = INFINITY, hi = -INFINITY;
  for (const SweepSeries& se : series)
    for (const SweepPoint& p : se.points) {
      if (std::isfinite(p.observations.mean)) xmax = std::max(xmax, p.observations.mean);
      if (std::isfinite(p.ate.mean) && p.ate.mean > 0) {
        lo = std::min(lo, std::log10(p.ate.mean));
        hi = std::max(hi, std::log10(p.ate.mean));
      }
    }
  if (!std::isfinite(lo)) lo = -1, hi = 0;
  lo = std::floor(lo);
  hi = std::max(std::ceil(hi), lo + 1);
  const auto log_ate = [](double v) { return v > 0 ? std::log10(v) : NAN; };
  Svg svg(800, 500);
  Axes ax{90, 40, 540, 380, 0, xmax * 1.05, lo, hi};
  ax.draw(svg, "local-BA observations (sum over the run, mean over seeds)", "log10 RMS ATE (m)",
          name + ": ATE against local-BA size over the kept fraction F");
  const char* colours[] = {"#000000", "#1f77b4", "#7f7f7f", "#2ca02c", "#d62728"};
  double ly = 60;
  for (std::size_t m = 0; m < series.size(); ++m) {
    const char* c = colours[m];
    const auto& pts = series[m].points;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const SweepPoint& p = pts[i];
      if (!std::isfinite(p.observations.mean) || !std::isfinite(log_ate(p.ate.mean))) continue;
      const double x = ax.X(p.observations.mean), y = ax.Y(log_ate(p.ate.mean));
      if (i > 0 && std::isfinite(log_ate(pts[i - 1].ate.mean)) && std::isfinite(pts[i - 1].observations.mean))
        svg.line(ax.X(pts[i - 1].observations.mean), ax.Y(log_ate(pts[i - 1].ate.mean)), x, y, c, 1.5);
      svg.circle(x, y, 4, c);
      if (m > 0) svg.text(x + 6, y - 6, "F " + f(p.fraction, 2), "start", 9);
      if (p.failed > 0) {
        svg.o << "<circle cx=\"" << f(x, 1) << "\" cy=\"" << f(y, 1) << "\" r=\"9\" fill=\"none\" stroke=\"#d00\" "
              << "stroke-width=\"2\"/>\n";
        svg.text(x + 6, y + 14, std::to_string(p.failed) + "/" + std::to_string(p.seeds) + " failed", "start", 9);
      }
    }
    svg.circle(650, ly, 4, c);
    svg.text(660, ly + 4, series[m].method);
    ly += 20;
  }
  svg.o << "<circle cx=\"650\" cy=\"" << f(ly, 1) << "\" r=\"7\" fill=\"none\" stroke=\"#d00\" stroke-width=\"2\"/>\n";
  svg.text(660, ly + 4, "failed seeds (lost tracking)");
  return svg.str();
}

std::string file_name_of(const std::string& name) {
  std::string o;
  for (char c : name) o += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return o;
}

std::string svg_keypoints(const Snapshot& sn) {
  const double scale = std::min(1.0, 700.0 / std::max(sn.width, 1));
  const double w = sn.width * scale, h = sn.height * scale;
  Svg svg(static_cast<int>(w + 40), static_cast<int>(2 * h + 110));
  auto panel = [&](const std::vector<SnapshotPoint>& pts, double y0, const std::string& title) {
    svg.text(20, y0 - 6, title, "start", 13);
    svg.o << "<rect x=\"20\" y=\"" << f(y0, 1) << "\" width=\"" << f(w, 1) << "\" height=\"" << f(h, 1)
          << "\" fill=\"#f7f7f7\" stroke=\"black\"/>\n";
    int kept = 0, culled = 0;
    for (const auto& p : pts) {
      const char* c = p.state == 1 ? "#2ca02c" : p.state == 2 ? "#d62728" : "#c7c7c7";
      kept += p.state == 1;
      culled += p.state == 2;
      svg.circle(20 + p.u * scale, y0 + p.v * scale, p.state == 0 ? 1.2 : 2.0, c);
    }
    svg.text(20 + w, y0 - 6, std::to_string(kept) + " kept (green), " + std::to_string(culled) + " culled (red)", "end");
  };
  panel(sn.ours, 30, "ours (M=" + std::to_string(sn.M) + "), " + sn.input);
  panel(sn.anms, 30 + h + 50, "ANMS (SSC), equal count, " + sn.input);
  return svg.str();
}

}  // namespace

std::string markdown_tables(const EvalSummary& s) {
  std::ostringstream o;
  const int nseeds = static_cast<int>(s.seeds.size());
  o << "Seeds " << (s.seeds.empty() ? 0 : s.seeds.front()) << "–" << (s.seeds.empty() ? 0 : s.seeds.back()) << " ("
    << nseeds << "); every figure is mean ± sd over them. " << s.settings;
  for (const auto& i : s.settings_inputs) o << "; " << i;
  o << ". ATE after SE(3) alignment where scale is metric (stereo, RGB-D; evo's `--align`), Sim(3) for monocular runs "
       "(`--align --correct_scale`); column *align*. Error floor (added in quadrature to both sides of the floored ratio): ";
  bool first = true;
  for (const auto& [g, v] : s.error_floor) {
    o << (first ? "" : ", ") << g << " " << f(v, 4) << " m";
    first = false;
  }
  if (s.error_floor.empty()) o << "none";
  o << ".\n\n";

  for (const std::string& label : labels_of(s.runs)) {
    o << "#### Accuracy at equal kept fraction (" << label << ")\n\n"
         "| Input | kind | align | seeds | M | MP % | KF % | BA time % | ATE original | ATE ours | ours / original | "
         "√(obs ratio) | floor (m) | ratio with floor | better / worse seeds |\n"
         "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const ContractRun& r : s.runs) {
      if (op_label(r) != label) continue;
      o << "| " << r.info.name << " | " << r.info.kind << " | " << (r.info.sim3 ? "Sim(3)" : "SE(3)") << " | " << r.seeds
        << " | " << r.M << " | " << pm(r.mp_percent, 1) << " | " << pm(r.kf_percent, 1) << " | "
        << pm(r.ba_time_percent, 1) << " | " << with_failed(ate_pm(r.ate_original), r.failed.original) << " | "
        << with_failed(ate_pm(r.ate_ours), r.failed.ours) << " | "
        << over_ratio_seeds(bold_if(r.ate_ratio <= 1.0, f(r.ate_ratio, 2)), r) << " | " << f(r.sqrt_obs_ratio, 2) << " | "
        << (r.info.error_floor_m > 0 ? f(r.info.error_floor_m, 4) : "–") << " | " << f(r.ate_ratio_floored, 3) << " | "
        << r.better_seeds << " / " << r.worse_seeds << " |\n";
    }
    o << "\n#### Baselines keeping the same count per window (" << label << "; ATE in m, lowest mean in bold; "
         "\"ours below\": seeds on which ours had the lower ATE, then ours' ATE minus the baseline's, "
         "mean ± standard error over the seeds)\n\n"
         "| Input | ours | random | longest track | ANMS (SSC) | MP % ours / random / longest / ANMS | "
         "KF % ours / random / longest / ANMS | ATE ratio (√(obs ratio)) ours / random / longest / ANMS | "
         "ours below random | below longest | below ANMS |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const ContractRun& r : s.runs) {
      if (op_label(r) != label) continue;
      double best = r.ate_ours.mean;
      for (const Stat* a : {&r.ate_random, &r.ate_longest_track, &r.ate_anms})
        if (a->n > 0) best = std::min(best, a->mean);
      auto cell = [&](const Stat& a, int failed) {
        return a.n == 0 ? std::string("–") : with_failed(bold_if(a.mean == best, ate_pm(a)), failed);
      };
      const int digits = ate_digits(r.ate_ours.mean);
      auto below = [&](const Stat& a, int n, const Stat& d) {
        if (a.n == 0) return std::string("–");
        if (r.seeds > 1 && repeated(r.ate_ours) && repeated(a)) {
          return std::string(n > 0 ? "below" : "not below") + " (one run each)";
        }
        const std::string seeds = std::to_string(n) + " / " + std::to_string(r.seeds);
        if (!std::isfinite(d.mean)) return seeds;
        return seeds + " (" + (d.mean >= 0 ? "+" : "") + f(d.mean, digits) + " ± " + f(d.se(), digits) + ")";
      };
      auto quad = [](double a, double b, double c, double d, int prec) {
        return f(a, prec) + " / " + f(b, prec) + " / " + f(c, prec) + " / " + f(d, prec);
      };
      auto rq = [&](double ratio, double sq) { return f(ratio, 2) + " (" + f(sq, 2) + ")"; };
      o << "| " << r.info.name << " | " << cell(r.ate_ours, r.failed.ours) << " | "
        << cell(r.ate_random, r.failed.random) << " | " << cell(r.ate_longest_track, r.failed.longest_track) << " | "
        << cell(r.ate_anms, r.failed.anms) << " | "
        << quad(r.mp_percent.mean, r.mp_percent_random.mean, r.mp_percent_longest_track.mean, r.mp_percent_anms.mean, 1) << " | "
        << quad(r.kf_percent.mean, r.kf_percent_random.mean, r.kf_percent_longest_track.mean, r.kf_percent_anms.mean, 0) << " | "
        << over_ratio_seeds(rq(r.ate_ratio, r.sqrt_obs_ratio) + " / " + rq(r.ate_ratio_random, r.sqrt_obs_ratio_random) +
                                " / " + rq(r.ate_ratio_longest_track, r.sqrt_obs_ratio_longest_track) + " / " +
                                rq(r.ate_ratio_anms, r.sqrt_obs_ratio_anms), r) << " | "
        << below(r.ate_random, r.below_random_seeds, r.ate_diff_random) << " | "
        << below(r.ate_longest_track, r.below_longest_track_seeds, r.ate_diff_longest_track) << " | "
        << below(r.ate_anms, r.below_anms_seeds, r.ate_diff_anms) << " |\n";
    }
    // The real VO: tracking is part of the result (a lost frame is not scored by the ATE).
    bool vo_header = false;
    for (const ContractRun& r : s.runs) {
      if (op_label(r) != label || r.frames <= 0) continue;
      if (!vo_header)
        o << "\n#### Real VO: frames tracked (" << label << "; mean over seeds)\n\n"
             "| Input | frames | original | ours | random | longest track | ANMS (SSC) |\n|---|---:|---:|---:|---:|---:|---:|\n";
      vo_header = true;
      o << "| " << r.info.name << " | " << r.frames << " | " << f(r.frames_tracked_original.mean, 1) << " | "
        << f(r.frames_tracked.mean, 1) << " | " << f(r.frames_tracked_random.mean, 1) << " | "
        << f(r.frames_tracked_longest_track.mean, 1) << " | " << f(r.frames_tracked_anms.mean, 1) << " |\n";
    }
    // Failures, per method: every table's means include them (marked).
    o << "\n#### Failures (" << label << "; runs that lost tracking, frames tracked < frames, or whose BA diverged; "
         "n / seeds)\n\n| Input | original | ours | random | longest track | ANMS (SSC) |\n|---|---:|---:|---:|---:|---:|\n";
    for (const ContractRun& r : s.runs) {
      if (op_label(r) != label) continue;
      auto n = [&](int failed, const Stat& ran) {
        return ran.n == 0 ? std::string("–") : std::to_string(failed) + " / " + std::to_string(ran.n);
      };
      o << "| " << r.info.name << " | " << n(r.failed.original, r.ate_original) << " | " << n(r.failed.ours, r.ate_ours)
        << " | " << n(r.failed.random, r.ate_random) << " | " << n(r.failed.longest_track, r.ate_longest_track) << " | "
        << n(r.failed.anms, r.ate_anms) << " |\n";
    }
    o << "\n";
    // The coverage floor: how often it bound on ours's windows (only when it ever did or was asked for).
    bool floor_header = false;
    for (const ContractRun& r : s.runs) {
      if (op_label(r) != label || !(r.windows > 0)) continue;
      if (s.coverage_floor == 0 && r.floor_keyframes.mean == 0 && r.floor_short.mean == 0) continue;
      if (!floor_header)
        o << "\n#### Coverage floor (" << label << "; ours, per run, mean over seeds)\n\n"
             "| Input | selector windows | keyframes where the floor bound | points promoted | keyframes short |\n"
             "|---|---:|---:|---:|---:|\n";
      floor_header = true;
      o << "| " << r.info.name << " | " << f(r.windows, 1) << " | " << pm(r.floor_keyframes, 1) << " | "
        << pm(r.floor_promoted, 1) << " | " << pm(r.floor_short, 1) << " |\n";
    }
    const std::vector<GroupRow> groups = group_rows(s.runs, label);
    if (!groups.empty()) {
      o << "\n#### Per trajectory group (" << label << "; as the paper's Table V, but each ATE as a ratio to the "
           "original's, averaged over the group's inputs, √(obs ratio) in brackets; lowest in bold)\n\n"
           "| Group | inputs | MP % | KF % | BA time % | ours | random | longest track | ANMS |\n"
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
      for (const GroupRow& g : groups) {
        const double best = std::min({g.ours, g.random, g.longest, g.anms});
        o << "| " << g.group << " | " << g.inputs << " | " << f(g.mp, 1) << " | " << f(g.kf, 1) << " | " << f(g.ba, 1)
          << " | " << bold_if(g.ours == best, f(g.ours, 2)) << " (" << f(g.sq_ours, 2) << ") | "
          << bold_if(g.random == best, f(g.random, 2)) << " (" << f(g.sq_random, 2) << ") | "
          << bold_if(g.longest == best, f(g.longest, 2)) << " (" << f(g.sq_longest, 2) << ") | "
          << bold_if(g.anms == best, f(g.anms, 2)) << " (" << f(g.sq_anms, 2) << ") |\n";
      }
    }
  }

  bool any_ablation = false;
  for (const Comparison& c : s.comparisons) any_ablation |= !c.ablation.empty();
  if (any_ablation) {
    o << "\n#### Cost ablation (as the paper's Table VI; C observations per point, F mean keyframe span per point, "
         "S % of a 64×48 grid occupied; at the first operating point's M)\n\n"
         "| Input | costs | M | MP % | C | F | S | ATE (m) |\n|---|---|---:|---:|---:|---:|---:|---:|\n";
    for (const Comparison& c : s.comparisons)
      for (const auto& [costs, runs] : ablation_rows(c))
        o << "| " << c.info.name << " | " << costs << " | " << c.M << " | "
          << pm(stat_by(runs, [&](const RunRecord& r) { return mp_percent_of(c, r); }), 1) << " | "
          << pm(stat_by(runs, [](const RunRecord& r) { return r.C; }), 2) << " | "
          << pm(stat_by(runs, [](const RunRecord& r) { return r.F; }), 2) << " | "
          << pm(stat_by(runs, [](const RunRecord& r) { return r.S; }), 2) << " | "
          << ate_pm(stat_by(runs, [](const RunRecord& r) { return r.ate_m; })) << " |\n";
  }

  // Claims, computed from the runs above.
  for (const std::string& label : labels_of(s.runs)) {
    o << "\n#### Which claims held (" << label << ", trajectories unless stated)\n\n| Claim (target) | Measured | Held? |\n|---|---|---|\n";
    double mp = 0, kf = 0, ba = 0, rat = 0;
    int n = 0, better = 0, worse = 0, seeds = 0;
    for (const ContractRun& r : s.runs) {
      if (r.info.kind != "trajectory" || op_label(r) != label) continue;
      mp += r.mp_percent.mean; kf += r.kf_percent.mean; ba += r.ba_time_percent.mean; rat += r.ate_ratio;
      better += r.better_seeds; worse += r.worse_seeds; seeds += r.ratio_seeds;
      ++n;
    }
    if (n == 0) continue;
    mp /= n; kf /= n; ba /= n; rat /= n;
    auto yes = [](bool b) { return b ? std::string("**yes**") : std::string("**no**"); };
    o << "| Fewer keyframes (paper: KF % 60–75) | KF % " << f(kf, 1) << " mean at MP % " << f(mp, 1) << " | " << yes(kf <= 75) << " |\n";
    o << "| About half the BA computation (BA time ≤ 60 %) | " << f(ba, 1) << " % mean | " << yes(ba <= 60) << " |\n";
    o << "| Accuracy maintained (mean ATE ratio ≤ 1.05; better seeds ≥ worse) | ratio " << f(rat, 2) << "; " << better
      << " better / " << worse << " worse of " << seeds << " input-seeds | " << yes(rat <= 1.05 && better >= worse) << " |\n";
    const std::vector<GroupRow> groups = group_rows(s.runs, label);
    const int ng = static_cast<int>(groups.size());
    auto beats = [&](double GroupRow::*b) {
      int k = 0;
      for (const GroupRow& g : groups) k += g.ours < g.*b ? 1 : 0;
      return k;
    };
    const int need = (3 * ng + 3) / 4;  // the paper's "3 of 4"
    for (auto [name, field] : {std::pair{"random", &GroupRow::random}, std::pair{"longest-track-first", &GroupRow::longest},
                               std::pair{"ANMS (SSC)", &GroupRow::anms}})
      o << "| Beats " << name << " at equal count (≥ " << need << " of " << ng << " groups) | ours lower on " << beats(field)
        << " of " << ng << " | " << yes(beats(field) >= need) << " |\n";
    // The other kinds, input by input: against the original (not for BAL,
    // whose original is the reference itself) and against each baseline run.
    for (const ContractRun& r : s.runs) {
      if (r.info.kind == "trajectory" || op_label(r) != label) continue;
      const std::string what = r.info.kind + " " + r.info.name + " (" + (r.info.sim3 ? "Sim(3)" : "SE(3)") + ")";
      if (r.info.kind != "bal")
        o << "| " << what << ": not worse than the original | ratio " << f(r.ate_ratio, 2) << ", " << r.better_seeds
          << " better / " << r.worse_seeds << " worse of " << r.ratio_seeds << " | "
          << yes(r.ate_ratio <= 1.0 && r.better_seeds >= r.worse_seeds) << " |\n";
      for (auto [name, a, below] : {std::tuple{"random", &r.ate_random, r.below_random_seeds},
                                    std::tuple{"longest-track-first", &r.ate_longest_track, r.below_longest_track_seeds},
                                    std::tuple{"ANMS (SSC)", &r.ate_anms, r.below_anms_seeds}})
        if (a->n > 0 && r.seeds > 1 && repeated(r.ate_ours) && repeated(*a))  // one comparison, not r.seeds
          o << "| " << what << ": beats " << name << " at equal count | " << ate_pm(r.ate_ours) << " vs "
            << ate_pm(*a) << ", one run each (both deterministic; the seeds repeat it) | "
            << yes(r.ate_ours.mean < a->mean) << " (one comparison) |\n";
        else if (a->n > 0)
          o << "| " << what << ": beats " << name << " at equal count | " << ate_pm(r.ate_ours) << " vs "
            << ate_pm(*a) << ", lower on " << below << " of " << r.seeds << " seeds | "
            << yes(r.ate_ours.mean < a->mean && 2 * below > r.seeds) << " |\n";
    }
  }
  o << sweep_tables(s);
  return o.str();
}

bool write_outputs(const EvalSummary& s, const std::string& out_dir, std::string* error) {
  namespace fsys = std::filesystem;
  std::error_code ec;
  fsys::create_directories(out_dir, ec);
  if (ec) {
    *error = out_dir + ": " + ec.message();
    return false;
  }
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream out(fsys::path(out_dir) / name);
    out << text;
    if (!out) *error = out_dir + "/" + name + ": write failed";
    return static_cast<bool>(out);
  };
  std::ostringstream csv;
  csv << kCsvHeader << "\n";
  for (const Comparison& c : s.comparisons)
    for (const auto* v : {&c.original, &c.ours, &c.random, &c.longest_track, &c.anms, &c.ablation})
      for (const RunRecord& r : *v)
        csv << c.info.input << "," << c.info.name << "," << c.info.group << "," << c.info.kind << ","
            << (c.info.sim3 ? "sim3" : "se3") << "," << r.variant << "," << r.seed << "," << r.M << ","
            << json_number(c.target_fraction, 3) << "," << c.M << "," << r.mps << "," << r.kfs << "," << r.observations
            << "," << f(r.ba_s, 4) << "," << f(r.total_s, 4) << "," << json_number(r.ate_m, 9) << ","
            << json_number(r.ate_r_deg, 6) << "," << json_number(r.C, 4) << "," << json_number(r.F, 4) << ","
            << json_number(r.S, 4) << "," << r.frames << "," << r.frames_tracked << "," << r.selector.windows << ","
            << r.selector.floor_keyframes << "," << r.selector.floor_promoted << "," << r.selector.floor_short << ","
            << json_number(r.ba_cpu_s, 4) << "," << (r.diverged ? 1 : 0) << "," << (r.failed() ? 1 : 0) << ","
            << json_number(r.refine_cpu_s, 4) << "\n";
  bool ok = write("runs.csv", csv.str());
  std::string meta = s.command + "\n" + s.mode + "\n" + s.settings + "\n" + json_number(s.elapsed_s, 1) + "\n";
  for (const std::string& i : s.settings_inputs) meta += i + "\n";
  ok = ok && write("meta.txt", meta);
  ok = ok && write("tables.md", "`" + s.command + "` (" + s.mode + ", " + f(s.elapsed_s / 60.0, 1) + " min)\n\n" + markdown_tables(s));
  if (!s.runs.empty()) ok = ok && write("ate_vs_kept.svg", svg_ate_vs_kept(s));
  for (const std::string& input : swept_inputs(s)) {
    std::string name;
    (void)sweep_of(s, input, &name);
    ok = ok && write("sweep_" + file_name_of(name) + ".svg", svg_sweep(s, input));
  }
  // One frame's keypoints: a real image if there is one.
  const Snapshot* pick = nullptr;
  for (const Snapshot& sn : s.snapshots)
    if (!sn.ours.empty() && (!pick || sn.kind == "images")) pick = &sn;
  if (pick) ok = ok && write("keypoints_ours_vs_anms.svg", svg_keypoints(*pick));
  return ok;
}

std::string json_summary(const EvalSummary& s) {
  std::ostringstream o;
  o << ",\"tool\":\"keepless_eval\",\"mode\":" << json_string(s.mode) << ",\"seeds\":[";
  for (std::size_t i = 0; i < s.seeds.size(); ++i) o << (i ? "," : "") << s.seeds[i];
  o << "],\"error_floor\":{";
  bool first = true;
  for (const auto& [g, v] : s.error_floor) {
    o << (first ? "" : ",") << json_string(g) << ":" << json_number(v, 4);
    first = false;
  }
  o << "},\"ablation\":[";
  first = true;
  for (const Comparison& c : s.comparisons)
    for (const auto& [costs, runs] : ablation_rows(c)) {
      const Stat ate = stat_by(runs, [](const RunRecord& r) { return r.ate_m; });
      o << (first ? "" : ",") << "{\"input\":" << json_string(c.info.name) << ",\"costs\":" << json_string(costs)
        << ",\"M\":" << c.M << ",\"seeds\":" << runs.size() << ",\"ate_m\":" << json_number(ate.mean)
        << ",\"ate_sd_m\":" << json_number(ate.sd)
        << ",\"C\":" << json_number(stat_by(runs, [](const RunRecord& r) { return r.C; }).mean, 4)
        << ",\"F\":" << json_number(stat_by(runs, [](const RunRecord& r) { return r.F; }).mean, 4)
        << ",\"S\":" << json_number(stat_by(runs, [](const RunRecord& r) { return r.S; }).mean, 4) << "}";
      first = false;
    }
  o << "]";
  if (!s.scope.empty())
    o << ",\"policy\":{\"scope\":" << json_string(s.scope) << ",\"floor\":" << s.coverage_floor
      << ",\"cost\":" << json_string(s.cost_model) << "}";
  o << ",\"elapsed_s\":" << json_number(s.elapsed_s, 2);
  return contract_json(s.runs, o.str());
}

namespace {
// Which input a record is, across directories: the sweep names inputs by absolute paths, a run by
// hand by relative ones, so the key is the path's last two components (the sequence's folder and
// its image folder or file), not the path as written.
std::string input_key(const std::string& input, double target_fraction, std::int64_t M) {
  std::filesystem::path p = std::filesystem::path(input).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  return (p.parent_path().filename() / p.filename()).string() + "|" + json_number(target_fraction, 3) + "|" +
         std::to_string(M);
}
}  // namespace

bool read_outputs(const std::string& out_dir, EvalSummary* s, std::string* error) {
  namespace fsys = std::filesystem;
  const std::string csv_path = (fsys::path(out_dir) / "runs.csv").string();
  std::ifstream csv(csv_path);
  if (!csv) {
    *error = csv_path + ":0: cannot open";
    return false;
  }
  // Several runs may be read into one summary: their commands and times add up.
  std::ifstream meta((fsys::path(out_dir) / "meta.txt").string());
  std::string command, elapsed, line;
  if (meta && std::getline(meta, command) && std::getline(meta, s->mode) && std::getline(meta, s->settings) &&
      std::getline(meta, elapsed)) {
    s->command += (s->command.empty() ? "" : "` and `") + command;
    s->elapsed_s += std::strtod(elapsed.c_str(), nullptr);
    s->settings_inputs.clear();
    while (std::getline(meta, line))
      if (!line.empty()) s->settings_inputs.push_back(line);
  }
  auto split = [](const std::string& l) {
    std::vector<std::string> v;
    std::stringstream ss(l);
    std::string t;
    while (std::getline(ss, t, ',')) v.push_back(t);
    return v;
  };
  std::getline(csv, line);
  const std::vector<std::string> header = split(line);
  auto col = [&](const char* name) {
    const auto it = std::find(header.begin(), header.end(), name);
    return it == header.end() ? -1 : static_cast<int>(it - header.begin());
  };
  for (const char* need : {"input", "name", "group", "kind", "alignment", "variant", "seed", "M", "target_fraction",
                           "mps", "kfs", "observations", "ba_s", "total_s", "ate_m", "ate_r_deg"})
    if (col(need) < 0) {
      *error = csv_path + ":1: no column " + need;
      return false;
    }
  // One comparison per input and operating point across every directory
  // read: a directory holding other seeds of the same point (the sweep's
  // one process per seed) adds its records to the same comparison.
  std::vector<std::string> keys;
  for (const Comparison& c : s->comparisons) keys.push_back(input_key(c.info.input, c.target_fraction, c.M));
  int lineno = 1;
  while (std::getline(csv, line)) {
    ++lineno;
    if (line.empty()) continue;
    const std::vector<std::string> v = split(line);
    if (v.size() != header.size()) {
      *error = csv_path + ":" + std::to_string(lineno) + ": " + std::to_string(v.size()) + " fields, want " +
               std::to_string(header.size());
      return false;
    }
    auto str = [&](const char* name) { return col(name) < 0 ? std::string() : v[static_cast<std::size_t>(col(name))]; };
    auto num = [&](const char* name) {
      const std::string t = str(name);
      return t.empty() || t == "null" ? NAN : std::strtod(t.c_str(), nullptr);
    };
    RunRecord r;
    r.variant = str("variant");
    r.seed = static_cast<std::uint64_t>(num("seed"));
    r.M = static_cast<std::int64_t>(num("M"));
    r.mps = static_cast<std::uint64_t>(num("mps"));
    r.kfs = static_cast<std::uint64_t>(num("kfs"));
    r.observations = static_cast<std::uint64_t>(num("observations"));
    r.ba_s = num("ba_s");
    r.total_s = num("total_s");
    r.ate_m = num("ate_m");
    r.ate_r_deg = num("ate_r_deg");
    r.C = num("C");
    r.F = num("F");
    r.S = num("S");
    r.frames = col("frames") < 0 ? 0 : static_cast<int>(num("frames"));  // absent in older files
    r.frames_tracked = col("frames_tracked") < 0 ? 0 : static_cast<int>(num("frames_tracked"));
    auto count = [&](const char* name) { return col(name) < 0 ? 0 : static_cast<std::uint64_t>(num(name)); };
    r.selector.windows = count("windows");
    r.selector.floor_keyframes = count("floor_keyframes");
    r.selector.floor_promoted = count("floor_promoted");
    r.selector.floor_short = count("floor_short");
    r.ba_cpu_s = col("ba_cpu_s") < 0 ? NAN : num("ba_cpu_s");
    r.refine_cpu_s = col("refine_cpu_s") < 0 ? NAN : num("refine_cpu_s");  // absent in older files
    r.diverged = count("diverged") != 0;
    // One comparison per input and operating point (compared_M tells --M points apart).
    const std::int64_t compared_m = col("compared_M") < 0 ? 0 : static_cast<std::int64_t>(num("compared_M"));
    const std::string key = input_key(str("input"), num("target_fraction"), compared_m);
    auto it = std::find(keys.begin(), keys.end(), key);
    if (it == keys.end()) {
      keys.push_back(key);
      Comparison c;
      c.info.input = str("input");
      c.info.name = str("name");
      c.info.group = str("group");
      c.info.kind = str("kind");
      c.info.sim3 = str("alignment") == "sim3";
      c.target_fraction = num("target_fraction");
      c.M = static_cast<std::int64_t>(num("compared_M"));  // absent in older files: from the variants below
      s->comparisons.push_back(c);
      it = keys.end() - 1;
    }
    Comparison& c = s->comparisons[static_cast<std::size_t>(it - keys.begin())];
    if (r.variant != "original" && col("compared_M") < 0) c.M = r.M;
    std::vector<RunRecord>* to = &c.ablation;
    if (r.variant == "original") to = &c.original;
    else if (r.variant == "ours") to = &c.ours;
    else if (r.variant == "random") to = &c.random;
    else if (r.variant == "longest_track") to = &c.longest_track;
    else if (r.variant == "anms") to = &c.anms;
    to->push_back(r);
    if (std::find(s->seeds.begin(), s->seeds.end(), r.seed) == s->seeds.end()) s->seeds.push_back(r.seed);
  }
  std::sort(s->seeds.begin(), s->seeds.end());
  return true;
}

}  // namespace keepless::eval
