// COLMAP's text layout (src/base/reconstruction.cc, Read/Write*Text): '#'
// comment lines, then one line a record, fields separated by spaces:
//   cameras.txt   CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]
//   images.txt    IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME
//                 POINTS2D[] as (X Y POINT3D_ID), -1 for none (the line may be empty)
//   points3D.txt  POINT3D_ID X Y Z R G B ERROR TRACK[] as (IMAGE_ID POINT2D_IDX)
// Numbers are written as COLMAP writes them (std::ostream, precision 17 =
// "%.17g"), so a model COLMAP wrote comes back byte for byte.

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <string>
#include <string_view>

#include "colmap_parse.hpp"
#include "keepless/core/window_file.hpp"
#include "token_text.hpp"

namespace keepless::io::detail {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Lines of a text, numbered from 1, trailing blanks removed.
class Lines {
 public:
  explicit Lines(const std::string& text) : text_(text) {}
  bool next(std::string_view* line, std::uint64_t* number) {
    if (at_ >= text_.size()) return false;
    std::size_t end = text_.find('\n', at_);
    if (end == std::string::npos) end = text_.size();
    std::size_t stop = end;
    while (stop > at_ && is_blank(text_[stop - 1])) --stop;
    *line = std::string_view(text_).substr(at_, stop - at_);
    *number = ++line_;
    at_ = end + 1;
    return true;
  }
  // The next record line: skips blank and '#' lines.
  bool next_record(std::string_view* line, std::uint64_t* number) {
    while (next(line, number)) {
      std::size_t i = 0;
      while (i < line->size() && is_blank((*line)[i])) ++i;
      if (i < line->size() && (*line)[i] != '#') return true;
    }
    return false;
  }

 private:
  const std::string& text_;
  std::size_t at_ = 0;
  std::uint64_t line_ = 0;
};

// One line's fields, parsed strictly. Tokens are found on demand by a
// cursor over the line (a POINTS2D line is read left to right): nothing is
// stored per token, so a line of millions of fields costs no more than the
// text that holds it.
class Fields {
 public:
  Fields(const std::string& name, std::string_view line, std::uint64_t number, std::string* error)
      : name_(name), line_(line), number_(number), error_(error) {
    cursor_ = skip_blanks(0);
    for (std::size_t i = cursor_; i < line.size(); i = skip_blanks(skip_token(i))) ++count_;
  }
  std::size_t size() const { return count_; }
  // The line from field i on (the image name).
  std::string rest(std::size_t i) const { return std::string(line_.substr(start(i))); }
  // Field i as a string (short: a number or a name).
  std::string token(std::size_t i) const {
    const std::size_t at = start(i);
    return std::string(line_.substr(at, skip_token(at) - at));
  }

  bool fail(const std::string& reason) {
    *error_ = name_ + ":" + std::to_string(number_) + ": " + reason;
    return false;
  }
  bool at_least(std::size_t n, const char* what) {
    return count_ >= n || fail(std::string("expected ") + what + ", got " + std::to_string(count_) + " fields");
  }
  bool u64(std::size_t i, const char* what, std::uint64_t* out) {
    const std::string& t = field(i);
    return core::parse_uint64(t, out) || bad(i, what, "an unsigned integer");
  }
  template <typename T>
  bool uint(std::size_t i, const char* what, T max, T* out) {
    std::uint64_t v = 0;
    if (!u64(i, what, &v)) return false;
    if (v > max) return bad(i, what, "at most " + std::to_string(max));
    *out = static_cast<T>(v);
    return true;
  }
  bool u32(std::size_t i, const char* what, std::uint32_t* out) {
    return uint<std::uint32_t>(i, what, UINT32_MAX, out);
  }
  bool f64(std::size_t i, const char* what, double* out) {
    return core::parse_finite_double(field(i), out) || bad(i, what, "a finite number");
  }
  // Fields first .. first + n - 1 into out[0 .. n - 1].
  bool f64s(std::size_t first, std::size_t n, const char* what, double* out) {
    for (std::size_t k = 0; k < n; ++k) {
      if (!f64(first + k, what, &out[k])) return false;
    }
    return true;
  }

