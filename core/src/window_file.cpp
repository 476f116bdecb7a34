#include "keepless/core/window_file.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <cstring>
#include <limits>
#include <iterator>
#include <unordered_map>
#include <unordered_set>

namespace keepless::core {

static_assert(sizeof(unsigned long long) == sizeof(std::uint64_t), "strtoull must be 64-bit");

namespace {

enum class NumberError { kOk, kMalformed, kNegative, kOverflow, kNonFinite, kOutOfRange };

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

NumberError read_uint64(const char* text, std::uint64_t* out) {
  if (text[0] == '-') return NumberError::kNegative;
  // strtoull alone would accept a sign, leading spaces and "-1" (wrapping it).
  if (!is_digit(text[0])) return NumberError::kMalformed;
  for (const char* c = text; *c != '\0'; ++c) {
    if (!is_digit(*c)) return NumberError::kMalformed;
  }
  errno = 0;
  char* end = nullptr;
  const unsigned long long value = std::strtoull(text, &end, 10);
  if (errno == ERANGE) return NumberError::kOverflow;
  if (end == text || *end != '\0') return NumberError::kMalformed;
  *out = static_cast<std::uint64_t>(value);
  return NumberError::kOk;
}

NumberError read_double(const char* text, double* out) {
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0') return NumberError::kMalformed;
  // glibc sets ERANGE for a subnormal result too; that is a finite double.
  // Out of range: an overflow, or an underflow all the way to 0.
  if (errno == ERANGE && (value == 0.0 || std::fabs(value) > 1.0)) return NumberError::kOutOfRange;
  if (!std::isfinite(value)) return NumberError::kNonFinite;
  // Plain decimal only: strtod would also take hex floats.
  for (const char* c = text; *c != '\0'; ++c) {
    if (!is_digit(*c) && *c != '+' && *c != '-' && *c != '.' && *c != 'e' && *c != 'E') {
      return NumberError::kMalformed;
    }
  }
  *out = value;
  return NumberError::kOk;
}

// A token as shown in an error: bounded, so one bad line gives one short line.
std::string shown(const char* token) {
  constexpr std::size_t kMax = 40;
  const std::size_t n = std::strlen(token);
  if (n <= kMax) return "'" + std::string(token) + "'";
  return "'" + std::string(token, kMax) + "...'";
}

std::string id_problem(const char* what, const char* token, NumberError e) {
  switch (e) {
    case NumberError::kNegative:
      return std::string("negative ") + what + " " + shown(token);
    case NumberError::kOverflow:
      return std::string(what) + " " + shown(token) + " exceeds 2^64-1";
    default:
      return std::string("malformed ") + what + " " + shown(token) + " (unsigned decimal expected)";
  }
}

std::string number_problem(const char* what, const char* token, NumberError e) {
  switch (e) {
    case NumberError::kNonFinite:
      return std::string("non-finite ") + what + " " + shown(token);
    case NumberError::kOutOfRange:
      return std::string(what) + " " + shown(token) + " out of double range";
    default:
      return std::string("malformed ") + what + " " + shown(token);
  }
}

// (keyframe index, point index) -> one 64-bit key; both are < 2^32 because
// the limits are 32-bit.
std::uint64_t observation_key(std::uint32_t kf_index, std::uint32_t point_index) {
  return (static_cast<std::uint64_t>(kf_index) << 32) | point_index;
}

void append_double(std::string* s, double x) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);  // shortest round trip
  s->append(buf, r.ptr);
}

void append_uint(std::string* s, std::uint64_t x) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  s->append(buf, r.ptr);
}

}  // namespace

