// COLMAP's binary layout (src/base/reconstruction.cc, Read/Write*Binary),
// little-endian throughout:
//   cameras.bin   u64 n; n x {u32 id, i32 model, u64 width, u64 height, f64 params[model]}
//   images.bin    u64 n; n x {u32 id, f64 q[4], f64 t[3], u32 camera, name NUL-terminated,
//                             u64 m, m x {f64 x, f64 y, u64 point3D_id (all ones: none)}}
//   points3D.bin  u64 n; n x {u64 id, f64 xyz[3], u8 rgb[3], f64 error,
//                             u64 t, t x {u32 image_id, u32 point2D_idx}}

#include <cinttypes>
#include <cmath>
#include <cstring>

#include "colmap_parse.hpp"

namespace keepless::io::detail {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "COLMAP's binary files are little-endian");

namespace {

class ByteReader {
 public:
  ByteReader(const std::string& name, const std::string& bytes, std::string* error)
      : name_(name), bytes_(bytes), error_(error) {}

  std::uint64_t offset() const { return at_; }
  std::uint64_t left() const { return bytes_.size() - at_; }

  template <typename T>
  bool read(const char* what, T* out) {
    if (left() < sizeof(T)) {
      return fail(at_, std::string("truncated: ") + what + " needs " + std::to_string(sizeof(T)) +
                           " bytes, " + std::to_string(left()) + " left");
    }
    std::memcpy(out, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return true;
  }

  bool finite(const char* what, double* out) {
    const std::uint64_t start = at_;
    if (!read(what, out)) return false;
    if (!std::isfinite(*out)) return fail(start, std::string("non-finite ") + what);
    return true;
  }

  // A count whose records take at least `min_record` bytes each.
  bool count(const char* what, std::uint64_t min_record, std::uint64_t* out) {
    const std::uint64_t start = at_;
    if (!read(what, out)) return false;
    if (*out > left() / min_record) {
      return fail(start, std::string(what) + " " + std::to_string(*out) + " needs at least " +
                             std::to_string(min_record) + " bytes each, " + std::to_string(left()) +
                             " left");
    }
    return true;
  }

  bool name(std::string* out) {
    const char* begin = bytes_.data() + at_;
    const void* nul = std::memchr(begin, '\0', left());
    if (nul == nullptr) return fail(at_, "truncated: image name has no terminating NUL");
    const std::size_t n = static_cast<const char*>(nul) - begin;
    out->assign(begin, n);  // checked with the model (check_model)
    at_ += n + 1;
    return true;
  }

  bool end() {
    if (left() != 0) return fail(at_, std::to_string(left()) + " bytes after the last record");
    return true;
  }

  bool fail(std::uint64_t offset, const std::string& reason) {
    *error_ = name_ + ":" + std::to_string(offset) + ": " + reason;
    return false;
  }

 private:
  const std::string& name_;
  const std::string& bytes_;
  std::string* error_;
  std::uint64_t at_ = 0;
};

class ByteWriter {
 public:
  explicit ByteWriter(std::string* out) : out_(out) {}
  template <typename T>
  void put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    out_->append(b, sizeof(T));
  }
  void bytes(const std::string& s) { out_->append(s.data(), s.size()); }

 private:
  std::string* out_;
};

}  // namespace

bool parse_cameras_binary(const std::string& name, const std::string& bytes, ColmapModel* out,
                          Positions* pos, std::string* error) {
  ByteReader r(name, bytes, error);
  std::uint64_t n = 0;
  if (!r.count("num_cameras", 24, &n)) return false;
  out->cameras.resize(n);
  pos->camera.resize(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    ColmapCamera& c = out->cameras[i];
    pos->camera[i] = r.offset();
    if (!r.read("camera_id", &c.id)) return false;
    const std::uint64_t model_at = r.offset();
    std::int32_t model = 0;
    if (!r.read("model_id", &model)) return false;
    const CameraModelInfo* info = camera_model_by_id(model);
    if (info == nullptr) return r.fail(model_at, "unknown camera model id " + std::to_string(model));
    c.model_id = model;
    const std::uint64_t size_at = r.offset();
    if (!r.read("width", &c.width) || !r.read("height", &c.height)) return false;
    if (!camera_size_ok(c.width) || !camera_size_ok(c.height)) {
      return r.fail(camera_size_ok(c.width) ? size_at + 8 : size_at,
                    "camera " + std::to_string(c.id) + " is " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                        " pixels (each side must be 1.." + std::to_string(kMaxCameraSide) + ")");
    }
    c.params.resize(info->num_params);
    for (double& p : c.params) {
      if (!r.finite("camera parameter", &p)) return false;
    }
  }
  return r.end();
}