 private:
  std::size_t skip_blanks(std::size_t i) const {
    while (i < line_.size() && is_blank(line_[i])) ++i;
    return i;
  }
  std::size_t skip_token(std::size_t i) const {
    while (i < line_.size() && !is_blank(line_[i])) ++i;
    return i;
  }
  // Where field i starts: from the cursor when i is at or after it, else
  // from the line's start (fields are mostly read in order).
  std::size_t start(std::size_t i) const {
    if (i < cursor_index_) {
      cursor_index_ = 0;
      cursor_ = skip_blanks(0);
    }
    for (; cursor_index_ < i; ++cursor_index_) cursor_ = skip_blanks(skip_token(cursor_));
    return cursor_;
  }
  // Field i in a buffer reused across fields (its capacity settles at the
  // longest field read).
  const std::string& field(std::size_t i) {
    const std::size_t at = start(i);
    buffer_.assign(line_.data() + at, skip_token(at) - at);
    return buffer_;
  }
  bool bad(std::size_t i, const char* what, const std::string& expected) {
    return fail(std::string("bad ") + what + " '" + shown_token(token(i)) + "' (field " + std::to_string(i + 1) + ", " +
                expected + ")");
  }
  const std::string& name_;
  std::string_view line_;
  std::uint64_t number_;
  std::string* error_;
  std::size_t count_ = 0;
  mutable std::size_t cursor_index_ = 0, cursor_ = 0;  // field cursor_index_ starts at cursor_
  std::string buffer_;
};

// Calls parse(fields, line number, lines) for each record line; stops at
// the first false.
template <typename Parse>
bool for_each_record(const std::string& name, const std::string& text, std::string* error, Parse parse) {
  // Lines end in \n (or \r\n): a file of old Mac line endings would be one
  // comment line, an empty model.
  for (std::size_t cr = text.find('\r'); cr != std::string::npos; cr = text.find('\r', cr + 1)) {
    if (cr + 1 == text.size() || text[cr + 1] == '\n') continue;
    const auto line = std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(cr), '\n') + 1;
    *error = name + ":" + std::to_string(line) + ": a carriage return not followed by a line feed (lines end in \\n or \\r\\n)";
    return false;
  }
  Lines lines(text);
  std::string_view line;
  std::uint64_t number = 0;
  while (lines.next_record(&line, &number)) {
    Fields f(name, line, number, error);
    if (!parse(f, number, lines)) return false;
  }
  return true;
}

// Appends "%.17g" of v (what std::ostream with precision 17 prints).
void put(std::string* s, double v) {
  char b[40];
  const int n = std::snprintf(b, sizeof b, "%.17g", v);
  s->append(b, static_cast<std::size_t>(n));
}
void put(std::string* s, std::uint64_t v) { s->append(std::to_string(v)); }

}  // namespace

bool parse_cameras_text(const std::string& name, const std::string& text, ColmapModel* out,
                        Positions* pos, std::string* error) {
  return for_each_record(name, text, error, [&](Fields& f, std::uint64_t number, Lines&) {
    if (!f.at_least(4, "CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]")) return false;
    ColmapCamera c;
    const CameraModelInfo* info = camera_model_by_name(f.token(1));
    if (info == nullptr) return f.fail("unknown camera model '" + shown_token(f.token(1)) + "'");
    if (f.size() != 4 + static_cast<std::size_t>(info->num_params)) {
      return f.fail(std::string(info->name) + " takes " + std::to_string(info->num_params) +
                    " parameters, got " + std::to_string(f.size() - 4));
    }
    c.model_id = info->id;
    if (!f.u32(0, "CAMERA_ID", &c.id) || !f.u64(2, "WIDTH", &c.width) || !f.u64(3, "HEIGHT", &c.height)) {
      return false;
    }
    if (!camera_size_ok(c.width) || !camera_size_ok(c.height)) {
      return f.fail("camera " + std::to_string(c.id) + " is " + std::to_string(c.width) + "x" +
                    std::to_string(c.height) + " pixels (each side must be 1.." + std::to_string(kMaxCameraSide) + ")");
    }
    c.params.resize(info->num_params);
    if (!f.f64s(4, c.params.size(), "camera parameter", c.params.data())) return false;
    out->cameras.push_back(std::move(c));
    pos->camera.push_back(number);
    return true;
  });
}

bool parse_images_text(const std::string& name, const std::string& text, ColmapModel* out,
                       Positions* pos, std::string* error) {
  return for_each_record(name, text, error, [&](Fields& f, std::uint64_t number, Lines& lines) {
    if (!f.at_least(10, "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME")) return false;
    ColmapImage im;
    if (!f.u32(0, "IMAGE_ID", &im.id)) return false;
    if (!f.f64s(1, 4, "quaternion", im.qvec) || !f.f64s(5, 3, "translation", im.tvec)) return false;
    if (!f.u32(8, "CAMERA_ID", &im.camera_id)) return false;
    im.name = f.rest(9);
    // images.bin ends a name at its NUL: a name holding one could not be written back.
    if (im.name.find('\0') != std::string::npos) return f.fail("NAME holds a NUL byte");
    // COLMAP's text reader ends a name at its first space.
    if (f.size() > 10) {
      return f.fail("NAME '" + im.name.substr(0, 60) + "' holds a blank: COLMAP would read it as '" + f.token(9) +
                    "'");
    }
    pos->image.push_back(number);
    std::string_view line;
    std::uint64_t points_line = 0;
    if (!lines.next(&line, &points_line)) {
      return f.fail("image " + std::to_string(im.id) + " has no POINTS2D line");
    }
    Fields p(name, line, points_line, error);
    if (p.size() % 3 != 0) {
      return p.fail("POINTS2D needs (X Y POINT3D_ID) triples, got " + std::to_string(p.size()) + " fields");
    }
    im.points2D.resize(p.size() / 3);
    for (std::size_t k = 0; k < im.points2D.size(); ++k) {
      ColmapPoint2D& q = im.points2D[k];
      if (!p.f64(3 * k, "X", &q.x) || !p.f64(3 * k + 1, "Y", &q.y)) return false;
      if (p.token(3 * k + 2) == "-1") {
        q.point3D_id = kNoPoint3D;
      } else if (!p.uint<std::uint64_t>(3 * k + 2, "POINT3D_ID", kNoPoint3D - 1, &q.point3D_id)) {
        return false;
      }
    }
    pos->image_points.push_back(points_line);
    out->images.push_back(std::move(im));
    return true;
  });
}