void append_window_keyframe(std::string* s, const Keyframe& kf, const std::vector<Observation>& obs) {
  s->append("kf ");
  append_uint(s, kf.id);
  for (double c : kf.centre) {
    s->push_back(' ');
    append_double(s, c);
  }
  const double* q = kf.orientation;
  // Bit-exact identity: a -0 component must be written to round-trip.
  const auto plus_zero = [](double x) { return x == 0.0 && !std::signbit(x); };
  if (!(q[0] == 1.0 && plus_zero(q[1]) && plus_zero(q[2]) && plus_zero(q[3]))) {
    for (int i = 0; i < 4; ++i) {
      s->push_back(' ');
      append_double(s, q[i]);
    }
  }
  s->push_back('\n');
  for (const Observation& o : obs) {
    s->append("obs ");
    append_uint(s, kf.id);
    s->push_back(' ');
    append_uint(s, o.point);
    s->push_back(' ');
    append_double(s, o.u);
    s->push_back(' ');
    append_double(s, o.v);
    s->push_back('\n');
  }
}

bool parse_uint64(const char* text, std::uint64_t* out) {
  return text != nullptr && read_uint64(text, out) == NumberError::kOk;
}

bool parse_finite_double(const char* text, double* out) {
  return text != nullptr && read_double(text, out) == NumberError::kOk;
}

bool parse_uint64(const std::string& token, std::uint64_t* out) {
  return token.find('\0') == std::string::npos && parse_uint64(token.c_str(), out);
}

bool parse_finite_double(const std::string& token, double* out) {
  return token.find('\0') == std::string::npos && parse_finite_double(token.c_str(), out);
}

bool parse_box(const char* text, int* width, int* height) {
  if (text == nullptr) return false;
  const char* x = std::strchr(text, 'x');
  if (x == nullptr || std::strchr(x + 1, 'x') != nullptr) return false;
  const std::string w(text, x);
  std::uint64_t wv = 0, hv = 0;
  if (!parse_uint64(w.c_str(), &wv) || !parse_uint64(x + 1, &hv)) return false;
  constexpr std::uint64_t kMax = static_cast<std::uint64_t>(std::numeric_limits<int>::max());
  if (wv > kMax || hv > kMax) return false;
  *width = static_cast<int>(wv);
  *height = static_cast<int>(hv);
  return true;
}

// The parser's bytes per record held (hash-map nodes and buckets, the
// stored observation), estimated for the memory limit.
constexpr double kKeyframeBytes = 160;
constexpr double kPointBytes = 48;
constexpr double kObservationBytes = 24 + 48;

WindowFileParser::WindowFileParser(std::string name, WindowFileLimits limits)
    : name_(std::move(name)), limits_(std::move(limits)) {}

double WindowFileParser::bytes() const {
  return kKeyframeBytes * static_cast<double>(file_.keyframes.size()) +
         kPointBytes * static_cast<double>(points_.size()) +
         kObservationBytes * static_cast<double>(observation_total_) + static_cast<double>(partial_.capacity());
}

bool WindowFileParser::fail(const std::string& reason) {
  if (!failed_) error_ = name_ + ":" + std::to_string(line_no_) + ": " + reason;
  failed_ = true;
  return false;
}

void WindowFileParser::fail_at(std::uint64_t line, const std::string& reason) {
  if (failed_) return;
  line_no_ = line;
  fail(reason);
}

bool WindowFileParser::within_memory() {
  if (limits_.max_bytes == 0 || !limits_.solve_bytes) return true;
  const Capacities needs{static_cast<std::uint32_t>(file_.keyframes.size()),
                         static_cast<std::uint32_t>(points_.size()),
                         static_cast<std::uint32_t>(observation_total_), static_cast<std::uint32_t>(pair_arcs_)};
  const double need = bytes() + limits_.solve_bytes(needs);
  if (need <= static_cast<double>(limits_.max_bytes)) return true;
  char text[160];
  std::snprintf(text, sizeof text, "memory limit exceeded: the window needs about %.0f MiB, above the limit of %.0f MiB",
                need / 1048576.0, static_cast<double>(limits_.max_bytes) / 1048576.0);
  return fail(text);
}

