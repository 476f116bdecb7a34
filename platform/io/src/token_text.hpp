#pragma once
// How the text readers show a bad token in an error.

#include <string>
#include <string_view>

namespace keepless::io::detail {

// Its first 40 bytes, a NUL byte as \0 (one line on a terminal).
inline std::string shown_token(std::string_view token) {
  std::string shown;
  for (const char c : token.substr(0, 40)) shown += c == '\0' ? std::string("\\0") : std::string(1, c);
  return shown;
}

}  // namespace keepless::io::detail
