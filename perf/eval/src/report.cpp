#include "report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace keepless::eval {
namespace {

std::string f(double v, int prec) {
  if (!std::isfinite(v)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", prec, v);
  return buf;
}
std::string fs(double v, int prec) {  // signed
  char buf[64];
  std::snprintf(buf, sizeof buf, "%+.*f", prec, v);
  return buf;
}
double pct(double a, double b) { return b > 0 ? 100.0 * a / b : 0.0; }
std::string jnum(double v, int prec = 6) { return std::isfinite(v) ? f(v, prec) : "null"; }
std::string jstr(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}
std::string bold_if(bool b, const std::string& s) { return b ? "**" + s + "**" : s; }

const RunResult& op(const InputReport& in) { return in.ours[in.op_index]; }

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
  void square(double x, double y, double r, const char* c) {
    o << "<rect x=\"" << f(x - r, 1) << "\" y=\"" << f(y - r, 1) << "\" width=\"" << f(2 * r, 1) << "\" height=\""
      << f(2 * r, 1) << "\" fill=\"" << c << "\"/>\n";
  }
  void polyline(const std::vector<std::pair<double, double>>& p, const char* c) {
    o << "<polyline fill=\"none\" stroke=\"" << c << "\" stroke-width=\"2\" points=\"";
    for (const auto& q : p) o << f(q.first, 1) << "," << f(q.second, 1) << " ";
    o << "\"/>\n";
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
  for (const auto& in : s.inputs) {
    if (in.original.ate_m <= 0) continue;
    for (const auto& r : in.ours) ymax = std::max(ymax, r.ate_m / in.original.ate_m);
    if (in.has_baselines) ymax = std::max({ymax, in.anms.ate_m / in.original.ate_m, in.random.ate_m / in.original.ate_m});
  }
  ymax = std::min(std::ceil(ymax * 2) / 2, 10.0);
  Axes ax{80, 40, 520, 380, 0, 100, 0, ymax};
  ax.draw(svg, "map points kept (% of original)", "RMS ATE / original", "ATE vs kept points (each input, each variant)");
  svg.line(ax.X(0), ax.Y(1), ax.X(100), ax.Y(1), "#999");
  for (const auto& in : s.inputs) {
    if (in.original.ate_m <= 0 || in.original.mps == 0) continue;
    auto y = [&](const RunResult& r) { return ax.Y(std::min(ymax, r.ate_m / in.original.ate_m)); };
    auto x = [&](const RunResult& r) { return ax.X(std::min(100.0, pct(r.mps, in.original.mps))); };
    for (const auto& r : in.ours) svg.circle(x(r), y(r), 4, "#1f77b4");
    if (in.has_baselines) {
      svg.square(x(in.anms), y(in.anms), 4, "#d62728");
      svg.square(x(in.random), y(in.random), 3, "#7f7f7f");
    }
  }
  svg.circle(620, 60, 4, "#1f77b4"); svg.text(630, 64, "ours (every M)");
  svg.square(620, 80, 4, "#d62728"); svg.text(630, 84, "ANMS (SSC), equal count");
  svg.square(620, 100, 3, "#7f7f7f"); svg.text(630, 104, "random, equal count");
  return svg.str();
}

std::string svg_time_vs_M(const EvalSummary& s) {
  Svg svg(760, 480);
  Axes ax{80, 40, 520, 380, 0, 0, 0, 110};
  std::vector<std::int64_t> Ms = s.Ms;
  std::sort(Ms.begin(), Ms.end());
  if (Ms.empty()) return svg.str();
  ax.xmin = 0;
  ax.xmax = double(Ms.back()) * 1.1;
  std::vector<std::pair<double, double>> ba, tt, mp;
  double ymax = 110;
  for (std::int64_t M : Ms) {
    double sb = 0, st = 0, sm = 0;
    int n = 0;
    for (const auto& in : s.inputs)
      for (const auto& r : in.ours)
        if (r.spec.M == M && in.original.ba_s > 0) {
          sb += pct(r.ba_s, in.original.ba_s);
          st += pct(r.total_s, in.original.total_s);
          sm += pct(r.mps, in.original.mps);
          ++n;
        }
    if (n == 0) continue;
    ba.emplace_back(M, sb / n);
    tt.emplace_back(M, st / n);
    mp.emplace_back(M, sm / n);
    ymax = std::max({ymax, sb / n, st / n});
  }
  ax.ymax = std::ceil(ymax / 10) * 10;
  ax.draw(svg, "M (pair capacity)", "% of original (mean over inputs)", "BA time, total time and map points vs M");
  auto map = [&](const std::vector<std::pair<double, double>>& v) {
    std::vector<std::pair<double, double>> o;
    for (const auto& p : v) o.emplace_back(ax.X(p.first), ax.Y(p.second));
    return o;
  };
  svg.polyline(map(ba), "#d62728");
  svg.polyline(map(tt), "#ff7f0e");
  svg.polyline(map(mp), "#1f77b4");
  for (const auto& p : map(ba)) svg.circle(p.first, p.second, 3, "#d62728");
  for (const auto& p : map(tt)) svg.circle(p.first, p.second, 3, "#ff7f0e");
  for (const auto& p : map(mp)) svg.circle(p.first, p.second, 3, "#1f77b4");
  svg.line(ax.X(0), ax.Y(100), ax.X(ax.xmax), ax.Y(100), "#999");
  svg.line(620, 60, 640, 60, "#d62728", 2); svg.text(645, 64, "local BA time %");
  svg.line(620, 80, 640, 80, "#ff7f0e", 2); svg.text(645, 84, "total time %");
  svg.line(620, 100, 640, 100, "#1f77b4", 2); svg.text(645, 104, "map points %");
  return svg.str();
}

std::string svg_keypoints(const InputReport& in) {
  const double scale = std::min(1.0, 700.0 / std::max<std::uint32_t>(in.width, 1));
  const double w = in.width * scale, h = in.height * scale;
  Svg svg(static_cast<int>(w + 40), static_cast<int>(2 * h + 110));
  auto panel = [&](const RunResult& r, double y0, const std::string& title) {
    svg.text(20, y0 - 6, title, "start", 13);
    svg.o << "<rect x=\"20\" y=\"" << f(y0, 1) << "\" width=\"" << f(w, 1) << "\" height=\"" << f(h, 1)
          << "\" fill=\"#f7f7f7\" stroke=\"black\"/>\n";
    int kept = 0, culled = 0;
    for (const auto& p : r.snapshot) {
      const char* c = p.state == 1 ? "#2ca02c" : p.state == 2 ? "#d62728" : "#c7c7c7";
      kept += p.state == 1;
      culled += p.state == 2;
      svg.circle(20 + p.u * scale, y0 + p.v * scale, p.state == 0 ? 1.2 : 2.0, c);
    }
    svg.text(20 + w, y0 - 6, std::to_string(kept) + " kept (green), " + std::to_string(culled) + " culled (red)", "end");
  };
  panel(op(in), 30, "ours (M=" + std::to_string(in.op_M) + "), " + in.name);
  panel(in.anms, 30 + h + 50, "ANMS (SSC), equal count, " + in.name);
  return svg.str();
}

}  // namespace

std::string markdown_tables(const EvalSummary& s) {
  std::ostringstream o;
  const auto& ins = s.inputs;
  // Table I: MP and KF ratio per M.
  o << "### Table I: selected map points and keyframes per M (as the paper's Table I)\n\n| Sequence | #MPs | #KFs |";
  for (auto M : s.Ms) o << " MP % (M=" << M << ") | KF % (M=" << M << ") |";
  o << "\n|---|---:|---:|";
  for (std::size_t i = 0; i < s.Ms.size(); ++i) o << "---:|---:|";
  o << "\n";
  for (const auto& in : ins) {
    o << "| " << in.name << " | " << in.original.mps << " | " << in.original.kfs << " |";
    for (const auto& r : in.ours)
      o << " " << f(pct(r.mps, in.original.mps), 2) << " | " << f(pct(r.kfs, in.original.kfs), 2) << " |";
    o << "\n";
  }
  // Table III: relative differences per M.
  o << "\n### Table III: per M, relative to the original run (as the paper's Table III; ATE differences, lower than original in bold)\n\n| Sequence |";
  for (std::size_t i = 0; i < s.Ms.size(); ++i) o << " MP % (M=" << s.Ms[i] << ") | KF % | BA time % | time % | ΔATE_r (°) | ΔATE (m) |";
  o << "\n|---|";
  for (std::size_t i = 0; i < s.Ms.size(); ++i) o << "---:|---:|---:|---:|---:|---:|";
  o << "\n";
  std::vector<std::array<double, 6>> avg(s.Ms.size(), std::array<double, 6>{});
  for (const auto& in : ins) {
    o << "| " << in.name << " |";
    for (std::size_t m = 0; m < in.ours.size(); ++m) {
      const RunResult& r = in.ours[m];
      const double v[6] = {pct(r.mps, in.original.mps), pct(r.kfs, in.original.kfs), pct(r.ba_s, in.original.ba_s),
                           pct(r.total_s, in.original.total_s), r.ate_r_deg - in.original.ate_r_deg,
                           r.ate_m - in.original.ate_m};
      for (int j = 0; j < 6; ++j) avg[m][static_cast<std::size_t>(j)] += v[j] / double(ins.size());
      o << " " << f(v[0], 2) << " | " << f(v[1], 2) << " | " << f(v[2], 2) << " | " << f(v[3], 2) << " | "
        << bold_if(v[4] < 0, fs(v[4], 5)) << " | " << bold_if(v[5] < 0, fs(v[5], 5)) << " |";
    }
    o << "\n";
  }
  if (!ins.empty()) {
    o << "| **Avg.** |";
    for (const auto& a : avg)
      o << " " << f(a[0], 2) << " | " << f(a[1], 2) << " | " << f(a[2], 2) << " | " << f(a[3], 2) << " | "
        << bold_if(a[4] < 0, fs(a[4], 5)) << " | " << bold_if(a[5] < 0, fs(a[5], 5)) << " |";
    o << "\n";
  }
  // Tables II/IV: absolute values, KITTI-shaped.
  o << "\n### Table II/IV: absolute values (as the paper's Tables II and IV)\n\n| Sequence | #MPs | #KFs | time (s) | BA (s) | ATE_r (°) | ATE (m) |";
  for (auto M : s.Ms) o << " MP % (M=" << M << ") | KF % | time % | ATE_r (°) | ATE (m) |";
  o << "\n|---|---:|---:|---:|---:|---:|---:|";
  for (std::size_t i = 0; i < s.Ms.size(); ++i) o << "---:|---:|---:|---:|---:|";
  o << "\n";
  for (const auto& in : ins) {
    const RunResult& g = in.original;
    o << "| " << in.name << " | " << g.mps << " | " << g.kfs << " | " << f(g.total_s, 2) << " | " << f(g.ba_s, 2)
      << " | " << f(g.ate_r_deg, 5) << " | " << f(g.ate_m, 5) << " |";
    for (const auto& r : in.ours)
      o << " " << f(pct(r.mps, g.mps), 1) << " | " << f(pct(r.kfs, g.kfs), 1) << " | " << f(pct(r.total_s, g.total_s), 2)
        << " | " << bold_if(r.ate_r_deg < g.ate_r_deg, f(r.ate_r_deg, 5)) << " | "
        << bold_if(r.ate_m < g.ate_m, f(r.ate_m, 5)) << " |";
    o << "\n";
  }
  // Table V: comparison with ANMS (and random) per group, at equal count.
  o << "\n### Table V: comparison at equal point count, per trajectory group (as the paper's Table V; lowest ATE in bold)\n\n"
       "| Group | inputs | #MPs | #KFs | time (s) | ATE (m) | ANMS MP % | KF % | time (s) | connect. | ATE (m) "
       "| random MP % | KF % | time (s) | connect. | ATE (m) | ours MP % | KF % | time (s) | connect. | ATE (m) |\n"
       "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  std::vector<std::string> groups;
  for (const auto& in : ins)
    if (in.has_baselines && std::find(groups.begin(), groups.end(), in.group) == groups.end()) groups.push_back(in.group);
  for (const auto& g : groups) {
    double a[4][5] = {};
    double mp[4] = {}, kf[4] = {};
    int n = 0;
    for (const auto& in : ins) {
      if (in.group != g || !in.has_baselines) continue;
      ++n;
      const RunResult* rs[4] = {&in.original, &in.anms, &in.random, &op(in)};
      for (int v = 0; v < 4; ++v) {
        a[v][0] += rs[v]->mps;
        a[v][1] += rs[v]->kfs;
        a[v][2] += rs[v]->total_s;
        a[v][3] += rs[v]->C;
        a[v][4] += rs[v]->ate_m;
        mp[v] += pct(rs[v]->mps, in.original.mps);
        kf[v] += pct(rs[v]->kfs, in.original.kfs);
      }
    }
    for (auto& v : a)
      for (double& x : v) x /= n;
    for (int v = 0; v < 4; ++v) {
      mp[v] /= n;
      kf[v] /= n;
    }
    const double best = std::min({a[0][4], a[1][4], a[2][4], a[3][4]});
    o << "| " << g << " | " << n << " | " << f(a[0][0], 0) << " | " << f(a[0][1], 0) << " | " << f(a[0][2], 2) << " | "
      << bold_if(a[0][4] == best, f(a[0][4], 5)) << " |";
    for (int v = 1; v < 4; ++v)
      o << " " << f(mp[v], 1) << " | " << f(kf[v], 1) << " | " << f(a[v][2], 2) << " | " << f(a[v][3], 2) << " | "
        << bold_if(a[v][4] == best, f(a[v][4], 5)) << " |";
    o << "\n";
  }
  // Table VI: ablation.
  bool any_ablation = false;
  for (const auto& in : ins) any_ablation |= !in.ablation.empty();
  if (any_ablation) {
    o << "\n### Table VI: cost ablation at M=" << (ins.empty() ? 100 : ins[0].op_M)
      << " (as the paper's Table VI; C connections per point, F mean keyframe span per point, S % of a 64x48 grid occupied)\n\n"
         "| Sequence | all C | F | S | ATE (m) | c_c C | F | S | ATE (m) | c_c+c_b C | F | S | ATE (m) | c_c+c_s C | F | S | ATE (m) |\n"
         "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const auto& in : ins) {
      if (in.ablation.size() != 3) continue;
      const RunResult* rs[4] = {&op(in), &in.ablation[0], &in.ablation[2], &in.ablation[1]};
      double best = rs[0]->ate_m;
      for (auto* r : rs) best = std::min(best, r->ate_m);
      o << "| " << in.name << " |";
      for (auto* r : rs)
        o << " " << f(r->C, 2) << " | " << f(r->F, 2) << " | " << f(r->S, 2) << " | " << bold_if(r->ate_m == best, f(r->ate_m, 5)) << " |";
      o << "\n";
    }
  }
  // BAL.
  if (!s.bal.empty()) {
    o << "\n### BAL: sparsify, re-solve, compare with the full solution (Sim(3)-aligned camera poses)\n\n"
         "| Problem | variant | M | points | observations | solve (s) | solve % | iterations | centre RMS | centre RMS / extent % | rot RMS (°) |\n"
         "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const auto& b : s.bal) {
      const std::string name = std::filesystem::path(b.input).filename().string();
      auto row = [&](const BalRun& r) {
        o << "| " << name << " | " << r.variant << " | " << (r.M ? std::to_string(r.M) : "-") << " | " << r.points << " ("
          << f(pct(r.points, b.points), 1) << " %) | " << r.observations << " | " << f(r.solve_s, 3) << " | "
          << f(pct(r.solve_s, b.full.solve_s), 1) << " | " << r.iterations << " | " << f(r.pos_rms, 5) << " | "
          << f(pct(r.pos_rms, b.extent), 3) << " | " << f(r.rot_rms_deg, 4) << " |\n";
      };
      row(b.full);
      for (std::size_t i = 0; i < b.ours.size(); ++i) {
        row(b.ours[i]);
        row(b.random[i]);
      }
    }
  }
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
  csv << "input,name,group,kind,variant,selector,M,cost_terms,keyframes,mps,mps_created,kfs,mp_percent,kf_percent,"
         "ba_s,select_s,total_s,ba_time_percent,time_percent,ba_calls,selector_culled,selector_errors,ate_m,ate_r_deg,C,F,S\n";
  for (const auto& in : s.inputs) {
    std::vector<const RunResult*> rs{&in.original};
    for (const auto& r : in.ours) rs.push_back(&r);
    if (in.has_baselines) {
      rs.push_back(&in.anms);
      rs.push_back(&in.random);
    }
    for (const auto& r : in.ablation) rs.push_back(&r);
    for (const RunResult* r : rs)
      csv << in.input << "," << in.name << "," << in.group << "," << in.kind << "," << r->spec.name << ","
          << to_string(r->spec.selector) << "," << r->spec.M << "," << int(r->spec.cost_terms) << "," << r->kfs_total
          << "," << r->mps << "," << r->mps_created << "," << r->kfs << "," << f(pct(r->mps, in.original.mps), 3) << ","
          << f(pct(r->kfs, in.original.kfs), 3) << "," << f(r->ba_s, 4) << "," << f(r->select_s, 4) << ","
          << f(r->total_s, 4) << "," << f(pct(r->ba_s, in.original.ba_s), 3) << ","
          << f(pct(r->total_s, in.original.total_s), 3) << "," << r->ba_calls << "," << r->selector_culled << ","
          << r->selector_errors << "," << f(r->ate_m, 6) << "," << f(r->ate_r_deg, 6) << "," << f(r->C, 3) << ","
          << f(r->F, 3) << "," << f(r->S, 3) << "\n";
  }
  for (const auto& b : s.bal) {
    std::vector<const BalRun*> rs{&b.full};
    for (std::size_t i = 0; i < b.ours.size(); ++i) {
      rs.push_back(&b.ours[i]);
      rs.push_back(&b.random[i]);
    }
    for (const BalRun* r : rs)
      csv << b.input << ",bal,bal,bal," << r->variant << "," << (r->variant == "ours" ? "keepless" : r->variant == "random" ? "random" : "none")
          << "," << r->M << ",7," << b.cameras << "," << r->points << "," << b.points << "," << b.cameras << ","
          << f(pct(r->points, b.points), 3) << ",100.000," << f(r->solve_s, 4) << "," << f(r->variant == "ours" ? b.sparsify_s : 0, 4)
          << "," << f(r->solve_s, 4) << "," << f(pct(r->solve_s, b.full.solve_s), 3) << ","
          << f(pct(r->solve_s, b.full.solve_s), 3) << ",1,0,0," << f(r->pos_rms, 6) << "," << f(r->rot_rms_deg, 6)
          << ",0,0,0\n";
  }
  bool ok = write("runs.csv", csv.str());
  ok = ok && write("tables.md", "# keepless_eval (" + s.mode + ", seed " + std::to_string(s.seed) + ")\n\n`" +
                                    s.command + "`\n\n" + markdown_tables(s));
  if (!s.inputs.empty()) {
    ok = ok && write("ate_vs_kept.svg", svg_ate_vs_kept(s));
    ok = ok && write("time_vs_M.svg", svg_time_vs_M(s));
    // One frame's keypoints: a real image if there is one.
    const InputReport* pick = nullptr;
    for (const auto& in : s.inputs)
      if (in.has_baselines && !op(in).snapshot.empty() && (!pick || in.kind == "images")) pick = &in;
    if (pick) ok = ok && write("keypoints_ours_vs_anms.svg", svg_keypoints(*pick));
  }
  return ok;
}

