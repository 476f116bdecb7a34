#include "model_run.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <new>
#include <numeric>
#include <optional>
#include <string>
#include <utility>

#include <unistd.h>

#include "keepless/core/keep_thresholds.hpp"
#include "keepless/io/atomic_file.hpp"
#include "keepless/io/bal_problem.hpp"
#include "keepless/io/colmap_model.hpp"
#include "keepless/platform/atomic_file_writer.hpp"
#include "keepless/platform/window_file_io.hpp"
#include "keepless/platform/memory_estimate.hpp"
#include "keepless/platform/monotonic_clock.hpp"
#include "keepless/platform/regular_file.hpp"
#include "sparsify/exact_count.hpp"

namespace keepless::sparsify {

namespace {

namespace fs = std::filesystem;

constexpr int kExitInput = 2;
constexpr int kExitInternal = 1;

const char* input_name(Input in) {
  switch (in) {
    case Input::kColmap: return "colmap";
    case Input::kBal: return "bal";
    case Input::kWindow: return "window";
  }
  return "?";
}

double ms_since(std::uint64_t start_ns) {
  return static_cast<double>(platform::monotonic_ns() - start_ns) / 1e6;
}

// A model as read, with its keyframes in replay order and each image's
// observations by point id (duplicates included) in the same order.
struct Loaded {
  io::ColmapModel colmap;
  io::ColmapFormat format = io::ColmapFormat::kBinary;
  io::BalProblem bal;
  core::WindowFile window;
  io::Keyframes keyframes;
  std::vector<std::vector<core::PointId>> images;
  std::uint64_t model_points = 0;
  std::uint64_t compacted = 0;  // 2D points --compact dropped
};

io::ColmapFormat out_format(const ModelOptions& opt, const Loaded& m) {
  if (opt.out_format == "bin") return io::ColmapFormat::kBinary;
  if (opt.out_format == "txt") return io::ColmapFormat::kText;
  return m.format;
}

bool load(const ModelOptions& opt, const core::WindowFileLimits& window_limits, Loaded* m, std::string* error) {
  io::Similarity metric;
  metric.scale = opt.scale;
  if (!opt.sim3.empty() && !io::read_similarity(opt.sim3, &metric, error)) return false;
  switch (opt.input) {
    case Input::kColmap: {
      if (!io::read_colmap_model(opt.path, &m->colmap, &m->format, error)) return false;
      const io::KeyframeOrder order = opt.order_given ? opt.order : io::KeyframeOrder::kName;
      m->keyframes = io::keyframes_from_colmap(m->colmap, order, metric,
                                               opt.params.cost_model == core::CostModel::kAuthors);
      m->images = io::observed_point_ids(m->colmap, m->keyframes);
      m->model_points = m->colmap.points.size();
      return true;
    }
    case Input::kBal: {
      if (!io::read_bal(opt.path, &m->bal, error)) return false;
      m->keyframes = io::keyframes_from_bal(m->bal, io::KeyframeOrder::kFile, metric);
      m->images.resize(m->bal.num_cameras);
      for (const io::BalObservation& o : m->bal.observations) m->images[o.camera].push_back(o.point);
      m->model_points = m->bal.num_points;
      return true;
    }
    case Input::kWindow: {
      if (!platform::read_window_file(opt.path, &m->window, error, window_limits)) return false;
      core::WindowFile& f = m->keyframes.file;
      std::vector<std::size_t> order(m->window.keyframes.size());
      std::iota(order.begin(), order.end(), 0);
      if (opt.order_given && opt.order == io::KeyframeOrder::kId) {
        std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
          return m->window.keyframes[a].id < m->window.keyframes[b].id;
        });
      }
      for (const std::size_t k : order) {
        f.keyframes.push_back(m->window.keyframes[k]);
        f.keyframe_lines.push_back(m->window.keyframe_lines[k]);
        f.observations.push_back(m->window.observations[k]);
        core::Keyframe& kf = f.keyframes.back();
        const double c[3] = {kf.centre[0], kf.centre[1], kf.centre[2]};
        io::to_metric(metric, c, kf.centre);
        std::vector<core::PointId>& ids = m->images.emplace_back();
        for (const core::Observation& o : m->window.observations[k]) ids.push_back(o.point);
      }
      f.needs = m->window.needs;
      m->model_points = f.needs.max_points;
      return true;
    }
  }
  return false;
}

