#include "keepless/io/bal_problem.hpp"

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <string_view>
#include <vector>

#include "keepless/core/window_file.hpp"
#include "keepless/io/atomic_file.hpp"
#include "rotation.hpp"
#include "token_text.hpp"

namespace keepless::io {

namespace {

// The file's tokens in order, found on demand (nothing is stored per
// token), with the line each is on.
class Tokens {
 public:
  explicit Tokens(const std::string& text) : text_(text) {}
  // The next token, or false at the end.
  bool next(std::string_view* token, std::uint64_t* line) {
    while (at_ < text_.size() && blank(text_[at_])) line_ += text_[at_++] == '\n' ? 1 : 0;
    if (at_ >= text_.size()) return false;
    const std::size_t start = at_;
    while (at_ < text_.size() && !blank(text_[at_])) ++at_;
    *token = std::string_view(text_).substr(start, at_ - start);
    *line = line_;
    return true;
  }

 private:
  static bool blank(char c) { return c == '\n' || c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
  const std::string& text_;
  std::size_t at_ = 0;
  std::uint64_t line_ = 1;
};

}  // namespace

bool parse_bal(const std::string& name, const std::string& text, BalProblem* out, std::string* error) {
  *out = BalProblem{};
  Tokens tokens(text);
  std::string word;
  std::uint64_t at_line = 1;
  const auto fail = [&](std::uint64_t line, const std::string& reason) {
    *error = name + ":" + std::to_string(line) + ": " + reason;
    return false;
  };
  // The next token into `word`, or an error naming what was missing.
  const auto take = [&](const char* what) {
    std::string_view t;
    if (!tokens.next(&t, &at_line)) return fail(at_line, std::string("truncated: missing ") + what);
    word.assign(t.data(), t.size());
    return true;
  };
  const auto index = [&](const char* what, std::uint64_t limit, std::uint32_t* v) {
    std::uint64_t x = 0;
    if (!take(what)) return false;
    if (!core::parse_uint64(word, &x) || x >= limit) {
      return fail(at_line, std::string("bad ") + what + " '" + detail::shown_token(word) + "' (an integer below " +
                               std::to_string(limit) + ")");
    }
    *v = static_cast<std::uint32_t>(x);
    return true;
  };
  const auto number = [&](const char* what, double* v, std::string* keep) {
    if (!take(what)) return false;
    if (!core::parse_finite_double(word, v)) {
      return fail(at_line, std::string("bad ") + what + " '" + detail::shown_token(word) + "' (a finite number)");
    }
    *keep = word;
    return true;
  };
  std::uint32_t nobs = 0;
  constexpr std::uint64_t kCount = UINT32_MAX;
  if (!index("camera count", kCount, &out->num_cameras) || !index("point count", kCount, &out->num_points) ||
      !index("observation count", kCount, &nobs)) {
    return false;
  }
  // The counts against the values the file holds, before anything is sized
  // by them: one counting pass over the rest of the file.
  const std::uint64_t needed = 4 * std::uint64_t{nobs} + 9 * std::uint64_t{out->num_cameras} +
                               3 * std::uint64_t{out->num_points};
  {
    Tokens rest = tokens;
    std::string_view t;
    std::uint64_t line = at_line, have = 0, extra_line = 0;
    while (rest.next(&t, &line)) {
      if (have++ == needed) extra_line = line;
    }
    if (have < needed) {  // on the line of the last value
      return fail(line, "truncated: the counts need " + std::to_string(needed + 3) + " values, the file has " +
                            std::to_string(have + 3));
    }
    if (have > needed) return fail(extra_line, "values after the last point");
  }
  out->observations.resize(nobs);
  for (BalObservation& o : out->observations) {
    if (!index("camera index", out->num_cameras, &o.camera) || !index("point index", out->num_points, &o.point) ||
        !number("observation x", &o.x, &o.x_text) || !number("observation y", &o.y, &o.y_text)) {
      return false;
    }
  }
  out->camera_params.resize(9 * std::size_t{out->num_cameras});
  out->camera_text.resize(out->camera_params.size());
  // A rotation whose angle overflows, or a centre out of range, is no camera:
  // each is checked once its 9 values are read, at the line of its first.
  std::uint64_t camera_line = 0;
  for (std::size_t i = 0; i < out->camera_params.size(); ++i) {
    if (!number("camera parameter", &out->camera_params[i], &out->camera_text[i])) return false;
    if (i % 9 == 0) camera_line = at_line;
    if (i % 9 != 8) continue;
    const auto camera = static_cast<std::uint32_t>(i / 9);
    const double* r = &out->camera_params[i - 8];
    double c[3];
    bal_camera_centre(*out, camera, c);
    if (!std::isfinite(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) || !std::isfinite(c[0]) || !std::isfinite(c[1]) ||
        !std::isfinite(c[2])) {
      return fail(camera_line,
                  "camera " + std::to_string(camera) + ": its rotation or centre is not finite (out of range)");
    }
  }
  out->point_params.resize(3 * std::size_t{out->num_points});
  out->point_text.resize(out->point_params.size());
  for (std::size_t i = 0; i < out->point_params.size(); ++i) {
    if (!number("point coordinate", &out->point_params[i], &out->point_text[i])) return false;
  }
  return true;
}

bool read_bal(const std::string& path, BalProblem* out, std::string* error) {
  std::string text;
  return read_file(path, &text, error) && parse_bal(path, text, out, error);
}

std::string format_bal(const BalProblem& p) {
  std::string s = std::to_string(p.num_cameras) + " " + std::to_string(p.num_points) + " " +
                  std::to_string(p.observations.size()) + "\n";
  for (const BalObservation& o : p.observations) {
    s += std::to_string(o.camera);
    s += ' ';
    s += std::to_string(o.point);
    s += "     ";
    s += o.x_text;
    s += ' ';
    s += o.y_text;
    s += '\n';
  }
  for (const std::string& v : p.camera_text) {
    s += v;
    s += '\n';
  }
  for (const std::string& v : p.point_text) {
    s += v;
    s += '\n';
  }
  return s;
}

BalProblem remove_points(const BalProblem& p, const std::vector<bool>& culled) {
  BalProblem out;
  out.num_cameras = p.num_cameras;
  out.camera_params = p.camera_params;
  out.camera_text = p.camera_text;
  std::vector<std::uint32_t> renumber(p.num_points, 0);
  for (std::uint32_t i = 0; i < p.num_points; ++i) {
    if (culled[i]) continue;
    renumber[i] = out.num_points++;
    for (int k = 0; k < 3; ++k) {
      out.point_params.push_back(p.point_params[3 * std::size_t{i} + k]);
      out.point_text.push_back(p.point_text[3 * std::size_t{i} + k]);
    }
  }
  for (const BalObservation& o : p.observations) {
    if (culled[o.point]) continue;
    out.observations.push_back(o);
    out.observations.back().point = renumber[o.point];
  }
  return out;
}

void bal_camera_centre(const BalProblem& p, std::uint32_t i, double centre[3]) {
  const double* c = &p.camera_params[9 * std::size_t{i}];
  const double minus_r[3] = {-c[0], -c[1], -c[2]};
  double rt[3];
  detail::angle_axis_rotate(minus_r, c + 3, rt);  // R^T t
  for (int k = 0; k < 3; ++k) centre[k] = -rt[k];
}

}  // namespace keepless::io
