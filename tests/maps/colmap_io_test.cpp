// keepless::io's COLMAP reader and writer: byte-exact round trips on the
// real fixture in both formats, and, on a small model encoded here field by
// field from COLMAP's documented layout, an error at the right FILE:OFFSET
// (or FILE:LINE) for a file cut at every byte (line) or spoilt at every field.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "keepless/io/colmap_model.hpp"
#include "maps_support.hpp"

namespace keepless {
namespace {

namespace fs = std::filesystem;
using maps_test::fixture;
using maps_test::read_all;

io::ColmapFiles read_files(const std::string& dir, const std::string& ext) {
  return {read_all(dir + "/cameras." + ext), read_all(dir + "/images." + ext), read_all(dir + "/points3D." + ext)};
}

void expect_same_files(const io::ColmapFiles& a, const io::ColmapFiles& b) {
  EXPECT_TRUE(a.cameras == b.cameras) << "cameras differ";
  EXPECT_TRUE(a.images == b.images) << "images differ (" << a.images.size() << " vs " << b.images.size() << " bytes)";
  EXPECT_TRUE(a.points3D == b.points3D) << "points3D differ (" << a.points3D.size() << " vs " << b.points3D.size()
                                        << " bytes)";
}

// Records sorted by id: COLMAP writes them in its hash maps' order, which
// differs between a model it read from .bin and one it read from .txt.
io::ColmapModel sorted(io::ColmapModel m) {
  std::sort(m.cameras.begin(), m.cameras.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  std::sort(m.images.begin(), m.images.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  std::sort(m.points.begin(), m.points.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return m;
}

TEST(ColmapFixture, EachFormatRoundTripsByteForByteThroughTheOther) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  KEEPLESS_MAPS_NEED(maps_test::fixture("txt/images.txt"));
  const io::ColmapFiles bin = read_files(fixture("sparse"), "bin");
  const io::ColmapFiles txt = read_files(fixture("txt"), "txt");
  io::ColmapModel from_bin, from_txt;
  std::string error;
  ASSERT_TRUE(io::parse_colmap("sparse", bin, io::ColmapFormat::kBinary, &from_bin, &error)) << error;
  ASSERT_TRUE(io::parse_colmap("txt", txt, io::ColmapFormat::kText, &from_txt, &error)) << error;
  EXPECT_EQ(from_bin.cameras.size(), 1u);
  EXPECT_EQ(from_bin.images.size(), 51u);
  EXPECT_EQ(from_bin.points.size(), 14195u);
  std::size_t observations = 0;
  for (const auto& p : from_bin.points) observations += p.track.size();
  EXPECT_EQ(observations, 83883u);  // SOURCES.md

  expect_same_files(io::format_colmap(from_bin, io::ColmapFormat::kBinary), bin);
  expect_same_files(io::format_colmap(from_txt, io::ColmapFormat::kText), txt);
  // bin -> txt -> bin and txt -> bin -> txt.
  io::ColmapModel via;
  ASSERT_TRUE(io::parse_colmap("x", io::format_colmap(from_bin, io::ColmapFormat::kText), io::ColmapFormat::kText,
                               &via, &error))
      << error;
  expect_same_files(io::format_colmap(via, io::ColmapFormat::kBinary), bin);
  ASSERT_TRUE(io::parse_colmap("x", io::format_colmap(from_txt, io::ColmapFormat::kBinary), io::ColmapFormat::kBinary,
                               &via, &error))
      << error;
  expect_same_files(io::format_colmap(via, io::ColmapFormat::kText), txt);
  // COLMAP's own .txt of the .bin holds the same records (in another order)
  // and every number to the bit.
  expect_same_files(io::format_colmap(sorted(from_bin), io::ColmapFormat::kText),
                    io::format_colmap(sorted(from_txt), io::ColmapFormat::kText));
  expect_same_files(io::format_colmap(sorted(from_bin), io::ColmapFormat::kBinary),
                    io::format_colmap(sorted(from_txt), io::ColmapFormat::kBinary));
}

TEST(ColmapFixture, RemovingPointsClearsTheirReferencesAndKeepsEverythingElse) {
  KEEPLESS_MAPS_NEED(maps_test::fixture("sparse/images.bin"));
  io::ColmapModel m;
  io::ColmapFormat format;
  std::string error;
  ASSERT_TRUE(io::read_colmap_model(fixture("sparse"), &m, &format, &error)) << error;
  EXPECT_EQ(format, io::ColmapFormat::kBinary);
  const io::ColmapModel before = m;
  std::vector<bool> culled(m.points.size());
  for (std::size_t i = 0; i < culled.size(); ++i) culled[i] = i % 3 != 0;
  io::remove_points(&m, culled);
  ASSERT_EQ(m.points.size(), (before.points.size() + 2) / 3);
  std::string again;
  io::ColmapModel reread;
  const io::ColmapFiles files = io::format_colmap(m, io::ColmapFormat::kBinary);
  ASSERT_TRUE(io::parse_colmap("x", files, io::ColmapFormat::kBinary, &reread, &error)) << error;  // consistent
  for (std::size_t i = 0; i < m.images.size(); ++i) {
    ASSERT_EQ(m.images[i].points2D.size(), before.images[i].points2D.size());
    EXPECT_EQ(m.images[i].name, before.images[i].name);
    for (std::size_t k = 0; k < m.images[i].points2D.size(); ++k) {
      const auto& now = m.images[i].points2D[k];
      const auto& was = before.images[i].points2D[k];
      EXPECT_EQ(now.x, was.x);
      EXPECT_EQ(now.y, was.y);
      EXPECT_TRUE(now.point3D_id == was.point3D_id || now.point3D_id == io::kNoPoint3D);
    }
  }
  EXPECT_TRUE(io::format_colmap(m, io::ColmapFormat::kBinary).cameras ==
              io::format_colmap(before, io::ColmapFormat::kBinary).cameras);
}

TEST(ColmapCameraModels, ParameterCountsAreCOLMAPs) {
  // COLMAP's src/base/camera_models.h: model id, name, parameter count.
  const struct {
    int id;
    const char* name;
    int params;
  } documented[] = {{0, "SIMPLE_PINHOLE", 3}, {1, "PINHOLE", 4},        {2, "SIMPLE_RADIAL", 4},
                    {3, "RADIAL", 5},         {4, "OPENCV", 8},         {5, "OPENCV_FISHEYE", 8},
                    {6, "FULL_OPENCV", 12},   {7, "FOV", 5},            {8, "SIMPLE_RADIAL_FISHEYE", 4},
                    {9, "RADIAL_FISHEYE", 5}, {10, "THIN_PRISM_FISHEYE", 12}};
  for (const auto& d : documented) {
    const io::CameraModelInfo* by_id = io::camera_model_by_id(d.id);
    ASSERT_NE(by_id, nullptr) << d.name;
    EXPECT_STREQ(by_id->name, d.name);
    EXPECT_EQ(by_id->num_params, d.params) << d.name;
    EXPECT_EQ(io::camera_model_by_name(d.name), by_id);
  }
  EXPECT_EQ(io::camera_model_by_id(-1), nullptr);
  EXPECT_EQ(io::camera_model_by_id(12), nullptr);
  EXPECT_EQ(io::camera_model_by_name("pinhole"), nullptr);
}

// ---- A small model, and its binary files encoded here with each field's offset.

io::ColmapModel small_model() {
  io::ColmapModel m;
  for (int c = 0; c <= 11; ++c) {  // one camera of every model
    io::ColmapCamera cam;
    cam.id = static_cast<std::uint32_t>(c + 1);
    cam.model_id = c;
    cam.width = 640 + c;
    cam.height = 480;
    for (int k = 0; k < io::camera_model_by_id(c)->num_params; ++k) cam.params.push_back(100.5 + k * 0.25);
    m.cameras.push_back(cam);
  }
  // Points 7, 9, 12; image 5 sees point 9 twice (as COLMAP tracks can).
  const auto image = [](std::uint32_t id, std::uint32_t camera, const char* name,
                        std::vector<io::ColmapPoint2D> pts) {
    io::ColmapImage im;
    im.id = id;
    im.qvec[0] = 0.5;
    im.qvec[1] = 0.5;
    im.qvec[2] = -0.5;
    im.qvec[3] = 0.5;
    im.tvec[0] = id * 0.5;
    im.tvec[1] = -1.25;
    im.tvec[2] = 3;
    im.camera_id = camera;
    im.name = name;
    im.points2D = std::move(pts);
    return im;
  };
  m.images.push_back(image(5, 2, "b.png", {{1.5, 2.5, 9}, {3.5, 4.5, io::kNoPoint3D}, {5.5, 6.5, 7}, {7.5, 8.5, 9}}));
  m.images.push_back(image(2, 1, "a.png", {{10.25, 20.5, 7}, {30.5, 40.5, 12}, {50.5, 60.5, 9}}));
  m.images.push_back(image(8, 12, "c.png", {}));
  m.images.push_back(image(3, 3, "d.png", {{1, 1, 12}}));
  const auto point = [](std::uint64_t id, std::vector<io::ColmapTrackElement> track) {
    io::ColmapPoint3D p;
    p.id = id;
    p.xyz[0] = 1.0 * id;
    p.xyz[1] = -2.5;
    p.xyz[2] = 7.125;
    p.rgb[0] = 255;
    p.rgb[1] = 0;
    p.rgb[2] = 17;
    p.error = 0.375;
    p.track = std::move(track);
    return p;
  };
  m.points.push_back(point(9, {{5, 0}, {2, 2}, {5, 3}}));
  m.points.push_back(point(7, {{2, 0}, {5, 2}}));
  m.points.push_back(point(12, {{2, 1}, {3, 0}}));
  return m;
}

// A count field: the records after it take at least `min_record` bytes each.
struct Field {
  std::size_t offset;
  std::size_t size;
  std::string kind;
  std::uint64_t count = 0;
  std::uint64_t min_record = 0;
};

class Encoder {
 public:
  template <typename T>
  void put(const char* kind, T v) {
    fields.push_back({bytes.size(), sizeof(T), kind});
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    bytes.append(b, sizeof(T));
  }
  void count(std::uint64_t n, std::uint64_t min_record) {
    put<std::uint64_t>("count", n);
    fields.back().count = n;
    fields.back().min_record = min_record;
  }
  void name(const std::string& s) {
    fields.push_back({bytes.size(), s.size() + 1, "name"});
    bytes += s;
    bytes += '\0';
  }
  std::string bytes;
  std::vector<Field> fields;
};

// COLMAP's layout, written out independently of the library.
Encoder encode_cameras(const io::ColmapModel& m) {
  Encoder e;
  e.count(m.cameras.size(), 24);
  for (const auto& c : m.cameras) {
    e.put<std::uint32_t>("camera_id", c.id);
    e.put<std::int32_t>("model_id", c.model_id);
    e.put<std::uint64_t>("width", c.width);
    e.put<std::uint64_t>("height", c.height);
    for (double p : c.params) e.put<double>("f64", p);
  }
  return e;
}
Encoder encode_images(const io::ColmapModel& m) {
  Encoder e;
  e.count(m.images.size(), 74);
  for (const auto& im : m.images) {
    e.put<std::uint32_t>("image_id", im.id);
    for (double q : im.qvec) e.put<double>("f64", q);
    for (double t : im.tvec) e.put<double>("f64", t);
    e.put<std::uint32_t>("camera_id", im.camera_id);
    e.name(im.name);
    e.count(im.points2D.size(), 24);
    for (const auto& p : im.points2D) {
      e.put<double>("f64", p.x);
      e.put<double>("f64", p.y);
      e.put<std::uint64_t>("point3D_id", p.point3D_id);
    }
  }
  return e;
}
Encoder encode_points(const io::ColmapModel& m) {
  Encoder e;
  e.count(m.points.size(), 51);
  for (const auto& p : m.points) {
    e.put<std::uint64_t>("point3D_id", p.id);
    for (double x : p.xyz) e.put<double>("f64", x);
    for (std::uint8_t c : p.rgb) e.put<std::uint8_t>("rgb", c);
    e.put<double>("f64", p.error);
    e.count(p.track.size(), 8);
    for (const auto& t : p.track) {
      e.put<std::uint32_t>("track_image", t.image_id);
      e.put<std::uint32_t>("track_idx", t.point2D_idx);
    }
  }
  return e;
}

// Where a reader must stop on a file cut to `length` bytes: the first field
// not complete, or an earlier count that the bytes left cannot hold.
std::size_t expected_offset(const std::vector<Field>& fields, std::size_t length) {
  for (const Field& f : fields) {
    if (f.offset + f.size > length) return f.offset;
    if (f.min_record > 0 && f.count > (length - f.offset - f.size) / f.min_record) return f.offset;
  }
  return std::string::npos;
}

std::string error_of(const io::ColmapFiles& files, io::ColmapFormat format) {
  io::ColmapModel m;
  std::string error;
  EXPECT_FALSE(io::parse_colmap("D", files, format, &m, &error)) << "accepted a bad model";
  return error;
}

class ColmapBinaryErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    model = small_model();
    enc[0] = encode_cameras(model);
    enc[1] = encode_images(model);
    enc[2] = encode_points(model);
    files = io::format_colmap(model, io::ColmapFormat::kBinary);
  }
  std::string& part(io::ColmapFiles& f, int i) { return i == 0 ? f.cameras : (i == 1 ? f.images : f.points3D); }
  io::ColmapModel model;
  Encoder enc[3];
  io::ColmapFiles files;
  const char* names[3] = {"D/cameras.bin", "D/images.bin", "D/points3D.bin"};
};

TEST_F(ColmapBinaryErrors, TheLibraryWritesTheDocumentedLayoutAndReadsItBack) {
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(part(files, i) == enc[i].bytes) << names[i];
  io::ColmapModel back;
  std::string error;
  ASSERT_TRUE(io::parse_colmap("D", files, io::ColmapFormat::kBinary, &back, &error)) << error;
  const io::ColmapFiles again = io::format_colmap(back, io::ColmapFormat::kBinary);
  EXPECT_TRUE(again.images == files.images && again.points3D == files.points3D && again.cameras == files.cameras);
  ASSERT_EQ(back.cameras.size(), 12u);
  EXPECT_EQ(back.cameras[11].params.size(), 16u);
}

TEST_F(ColmapBinaryErrors, AFileCutAtEveryByteFailsAtTheFieldItCut) {
  for (int i = 0; i < 3; ++i) {
    const std::string whole = part(files, i);
    for (std::size_t length = 0; length < whole.size(); ++length) {
      io::ColmapFiles cut = files;
      part(cut, i) = whole.substr(0, length);
      const std::string error = error_of(cut, io::ColmapFormat::kBinary);
      const std::string want = std::string(names[i]) + ":" + std::to_string(expected_offset(enc[i].fields, length)) + ": ";
      ASSERT_EQ(error.rfind(want, 0), 0u) << "cut at " << length << ": " << error;
    }
  }
}

TEST_F(ColmapBinaryErrors, TrailingBytesAreRefused) {
  for (int i = 0; i < 3; ++i) {
    io::ColmapFiles longer = files;
    part(longer, i) += '\0';
    EXPECT_EQ(error_of(longer, io::ColmapFormat::kBinary),
              std::string(names[i]) + ":" + std::to_string(part(files, i).size()) + ": 1 bytes after the last record");
  }
}

TEST_F(ColmapBinaryErrors, ANonFiniteNumberInAnyFieldIsRefusedAtItsOffset) {
  for (int i = 0; i < 3; ++i) {
    for (const Field& f : enc[i].fields) {
      if (f.kind != "f64") continue;
      for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
        io::ColmapFiles spoilt = files;
        std::memcpy(&part(spoilt, i)[f.offset], &bad, sizeof bad);
        const std::string error = error_of(spoilt, io::ColmapFormat::kBinary);
        const std::string want = std::string(names[i]) + ":" + std::to_string(f.offset) + ": non-finite";
        ASSERT_EQ(error.rfind(want, 0), 0u) << error;
      }
    }
  }
}

// Every id and index field, set to a value that breaks a reference, is
// reported at its own offset (or, for an image's camera or a duplicated id,
// at the start of the record holding it).
TEST_F(ColmapBinaryErrors, BrokenIdsAndReferencesAreRefusedWhereTheyAre) {
  struct Case {
    int file;
    const char* kind;
    std::uint64_t value;
    const char* reason;
  };
  const Case cases[] = {
      {0, "model_id", 12, "unknown camera model id 12"},
      {0, "camera_id", 0xFFFFFFFFu, "camera id 4294967295 is COLMAP's invalid id"},
      {1, "point3D_id", 99, "names unknown point3D 99"},
      {2, "track_idx", 1000, "has no 2D point 1000"},
      {2, "track_image", 77, "unknown image 77"},
  };
  for (const Case& c : cases) {
    int spoilt_fields = 0;  // a renamed field kind would otherwise check nothing
    for (const Field& f : enc[c.file].fields) {
      if (f.kind != c.kind) continue;
      ++spoilt_fields;
      io::ColmapFiles spoilt = files;
      std::memcpy(&part(spoilt, c.file)[f.offset], &c.value, f.size);
      const std::string error = error_of(spoilt, io::ColmapFormat::kBinary);
      // A 2D point whose 3D point is "none" now names 99: still unknown.
      const std::string want = std::string(names[c.file]) + ":" + std::to_string(f.offset) + ": ";
      EXPECT_EQ(error.rfind(want, 0), 0u) << c.kind << " at " << f.offset << ": " << error;
      EXPECT_NE(error.find(c.reason), std::string::npos) << error;
    }
    EXPECT_GT(spoilt_fields, 0) << c.kind;
  }
  // An image naming a camera that does not exist: at the image's record.
  io::ColmapFiles spoilt = files;
  const Field* camera = nullptr;
  const Field* first = nullptr;
  for (const Field& f : enc[1].fields) {
    if (f.kind == "image_id" && first == nullptr) first = &f;
    if (f.kind == "camera_id") {
      camera = &f;
      break;
    }
  }
  ASSERT_TRUE(camera != nullptr && first != nullptr);
  const std::uint32_t unknown = 500;
  std::memcpy(&spoilt.images[camera->offset], &unknown, 4);
  EXPECT_EQ(error_of(spoilt, io::ColmapFormat::kBinary),
            "D/images.bin:" + std::to_string(first->offset) + ": image 5 names unknown camera 500");
  // A count of 2^60 records cannot allocate: refused at the count.
  spoilt = files;
  const std::uint64_t huge = std::uint64_t{1} << 60;
  std::memcpy(&spoilt.points3D[0], &huge, 8);
  EXPECT_EQ(error_of(spoilt, io::ColmapFormat::kBinary).rfind("D/points3D.bin:0: num_points3D 1152921504606846976", 0),
            0u);
}

TEST_F(ColmapBinaryErrors, TracksAndImagesMustReferenceEachOtherExactly) {
  // Point 7's track drops (5, 2): image 5's 2D point 2 still names point 7.
  io::ColmapModel m = small_model();
  m.points[1].track.pop_back();
  io::ColmapFiles f = io::format_colmap(m, io::ColmapFormat::kBinary);
  std::string error = error_of(f, io::ColmapFormat::kBinary);
  EXPECT_NE(error.find("D/images.bin:"), std::string::npos) << error;
  EXPECT_NE(error.find("is not in the track of point3D 7"), std::string::npos) << error;
  // A repeated track element.
  m = small_model();
  m.points[1].track.push_back(m.points[1].track[0]);
  error = error_of(io::format_colmap(m, io::ColmapFormat::kBinary), io::ColmapFormat::kBinary);
  EXPECT_NE(error.find("D/points3D.bin:"), std::string::npos) << error;
  EXPECT_NE(error.find("repeated"), std::string::npos) << error;
  // Duplicate ids.
  m = small_model();
  m.images[1].id = 5;
  EXPECT_NE(error_of(io::format_colmap(m, io::ColmapFormat::kText), io::ColmapFormat::kText)
                .find("D/images.txt:7: duplicate image id 5"),
            std::string::npos);
}

// ---- Text: every field spoilt, and the files cut at every line.

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> lines;
  std::size_t at = 0;
  while (at < s.size()) {
    const std::size_t nl = s.find('\n', at);
    lines.push_back(s.substr(at, nl - at));
    at = nl + 1;
  }
  return lines;
}

