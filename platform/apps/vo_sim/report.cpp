#include "report.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace keepless::vo_sim {

std::string format_table(const std::string& title, const SummaryRows& rows) {
  std::size_t w = 0, vw = 0;
  for (const auto& r : rows) {
    w = std::max(w, r.first.size());
    vw = std::max(vw, r.second.size());
  }
  std::string line = "+" + std::string(w + 2, '-') + "+" + std::string(vw + 2, '-') + "+\n";
  std::ostringstream out;
  out << title << "\n" << line;
  for (const auto& r : rows) {
    out << "| " << r.first << std::string(w - r.first.size(), ' ') << " | " << std::string(vw - r.second.size(), ' ')
        << r.second << " |\n";
  }
  out << line;
  return out.str();
}

namespace {

bool make_dir(const std::string& dir, std::string& error) {
  std::string partial;
  std::stringstream ss(dir);
  std::string part;
  if (!dir.empty() && dir[0] == '/') partial = "/";
  while (std::getline(ss, part, '/')) {
    if (part.empty()) continue;
    partial += part + "/";
    if (::mkdir(partial.c_str(), 0755) != 0 && errno != EEXIST) {
      error = partial + ": " + std::strerror(errno);
      return false;
    }
  }
  return true;
}

const char* state_name(PointState s) {
  switch (s) {
    case PointState::kUnseen: return "unseen";
    case PointState::kMapped: return "kept";
    case PointState::kCulled: return "culled";
    case PointState::kDeleted: return "deleted";
  }
  return "?";
}

constexpr const char* kKeptColour = "#1a9850";
constexpr const char* kCulledColour = "#d73027";
constexpr const char* kDeletedColour = "#999999";
constexpr const char* kPathColour = "#2166ac";

void svg_map(std::ostream& o, const World& world, const std::vector<Pose>& path, std::size_t keyframes) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  auto grow = [&](double x, double y) {
    x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
  };
  for (const ScenePoint& p : world.points()) {
    if (p.state != PointState::kUnseen) grow(p.position.x, p.position.y);
  }
  for (std::size_t i = 0; i < keyframes && i < path.size(); ++i) grow(path[i].centre.x, path[i].centre.y);
  if (x0 > x1) x0 = y0 = 0, x1 = y1 = 1;
  const double pad = 0.03 * std::max(x1 - x0, y1 - y0) + 0.5;
  x0 -= pad, y0 -= pad, x1 += pad, y1 += pad;
  const double width = 1000;
  const double scale = width / (x1 - x0);
  const double height = (y1 - y0) * scale;
  const double r = std::max(0.6, std::min(2.0, 0.05 * scale));
  auto px = [&](double x) { return (x - x0) * scale; };
  auto py = [&](double y) { return (y1 - y) * scale; };  // north up
  char buf[160];
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height + 40
    << "\" viewBox=\"0 0 " << width << " " << height + 40 << "\">\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  std::size_t kept = 0, culled = 0, deleted = 0;
  // Culled under kept, so the surviving map reads on top.
  for (PointState pass : {PointState::kDeleted, PointState::kCulled, PointState::kMapped}) {
    const char* colour = pass == PointState::kMapped ? kKeptColour : pass == PointState::kCulled ? kCulledColour : kDeletedColour;
    o << "<g fill=\"" << colour << "\" fill-opacity=\"" << (pass == PointState::kMapped ? "0.8" : "0.45") << "\">\n";
    for (const ScenePoint& p : world.points()) {
      if (p.state != pass) continue;
      (pass == PointState::kMapped ? kept : pass == PointState::kCulled ? culled : deleted)++;
      std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\"/>\n", px(p.position.x), py(p.position.y), r);
      o << buf;
    }
    o << "</g>\n";
  }
  o << "<polyline fill=\"none\" stroke=\"" << kPathColour << "\" stroke-width=\"1.5\" points=\"";
  for (std::size_t i = 0; i < keyframes && i < path.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.1f,%.1f ", px(path[i].centre.x), py(path[i].centre.y));
    o << buf;
  }
  o << "\"/>\n";
  std::snprintf(buf, sizeof buf,
                "<text x=\"10\" y=\"%.0f\" font-family=\"sans-serif\" font-size=\"14\">top-down map: ", height + 25);
  o << buf << "<tspan fill=\"" << kKeptColour << "\">kept " << kept << "</tspan>, <tspan fill=\"" << kCulledColour
    << "\">culled " << culled << "</tspan>";
  if (deleted > 0) o << ", <tspan fill=\"" << kDeletedColour << "\">deleted by the VO " << deleted << "</tspan>";
  o << ", <tspan fill=\"" << kPathColour << "\">camera path</tspan> (" << keyframes << " keyframes, "
    << static_cast<int>(x1 - x0) << " m across)</text>\n</svg>\n";
}