const char* WindowFileParser::line_problem(const char* data, std::size_t size, std::size_t before) {
  // A NUL within the first max_line_bytes decides first, then the length.
  const std::size_t room = limits_.max_line_bytes > before ? limits_.max_line_bytes - before : 0;
  if (std::memchr(data, '\0', std::min(size, room)) != nullptr) return "NUL byte in line";
  if (before + size > limits_.max_line_bytes) {
    too_long_ = "line longer than " + std::to_string(limits_.max_line_bytes) + " bytes";
    return too_long_.c_str();
  }
  return nullptr;
}

bool WindowFileParser::feed(const char* data, std::size_t size) {
  if (failed_) return false;
  if (finished_) return fail("input after the end (finish() was called)");
  const char* const stop = data + size;
  while (data < stop) {
    const char* nl = static_cast<const char*>(std::memchr(data, '\n', static_cast<std::size_t>(stop - data)));
    const char* end = nl != nullptr ? nl : stop;
    const auto piece = static_cast<std::size_t>(end - data);
    // The same verdict as feed_line on the whole line, however it is
    // chunked, and at once, not after gigabytes of it.
    if (const char* problem = line_problem(data, piece, partial_.size())) {
      ++line_no_;
      return fail(problem);
    }
    if (nl == nullptr) {  // the rest of this line comes with the next chunk
      partial_.append(data, piece);
      return true;
    }
    if (partial_.empty()) {
      if (!feed_line(data, piece)) return false;
    } else {
      partial_.append(data, piece);
      const bool ok = feed_line(partial_.data(), partial_.size());
      partial_.clear();
      if (!ok) return false;
    }
    data = nl + 1;
  }
  return true;
}

bool WindowFileParser::feed_line(const char* data, std::size_t size) {
  if (failed_) return false;
  if (finished_) return fail("input after the end (finish() was called)");
  ++line_no_;
  if (const char* problem = line_problem(data, size, 0)) return fail(problem);
  // Tokens are split in place, in a bounded copy of the line.
  char line[4097];
  char* buf = line;
  std::string big;
  if (size + 1 > sizeof line) {
    big.assign(data, size);
    big.push_back('\0');
    buf = big.data();
  } else {
    std::memcpy(line, data, size);
    line[size] = '\0';
  }
  return parse_record(buf, buf + size);
}

bool WindowFileParser::parse_record(char* begin, char* end) {
  if (char* hash = static_cast<char*>(std::memchr(begin, '#', static_cast<std::size_t>(end - begin)))) end = hash;
  constexpr int kMaxTokens = 9;  // kf with orientation
  char* tokens[kMaxTokens];
  int count = 0;
  char* i = begin;
  while (i < end) {
    while (i < end && is_space(*i)) ++i;
    if (i >= end) break;
    char* start = i;
    while (i < end && !is_space(*i)) ++i;
    if (count < kMaxTokens) tokens[count] = start;
    ++count;
    *i = '\0';  // i <= end, and *end is the line's own terminator or '#'
    ++i;
  }
  if (count == 0) return true;
  const int values = count - 1;
  if (std::strcmp(tokens[0], "kf") == 0) return keyframe_record(tokens, values);
  if (std::strcmp(tokens[0], "obs") == 0) {
    if (values != 4) return fail("obs needs 4 values (kf_id point_id u v), got " + std::to_string(values));
    return observation_record(tokens);
  }
  return fail("unknown record " + shown(tokens[0]) + " (expected kf or obs)");
}