TEST(ColmapText, EveryFieldSpoiltIsReportedOnItsLine) {
  const io::ColmapFiles files = io::format_colmap(small_model(), io::ColmapFormat::kText);
  const char* names[3] = {"D/cameras.txt", "D/images.txt", "D/points3D.txt"};
  const std::string* parts[3] = {&files.cameras, &files.images, &files.points3D};
  int spoilt_fields = 0;
  for (int i = 0; i < 3; ++i) {
    const std::vector<std::string> lines = split_lines(*parts[i]);
    for (std::size_t l = 0; l < lines.size(); ++l) {
      if (lines[l].empty() || lines[l][0] == '#') continue;
      const bool image_line = i == 1 && lines[l].find(".png") != std::string::npos;
      std::vector<std::size_t> starts;
      for (std::size_t c = 0; c < lines[l].size(); ++c) {
        if (lines[l][c] != ' ' && (c == 0 || lines[l][c - 1] == ' ')) starts.push_back(c);
      }
      for (std::size_t t = 0; t < starts.size(); ++t) {
        if (image_line && t == 9) continue;  // NAME: any text
        std::string bad = lines[l];
        const std::size_t end = bad.find(' ', starts[t]);
        bad.replace(starts[t], (end == std::string::npos ? bad.size() : end) - starts[t], "1x");
        std::vector<std::string> copy = lines;
        copy[l] = bad;
        std::string text;
        for (const std::string& s : copy) text += s + "\n";
        io::ColmapFiles spoilt = files;
        *(i == 0 ? &spoilt.cameras : (i == 1 ? &spoilt.images : &spoilt.points3D)) = text;
        const std::string error = error_of(spoilt, io::ColmapFormat::kText);
        const std::string want = std::string(names[i]) + ":" + std::to_string(l + 1) + ": ";
        ASSERT_EQ(error.rfind(want, 0), 0u) << "field " << t << " of line " << l + 1 << ": " << error;
        ++spoilt_fields;
      }
    }
  }
  EXPECT_GT(spoilt_fields, 100);
}

