// keepless_make_colmap: a synthetic COLMAP binary model for scale runs.
//
//   keepless_make_colmap --out DIR [--images 1000] [--points 100000] [--seed 1]
//
// A PINHOLE camera (KITTI's intrinsics) drives straight down +z, 1 m per
// image; each point is seen by a run of consecutive images (track length
// 2 + a geometric draw of mean 3: mean ~5, the KITTI fixture's is ~6), lies ahead of
// the last of them, and is projected exactly into each. Deterministic for a
// seed (std::mt19937_64).

#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include <vector>

#include "cli/cli.hpp"
#include "keepless/core/window_file.hpp"
#include "keepless/io/colmap_model.hpp"

int main(int argc, char** argv) {
  namespace io = keepless::io;
  namespace cli = keepless::cli;
  constexpr const char* kTool = "keepless_make_colmap";
  const std::vector<cli::Flag> flags = {
      {"--out", "DIR", "the model directory to write (required)"},
      {"--images", "N", "images, 2..10000000 (default 1000)"},
      {"--points", "N", "3D points, 0..4294967295 (default 100000)"},
      {"--seed", "S", "random seed (default 1)"},
  };
  std::string out;
  std::uint32_t images = 1000, points = 100000;
  std::uint64_t seed = 1;
  const std::string help = cli::usage("usage: keepless_make_colmap --out DIR [options]", flags,
                                      "Writes a synthetic COLMAP binary model: a PINHOLE camera driving straight\n"
                                      "ahead, 1 m per image, tracks of mean length ~5. Deterministic for a seed.");
  for (int i = 1; i < argc; ++i) {
    const cli::Flag* flag = nullptr;
    const char* value = nullptr;
    int status = 0;
    if (!cli::next_flag(kTool, help, flags, argc, argv, &i, &flag, &value, &status)) return status;
    const std::string f = flag->name;
    std::uint64_t n = 0;
    const bool number = keepless::core::parse_uint64(value, &n);
    const std::string bad = "bad value for " + f + ": '" + value + "'";
    if (f == "--out") {
      if (*value == '\0') return cli::usage_error(kTool, bad);
      out = value;
    } else if (f == "--images") {
      if (!number || n < 2 || n > 10000000) return cli::usage_error(kTool, bad + " (an integer in 2..10000000)");
      images = static_cast<std::uint32_t>(n);
    } else if (f == "--points") {
      if (!number || n > UINT32_MAX) return cli::usage_error(kTool, bad + " (an integer in 0..4294967295)");
      points = static_cast<std::uint32_t>(n);
    } else if (f == "--seed") {
      if (!number) return cli::usage_error(kTool, bad);
      seed = n;
    }
  }
  if (out.empty()) return cli::usage_error(kTool, "--out is required");
  const double fx = 707.0912, cx = 601.8873, cy = 183.1104;
  io::ColmapModel m;
  m.cameras.push_back({1, 1, 1226, 370, {fx, fx, cx, cy}});
  for (std::uint32_t i = 0; i < images; ++i) {
    io::ColmapImage im;
    im.id = i + 1;
    im.tvec[2] = -static_cast<double>(i);  // centre (0, 0, i), no rotation
    im.camera_id = 1;
    char name[32];
    std::snprintf(name, sizeof name, "%06u.png", i);
    im.name = name;
    m.images.push_back(im);
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::geometric_distribution<std::uint32_t> extra(0.25);
  for (std::uint32_t p = 0; p < points; ++p) {
    const std::uint32_t length = std::min<std::uint32_t>(2 + extra(rng), images);
    const std::uint32_t first = static_cast<std::uint32_t>(unit(rng) * (images - length + 1));
    const double last_z = first + length - 1.0;
    io::ColmapPoint3D pt;
    pt.id = p + 1;
    pt.xyz[2] = last_z + 3 + 37 * unit(rng);
    pt.xyz[0] = (unit(rng) - 0.5) * 0.8 * (pt.xyz[2] - first);
    pt.xyz[1] = (unit(rng) - 0.5) * 0.25 * (pt.xyz[2] - first);
    pt.rgb[0] = pt.rgb[1] = pt.rgb[2] = static_cast<std::uint8_t>(p % 256);
    pt.error = 0.5;
    for (std::uint32_t i = first; i < first + length; ++i) {
      io::ColmapImage& im = m.images[i];
      const double z = pt.xyz[2] - i;
      pt.track.push_back({im.id, static_cast<std::uint32_t>(im.points2D.size())});
      im.points2D.push_back({fx * pt.xyz[0] / z + cx, fx * pt.xyz[1] / z + cy, pt.id});
    }
    m.points.push_back(std::move(pt));
  }
  std::string error;
  if (!io::write_colmap_model(out, m, io::ColmapFormat::kBinary, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  std::printf("{\"images\":%u,\"points\":%u,\"out\":\"%s\"}\n", images, points, out.c_str());
  return 0;
}
