// libFuzzer harness for keepless::io's COLMAP reader, both formats.
// Input: byte 0 picks the format (even: binary, odd: text); bytes 1-4 are
// the lengths of cameras and images (two little-endian u16); the rest is
// points3D. Oracle: a model that parses is written and parsed back to the
// same model; binary files written back are the input bytes exactly (the
// layout is canonical), text files are a fixed point of write(parse()).
// Anything else must be a clean error "FILE:POS: reason".

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_check.hpp"
#include "keepless/io/colmap_model.hpp"


extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace io = keepless::io;
  if (size < 5) return 0;
  const io::ColmapFormat format = data[0] % 2 == 0 ? io::ColmapFormat::kBinary : io::ColmapFormat::kText;
  std::size_t cameras = data[1] | (std::size_t{data[2]} << 8);
  std::size_t images = data[3] | (std::size_t{data[4]} << 8);
  const char* rest = reinterpret_cast<const char*>(data + 5);
  std::size_t left = size - 5;
  cameras = cameras < left ? cameras : left;
  left -= cameras;
  images = images < left ? images : left;
  left -= images;
  const io::ColmapFiles in{std::string(rest, cameras), std::string(rest + cameras, images),
                           std::string(rest + cameras + images, left)};
  io::ColmapModel model;
  std::string error;
  if (!io::parse_colmap("fuzz", in, format, &model, &error)) {
    KEEPLESS_FUZZ_CHECK(error.rfind("fuzz/", 0) == 0 && error.find(": ") != std::string::npos);  // FILE:POS: reason
    return 0;
  }
  const io::ColmapFiles out = io::format_colmap(model, format);
  if (format == io::ColmapFormat::kBinary) {
    KEEPLESS_FUZZ_CHECK(out.cameras == in.cameras && out.images == in.images && out.points3D == in.points3D);
  }
  io::ColmapModel again;
  KEEPLESS_FUZZ_CHECK(io::parse_colmap("fuzz", out, format, &again, &error));
  const io::ColmapFiles twice = io::format_colmap(again, format);
  KEEPLESS_FUZZ_CHECK(twice.cameras == out.cameras && twice.images == out.images && twice.points3D == out.points3D);
  // The other format carries the same model; a name with a blank only
  // binary can hold (COLMAP's text reader ends a name at its first space).
  const io::ColmapFormat other = format == io::ColmapFormat::kBinary ? io::ColmapFormat::kText : io::ColmapFormat::kBinary;
  for (const io::ColmapImage& im : model.images) {
    if (other == io::ColmapFormat::kText && im.name.find_first_of(" \t\v\f\r") != std::string::npos) return 0;
  }
  io::ColmapModel converted;
  KEEPLESS_FUZZ_CHECK(io::parse_colmap("fuzz", io::format_colmap(model, other), other, &converted, &error));
  const io::ColmapFiles back = io::format_colmap(converted, format);
  KEEPLESS_FUZZ_CHECK(back.cameras == out.cameras && back.images == out.images && back.points3D == out.points3D);
  return 0;
}