// The readers refuse cameras whose centres are not finite; a --scale or
// --sim3 can still carry one out of range.
bool check_centres(const ModelOptions& opt, const Loaded& m, std::string* error) {
  for (const core::Keyframe& kf : m.keyframes.file.keyframes) {
    if (std::isfinite(kf.centre[0]) && std::isfinite(kf.centre[1]) && std::isfinite(kf.centre[2])) continue;
    *error = opt.path + ":0: image " + std::to_string(kf.id) +
             "'s centre is not finite in metres (--scale or --sim3 out of range)";
    return false;
  }
  return true;
}

// The model's own limits: the window file's reader checks them itself. The
// pair arcs bound the whole mode's one window (a replay window of K images
// holds fewer), and so do a point's views (core::kMaxPointViews).
bool check_limits(const ModelOptions& opt, Mode mode, const Loaded& m, std::string* error) {
  const core::Capacities& n = m.keyframes.file.needs;
  const auto over = [&](std::uint64_t have, std::uint32_t limit, const char* what, const char* flag) {
    if (have <= limit) return false;
    *error = opt.path + ":0: " + std::to_string(have) + " " + what + " exceed " + flag + " " + std::to_string(limit);
    return true;
  };
  if (over(m.keyframes.file.keyframes.size(), opt.limits.max_keyframes, "images", "--max-keyframes") ||
      over(m.model_points, opt.limits.max_points, "points", "--max-points") ||
      over(n.max_observations, opt.limits.max_observations, "observations", "--max-observations") ||
      (mode == Mode::kWhole && opt.input != Input::kWindow &&
       over(n.max_pair_arcs, opt.limits.max_pair_arcs, "pair arcs in the whole mode's window", "--max-pair-arcs"))) {
    return false;
  }
  // A replay window holds K images: only a K above core::kMaxPointViews can
  // hold a point seen by more (checked over the whole model, which is safe).
  if (mode != Mode::kWhole && opt.K <= core::kMaxPointViews) return true;
  std::string why = point_views_refusal(m.keyframes.file, opt.params, opt.path);
  if (why.empty()) return true;
  *error = std::move(why);
  return false;
}

bool is_culled(const std::vector<core::PointDecision>& decisions, core::PointId p) {
  const std::int64_t s = find_decision(decisions, p);
  return s >= 0 && decisions[s].verdict == core::Verdict::kCull;
}

// Writes the sparsified model in the input's format.
bool write_model(const ModelOptions& opt, Loaded* m, const std::vector<core::PointDecision>& decisions,
                 std::string* error) {
  switch (opt.input) {
    case Input::kColmap: {
      std::vector<bool> culled(m->colmap.points.size());
      for (std::size_t i = 0; i < culled.size(); ++i) culled[i] = is_culled(decisions, m->colmap.points[i].id);
      io::remove_points(&m->colmap, culled);
      if (opt.compact) m->compacted = io::compact_points2D(&m->colmap);
      return io::write_colmap_model(opt.out, m->colmap, out_format(opt, *m), error);
    }
    case Input::kBal: {
      std::vector<bool> culled(m->bal.num_points);
      for (std::uint32_t i = 0; i < m->bal.num_points; ++i) culled[i] = is_culled(decisions, i);
      return io::write_file_atomically(opt.out, io::format_bal(io::remove_points(m->bal, culled)), error);
    }
    case Input::kWindow: {
      core::WindowFile out = m->window;  // file order
      for (auto& obs : out.observations) {
        obs.erase(std::remove_if(obs.begin(), obs.end(),
                                 [&](const core::Observation& o) { return is_culled(decisions, o.point); }),
                  obs.end());
      }
      return io::write_file_atomically(opt.out, core::format_window_file(out), error);
    }
  }
  return false;
}

double median(std::vector<std::uint32_t> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 == 1 ? v[h] : 0.5 * (static_cast<double>(v[h - 1]) + v[h]);
}

// 1,234,567
std::string grouped(std::uint64_t v) {
  std::string s = std::to_string(v);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<std::size_t>(i), ",");
  return s;
}

std::uint64_t file_size(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t n = fs::file_size(path, ec);
  return ec ? 0 : static_cast<std::uint64_t>(n);
}

// The files a model is in: COLMAP's three (.bin when all three are there,
// as the reader chooses), else the one file.
std::vector<std::string> model_files(Input input, const std::string& path, const char* ext = nullptr) {
  if (input != Input::kColmap) return {path};
  const auto three = [&](const char* e) {
    return std::vector<std::string>{path + "/cameras." + e, path + "/images." + e, path + "/points3D." + e};
  };
  if (ext != nullptr) return three(ext);
  for (const std::string& f : three("bin")) {
    if (!fs::exists(f)) return three("txt");
  }
  return three("bin");
}

