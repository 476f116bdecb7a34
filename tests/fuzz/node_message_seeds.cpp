// Writes the seed corpus of node_message_fuzzer (node_message_seed_corpus.hpp)
// into argv[1].

#include <cstdio>
#include <string>
#include <vector>

#include "node_message_seed_corpus.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const std::vector<std::vector<unsigned char>> seeds = keepless::fuzz::node_message_seed_corpus();
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    const std::string path = std::string(argv[1]) + "/seed_" + std::to_string(i);
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) return 1;
    std::fwrite(seeds[i].data(), 1, seeds[i].size(), f);
    std::fclose(f);
  }
  return 0;
}
