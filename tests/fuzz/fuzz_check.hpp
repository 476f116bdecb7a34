#pragma once
// The fuzz harnesses' oracle: a broken property aborts, naming its line.

#include <cstdio>
#include <cstdlib>

#define KEEPLESS_FUZZ_CHECK(ok)                                                         \
  do {                                                                                  \
    if (!(ok)) {                                                                        \
      std::fprintf(stderr, "%s:%d: oracle failed: %s\n", __FILE__, __LINE__, #ok);      \
      std::abort();                                                                     \
    }                                                                                   \
  } while (0)