std::uint64_t total_size(const std::vector<std::string>& files) {
  std::uint64_t n = 0;
  for (const std::string& f : files) n += file_size(f);
  return n;
}

// Whitespace-separated tokens and lines of the files, read in chunks
// (nothing held); a file that cannot be opened counts none (reading it
// reports why).
struct TextCounts {
  std::uint64_t tokens = 0, lines = 0;
};
TextCounts count_text(const std::vector<std::string>& files) {
  TextCounts c;
  char buf[1 << 16];
  for (const std::string& f : files) {
    platform::RegularFile file;
    std::string problem;
    if (!platform::open_regular_file(f, &file, &problem)) continue;
    bool in_token = false;
    for (;;) {
      const ssize_t n = ::read(file.fd, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      for (ssize_t i = 0; i < n; ++i) {
        const bool blank = buf[i] == ' ' || buf[i] == '\n' || buf[i] == '\t' || buf[i] == '\r';
        c.tokens += !blank && !in_token;
        c.lines += buf[i] == '\n';
        in_token = !blank;
      }
    }
  }
  return c;
}

// a is b or lies inside it (both resolved).
bool within(const fs::path& a, const fs::path& b) {
  auto ai = a.begin();
  for (auto bi = b.begin(); bi != b.end(); ++bi, ++ai) {
    if (bi->empty()) continue;  // a trailing separator
    if (ai == a.end() || *ai != *bi) return false;
  }
  return true;
}

// --out may not be the input, hold it or lie inside it (resolved: "./m",
// "m/" and links count), so a typo never overwrites the model it reads.
bool out_is_safe(const ModelOptions& opt, std::string* error) {
  std::error_code ec;
  const fs::path in = fs::weakly_canonical(opt.path, ec);
  if (ec) return true;  // the reader names the problem
  const fs::path out = fs::weakly_canonical(opt.out, ec);
  if (ec) return true;
  const char* how = out == in ? "is" : within(in, out) ? "contains" : within(out, in) ? "lies inside" : nullptr;
  if (how == nullptr) return true;
  *error = opt.out + ": --out " + how + " the input " + opt.path + "; write the sparsified map elsewhere";
  return false;
}

// The same file: one resolved path, or one inode (a hard link).
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  const fs::path ra = fs::weakly_canonical(a, ec);
  if (ec) return false;
  const fs::path rb = fs::weakly_canonical(b, ec);
  if (ec) return false;
  return ra == rb || fs::equivalent(ra, rb, ec);
}

}  // namespace

std::string format_decisions(const core::PointDecision* decisions, std::size_t n) {
  std::string s;
  char line[96];
  for (std::size_t i = 0; i < n; ++i) {
    const core::PointDecision& d = decisions[i];
    const int len = std::snprintf(line, sizeof line, "%" PRIu64 " %s %" PRId64 " %" PRId64 "\n", d.point,
                                  core::to_string(d.verdict), d.flow, d.capacity);
    s.append(line, static_cast<std::size_t>(len));
  }
  return s;
}

bool outputs_are_safe(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs, std::string* error) {
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    for (const NamedPath& in : inputs) {
      if (!same_file(outputs[o].path, in.path)) continue;
      *error = outputs[o].path + ": " + outputs[o].flag + " is the input " + in.flag + " " + in.path +
               "; write it elsewhere";
      return false;
    }
    for (std::size_t p = 0; p < o; ++p) {
      if (!same_file(outputs[o].path, outputs[p].path)) continue;
      *error = outputs[o].path + ": " + outputs[o].flag + " and " + outputs[p].flag + " name the same file";
      return false;
    }
  }
  return true;
}