TEST(ColmapText, FilesCutAtEveryLineAreRefused) {
  const io::ColmapFiles files = io::format_colmap(small_model(), io::ColmapFormat::kText);
  for (int i = 0; i < 3; ++i) {
    const std::string& whole = i == 0 ? files.cameras : (i == 1 ? files.images : files.points3D);
    const std::vector<std::string> lines = split_lines(whole);
    std::string text;
    for (std::size_t l = 0; l < lines.size(); ++l) {
      io::ColmapFiles cut = files;
      *(i == 0 ? &cut.cameras : (i == 1 ? &cut.images : &cut.points3D)) = text;
      const std::string error = error_of(cut, io::ColmapFormat::kText);
      EXPECT_EQ(error.rfind("D/", 0), 0u) << error;
      EXPECT_NE(error.find(".txt:"), std::string::npos) << error;
      text += lines[l] + "\n";
    }
  }
}

// Old Mac line endings made each file one '#' line: an empty model, read
// without a word. CRLF stays accepted.
TEST(ColmapText, ACarriageReturnWithoutALineFeedIsRefusedOnItsLine) {
  io::ColmapFiles f = io::format_colmap(small_model(), io::ColmapFormat::kText);
  io::ColmapFiles crlf = f;
  for (std::string* t : {&crlf.cameras, &crlf.images, &crlf.points3D}) {
    std::string out;
    for (const char c : *t) out += c == '\n' ? std::string("\r\n") : std::string(1, c);
    *t = out;
  }
  io::ColmapModel m;
  std::string error;
  EXPECT_TRUE(io::parse_colmap("D", crlf, io::ColmapFormat::kText, &m, &error)) << error;
  EXPECT_EQ(m.images.size(), small_model().images.size());
  std::replace(f.images.begin(), f.images.end(), '\n', '\r');
  EXPECT_EQ(error_of(f, io::ColmapFormat::kText),
            "D/images.txt:1: a carriage return not followed by a line feed (lines end in \\n or \\r\\n)");
}

