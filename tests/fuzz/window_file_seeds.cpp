// Writes the seed corpus of window_file_fuzzer into argv[1]: valid windows
// (with and without orientations, comments, blank lines, CRLF, -0,
// subnormals, large ids) and one of each error class. The first byte of a
// seed is the fuzzer's chunk split.

#include <cstdio>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const std::vector<std::string> seeds = {
      "kf 1 0 0 0\nobs 1 5 10 20\nkf 2 1 0 0\nobs 2 5 11 21\nobs 2 6 30 40\nobs 1 6 31 41\n",
      "# window\n\nkf 18446744073709551615 0.5 -2.25 1e-3 0.70710678118654757 0 0.70710678118654757 0\r\n"
      "obs 18446744073709551615 42 1.25 2 # a comment\n",
      "kf 3 -0 4e-320 0 1 -0 0 0\nobs 3 7 0 -0\n",
      "kf 1 0 0 0\nkf 2 0 0 0\nkf 3 0 0 0\nobs 1 10 0 0\nobs 2 10 0 0\nobs 3 10 0 0\nobs 1 11 0 0\nobs 2 11 0 0",
      "kf 1 0 0 0 0 0 0 0\n",             // zero quaternion
      "obs 1 2 3 4\n",                    // unknown keyframe
      "kf 1 0 0 0\nkf 1 0 0 0\n",         // duplicate keyframe
      "kf 1 0 0 0\nobs 1 2 0 0\nobs 1 2 0 0\n",  // duplicate observation
      "kf 1 nan 0 0\n",
      "kf 1 1e999 0 0\n",
      "kf -1 0 0 0\n",
      "kf 99999999999999999999 0 0 0\n",
      "frame 1\n",
      "kf 1 0x10 0 0\n",
      std::string("kf 1 0 0 0\nobs 1 2 3 4\0\n", 24),
  };
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    const std::string path = std::string(argv[1]) + "/seed_" + std::to_string(i);
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) return 1;
    const unsigned char split = static_cast<unsigned char>(i * 7);
    std::fputc(split, f);
    std::fwrite(seeds[i].data(), 1, seeds[i].size(), f);
    std::fclose(f);
  }
  return 0;
}