namespace {

// When memory runs out below --max-memory-mb: the address space
// (ulimit -v) or the machine has less than the estimate.
std::string out_of_memory(const std::string& path, const char* stage, double need_bytes, std::uint64_t limit_mb) {
  char b[512];
  std::snprintf(b, sizeof b,
                "%s: out of memory while %s (about %.0f MiB needed; --max-memory-mb %llu allowed it, but the process "
                "got less: check `ulimit -v` and free memory, or lower the need with --mode replay or a smaller --K)",
                path.c_str(), stage, need_bytes / 1048576.0, static_cast<unsigned long long>(limit_mb));
  return b;
}

// Images that keep fewer than COLMAP's registration minimum of
// observations (kDefaultFloor, Mapper.abs_pose_min_num_inliers = 30).
void warn_thin_images(const Loaded& m, const std::vector<core::PointDecision>& decisions) {
  const std::vector<std::uint32_t> now = kept_observations(m.images, decisions);
  std::size_t thin = 0, thin_before = 0, worst = 0;
  for (std::size_t i = 0; i < now.size(); ++i) {
    if (now[i] >= kDefaultFloor) continue;
    ++thin;
    thin_before += m.images[i].size() < kDefaultFloor;
    if (now[i] < now[worst] || now[worst] >= kDefaultFloor) worst = i;
  }
  if (thin == 0) return;
  std::string image = "#" + std::to_string(worst + 1);
  if (!m.colmap.images.empty()) {
    const core::KeyframeId id = m.keyframes.file.keyframes[worst].id;
    for (const io::ColmapImage& im : m.colmap.images) {
      if (im.id == id) image = im.name;
    }
  }
  std::fprintf(stderr,
               "keepless_sparsify: warning: %zu of %zu images keep fewer than %u observations (fewest: %u, image %s)"
               "%s; COLMAP registers an image from %u (Mapper.abs_pose_min_num_inliers): raise "
               "--min-obs-per-image or --M\n",
               thin, now.size(), kDefaultFloor, now[worst], image.c_str(),
               thin_before == thin ? ", all of them had fewer already" : "", kDefaultFloor);
}

// Below the smallest M whose sparsified COLMAP model kept the full model's
// accuracy in the evidence (the KITTI 06 fixture, perf/maps).
void warn_low_m(std::int64_t M) {
  std::fprintf(stderr,
               "keepless_sparsify: warning: M = %lld is below %lld, the smallest M at which a sparsified COLMAP test "
               "model (KITTI 06, 51 images) kept the full model's accuracy after colmap bundle_adjuster; at M = 100 "
               "its ATE rose from 0.024 to 0.033 m and bundle_adjuster stopped at its 100-iteration limit: check the "
               "result, and give bundle_adjuster more iterations (--BundleAdjustment.max_num_iterations)\n",
               static_cast<long long>(M), static_cast<long long>(kEvidenceM));
}

std::string mebibytes(double bytes) {
  char b[32];
  std::snprintf(b, sizeof b, "%.0f MiB", bytes / 1048576.0);
  return b;
}

}  // namespace

bool parse_map_flag(const std::string& flag, const char* value, ModelOptions* opt, std::string* error) {
  const std::string v = value;
  const std::string bad = "bad value for " + flag + ": '" + v + "'";
  std::uint64_t n = 0;
  error->clear();
  if (flag == "--colmap" || flag == "--bal") {
    if (v.empty() || !opt->path.empty()) *error = bad + " (one input)";
    opt->path = v;
    opt->input = flag == "--colmap" ? Input::kColmap : Input::kBal;
  } else if (flag == "--out" || flag == "--sim3") {
    if (v.empty()) *error = bad;
    (flag == "--out" ? opt->out : opt->sim3) = v;
  } else if (flag == "--out-format") {
    if (v != "bin" && v != "txt") *error = bad + " (bin or txt)";
    opt->out_format = v;
  } else if (flag == "--mode") {
    if (v != "replay" && v != "whole") *error = bad + " (replay or whole)";
    opt->mode = v == "whole" ? Mode::kWhole : Mode::kReplay;
    opt->mode_given = true;
  } else if (flag == "--order") {
    if (v != "name" && v != "id" && v != "file") *error = bad + " (name, id or file)";
    opt->order = v == "id" ? io::KeyframeOrder::kId : (v == "file" ? io::KeyframeOrder::kFile : io::KeyframeOrder::kName);
    opt->order_given = true;
  } else if (flag == "--K" || flag == "--min-obs-per-image") {
    const bool k = flag == "--K";
    if (!core::parse_uint64(value, &n) || n < (k ? 1u : 0u) || n > UINT32_MAX) {
      *error = bad + (k ? " (an integer >= 1)" : " (an integer >= 0)");
    } else if (k) {
      opt->K = static_cast<std::uint32_t>(n);
      opt->K_given = true;
    } else {
      opt->floor = static_cast<std::int64_t>(n);
    }
  } else if (flag == "--scale") {
    if (!core::parse_finite_double(value, &opt->scale) || !(opt->scale > 0)) *error = bad + " (a number > 0)";
    opt->scale_given = true;
  } else if (flag == "--floor-over-longest") {
    double& r = opt->floor_over_longest;
    if (!core::parse_finite_double(value, &r) || !(r == 0 || (r >= 1 && r <= 100))) {
      *error = bad + " (0, or a number in [1, 100])";
    }
  } else {
    return false;
  }
  opt->map_flags = true;
  return true;
}