void svg_keyframe(std::ostream& o, const World& world, const SnapshotKeyframe& snap) {
  const Camera& cam = world.camera();
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << cam.width << "\" height=\"" << cam.height + 30
    << "\" viewBox=\"0 0 " << cam.width << " " << cam.height + 30 << "\">\n";
  o << "<rect width=\"" << cam.width << "\" height=\"" << cam.height << "\" fill=\"#202020\"/>\n";
  std::size_t kept = 0, culled = 0, other = 0;
  char buf[160];
  for (const SimObservation& ob : snap.observations) {
    const ScenePoint& p = world.points()[ob.point];
    const bool is_kept = p.state == PointState::kMapped;
    const bool is_culled = p.state == PointState::kCulled;
    (is_kept ? kept : is_culled ? culled : other)++;
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"2.2\" fill=\"%s\"/>\n", ob.u, ob.v,
                  is_kept ? "#66ff66" : is_culled ? "#ff4444" : "#aaaaaa");
    o << buf;
  }
  o << "<text x=\"8\" y=\"" << cam.height + 20 << "\" font-family=\"sans-serif\" font-size=\"13\">keyframe "
    << snap.index << ": " << snap.observations.size() << " keypoints; their map points at the end: <tspan fill=\""
    << kKeptColour << "\">" << kept << " kept</tspan>, <tspan fill=\"" << kCulledColour << "\">" << culled
    << " culled</tspan>";
  if (other > 0) o << ", <tspan fill=\"" << kDeletedColour << "\">" << other << " deleted by the VO</tspan>";
  o << "</text>\n</svg>\n";
}

}  // namespace

bool write_report(const std::string& dir, const World& world, const std::vector<Pose>& path,
                  const std::vector<KeyframeRecord>& records, const SnapshotKeyframe& snapshot,
                  const std::string& summary_text, std::string& error) {
  if (!make_dir(dir, error)) return false;
  auto open = [&](const std::string& name, std::ofstream& f) {
    f.open(dir + "/" + name);
    if (!f) error = dir + "/" + name + ": cannot write";
    return static_cast<bool>(f);
  };
  {
    std::ofstream f;
    if (!open("keyframes.csv", f)) return false;
    f << "index,sequence,keyframe_id,x,y,z,detected,observations,new_points,answered,status,window_keyframes,"
         "window_points,evaluated,kept,culled,skipped,latency_ms,node_total_ms,node_sparsify_ms,"
         "mapped_points,alive_points\n";
    char buf[512];
    for (const KeyframeRecord& r : records) {
      std::snprintf(buf, sizeof buf, "%d,%lld,%lld,%.3f,%.3f,%.3f,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d,%.4f,%.4f,%.4f,%lld,%lld\n",
                    r.index, static_cast<long long>(r.sequence), static_cast<long long>(r.keyframe_id), r.centre.x,
                    r.centre.y, r.centre.z, r.detected, r.observations, r.new_points, r.answered ? 1 : 0, r.status,
                    r.window_keyframes, r.window_points, r.evaluated, r.kept, r.culled, r.skipped, r.latency_ms,
                    r.node_total_ms, r.node_sparsify_ms, static_cast<long long>(r.mapped_points),
                    static_cast<long long>(r.alive_points));
      f << buf;
    }
    if (!f) return error = dir + "/keyframes.csv: write failed", false;
  }
  {
    std::ofstream f;
    if (!open("points.csv", f)) return false;
    f << "feature,x,y,z,kind,state,map_point_id,map_ids_issued,first_keyframe,observations\n";
    char buf[256];
    for (std::size_t i = 0; i < world.points().size(); ++i) {
      const ScenePoint& p = world.points()[i];
      if (p.state == PointState::kUnseen) continue;
      std::snprintf(buf, sizeof buf, "%zu,%.3f,%.3f,%.3f,%s,%s,%lld,%d,%d,%d\n", i, p.position.x, p.position.y,
                    p.position.z, to_string(p.kind), state_name(p.state), static_cast<long long>(p.landmark),
                    p.landmarks, p.first_keyframe, p.observations);
      f << buf;
    }
    if (!f) return error = dir + "/points.csv: write failed", false;
  }
  {
    std::ofstream f;
    if (!open("map_topdown.svg", f)) return false;
    svg_map(f, world, path, records.size());
  }
  if (snapshot.index >= 0) {
    std::ofstream f;
    char name[64];
    std::snprintf(name, sizeof name, "keyframe_%04d.svg", snapshot.index);
    if (!open(name, f)) return false;
    svg_keyframe(f, world, snapshot);
  }
  {
    std::ofstream f;
    if (!open("summary.txt", f)) return false;
    f << summary_text;
  }
  return true;
}

}  // namespace keepless::vo_sim
