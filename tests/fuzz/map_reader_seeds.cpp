// Writes the seed corpora of colmap_reader_fuzz and bal_reader_fuzz into
// argv[1]: a small consistent COLMAP model (two images sharing two points) in
// both formats, framed as colmap_reader_fuzz reads its input, and a small BAL
// problem. argv[2] picks the corpus (colmap or bal). Every seed is checked
// to parse, so a reader change that refuses them fails the build.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "keepless/io/bal_problem.hpp"
#include "keepless/io/colmap_model.hpp"

namespace io = keepless::io;

namespace {

bool write(const std::string& path, const std::string& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  return std::fclose(f) == 0 && ok;
}

// colmap_reader_fuzz's framing: format byte, two u16 lengths, the files.
std::string frame(io::ColmapFormat format, const io::ColmapFiles& f) {
  std::string s(1, format == io::ColmapFormat::kBinary ? '\0' : '\1');
  for (const std::size_t n : {f.cameras.size(), f.images.size()}) {
    s += static_cast<char>(n & 0xff);
    s += static_cast<char>((n >> 8) & 0xff);
  }
  return s + f.cameras + f.images + f.points3D;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) return 2;
  const std::string dir = argv[1], which = argv[2];
  std::string error;
  if (which == "colmap") {
    const io::ColmapFiles text{
        "# Camera list\n1 PINHOLE 640 480 500 500 320 240\n2 SIMPLE_RADIAL 640 480 510 320 240 0.01\n",
        "1 1 0 0 0 0 0 0 1 a.png\n10 20 7 30 40 8 50 60 -1\n"
        "2 0.70710678118654757 0 0.70710678118654757 0 1 0 0 2 b.png\n11 21 7 31 41 8\n",
        "7 0 0 5 255 0 0 0.5 1 0 2 0\n8 1 1 5 0 255 0 0.25 1 1 2 1\n"};
    io::ColmapModel model;
    if (!io::parse_colmap("seed", text, io::ColmapFormat::kText, &model, &error)) {
      std::fprintf(stderr, "map_reader_seeds: %s\n", error.c_str());
      return 1;
    }
    const bool ok = write(dir + "/text", frame(io::ColmapFormat::kText, text)) &&
                    write(dir + "/binary", frame(io::ColmapFormat::kBinary,
                                                 io::format_colmap(model, io::ColmapFormat::kBinary)));
    return ok ? 0 : 1;
  }
  if (which == "bal") {
    const std::string bal =
        "2 2 4\n0 0 -1.5 2.25\n1 0 3 -4\n0 1 0.5 0.5\n1 1 -0 1e-3\n"
        "0\n0\n0\n0\n0\n0\n500\n0\n0\n0.01\n0.02\n-0.03\n1\n0\n0\n510\n-0.1\n0.01\n"
        "0\n0\n-5\n1\n1\n-6\n";
    io::BalProblem p;
    if (!io::parse_bal("seed", bal, &p, &error)) {
      std::fprintf(stderr, "map_reader_seeds: %s\n", error.c_str());
      return 1;
    }
    return write(dir + "/problem", bal) ? 0 : 1;
  }
  return 2;
}