bool parse_points_text(const std::string& name, const std::string& text, ColmapModel* out,
                       Positions* pos, std::string* error) {
  return for_each_record(name, text, error, [&](Fields& f, std::uint64_t number, Lines&) {
    if (!f.at_least(8, "POINT3D_ID X Y Z R G B ERROR TRACK[]")) return false;
    if (f.size() % 2 != 0) return f.fail("TRACK needs (IMAGE_ID POINT2D_IDX) pairs");
    ColmapPoint3D p;
    if (!f.u64(0, "POINT3D_ID", &p.id)) return false;
    if (!f.f64s(1, 3, "coordinate", p.xyz)) return false;
    for (int k = 0; k < 3; ++k) {
      if (!f.uint<std::uint8_t>(4 + k, "colour", 255, &p.rgb[k])) return false;
    }
    if (!f.f64(7, "ERROR", &p.error)) return false;
    p.track.resize((f.size() - 8) / 2);
    for (std::size_t k = 0; k < p.track.size(); ++k) {
      if (!f.u32(8 + 2 * k, "IMAGE_ID", &p.track[k].image_id) ||
          !f.u32(9 + 2 * k, "POINT2D_IDX", &p.track[k].point2D_idx)) {
        return false;
      }
    }
    out->points.push_back(std::move(p));
    pos->point.push_back(number);
    pos->point_track.push_back(number);
    return true;
  });
}

// Appends " v": every field after a record's first.
template <typename T>
void field(std::string* s, T v) {
  *s += ' ';
  put(s, v);
}

// COLMAP's header: the comment lines, then "# Number of <what>: n[, <mean_label>: mean]".
std::string header(const char* comments, const char* what, std::size_t n, const char* mean_label,
                   std::uint64_t observations) {
  std::string s = comments;
  s += "# Number of ";
  s += what;
  s += ": ";
  put(&s, std::uint64_t{n});
  if (mean_label != nullptr) {
    s += ", ";
    s += mean_label;
    s += ": ";
    put(&s, n == 0 ? 0.0 : static_cast<double>(observations) / static_cast<double>(n));
  }
  s += '\n';
  return s;
}

std::string format_text_cameras(const ColmapModel& m) {
  std::string s = header("# Camera list with one line of data per camera:\n"
                         "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n",
                         "cameras", m.cameras.size(), nullptr, 0);
  for (const ColmapCamera& c : m.cameras) {
    put(&s, std::uint64_t{c.id});
    s += ' ';
    s += camera_model_by_id(c.model_id)->name;
    field(&s, c.width);
    field(&s, c.height);
    for (double p : c.params) field(&s, p);
    s += '\n';
  }
  return s;
}

std::string format_text_images(const ColmapModel& m) {
  std::string s = header("# Image list with two lines of data per image:\n"
                         "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
                         "#   POINTS2D[] as (X, Y, POINT3D_ID)\n",
                         "images", m.images.size(), "mean observations per image", count_observations(m));
  for (const ColmapImage& im : m.images) {
    put(&s, std::uint64_t{im.id});
    for (double q : im.qvec) field(&s, q);
    for (double t : im.tvec) field(&s, t);
    field(&s, std::uint64_t{im.camera_id});
    s += ' ';
    s += im.name;
    s += '\n';
    for (std::size_t k = 0; k < im.points2D.size(); ++k) {
      const ColmapPoint2D& p = im.points2D[k];
      if (k > 0) s += ' ';
      put(&s, p.x);
      field(&s, p.y);
      if (p.point3D_id == kNoPoint3D) {
        s += " -1";
      } else {
        field(&s, p.point3D_id);
      }
    }
    s += '\n';
  }
  return s;
}

std::string format_text_points(const ColmapModel& m) {
  std::string s = header("# 3D point list with one line of data per point:\n"
                         "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n",
                         "points", m.points.size(), "mean track length", count_observations(m));
  for (const ColmapPoint3D& p : m.points) {
    put(&s, p.id);
    for (double x : p.xyz) field(&s, x);
    for (std::uint8_t c : p.rgb) field(&s, std::uint64_t{c});
    field(&s, p.error);
    for (const ColmapTrackElement& e : p.track) {
      field(&s, std::uint64_t{e.image_id});
      field(&s, std::uint64_t{e.point2D_idx});
    }
    s += '\n';
  }
  return s;
}

}  // namespace keepless::io::detail
