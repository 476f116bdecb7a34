#include "keepless/io/colmap_model.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <unordered_map>
#include <unordered_set>

#include "colmap_parse.hpp"
#include "keepless/io/atomic_file.hpp"
#include "keepless/io/keyframes.hpp"

namespace keepless::io {

namespace {

// COLMAP's camera models (src/base/camera_models.h): id, name, parameters,
// focal lengths. 0-10 are COLMAP 3.8's; 11 was added in later releases.
constexpr CameraModelInfo kCameraModels[] = {
    {0, "SIMPLE_PINHOLE", 3, 1},  {1, "PINHOLE", 4, 2},
    {2, "SIMPLE_RADIAL", 4, 1},   {3, "RADIAL", 5, 1},
    {4, "OPENCV", 8, 2},          {5, "OPENCV_FISHEYE", 8, 2},
    {6, "FULL_OPENCV", 12, 2},    {7, "FOV", 5, 2},
    {8, "SIMPLE_RADIAL_FISHEYE", 4, 1}, {9, "RADIAL_FISHEYE", 5, 1},
    {10, "THIN_PRISM_FISHEYE", 12, 2},  {11, "RAD_TAN_THIN_PRISM_FISHEYE", 16, 2},
};

std::string at(const std::string& file, std::uint64_t pos) { return file + ":" + std::to_string(pos) + ": "; }

// Images and tracks must reference each other exactly; COLMAP itself
// assumes so (and crashes or mis-counts otherwise).
bool check_model(const detail::FileNames& names, const detail::Positions& pos, const ColmapModel& m,
                 std::string* error) {
  const auto fail = [&](const std::string& file, std::uint64_t p, const std::string& reason) {
    *error = at(file, p) + reason;
    return false;
  };
  std::unordered_map<std::uint32_t, std::size_t> cameras, images;
  std::unordered_map<std::string, std::uint32_t> names_seen;  // image name -> id
  std::unordered_map<std::uint64_t, std::size_t> points;
  for (std::size_t i = 0; i < m.cameras.size(); ++i) {
    // COLMAP's kInvalidCameraId: its reader aborts on a model holding it.
    if (m.cameras[i].id == 0xFFFFFFFFu) {
      return fail(names.cameras, pos.camera[i], "camera id 4294967295 is COLMAP's invalid id");
    }
    if (!cameras.emplace(m.cameras[i].id, i).second) {
      return fail(names.cameras, pos.camera[i], "duplicate camera id " + std::to_string(m.cameras[i].id));
    }
  }
  for (std::size_t i = 0; i < m.images.size(); ++i) {
    const ColmapImage& im = m.images[i];
    if (!images.emplace(im.id, i).second) {
      return fail(names.images, pos.image[i], "duplicate image id " + std::to_string(im.id));
    }
    if (cameras.count(im.camera_id) == 0) {
      return fail(names.images, pos.image[i],
                  "image " + std::to_string(im.id) + " names unknown camera " + std::to_string(im.camera_id));
    }
    // Names must survive the text format, which ends them at the line's end
    // and trims them.
    const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; };
    if (im.name.empty() || blank(im.name.front()) || blank(im.name.back()) ||
        im.name.find_first_of("\n\r") != std::string::npos) {
      return fail(names.images, pos.image[i],
                  "image " + std::to_string(im.id) + ": a name must be non-empty, on one line, without blanks at its ends");
    }
    // COLMAP finds images by name (the database, image_reader): names are unique.
    if (const auto [it, fresh] = names_seen.emplace(im.name, im.id); !fresh) {
      return fail(names.images, pos.image[i],
                  "image " + std::to_string(im.id) + " has the name '" + im.name.substr(0, 60) + "' of image " +
                      std::to_string(it->second) + " (names must be unique)");
    }
    if (im.qvec[0] == 0 && im.qvec[1] == 0 && im.qvec[2] == 0 && im.qvec[3] == 0) {
      return fail(names.images, pos.image[i], "image " + std::to_string(im.id) + " has a zero quaternion");
    }
    double centre[3];
    colmap_camera_centre(im, centre);
    if (!std::isfinite(centre[0]) || !std::isfinite(centre[1]) || !std::isfinite(centre[2])) {
      return fail(names.images, pos.image[i],
                  "image " + std::to_string(im.id) +
                      "'s camera centre is not finite (its translation is out of range)");
    }
  }
  for (std::size_t i = 0; i < m.points.size(); ++i) {
    const std::uint64_t id = m.points[i].id;
    if (id == kNoPoint3D) return fail(names.points3D, pos.point[i], "point3D id 2^64-1 is COLMAP's 'none'");
    if (!points.emplace(id, i).second) {
      return fail(names.points3D, pos.point[i], "duplicate point3D id " + std::to_string(id));
    }
  }
  // Where 2D point k of image i is (binary: its point3D_id field).
  const auto point2D_at = [&](std::size_t i, std::size_t k) {
    return pos.binary ? pos.image_points[i] + 24 * k + 16 : pos.image_points[i];
  };
  std::vector<std::vector<bool>> in_track(m.images.size());
  for (std::size_t i = 0; i < m.images.size(); ++i) {
    const ColmapImage& im = m.images[i];
    in_track[i].assign(im.points2D.size(), false);
    for (std::size_t k = 0; k < im.points2D.size(); ++k) {
      const std::uint64_t p = im.points2D[k].point3D_id;
      if (p != kNoPoint3D && points.count(p) == 0) {
        return fail(names.images, point2D_at(i, k),
                    "image " + std::to_string(im.id) + " 2D point " + std::to_string(k) + " names unknown point3D " +
                        std::to_string(p));
      }
    }
  }
  for (std::size_t j = 0; j < m.points.size(); ++j) {
    const ColmapPoint3D& p = m.points[j];
    for (std::size_t k = 0; k < p.track.size(); ++k) {
      const ColmapTrackElement& e = p.track[k];
      const std::uint64_t where = pos.binary ? pos.point_track[j] + 8 * k : pos.point_track[j];
      const std::string what = "point3D " + std::to_string(p.id) + " track element " + std::to_string(k) + ": ";
      const auto im = images.find(e.image_id);
      if (im == images.end()) return fail(names.points3D, where, what + "unknown image " + std::to_string(e.image_id));
      const ColmapImage& image = m.images[im->second];
      const std::uint64_t idx_at = pos.binary ? where + 4 : where;  // the point2D_idx field
      if (e.point2D_idx >= image.points2D.size()) {
        return fail(names.points3D, idx_at,
                    what + "image " + std::to_string(e.image_id) + " has no 2D point " + std::to_string(e.point2D_idx));
      }
      if (image.points2D[e.point2D_idx].point3D_id != p.id) {
        return fail(names.points3D, idx_at,
                    what + "image " + std::to_string(e.image_id) + " 2D point " + std::to_string(e.point2D_idx) +
                        " does not name this point");
      }
      if (in_track[im->second][e.point2D_idx]) return fail(names.points3D, where, what + "repeated");
      in_track[im->second][e.point2D_idx] = true;
    }
  }
  for (std::size_t i = 0; i < m.images.size(); ++i) {
    const ColmapImage& im = m.images[i];
    for (std::size_t k = 0; k < im.points2D.size(); ++k) {
      if (im.points2D[k].point3D_id != kNoPoint3D && !in_track[i][k]) {
        return fail(names.images, point2D_at(i, k),
                    "image " + std::to_string(im.id) + " 2D point " + std::to_string(k) + " is not in the track of point3D " +
                        std::to_string(im.points2D[k].point3D_id));
      }
    }
  }
  return true;
}

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

std::string without_trailing_slashes(std::string dir) {  // "out/" is the folder out
  while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  return dir;
}

}  // namespace