TEST(ColmapText, ModelNamesAndParameterCountsAreChecked) {
  io::ColmapFiles f = io::format_colmap(small_model(), io::ColmapFormat::kText);
  f.cameras = "1 PINHOLE 640 480 1 2 3\n";
  EXPECT_EQ(error_of(f, io::ColmapFormat::kText), "D/cameras.txt:1: PINHOLE takes 4 parameters, got 3");
  f.cameras = "# c\n\n1 PINHOLE_X 640 480 1 2 3 4\n";
  EXPECT_EQ(error_of(f, io::ColmapFormat::kText), "D/cameras.txt:3: unknown camera model 'PINHOLE_X'");
  f.cameras = std::string("1 PINHOLE") + '\0' + " 640 480 1 2 3 4\n";  // the NUL shown, not written raw
  EXPECT_EQ(error_of(f, io::ColmapFormat::kText), "D/cameras.txt:1: unknown camera model 'PINHOLE\\0'");
}

// Fuzzer finding: images.bin ends a name at its NUL, so a text name holding
// one parsed but could not be written to binary and read back.
TEST(ColmapText, AnImageNameWithANulByteIsRefused) {
  io::ColmapFiles f = io::format_colmap(small_model(), io::ColmapFormat::kText);
  const std::size_t name = f.images.find(".png");
  ASSERT_NE(name, std::string::npos);
  const std::size_t line = static_cast<std::size_t>(std::count(f.images.begin(), f.images.begin() + name, '\n')) + 1;
  f.images.insert(name, 1, '\0');
  EXPECT_EQ(error_of(f, io::ColmapFormat::kText), "D/images.txt:" + std::to_string(line) + ": NAME holds a NUL byte");
}

