// keepless_log_compare: checks that two LCM logs carry the same messages,
// byte for byte and in order, on the given channels. Used to show that
// replaying a recorded bus (lcm-logplayer) into a fresh keepless_node gives
// the decisions of the original run.
//   keepless_log_compare LOG_A CHANNEL_A LOG_B CHANNEL_B
// Exit 0 when identical (and non-empty), 1 when they differ, 2 on bad usage
// or a log that is not whole LCM events (not a log, truncated, corrupt).

#include <lcm/lcm-cpp.hpp>

#include "cli/cli.hpp"

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

namespace {

// The messages on `channel`; false (one line on stderr) unless the whole file
// is LCM events: LCM's reader stops quietly at junk or a cut event, which
// would compare a truncated log's prefix as if it were all of it.
bool read_channel(const std::string& path, const std::string& channel, std::vector<std::vector<std::uint8_t>>& out) {
  lcm::LogFile log(path, "r");
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!log.good() || ec) {
    std::fprintf(stderr, "keepless_log_compare: cannot read %s\n", path.c_str());
    return false;
  }
  std::uintmax_t read = 0;  // bytes of the events read
  std::size_t events = 0;
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    // Sync word, event number, timestamp, channel and data lengths, channel, data.
    read += 4 + 8 + 8 + 4 + 4 + e->channel.size() + static_cast<std::uintmax_t>(e->datalen);
    ++events;
    if (e->channel != channel) continue;
    const auto* p = static_cast<const std::uint8_t*>(e->data);
    out.emplace_back(p, p + e->datalen);
  }
  if (read != size) {
    if (events == 0) {
      std::fprintf(stderr, "keepless_log_compare: %s is not an LCM log\n", path.c_str());
    } else {
      std::fprintf(stderr, "keepless_log_compare: %s is truncated or corrupt after %zu events (%ju of %ju bytes)\n",
                   path.c_str(), events, read, size);
    }
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  constexpr const char* kTool = "keepless_log_compare";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(keepless::cli::usage("usage: keepless_log_compare LOG_A CHANNEL_A LOG_B CHANNEL_B", {},
                                      "Compares the messages on CHANNEL_A in LOG_A with those on CHANNEL_B in\n"
                                      "LOG_B, byte for byte and in order. Exit 0 when identical (and not empty),\n"
                                      "1 when they differ, 2 on bad usage or an unreadable log (not an LCM log,\n"
                                      "truncated or corrupt).")
                     .c_str(),
                 stdout);
      return 0;
    }
    if (a == "--version") return keepless::cli::print_version(kTool);
    if (a.size() > 1 && a[0] == '-') return keepless::cli::usage_error(kTool, keepless::cli::unknown_option(a));
  }
  if (argc != 5) {
    return keepless::cli::usage_error(kTool, "expected 4 arguments (LOG_A CHANNEL_A LOG_B CHANNEL_B), got " +
                                                 std::to_string(argc - 1));
  }
  std::vector<std::vector<std::uint8_t>> a, b;
  if (!read_channel(argv[1], argv[2], a) || !read_channel(argv[3], argv[4], b)) return 2;
  const std::size_t n = a.size() < b.size() ? a.size() : b.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (a[i] != b[i]) {
      std::printf("differ: message %zu of %s (%zu bytes) vs %s (%zu bytes)\n", i, argv[2], a[i].size(), argv[4],
                  b[i].size());
      return 1;
    }
  }
  if (a.size() != b.size()) {
    std::printf("differ: %zu messages on %s vs %zu on %s (the first %zu identical)\n", a.size(), argv[2], b.size(),
                argv[4], n);
    return 1;
  }
  if (a.empty()) {
    std::printf("no messages on %s\n", argv[2]);
    return 1;
  }
  std::size_t bytes = 0;
  for (const auto& m : a) bytes += m.size();
  std::printf("%zu messages (%zu bytes) identical byte for byte\n", a.size(), bytes);
  return 0;
}