bool WindowFileParser::keyframe_record(char** tokens, int values) {
  if (values != 4 && values != 8) {
    return fail("kf needs 4 or 8 values (kf_id cx cy cz [qw qx qy qz]), got " + std::to_string(values));
  }
  Keyframe kf;
  NumberError e = read_uint64(tokens[1], &kf.id);
  if (e != NumberError::kOk) return fail(id_problem("keyframe id", tokens[1], e));
  static const char* const kNames[7] = {"cx", "cy", "cz", "qw", "qx", "qy", "qz"};
  double* const fields[7] = {&kf.centre[0],      &kf.centre[1],      &kf.centre[2],     &kf.orientation[0],
                             &kf.orientation[1], &kf.orientation[2], &kf.orientation[3]};
  for (int f = 0; f < values - 1; ++f) {
    e = read_double(tokens[2 + f], fields[f]);
    if (e != NumberError::kOk) return fail(number_problem(kNames[f], tokens[2 + f], e));
  }
  const double* q = kf.orientation;
  const double norm2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (!(std::fabs(norm2 - 1.0) <= kQuaternionNormTolerance)) {
    char text[96];
    std::snprintf(text, sizeof text, "orientation is not a unit quaternion (|q|^2 = %.6g)", norm2);
    return fail(text);
  }
  const auto found = keyframe_index_.find(kf.id);
  if (found != keyframe_index_.end()) {
    return fail("duplicate keyframe id " + std::to_string(kf.id) + " (first declared on line " +
                std::to_string(file_.keyframe_lines[found->second]) + ")");
  }
  if (file_.keyframes.size() + 1 > limits_.max_keyframes) {
    return fail("capacity exceeded: more than " + std::to_string(limits_.max_keyframes) + " keyframes");
  }
  keyframe_index_.emplace(kf.id, static_cast<std::uint32_t>(file_.keyframes.size()));
  file_.keyframes.push_back(kf);
  file_.keyframe_lines.push_back(line_no_);
  file_.observations.emplace_back();
  return within_memory();
}

bool WindowFileParser::observation_record(char** tokens) {
  std::uint64_t kf_id = 0;
  Observation obs;
  NumberError e = read_uint64(tokens[1], &kf_id);
  if (e != NumberError::kOk) return fail(id_problem("keyframe id", tokens[1], e));
  e = read_uint64(tokens[2], &obs.point);
  if (e != NumberError::kOk) return fail(id_problem("point id", tokens[2], e));
  e = read_double(tokens[3], &obs.u);
  if (e != NumberError::kOk) return fail(number_problem("u", tokens[3], e));
  e = read_double(tokens[4], &obs.v);
  if (e != NumberError::kOk) return fail(number_problem("v", tokens[4], e));

  const auto kf = keyframe_index_.find(kf_id);
  if (kf == keyframe_index_.end()) {
    return fail("unknown keyframe " + std::to_string(kf_id) + " (no kf line before this one)");
  }
  const auto point = points_.find(obs.point);
  const bool new_point = point == points_.end();
  const std::uint32_t point_index = new_point ? static_cast<std::uint32_t>(points_.size()) : point->second.index;
  const std::uint64_t key = observation_key(kf->second, point_index);
  if (!new_point) {
    const auto seen = observed_.find(key);
    if (seen != observed_.end()) {
      return fail("duplicate observation of point " + std::to_string(obs.point) + " by keyframe " +
                  std::to_string(kf_id) + " (first on line " + std::to_string(seen->second) + ")");
    }
  }
  if (observation_total_ + 1 > limits_.max_observations) {
    return fail("capacity exceeded: more than " + std::to_string(limits_.max_observations) + " observations");
  }
  if (new_point && points_.size() + 1 > limits_.max_points) {
    return fail("capacity exceeded: more than " + std::to_string(limits_.max_points) + " distinct points");
  }
  // The n-th view of a point adds n-1 pairs: sum n(n-1)/2 incrementally.
  const std::uint32_t views_before = new_point ? 0 : point->second.views;
  if (pair_arcs_ + views_before > limits_.max_pair_arcs) {
    return fail("capacity exceeded: more than " + std::to_string(limits_.max_pair_arcs) + " pair arcs");
  }
  if (new_point) {
    points_.emplace(obs.point, PointEntry{point_index, 1});
  } else {
    ++point->second.views;
  }
  observed_.emplace(key, line_no_);
  pair_arcs_ += views_before;
  ++observation_total_;
  file_.observations[kf->second].push_back(obs);
  return within_memory();
}