// The 1-based line of images.txt holding `needle`.
std::size_t line_of(const std::string& text, const std::string& needle) {
  const std::size_t at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  return static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n')) + 1;
}

TEST(ColmapText, ANumberFollowedByANulIsRefused) {
  io::ColmapFiles f = io::format_colmap(small_model(), io::ColmapFormat::kText);
  // Image 5's CAMERA_ID "2" becomes "2\0": a C-string parse would read 2.
  const std::string record = "\n5 ";
  const std::size_t line = line_of(f.images, record) + 1;
  const std::size_t name = f.images.find(" b.png");
  ASSERT_NE(name, std::string::npos);
  f.images.insert(name, 1, '\0');
  EXPECT_EQ(error_of(f, io::ColmapFormat::kText),
            "D/images.txt:" + std::to_string(line) + ": bad CAMERA_ID '2\\0' (field 9, an unsigned integer)");
}

// Numbers are read as the other readers read them: a subnormal is the double
// it names (a binary model may hold one, "%.17g" writes it), an underflow to 0
// is out of range.
TEST(ColmapText, ASubnormalIsReadAndAnUnderflowIsRefused) {
  io::ColmapModel model = small_model();
  model.cameras[0].params[0] = std::numeric_limits<double>::denorm_min();
  io::ColmapFiles f = io::format_colmap(model, io::ColmapFormat::kText);
  io::ColmapModel back;
  std::string error;
  ASSERT_TRUE(io::parse_colmap("D", f, io::ColmapFormat::kText, &back, &error)) << error;
  EXPECT_EQ(back.cameras[0].params[0], std::numeric_limits<double>::denorm_min());
  const std::string subnormal = "4.9406564584124654e-324";
  const std::size_t at = f.cameras.find(subnormal);
  ASSERT_NE(at, std::string::npos) << f.cameras;
  const auto line = std::count(f.cameras.begin(), f.cameras.begin() + static_cast<std::ptrdiff_t>(at), '\n') + 1;
  f.cameras.replace(at, subnormal.size(), "1e-400");
  EXPECT_EQ(error_of(f, io::ColmapFormat::kText),
            "D/cameras.txt:" + std::to_string(line) + ": bad camera parameter '1e-400' (field 5, a finite number)");
}