namespace {

// A path's files as NamedPaths: a COLMAP folder's in both formats (the one
// not read or written is still a model there), else the path itself.
void add_files(const char* flag, Input input, const std::string& path, std::vector<NamedPath>* out) {
  if (input != Input::kColmap) {
    out->push_back({flag, path});
    return;
  }
  for (const char* ext : {"bin", "txt"}) {
    for (const std::string& f : model_files(Input::kColmap, path, ext)) out->push_back({flag, f});
  }
}

// What a run reads and writes, by flag, for outputs_are_safe. A COLMAP
// model's files are both formats' (the one not read is still the user's
// model); a COLMAP --out folder's files are its outputs (--out itself is
// out_is_safe's).
std::vector<NamedPath> model_inputs(const ModelOptions& opt) {
  const char* flag = opt.input == Input::kColmap ? "--colmap" : opt.input == Input::kBal ? "--bal" : "--window";
  std::vector<NamedPath> in;
  add_files(flag, opt.input, opt.path, &in);
  if (!opt.sim3.empty()) in.push_back({"--sim3", opt.sim3});
  return in;
}

// --out's and --decisions' folders, and a file output that is a folder,
// checked before deciding: either would fail the second write after the
// first was done. (A COLMAP --out that is a file, or holds a folder by a
// model file's name, is colmap_model_writable's.)
bool output_paths_usable(const ModelOptions& opt, std::string* error) {
  for (const std::string* p : {&opt.out, &opt.decisions}) {
    if (p->empty()) continue;
    std::error_code ec;
    if (p != &opt.out || opt.input != Input::kColmap) {
      if (fs::is_directory(*p, ec)) {
        *error = *p + ":0: cannot write: it is a folder";
        return false;
      }
    }
    fs::path path(*p);
    if (!path.has_filename()) path = path.parent_path();  // "out/" is the folder out
    const fs::path parent = path.parent_path();
    if (parent.empty() || fs::is_directory(parent, ec)) continue;
    *error = *p + ":0: cannot write: its folder " + parent.string() + " does not exist (create it first)";
    return false;
  }
  return true;
}

std::vector<NamedPath> model_outputs(const ModelOptions& opt) {
  std::vector<NamedPath> out;
  if (!opt.decisions.empty()) out.push_back({"--decisions", opt.decisions});
  if (!opt.out.empty()) add_files("--out", opt.input, opt.out, &out);
  return out;
}

}  // namespace

Mode mode_of(const ModelOptions& opt) {
  return opt.mode_given ? opt.mode : (opt.input == Input::kWindow ? Mode::kWhole : Mode::kReplay);
}