bool WindowFileParser::finish(WindowFile* out) {
  if (finished_) return fail("finish() after the end of the input");
  if (!failed_ && !partial_.empty()) {
    const std::string last = std::move(partial_);
    partial_.clear();
    if (!feed_line(last.data(), last.size())) return false;
  }
  if (failed_) return false;
  file_.needs.max_keyframes = static_cast<std::uint32_t>(file_.keyframes.size());
  file_.needs.max_points = static_cast<std::uint32_t>(points_.size());
  file_.needs.max_observations = static_cast<std::uint32_t>(observation_total_);
  file_.needs.max_pair_arcs = static_cast<std::uint32_t>(pair_arcs_);
  *out = std::move(file_);
  file_ = WindowFile{};
  finished_ = true;
  return true;
}

bool parse_window_text(const std::string& name, const std::string& text, WindowFile* out, std::string* error,
                       const WindowFileLimits& limits) {
  *out = WindowFile{};
  WindowFileParser parser(name, limits);
  if (parser.feed(text.data(), text.size()) && parser.finish(out)) return true;
  *error = parser.error();
  return false;
}

Capacities compute_needs(const WindowFile& file) {
  std::unordered_map<std::uint64_t, std::uint32_t> views;
  std::uint64_t observations = 0;
  std::uint64_t pair_arcs = 0;
  for (const auto& list : file.observations) {
    for (const Observation& o : list) {
      pair_arcs += views[o.point]++;
      ++observations;
    }
  }
  // Saturated, not wrapped: a need beyond 32 bits is beyond every limit.
  const auto u32 = [](std::uint64_t v) { return static_cast<std::uint32_t>(std::min<std::uint64_t>(v, UINT32_MAX)); };
  Capacities c{0, 0, 0, 0};
  c.max_keyframes = u32(file.keyframes.size());
  c.max_points = u32(views.size());
  c.max_observations = u32(observations);
  c.max_pair_arcs = u32(pair_arcs);
  return c;
}

std::string window_file_problem(const WindowFile& file) {
  if (file.observations.size() != file.keyframes.size()) {
    return std::to_string(file.keyframes.size()) + " keyframes but " + std::to_string(file.observations.size()) +
           " observation lists";
  }
  std::unordered_set<KeyframeId> ids;
  std::vector<PointId> points;
  for (std::size_t k = 0; k < file.keyframes.size(); ++k) {
    const Keyframe& kf = file.keyframes[k];
    const auto at = [&](const char* reason) {
      return "keyframe " + std::to_string(k) + " (id " + std::to_string(kf.id) + "): " + reason;
    };
    if (!ids.insert(kf.id).second) return at("duplicate keyframe id");
    double norm2 = 0;
    for (double q : kf.orientation) norm2 += q * q;
    if (!std::all_of(std::begin(kf.centre), std::end(kf.centre), [](double c) { return std::isfinite(c); }) ||
        !std::isfinite(norm2)) {
      return at("non-finite centre or orientation");
    }
    if (std::fabs(norm2 - 1.0) > kQuaternionNormTolerance) return at("orientation is not a unit quaternion");
    points.clear();
    for (const Observation& o : file.observations[k]) {
      if (!std::isfinite(o.u) || !std::isfinite(o.v)) return at("non-finite keypoint");
      points.push_back(o.point);
    }
    std::sort(points.begin(), points.end());
    if (std::adjacent_find(points.begin(), points.end()) != points.end()) return at("duplicate observation");
  }
  return {};
}

std::string format_window_file(const WindowFile& file) {
  static const std::vector<Observation> kNone;
  std::string s;
  for (std::size_t k = 0; k < file.keyframes.size(); ++k) {
    append_window_keyframe(&s, file.keyframes[k], k < file.observations.size() ? file.observations[k] : kNone);
  }
  return s;
}

}  // namespace keepless::core