// COLMAP's text reader ends a name at its first space: refused in text (read
// and write), kept exactly in binary.
TEST(ColmapText, AnImageNameWithABlankIsRefusedInTextAndKeptInBinary) {
  io::ColmapModel m = small_model();
  m.images[0].name = "left camera/b.png";
  io::ColmapFiles bin = io::format_colmap(m, io::ColmapFormat::kBinary);
  io::ColmapModel back;
  std::string error;
  ASSERT_TRUE(io::parse_colmap("D", bin, io::ColmapFormat::kBinary, &back, &error)) << error;
  EXPECT_EQ(back.images[0].name, "left camera/b.png");
  // Written as text by hand (format_colmap does not check): refused on reading.
  io::ColmapFiles txt = io::format_colmap(m, io::ColmapFormat::kText);
  EXPECT_EQ(error_of(txt, io::ColmapFormat::kText),
            "D/images.txt:" + std::to_string(line_of(txt.images, "left camera")) +
                ": NAME 'left camera/b.png' holds a blank: COLMAP would read it as 'left'");
  // write_colmap_model refuses text and writes binary.
  std::string dir = ::testing::TempDir() + "keepless_names_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  EXPECT_FALSE(io::write_colmap_model(dir + "/t", m, io::ColmapFormat::kText, &error));
  EXPECT_EQ(error, dir + "/t/images.txt:0: image 5's name 'left camera/b.png' holds a blank, which COLMAP's text "
                         "format cannot hold; write the binary format");
  EXPECT_FALSE(fs::exists(dir + "/t"));
  EXPECT_TRUE(io::write_colmap_model(dir + "/b", m, io::ColmapFormat::kBinary, &error)) << error;
  // A missing parent folder is named as the model's, not the staging folder's.
  EXPECT_FALSE(io::write_colmap_model(dir + "/none/b", m, io::ColmapFormat::kBinary, &error));
  EXPECT_EQ(error, dir + "/none/b:0: cannot write model: its parent folder does not exist (create it first)");
  EXPECT_FALSE(fs::exists(dir + "/none"));
  io::ColmapFormat format;
  ASSERT_TRUE(io::read_colmap_model(dir + "/b", &back, &format, &error)) << error;
  EXPECT_EQ(back.images[0].name, "left camera/b.png");
  fs::remove_all(dir);
}