int run_model(const ModelOptions& opt) {
  if (opt.order_given && opt.order == io::KeyframeOrder::kName && opt.input != Input::kColmap) {
    std::fprintf(stderr, "keepless_sparsify: --order name needs --colmap (BAL cameras and window keyframes have no names)\n");
    return kExitInput;
  }
  if (!opt.out_format.empty() && opt.input != Input::kColmap) {
    std::fprintf(stderr, "keepless_sparsify: --out-format applies to --colmap only\n");
    return kExitInput;
  }
  // Flags that would change nothing are refused, not ignored.
  if (!opt.out_format.empty() && opt.out.empty()) {
    std::fprintf(stderr, "keepless_sparsify: --out-format needs --out (it is the written model's format)\n");
    return kExitInput;
  }
  if (opt.scale_given && !opt.sim3.empty()) {
    std::fprintf(stderr, "keepless_sparsify: give --scale or --sim3, not both (the similarity holds its own scale)\n");
    return kExitInput;
  }
  if (opt.K_given && mode_of(opt) == Mode::kWhole) {
    std::fprintf(stderr, "keepless_sparsify: --K applies to --mode replay (whole mode decides all images in one window)\n");
    return kExitInput;
  }
  if (opt.compact && (opt.input != Input::kColmap || opt.out.empty())) {
    std::fprintf(stderr, "keepless_sparsify: --compact applies to --colmap with --out only\n");
    return kExitInput;
  }
  std::string error;
  if ((!opt.out.empty() && !out_is_safe(opt, &error)) ||
      !outputs_are_safe(model_inputs(opt), model_outputs(opt), &error) || !output_paths_usable(opt, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return kExitInput;
  }
  const Mode mode = mode_of(opt);
  std::uint32_t floor = opt.floor >= 0 ? static_cast<std::uint32_t>(opt.floor)
                                       : (opt.input == Input::kWindow ? 0 : kDefaultFloor);

  // --max-memory-mb, estimated before allocating: reading a COLMAP or BAL
  // model holds its files and the parsed model (ReadCost: per byte, and per
  // token and line of a text model, counted first); a window file is checked record
  // by record by its reader (whole mode: with the decision's memory too;
  // replay: after reading, below).
  const double limit = static_cast<double>(opt.max_memory_mb) * 1048576.0;
  const std::vector<std::string> inputs = model_files(opt.input, opt.path);
  const std::uint64_t input_bytes = total_size(inputs);
  const bool text = opt.input == Input::kBal || (opt.input == Input::kColmap && inputs[0].size() > 4 &&
                                                 inputs[0].compare(inputs[0].size() - 4, 4, ".txt") == 0);
  const ReadCost cost = opt.input == Input::kBal ? kBalRead : (text ? kColmapTextRead : kColmapBinaryRead);
  const TextCounts counts = text ? count_text(inputs) : TextCounts{};
  const double read_need = opt.input == Input::kWindow ? 0.0
                                                       : cost.per_byte * static_cast<double>(input_bytes) +
                                                             cost.per_token * static_cast<double>(counts.tokens) +
                                                             cost.per_line * static_cast<double>(counts.lines);
  if (read_need > limit) {
    const std::string words =
        text ? ", " + grouped(counts.tokens) + " numbers and names on " + grouped(counts.lines) + " lines" : "";
    std::fprintf(stderr, "%s: reading this model needs about %s (its %s bytes of files%s), above --max-memory-mb %llu\n",
                 opt.path.c_str(), mebibytes(read_need).c_str(), grouped(input_bytes).c_str(), words.c_str(),
                 static_cast<unsigned long long>(opt.max_memory_mb));
    return kExitInput;
  }
  core::WindowFileLimits window_limits = opt.limits;
  window_limits.max_bytes = opt.max_memory_mb << 20;
  const platform::MemoryModel whole_model = platform::probe_memory_model(opt.params, core::SolveMode::kFromScratch, 1);
  window_limits.solve_bytes = [&](const core::Capacities& c) { return mode == Mode::kWhole ? whole_model.bytes(c) : 0.0; };

  const std::uint64_t t_parse = platform::monotonic_ns();
  Loaded m;
  try {
    if (!load(opt, window_limits, &m, &error) || !check_limits(opt, mode, m, &error) ||
        !check_centres(opt, m, &error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return kExitInput;
    }
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "%s\n", out_of_memory(opt.path, "reading it", read_need, opt.max_memory_mb).c_str());
    return kExitInput;
  }
  const double parse_ms = ms_since(t_parse);

  // The authors' grid lies over the image: COLMAP's cameras give its size
  // when they all share one and --image was not given.
  core::Params params = opt.params;
  if (!opt.image_given && opt.input == Input::kColmap && !m.colmap.cameras.empty()) {
    const io::ColmapCamera& c = m.colmap.cameras.front();
    const bool one_size = std::all_of(m.colmap.cameras.begin(), m.colmap.cameras.end(), [&](const io::ColmapCamera& o) {
      return o.width == c.width && o.height == c.height;
    });
    if (one_size && c.width >= 1 && c.height >= 1 && c.width <= INT32_MAX && c.height <= INT32_MAX) {
      params.image_width = static_cast<std::int32_t>(c.width);
      params.image_height = static_cast<std::int32_t>(c.height);
    }
  }
  // The decision's windows and sparsifier, on top of the model still held.
  const double decide_need = read_need + decision_bytes(m.keyframes.file, mode, params, opt.K);
  if (decide_need > limit) {
    const std::string why = mode == Mode::kWhole
                                ? "all " + std::to_string(m.keyframes.file.keyframes.size()) +
                                      " images in one whole-mode window; --mode replay needs far less"
                                : "replay windows of " + std::to_string(opt.K) + " images; a smaller --K needs less";
    std::fprintf(stderr, "%s: deciding needs about %s (%s), above --max-memory-mb %llu\n", opt.path.c_str(),
                 mebibytes(decide_need).c_str(), why.c_str(), static_cast<unsigned long long>(opt.max_memory_mb));
    return kExitInput;
  }
  const std::uint64_t t_solve = platform::monotonic_ns();
  ModeResult r;
  core::Status s = core::Status::kOk;
  try {
    s = decide(m.keyframes.file, mode, params, opt.K, &r);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "%s\n", out_of_memory(opt.path, "deciding it", decide_need, opt.max_memory_mb).c_str());
    return kExitInput;
  }
  const double solve_ms = ms_since(t_solve);
  if (s != core::Status::kOk) {
    std::fprintf(stderr, "keepless_sparsify: %s failed: %s\n", to_string(mode), core::to_string(s));
    return kExitInternal;
  }
  // Whole mode with a count: a floor that binds takes its points from within
  // the count (the order's last make way), so the count stays exact; a track
  // share ranks by the model's track length (the window holds an image's
  // observation of a point once), floor or not.
  std::uint64_t count = 0;
  for (const core::PointDecision& d : r.decisions) count += d.verdict != core::Verdict::kCull;
  const bool whole_count = mode == Mode::kWhole && core::keeps_a_count(params.budget.kind);
  if (whole_count && opt.floor_over_longest > 0) {
    floor = std::max(floor, floor_over(opt.floor_over_longest, longest_tracks_poorest(m.images, r.decisions, count)));
  }
  std::uint32_t restored = apply_floor(m.images, floor, &r.decisions);
  bool floor_fits = true;
  const double share = core::track_share_at(params.budget, count, r.decisions.size());
  if ((restored > 0 || share > 0.0) && whole_count) {
    const ExactCount e = keep_exactly(m.images, floor, count, r.thresholds, &r.decisions, share);
    restored = e.restored;
    floor_fits = e.floor_fits;
  }
  const std::vector<std::uint32_t> per_image = kept_observations(m.images, r.decisions);
  const double time_ms = ms_since(t_solve);
  std::uint32_t culled = 0, kept = 0;
  for (const core::PointDecision& d : r.decisions) {
    culled += d.verdict == core::Verdict::kCull;
    kept += d.verdict == core::Verdict::kKeep;
  }

  // The model's refusals come before any output is written: a refused run
  // leaves an earlier decisions file as it was.
  if (!opt.out.empty() && opt.input == Input::kColmap &&
      !io::colmap_model_writable(opt.out, m.colmap, out_format(opt, m), &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return kExitInput;
  }
  // The decisions are staged (written whole under a temporary name) before
  // the model is written and renamed into place only after it: a model that
  // cannot be written (a folder without write access, a name too long)
  // leaves an earlier decisions file as it was.
  std::optional<platform::AtomicFileWriter> staged;
  const auto decisions_failed = [&opt](int err) {
    std::fprintf(stderr, "%s:0: cannot write: %s\n", opt.decisions.c_str(), std::strerror(err));
    return kExitInput;
  };
  if (!opt.decisions.empty()) {
    staged.emplace(opt.decisions);
    // commit() reports the open's or write's failure, PATH unchanged.
    if (!staged->write(format_decisions(r.decisions.data(), r.decisions.size()))) {
      return decisions_failed(staged->commit());
    }
  }
  if (!opt.out.empty() && !write_model(opt, &m, r.decisions, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return kExitInput;  // the staged decisions are removed unwritten
  }
  if (staged) {
    if (const int err = staged->commit(); err != 0) return decisions_failed(err);
  }
  // Warnings once all is written (an error stays the only stderr line).
  warn_thin_images(m, r.decisions);
  if (!floor_fits) {
    std::fprintf(stderr,
                 "keepless_sparsify: warning: the floor of %u observations per image alone needs more than the count of "
                 "%" PRIu64 " points: %u kept for it, none by the order\n",
                 floor, count - r.totals.skipped, restored);  // the count asked for: the skipped stay on top
  }
  // A keep budget sets the count directly: M does not apply.
  if (opt.input == Input::kColmap && params.budget.kind == core::BudgetKind::kNone && params.pair_capacity < kEvidenceM) {
    warn_low_m(params.pair_capacity);
  }

  // One kept figure: the points the sparsified model holds, i.e. not
  // culled (judged and kept, plus points never judged: seen in fewer than
  // two images of every window, which stay as they are).
  const std::uint64_t points_kept = m.model_points - culled;
  const std::uint64_t never_judged = points_kept - kept;
  const std::uint64_t output_bytes =
      opt.out.empty() ? 0
                      : total_size(model_files(opt.input, opt.out,
                                               opt.input == Input::kColmap ? io::extension(out_format(opt, m)) : nullptr));
  const std::uint32_t min_obs = per_image.empty() ? 0 : *std::min_element(per_image.begin(), per_image.end());
  const double med_obs = median(per_image);
  const io::KeyframeOrder order =
      opt.order_given ? opt.order : (opt.input == Input::kColmap ? io::KeyframeOrder::kName : io::KeyframeOrder::kFile);
  std::printf("%s", to_string(mode));
  if (mode == Mode::kReplay) std::printf(" (K = %u, order %s)", opt.K, io::to_string(order));
  std::printf(": kept %" PRIu64 " of %" PRIu64 " points (%.2f %%", points_kept, m.model_points,
              m.model_points ? 100.0 * points_kept / m.model_points : 100.0);
  if (never_judged > 0) std::printf("; %" PRIu64 " of them never judged, seen in under two images of any window", never_judged);
  std::printf("), observations per image min %u median %g, %.3f s\n", min_obs, med_obs, time_ms / 1e3);
  std::printf("input %s bytes", grouped(input_bytes).c_str());
  if (!opt.out.empty()) {
    std::printf(", output %s bytes (%.1f %%)", grouped(output_bytes).c_str(),
                input_bytes ? 100.0 * static_cast<double>(output_bytes) / static_cast<double>(input_bytes) : 0.0);
    if (opt.compact) std::printf(", %s unmatched 2D points dropped", grouped(m.compacted).c_str());
  }
  std::printf("\n");

  char theta[32], over_longest[32];
  *std::to_chars(theta, theta + sizeof theta - 1, opt.params.theta).ptr = '\0';
  *std::to_chars(over_longest, over_longest + sizeof over_longest - 1, opt.floor_over_longest).ptr = '\0';
  const core::Summary& t = r.totals;
  std::printf(
      "{\"keyframes\":%u,\"points\":%u,\"evaluated\":%u,\"kept\":%" PRIu64 ",\"culled\":%u,"
      "\"skipped\":%u,\"pairs\":%u,\"arcs\":%u,\"max_flow\":%" PRId64 ",\"total_cost\":%" PRId64
      ",\"M\":%" PRId64 ",\"theta\":%s,\"box_width\":%d,\"box_height\":%d,"
      "\"parse_ms\":%.3f,\"build_ms\":0,\"solve_ms\":%.3f,\"memory_bytes\":%zu,"
      "\"input\":\"%s\",\"format\":\"%s\",\"mode\":\"%s\",\"K\":%u,\"order\":\"%s\",\"slides\":%u,"
      "\"images\":%zu,\"model_points\":%" PRIu64 ",\"points_kept\":%" PRIu64 ",\"kept_fraction\":%.6f,"
      "\"min_obs_per_image\":%u,\"median_obs_per_image\":%g,\"obs_floor\":%u,\"floor_over_longest\":%s,\"floor_restored\":%u,"
      "\"duplicate_observations\":%" PRIu64 ",\"time_ms\":%.3f,"
      "\"scope\":\"%s\",\"floor\":%u,\"cost\":\"%s\",\"out_of_scope\":%u,"
      "\"floor_keyframes\":%u,\"floor_promoted\":%u,\"floor_short\":%u,"
      "\"input_bytes\":%" PRIu64 ",\"output_bytes\":%" PRIu64 ",\"points2D_dropped\":%" PRIu64 ","
      "\"maturity\":%u,\"guarded\":%u,\"track_fallback\":%u,\"track_share_from\":%g,\"track_share_to\":%g,\"track_share\":%g,"
      "\"budget\":\"%s\",\"budget_value\":%s}\n",
      t.keyframes, t.points, t.evaluated, points_kept, culled, t.skipped, t.pairs, t.arcs, t.max_flow, t.total_cost,
      opt.params.pair_capacity, theta, opt.params.box_width, opt.params.box_height, parse_ms, solve_ms,
      r.memory_bytes, input_name(opt.input),
      opt.input == Input::kColmap ? io::extension(m.format) : (opt.input == Input::kBal ? "bal" : "window"),
      to_string(mode), mode == Mode::kReplay ? opt.K : t.keyframes, io::to_string(order), r.slides,
      m.images.size(), m.model_points, points_kept,
      m.model_points ? static_cast<double>(points_kept) / static_cast<double>(m.model_points) : 1.0, min_obs,
      med_obs, floor, over_longest, restored, m.keyframes.duplicates, time_ms, core::to_string(opt.params.scope),
      opt.params.coverage_floor, core::to_string(opt.params.cost_model), t.out_of_scope, t.floor_keyframes,
      t.floor_promoted, t.floor_short, input_bytes, output_bytes, m.compacted,
      opt.params.maturity_keyframes, t.guarded, t.track_fallback, opt.params.budget.track_share_from,
      opt.params.budget.track_share_to, opt.params.budget.track_share, core::to_string(opt.params.budget.kind),
      budget_value(opt.params.budget).c_str());
  return std::fflush(stdout) == 0 ? 0 : kExitInternal;
}

}  // namespace keepless::sparsify
