#include "keepless/core/window_file.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <unordered_map>

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
  if (errno == ERANGE) return NumberError::kOutOfRange;
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

struct PointEntry {
  std::uint32_t index;  // order of first appearance
  std::uint32_t views;  // keyframes observing it so far
};

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

void append_keyframe(std::string* s, const Keyframe& kf, const std::vector<Observation>& obs) {
  s->append("kf ");
  append_uint(s, kf.id);
  for (double c : kf.centre) {
    s->push_back(' ');
    append_double(s, c);
  }
  const double* q = kf.orientation;
  if (!(q[0] == 1.0 && q[1] == 0.0 && q[2] == 0.0 && q[3] == 0.0)) {
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

}  // namespace

bool parse_uint64(const char* text, std::uint64_t* out) {
  return text != nullptr && read_uint64(text, out) == NumberError::kOk;
}

bool parse_finite_double(const char* text, double* out) {
  return text != nullptr && read_double(text, out) == NumberError::kOk;
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

bool parse_window_text(const std::string& name, std::string text, WindowFile* out,
                       std::string* error, const WindowFileLimits& limits) {
  *out = WindowFile{};
  std::uint64_t line_no = 0;
  const auto fail = [&](const std::string& reason) {
    *error = name + ":" + std::to_string(line_no) + ": " + reason;
    return false;
  };

  std::size_t lines = 0;
  for (char c : text) lines += (c == '\n');
  std::unordered_map<std::uint64_t, std::uint32_t> keyframe_index;  // id -> declaration index
  std::unordered_map<std::uint64_t, PointEntry> points;             // id -> entry
  std::unordered_map<std::uint64_t, std::uint64_t> observed;        // observation_key -> line
  points.reserve(std::min<std::size_t>(lines + 1, limits.max_points + 1ULL));
  observed.reserve(std::min<std::size_t>(lines + 1, limits.max_observations + 1ULL));
  std::uint64_t observation_total = 0;
  std::uint64_t pair_arcs = 0;

  constexpr int kMaxTokens = 9;  // kf with orientation
  char* tokens[kMaxTokens];
  const std::size_t size = text.size();
  std::size_t begin = 0;
  while (begin < size) {
    ++line_no;
    const char* nl = static_cast<const char*>(std::memchr(text.data() + begin, '\n', size - begin));
    const std::size_t end = nl != nullptr ? static_cast<std::size_t>(nl - text.data()) : size;
    const std::size_t next = end + 1;
    if (std::memchr(text.data() + begin, '\0', end - begin) != nullptr) {
      return fail("NUL byte in line");
    }
    const char* hash = static_cast<const char*>(std::memchr(text.data() + begin, '#', end - begin));
    const std::size_t stop = hash != nullptr ? static_cast<std::size_t>(hash - text.data()) : end;

    // Split [begin, stop) in place: each token ends with a written '\0'
    // (text[size] is the string's own terminator, so writing '\0' is fine).
    int count = 0;
    std::size_t i = begin;
    while (i < stop) {
      while (i < stop && is_space(text[i])) ++i;
      if (i >= stop) break;
      const std::size_t start = i;
      while (i < stop && !is_space(text[i])) ++i;
      if (count < kMaxTokens) tokens[count] = &text[start];
      ++count;
      text[i] = '\0';
      ++i;
    }
    begin = next;
    if (count == 0) continue;

    const int values = count - 1;
    if (std::strcmp(tokens[0], "kf") == 0) {
      if (values != 4 && values != 8) {
        return fail("kf needs 4 or 8 values (kf_id cx cy cz [qw qx qy qz]), got " +
                    std::to_string(values));
      }
      Keyframe kf;
      NumberError e = read_uint64(tokens[1], &kf.id);
      if (e != NumberError::kOk) return fail(id_problem("keyframe id", tokens[1], e));
      static const char* const kNames[7] = {"cx", "cy", "cz", "qw", "qx", "qy", "qz"};
      double* const fields[7] = {&kf.centre[0],      &kf.centre[1],      &kf.centre[2],
                                 &kf.orientation[0], &kf.orientation[1], &kf.orientation[2],
                                 &kf.orientation[3]};
      for (int f = 0; f < values - 1; ++f) {
        e = read_double(tokens[2 + f], fields[f]);
        if (e != NumberError::kOk) return fail(number_problem(kNames[f], tokens[2 + f], e));
      }
      const auto found = keyframe_index.find(kf.id);
      if (found != keyframe_index.end()) {
        return fail("duplicate keyframe id " + std::to_string(kf.id) + " (first declared on line " +
                    std::to_string(out->keyframe_lines[found->second]) + ")");
      }
      if (out->keyframes.size() + 1 > limits.max_keyframes) {
        return fail("capacity exceeded: more than " + std::to_string(limits.max_keyframes) +
                    " keyframes");
      }
      keyframe_index.emplace(kf.id, static_cast<std::uint32_t>(out->keyframes.size()));
      out->keyframes.push_back(kf);
      out->keyframe_lines.push_back(line_no);
      out->observations.emplace_back();
    } else if (std::strcmp(tokens[0], "obs") == 0) {
      if (values != 4) {
        return fail("obs needs 4 values (kf_id point_id u v), got " + std::to_string(values));
      }
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

      const auto kf = keyframe_index.find(kf_id);
      if (kf == keyframe_index.end()) {
        return fail("unknown keyframe " + std::to_string(kf_id) + " (no kf line before this one)");
      }
      const auto point = points.find(obs.point);
      const bool new_point = point == points.end();
      const std::uint32_t point_index =
          new_point ? static_cast<std::uint32_t>(points.size()) : point->second.index;
      const std::uint64_t key = observation_key(kf->second, point_index);
      if (!new_point) {
        const auto seen = observed.find(key);
        if (seen != observed.end()) {
          return fail("duplicate observation of point " + std::to_string(obs.point) +
                      " by keyframe " + std::to_string(kf_id) + " (first on line " +
                      std::to_string(seen->second) + ")");
        }
      }
      if (observation_total + 1 > limits.max_observations) {
        return fail("capacity exceeded: more than " + std::to_string(limits.max_observations) +
                    " observations");
      }
      if (new_point && points.size() + 1 > limits.max_points) {
        return fail("capacity exceeded: more than " + std::to_string(limits.max_points) +
                    " distinct points");
      }
      // The n-th view of a point adds n-1 pairs: sum n(n-1)/2 incrementally.
      const std::uint32_t views_before = new_point ? 0 : point->second.views;
      if (pair_arcs + views_before > limits.max_pair_arcs) {
        return fail("capacity exceeded: more than " + std::to_string(limits.max_pair_arcs) +
                    " pair arcs");
      }
      if (new_point) {
        points.emplace(obs.point, PointEntry{point_index, 1});
      } else {
        ++point->second.views;
      }
      observed.emplace(key, line_no);
      pair_arcs += views_before;
      ++observation_total;
      out->observations[kf->second].push_back(obs);
    } else {
      return fail("unknown record " + shown(tokens[0]) + " (expected kf or obs)");
    }
  }

  out->needs.max_keyframes = static_cast<std::uint32_t>(out->keyframes.size());
  out->needs.max_points = static_cast<std::uint32_t>(points.size());
  out->needs.max_observations = static_cast<std::uint32_t>(observation_total);
  out->needs.max_pair_arcs = static_cast<std::uint32_t>(pair_arcs);
  return true;
}

bool read_window_file(const std::string& path, WindowFile* out, std::string* error,
                      const WindowFileLimits& limits) {
  *out = WindowFile{};
  const auto fail = [&](const char* what, int err) {
    *error = path + ":0: " + what + ": " + std::strerror(err);
    return false;
  };
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return fail("cannot open", errno);
  std::string text;
  char buf[1 << 16];
  for (;;) {
    const std::size_t n = std::fread(buf, 1, sizeof buf, f);
    text.append(buf, n);
    if (n < sizeof buf) break;
  }
  const bool bad = std::ferror(f) != 0;
  const int err = errno;
  std::fclose(f);
  if (bad) return fail("cannot read", err != 0 ? err : EIO);
  return parse_window_text(path, std::move(text), out, error, limits);
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
  Capacities c{0, 0, 0, 0};
  c.max_keyframes = static_cast<std::uint32_t>(file.keyframes.size());
  c.max_points = static_cast<std::uint32_t>(views.size());
  c.max_observations = static_cast<std::uint32_t>(observations);
  c.max_pair_arcs = static_cast<std::uint32_t>(pair_arcs);
  return c;
}

std::string format_window_file(const WindowFile& file) {
  std::string s;
  for (std::size_t k = 0; k < file.keyframes.size(); ++k) {
    append_keyframe(&s, file.keyframes[k], file.observations[k]);
  }
  return s;
}

bool write_window_file(const std::string& path, const WindowFile& file, std::string* error) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) {
    *error = path + ": cannot open for writing: " + std::strerror(errno);
    return false;
  }
  // One keyframe at a time keeps the buffer small for a whole map.
  std::string chunk;
  bool ok = true;
  for (std::size_t k = 0; ok && k < file.keyframes.size(); ++k) {
    chunk.clear();
    append_keyframe(&chunk, file.keyframes[k], file.observations[k]);
    ok = std::fwrite(chunk.data(), 1, chunk.size(), f) == chunk.size();
  }
  const int err = errno;
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) *error = path + ": write failed: " + std::strerror(err != 0 ? err : EIO);
  return ok;
}

}  // namespace keepless::core