TEST(ColmapModelChecks, DuplicateImageNamesAreRefused) {
  io::ColmapModel m = small_model();
  m.images[2].name = "b.png";  // image 8 takes image 5's name
  const io::ColmapFiles txt = io::format_colmap(m, io::ColmapFormat::kText);
  EXPECT_EQ(error_of(txt, io::ColmapFormat::kText),
            "D/images.txt:" + std::to_string(line_of(txt.images, "\n8 ") + 1) +
                ": image 8 has the name 'b.png' of image 5 (names must be unique)");
  const Encoder enc = encode_images(m);
  std::size_t third = 0, seen = 0;
  for (const Field& f : enc.fields) {
    if (f.kind == "image_id" && ++seen == 3) third = f.offset;
  }
  EXPECT_EQ(error_of(io::format_colmap(m, io::ColmapFormat::kBinary), io::ColmapFormat::kBinary),
            "D/images.bin:" + std::to_string(third) + ": image 8 has the name 'b.png' of image 5 (names must be unique)");
}

TEST(ColmapModelChecks, CameraSidesOfZeroOrBeyondIntAreRefused) {
  for (const std::uint64_t bad : {std::uint64_t{0}, std::uint64_t{1} << 31, std::uint64_t{1} << 63}) {
    for (const bool width : {true, false}) {
      SCOPED_TRACE(std::to_string(bad) + (width ? " wide" : " high"));
      io::ColmapModel m = small_model();
      (width ? m.cameras[1].width : m.cameras[1].height) = bad;
      const std::string size = std::to_string(m.cameras[1].width) + "x" + std::to_string(m.cameras[1].height);
      const std::string reason = "camera 2 is " + size + " pixels (each side must be 1..2147483647)";
      const Encoder enc = encode_cameras(m);
      std::size_t at = 0, seen = 0;
      for (const Field& f : enc.fields) {
        if (f.kind == (width ? "width" : "height") && ++seen == 2) at = f.offset;
      }
      EXPECT_EQ(error_of(io::format_colmap(m, io::ColmapFormat::kBinary), io::ColmapFormat::kBinary),
                "D/cameras.bin:" + std::to_string(at) + ": " + reason);
      EXPECT_EQ(error_of(io::format_colmap(m, io::ColmapFormat::kText), io::ColmapFormat::kText),
                "D/cameras.txt:5: " + reason);
    }
  }
}