std::string json_summary(const EvalSummary& s) {
  std::ostringstream o;
  o << "{\"tool\":\"keepless_eval\",\"mode\":" << jstr(s.mode) << ",\"seed\":" << s.seed << ",\"M\":[";
  for (std::size_t i = 0; i < s.Ms.size(); ++i) o << (i ? "," : "") << s.Ms[i];
  o << "],\"inputs\":[";
  bool first = true;
  // Per-group tallies for the claims.
  std::map<std::string, std::array<double, 4>> grp;  // ours, anms, random, count
  double sum_mp = 0, sum_ba = 0, sum_ratio = 0;
  int n_op = 0;
  for (const auto& in : s.inputs) {
    const RunResult& g = in.original;
    const RunResult& r = op(in);
    o << (first ? "" : ",") << "{\"input\":" << jstr(in.input) << ",\"name\":" << jstr(in.name)
      << ",\"group\":" << jstr(in.group) << ",\"kind\":" << jstr(in.kind) << ",\"keyframes\":" << in.keyframes
      << ",\"M\":" << in.op_M << ",\"mps_original\":" << g.mps << ",\"kfs_original\":" << g.kfs
      << ",\"mps_ours\":" << r.mps << ",\"kfs_ours\":" << r.kfs << ",\"mp_percent\":" << jnum(pct(r.mps, g.mps), 3)
      << ",\"kf_percent\":" << jnum(pct(r.kfs, g.kfs), 3) << ",\"ba_time_percent\":" << jnum(pct(r.ba_s, g.ba_s), 3)
      << ",\"time_percent\":" << jnum(pct(r.total_s, g.total_s), 3) << ",\"ate_original_m\":" << jnum(g.ate_m)
      << ",\"ate_ours_m\":" << jnum(r.ate_m) << ",\"ate_anms_m\":" << (in.has_baselines ? jnum(in.anms.ate_m) : "null")
      << ",\"ate_random_m\":" << (in.has_baselines ? jnum(in.random.ate_m) : "null")
      << ",\"ate_r_original_deg\":" << jnum(g.ate_r_deg) << ",\"ate_r_ours_deg\":" << jnum(r.ate_r_deg)
      << ",\"ate_r_anms_deg\":" << (in.has_baselines ? jnum(in.anms.ate_r_deg) : "null")
      << ",\"ate_r_random_deg\":" << (in.has_baselines ? jnum(in.random.ate_r_deg) : "null")
      << ",\"mp_percent_anms\":" << (in.has_baselines ? jnum(pct(in.anms.mps, g.mps), 3) : "null")
      << ",\"mp_percent_random\":" << (in.has_baselines ? jnum(pct(in.random.mps, g.mps), 3) : "null")
      << ",\"selector_errors\":" << r.selector_errors << ",\"per_M\":[";
    for (std::size_t i = 0; i < in.ours.size(); ++i) {
      const RunResult& q = in.ours[i];
      o << (i ? "," : "") << "{\"M\":" << q.spec.M << ",\"mp_percent\":" << jnum(pct(q.mps, g.mps), 3)
        << ",\"kf_percent\":" << jnum(pct(q.kfs, g.kfs), 3) << ",\"ba_time_percent\":" << jnum(pct(q.ba_s, g.ba_s), 3)
        << ",\"time_percent\":" << jnum(pct(q.total_s, g.total_s), 3) << ",\"ate_m\":" << jnum(q.ate_m)
        << ",\"ate_r_deg\":" << jnum(q.ate_r_deg) << "}";
    }
    o << "],\"ablation\":[";
    for (std::size_t i = 0; i < in.ablation.size(); ++i) {
      const RunResult& q = in.ablation[i];
      o << (i ? "," : "") << "{\"costs\":" << jstr(q.spec.name) << ",\"C\":" << jnum(q.C, 4) << ",\"F\":" << jnum(q.F, 4)
        << ",\"S\":" << jnum(q.S, 4) << ",\"ate_m\":" << jnum(q.ate_m) << ",\"mp_percent\":" << jnum(pct(q.mps, g.mps), 3) << "}";
    }
    o << "]}";
    first = false;
    if (g.ate_m > 0) {
      sum_mp += pct(r.mps, g.mps);
      sum_ba += pct(r.ba_s, g.ba_s);
      sum_ratio += r.ate_m / g.ate_m;
      ++n_op;
    }
    if (in.has_baselines && in.kind == "trajectory") {
      auto& t = grp[in.group];
      t[0] += r.ate_m;
      t[1] += in.anms.ate_m;
      t[2] += in.random.ate_m;
      t[3] += 1;
    }
  }
  for (const auto& b : s.bal) {
    for (std::size_t i = 0; i < b.ours.size(); ++i) {
      if (i > 0) break;  // the first M is the operating point
      const BalRun& r = b.ours[i];
      o << (first ? "" : ",") << "{\"input\":" << jstr(b.input) << ",\"name\":\"bal\",\"group\":\"bal\",\"kind\":\"bal\""
        << ",\"keyframes\":" << b.cameras << ",\"M\":" << r.M << ",\"mps_original\":" << b.points
        << ",\"kfs_original\":" << b.cameras << ",\"mps_ours\":" << r.points << ",\"kfs_ours\":" << b.cameras
        << ",\"mp_percent\":" << jnum(pct(r.points, b.points), 3) << ",\"kf_percent\":100.000"
        << ",\"ba_time_percent\":" << jnum(pct(r.solve_s, b.full.solve_s), 3)
        << ",\"time_percent\":" << jnum(pct(r.solve_s + b.sparsify_s, b.full.solve_s), 3)
        << ",\"ate_original_m\":0.000000,\"ate_ours_m\":" << jnum(r.pos_rms) << ",\"ate_anms_m\":null"
        << ",\"ate_random_m\":" << jnum(b.random[i].pos_rms) << ",\"ate_r_original_deg\":0.000000"
        << ",\"ate_r_ours_deg\":" << jnum(r.rot_rms_deg) << ",\"ate_r_random_deg\":" << jnum(b.random[i].rot_rms_deg)
        << ",\"extent\":" << jnum(b.extent) << ",\"solve_s_full\":" << jnum(b.full.solve_s, 4)
        << ",\"solve_s_ours\":" << jnum(r.solve_s, 4) << ",\"sparsify_s\":" << jnum(b.sparsify_s, 4) << "}";
      first = false;
    }
  }
  o << "],\"claims\":{\"M\":" << (s.inputs.empty() ? 0 : s.inputs[0].op_M)
    << ",\"mean_mp_percent\":" << jnum(n_op ? sum_mp / n_op : NAN, 3)
    << ",\"mean_ba_time_percent\":" << jnum(n_op ? sum_ba / n_op : NAN, 3)
    << ",\"mean_ate_ratio\":" << jnum(n_op ? sum_ratio / n_op : NAN, 4) << ",\"groups\":{";
  int beats = 0;
  bool fg = true;
  for (const auto& [name, t] : grp) {
    const bool a = t[0] < t[1], b = t[0] < t[2];
    beats += (a && b) ? 1 : 0;
    o << (fg ? "" : ",") << jstr(name) << ":{\"inputs\":" << int(t[3]) << ",\"ate_ours_m\":" << jnum(t[0] / t[3])
      << ",\"ate_anms_m\":" << jnum(t[1] / t[3]) << ",\"ate_random_m\":" << jnum(t[2] / t[3])
      << ",\"ours_below_anms\":" << (a ? "true" : "false") << ",\"ours_below_random\":" << (b ? "true" : "false") << "}";
    fg = false;
  }
  o << "},\"groups_ours_below_both\":" << beats << ",\"groups_total\":" << grp.size() << "},\"elapsed_s\":"
    << jnum(s.elapsed_s, 2) << "}";
  return o.str();
}

}  // namespace keepless::eval