bool parse_images_binary(const std::string& name, const std::string& bytes, ColmapModel* out,
                         Positions* pos, std::string* error) {
  ByteReader r(name, bytes, error);
  std::uint64_t n = 0;
  // Smallest image: id, q, t, camera, a 1-byte name and NUL, no 2D points.
  if (!r.count("num_reg_images", 4 + 56 + 4 + 2 + 8, &n)) return false;
  out->images.resize(n);
  pos->image.resize(n);
  pos->image_points.resize(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    ColmapImage& im = out->images[i];
    pos->image[i] = r.offset();
    if (!r.read("image_id", &im.id)) return false;
    for (double& q : im.qvec) {
      if (!r.finite("qvec", &q)) return false;
    }
    for (double& t : im.tvec) {
      if (!r.finite("tvec", &t)) return false;
    }
    if (!r.read("camera_id", &im.camera_id) || !r.name(&im.name)) return false;
    std::uint64_t m = 0;
    if (!r.count("num_points2D", 24, &m)) return false;
    pos->image_points[i] = r.offset();
    im.points2D.resize(m);
    for (ColmapPoint2D& p : im.points2D) {
      if (!r.finite("point2D x", &p.x) || !r.finite("point2D y", &p.y) ||
          !r.read("point3D_id", &p.point3D_id)) {
        return false;
      }
    }
  }
  return r.end();
}

bool parse_points_binary(const std::string& name, const std::string& bytes, ColmapModel* out,
                         Positions* pos, std::string* error) {
  ByteReader r(name, bytes, error);
  std::uint64_t n = 0;
  if (!r.count("num_points3D", 8 + 24 + 3 + 8 + 8, &n)) return false;
  out->points.resize(n);
  pos->point.resize(n);
  pos->point_track.resize(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    ColmapPoint3D& p = out->points[i];
    pos->point[i] = r.offset();
    if (!r.read("point3D_id", &p.id)) return false;
    for (double& x : p.xyz) {
      if (!r.finite("xyz", &x)) return false;
    }
    for (std::uint8_t& c : p.rgb) {
      if (!r.read("rgb", &c)) return false;
    }
    if (!r.finite("error", &p.error)) return false;
    std::uint64_t t = 0;
    if (!r.count("track_length", 8, &t)) return false;
    pos->point_track[i] = r.offset();
    p.track.resize(t);
    for (ColmapTrackElement& e : p.track) {
      if (!r.read("track image_id", &e.image_id) || !r.read("track point2D_idx", &e.point2D_idx)) {
        return false;
      }
    }
  }
  return r.end();
}

std::string format_binary_cameras(const ColmapModel& m) {
  std::string s;
  ByteWriter w(&s);
  w.put<std::uint64_t>(m.cameras.size());
  for (const ColmapCamera& c : m.cameras) {
    w.put(c.id);
    w.put<std::int32_t>(c.model_id);
    w.put(c.width);
    w.put(c.height);
    for (double p : c.params) w.put(p);
  }
  return s;
}

std::string format_binary_images(const ColmapModel& m) {
  std::string s;
  ByteWriter w(&s);
  w.put<std::uint64_t>(m.images.size());
  for (const ColmapImage& im : m.images) {
    w.put(im.id);
    for (double q : im.qvec) w.put(q);
    for (double t : im.tvec) w.put(t);
    w.put(im.camera_id);
    w.bytes(im.name);
    w.put<char>('\0');
    w.put<std::uint64_t>(im.points2D.size());
    for (const ColmapPoint2D& p : im.points2D) {
      w.put(p.x);
      w.put(p.y);
      w.put(p.point3D_id);
    }
  }
  return s;
}

std::string format_binary_points(const ColmapModel& m) {
  std::string s;
  ByteWriter w(&s);
  w.put<std::uint64_t>(m.points.size());
  for (const ColmapPoint3D& p : m.points) {
    w.put(p.id);
    for (double x : p.xyz) w.put(x);
    for (std::uint8_t c : p.rgb) w.put(c);
    w.put(p.error);
    w.put<std::uint64_t>(p.track.size());
    for (const ColmapTrackElement& e : p.track) {
      w.put(e.image_id);
      w.put(e.point2D_idx);
    }
  }
  return s;
}

}  // namespace keepless::io::detail