TEST(ColmapModelFiles, AFolderWithoutAModelIsNamed) {
  std::string dir = ::testing::TempDir() + "keepless_nomodel_XXXXXX";
  ASSERT_NE(::mkdtemp(dir.data()), nullptr);
  io::ColmapModel m;
  io::ColmapFormat format;
  std::string error;
  EXPECT_FALSE(io::read_colmap_model(dir, &m, &format, &error));
  EXPECT_EQ(error, dir + ": no COLMAP model (cameras/images/points3D .bin or .txt)");
  EXPECT_FALSE(io::read_colmap_model(dir + "/absent", &m, &format, &error));
  EXPECT_EQ(error, dir + "/absent: no COLMAP model (cameras/images/points3D .bin or .txt)");
  // Some binary files: the missing one is named.
  maps_test::write_all(dir + "/images.bin", "x");
  EXPECT_FALSE(io::read_colmap_model(dir, &m, &format, &error));
  EXPECT_EQ(error.rfind(dir + "/cameras.bin:0: cannot open: No such file", 0), 0u) << error;
  fs::remove_all(dir);
}

// --compact: unmatched 2D points go, the tracks are renumbered, the model
// stays consistent (the reader's cross-checks pass) in both formats.
TEST(ColmapModelFiles, CompactDropsUnmatchedPoints2DAndRenumbersTracks) {
  io::ColmapModel m = small_model();
  io::remove_points(&m, {false, true, false});  // point 7 goes: two more 2D points become unmatched
  const std::vector<std::uint32_t> before = io::observations_per_image(m);
  EXPECT_EQ(io::compact_points2D(&m), 3u);  // image 5: two, image 2: one
  EXPECT_EQ(io::observations_per_image(m), before);
  for (const io::ColmapImage& im : m.images) {
    for (const io::ColmapPoint2D& p : im.points2D) EXPECT_NE(p.point3D_id, io::kNoPoint3D);
  }
  EXPECT_EQ(m.images[0].points2D.size(), 2u);
  EXPECT_EQ(m.images[0].points2D[1].x, 7.5);  // image 5's old 2D point 3
  for (const io::ColmapFormat format : {io::ColmapFormat::kBinary, io::ColmapFormat::kText}) {
    io::ColmapModel back;
    std::string error;
    ASSERT_TRUE(io::parse_colmap("D", io::format_colmap(m, format), format, &back, &error)) << error;
    EXPECT_EQ(back.points[0].track[2].point2D_idx, 1u);  // point 9 in image 5: 3 -> 1
  }
}

}  // namespace
}  // namespace keepless