namespace detail {

FileNames file_names(const std::string& dir, ColmapFormat format) {
  const std::string ext = std::string(".") + extension(format);
  const std::string base = dir.empty() ? "" : dir + "/";
  return {base + "cameras" + ext, base + "images" + ext, base + "points3D" + ext};
}

std::uint64_t count_observations(const ColmapModel& m) {
  std::uint64_t n = 0;
  for (const ColmapImage& im : m.images) {
    for (const ColmapPoint2D& p : im.points2D) n += p.point3D_id != kNoPoint3D;
  }
  return n;
}

}  // namespace detail

const CameraModelInfo* camera_model_by_id(int id) {
  for (const CameraModelInfo& c : kCameraModels) {
    if (c.id == id) return &c;
  }
  return nullptr;
}

const CameraModelInfo* camera_model_by_name(const std::string& name) {
  for (const CameraModelInfo& c : kCameraModels) {
    if (name == c.name) return &c;
  }
  return nullptr;
}

const char* extension(ColmapFormat format) { return format == ColmapFormat::kBinary ? "bin" : "txt"; }

bool parse_colmap(const std::string& dir, const ColmapFiles& files, ColmapFormat format, ColmapModel* out,
                  std::string* error) {
  *out = ColmapModel{};
  const detail::FileNames names = detail::file_names(dir, format);
  detail::Positions pos;
  pos.binary = format == ColmapFormat::kBinary;
  const bool ok =
      pos.binary ? detail::parse_cameras_binary(names.cameras, files.cameras, out, &pos, error) &&
                       detail::parse_images_binary(names.images, files.images, out, &pos, error) &&
                       detail::parse_points_binary(names.points3D, files.points3D, out, &pos, error)
                 : detail::parse_cameras_text(names.cameras, files.cameras, out, &pos, error) &&
                       detail::parse_images_text(names.images, files.images, out, &pos, error) &&
                       detail::parse_points_text(names.points3D, files.points3D, out, &pos, error);
  return ok && check_model(names, pos, *out, error);
}

ColmapFiles format_colmap(const ColmapModel& model, ColmapFormat format) {
  if (format == ColmapFormat::kBinary) {
    return {detail::format_binary_cameras(model), detail::format_binary_images(model),
            detail::format_binary_points(model)};
  }
  return {detail::format_text_cameras(model), detail::format_text_images(model), detail::format_text_points(model)};
}

bool read_colmap_model(const std::string& dir, ColmapModel* out, ColmapFormat* format, std::string* error) {
  const detail::FileNames bin = detail::file_names(dir, ColmapFormat::kBinary);
  const detail::FileNames txt = detail::file_names(dir, ColmapFormat::kText);
  const bool any_bin = exists(bin.cameras) || exists(bin.images) || exists(bin.points3D);
  const bool all_bin = exists(bin.cameras) && exists(bin.images) && exists(bin.points3D);
  const bool any_txt = exists(txt.cameras) || exists(txt.images) || exists(txt.points3D);
  if (!any_bin && !any_txt) {
    *error = dir + ": no COLMAP model (cameras/images/points3D .bin or .txt)";
    return false;
  }
  // The binary files when all three are there (COLMAP's preference); else
  // the format some of whose files are, so a missing one is named.
  *format = all_bin || !any_txt ? ColmapFormat::kBinary : ColmapFormat::kText;
  const detail::FileNames names = detail::file_names(dir, *format);
  ColmapFiles files;
  if (!read_file(names.cameras, &files.cameras, error) || !read_file(names.images, &files.images, error) ||
      !read_file(names.points3D, &files.points3D, error)) {
    return false;
  }
  return parse_colmap(dir, files, *format, out, error);
}

bool colmap_model_writable(const std::string& dir_as_given, const ColmapModel& model, ColmapFormat format,
                           std::string* error) {
  const std::string dir = without_trailing_slashes(dir_as_given);
  // COLMAP's text reader ends a name at its first space: such a name only survives in binary.
  if (format == ColmapFormat::kText) {
    for (const ColmapImage& im : model.images) {
      if (im.name.find_first_of(" \t\v\f\r") != std::string::npos) {
        *error = detail::file_names(dir, format).images + ":0: image " + std::to_string(im.id) + "'s name '" +
                 im.name.substr(0, 60) + "' holds a blank, which COLMAP's text format cannot hold; write the binary format";
        return false;
      }
    }
  }
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) return true;  // a new folder
  if (!S_ISDIR(st.st_mode)) {
    *error = dir + ":0: cannot write model: it is a file, not a folder";
    return false;
  }
  // The other format's files beside ours would be what COLMAP (and
  // read_colmap_model) reads first, or be read instead of ours.
  const detail::FileNames other =
      detail::file_names(dir, format == ColmapFormat::kBinary ? ColmapFormat::kText : ColmapFormat::kBinary);
  for (const std::string* f : {&other.cameras, &other.images, &other.points3D}) {
    if (exists(*f)) {
      *error = *f + ":0: a model in the other format is already there; write to another directory";
      return false;
    }
  }
  // Ours are renamed in one by one: one that cannot be replaced (a folder
  // by its name) would leave the others' new files beside its old one.
  const detail::FileNames ours = detail::file_names(dir, format);
  for (const std::string* f : {&ours.cameras, &ours.images, &ours.points3D}) {
    if (::stat(f->c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
      *error = *f + ":0: cannot write model: it is there and not a file";
      return false;
    }
  }
  return true;
}

bool write_colmap_model(const std::string& dir_as_given, const ColmapModel& model, ColmapFormat format,
                        std::string* error) {
  const std::string dir = without_trailing_slashes(dir_as_given);
  if (!colmap_model_writable(dir, model, format, error)) return false;
  const ColmapFiles files = format_colmap(model, format);
  // Staged on DIR's own file system: beside a new DIR, inside an existing one
  // (which may be a mount point), so the renames never cross devices.
  struct stat st {};
  const bool existing = ::stat(dir.c_str(), &st) == 0;
  const std::string tmp = existing ? dir + "/.keepless.tmp-" + std::to_string(::getpid())
                                   : dir + ".tmp-" + std::to_string(::getpid());
  const detail::FileNames staged = detail::file_names(tmp, format);
  const detail::FileNames final_names = detail::file_names(dir, format);
  const auto io_error = [&](const std::string& path, int err) {
    *error = path + ":0: cannot write model: " + std::strerror(err);
    std::remove(staged.cameras.c_str());
    std::remove(staged.images.c_str());
    std::remove(staged.points3D.c_str());
    ::rmdir(tmp.c_str());
    return false;
  };
  if (::mkdir(tmp.c_str(), 0777) != 0) {
    // The staging folder is ours; what the user can act on is the model's.
    if (errno == ENOENT) {
      *error = dir + ":0: cannot write model: its parent folder does not exist (create it first)";
      return false;
    }
    return io_error(tmp, errno);
  }
  const std::pair<const std::string*, const std::string*> parts[] = {
      {&staged.cameras, &files.cameras}, {&staged.images, &files.images}, {&staged.points3D, &files.points3D}};
  for (const auto& [path, contents] : parts) {
    const int err = write_whole_file(*path, *contents);
    if (err != 0) return io_error(*path, err);
  }
  // A new directory: all three files at once. An existing one: file by file.
  if (!existing) {
    if (std::rename(tmp.c_str(), dir.c_str()) != 0) return io_error(dir, errno);
    return true;
  }
  if (std::rename(staged.cameras.c_str(), final_names.cameras.c_str()) != 0 ||
      std::rename(staged.images.c_str(), final_names.images.c_str()) != 0 ||
      std::rename(staged.points3D.c_str(), final_names.points3D.c_str()) != 0) {
    return io_error(dir, errno);
  }
  ::rmdir(tmp.c_str());
  return true;
}

void remove_points(ColmapModel* model, const std::vector<bool>& culled) {
  std::unordered_set<std::uint64_t> gone;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < model->points.size(); ++i) {
    if (culled[i]) {
      gone.insert(model->points[i].id);
    } else {
      if (kept != i) model->points[kept] = std::move(model->points[i]);
      ++kept;
    }
  }
  model->points.resize(kept);
  for (ColmapImage& im : model->images) {
    for (ColmapPoint2D& p : im.points2D) {
      if (p.point3D_id != kNoPoint3D && gone.count(p.point3D_id) != 0) p.point3D_id = kNoPoint3D;
    }
  }
}

std::uint64_t compact_points2D(ColmapModel* model) {
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> renumber;  // image id -> new index per old one
  std::uint64_t dropped = 0;
  for (ColmapImage& im : model->images) {
    std::vector<std::uint32_t>& to = renumber[im.id];
    to.assign(im.points2D.size(), 0);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < im.points2D.size(); ++k) {
      if (im.points2D[k].point3D_id == kNoPoint3D) continue;
      to[k] = static_cast<std::uint32_t>(kept);
      im.points2D[kept++] = im.points2D[k];
    }
    dropped += im.points2D.size() - kept;
    im.points2D.resize(kept);
  }
  for (ColmapPoint3D& p : model->points) {
    for (ColmapTrackElement& e : p.track) e.point2D_idx = renumber[e.image_id][e.point2D_idx];
  }
  return dropped;
}

std::vector<std::uint32_t> observations_per_image(const ColmapModel& model) {
  std::vector<std::uint32_t> n(model.images.size(), 0);
  for (std::size_t i = 0; i < model.images.size(); ++i) {
    for (const ColmapPoint2D& p : model.images[i].points2D) n[i] += p.point3D_id != kNoPoint3D;
  }
  return n;
}

}  // namespace keepless::io
