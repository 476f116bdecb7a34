#include "cli/cli.hpp"

#include <algorithm>
#include <cstdio>

namespace keepless::cli {

namespace {

// Descriptions start in this column, or on the next line for a longer flag.
constexpr std::size_t kMaxColumn = 30;

std::string head(const Flag& f) {
  std::string s = std::string("  ") + f.name;
  if (f.value != nullptr) s += std::string(" ") + f.value;
  return s;
}

}  // namespace

std::string usage(std::string_view synopsis, const std::vector<Flag>& flags, std::string_view epilogue) {
  std::vector<Flag> all = flags;
  all.push_back({"--help", nullptr, "print this help and exit"});
  all.push_back({"--version", nullptr, "print the version and exit"});
  std::size_t column = 0;
  for (const Flag& f : all) {
    const std::size_t w = head(f).size() + 2;
    if (w <= kMaxColumn) column = std::max(column, w);
  }
  std::string out(synopsis);
  if (out.empty() || out.back() != '\n') out += '\n';
  out += '\n';
  for (const Flag& f : all) {
    std::string line = head(f);
    if (line.size() + 2 > column) {
      out += line + '\n';
      line.clear();
    }
    line.resize(column, ' ');
    for (const char c : std::string_view(f.help)) {
      if (c == '\n') {
        out += line + '\n';
        line.assign(column, ' ');
      } else {
        line += c;
      }
    }
    out += line + '\n';
  }
  if (!epilogue.empty()) {
    out += '\n';
    out += epilogue;
    if (out.back() != '\n') out += '\n';
  }
  return out;
}

const Flag* find(const std::vector<Flag>& flags, std::string_view name) {
  for (const Flag& f : flags) {
    if (name == f.name) return &f;
  }
  return nullptr;
}

const char* last_value(int argc, char** argv, std::string_view flag) {
  const char* value = nullptr;
  for (int i = 1; i + 1 < argc; ++i) {
    if (flag == argv[i]) value = argv[++i];
  }
  return value;
}

bool documents(std::string_view text, std::string_view flag) {
  for (std::size_t at = 0; at < text.size();) {
    std::size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(at, end - at);
    if (line.size() >= 2 + flag.size() && line.substr(0, 2) == "  " && line.substr(2, flag.size()) == flag) {
      const std::size_t after = 2 + flag.size();
      if (after == line.size() || line[after] == ' ' || line[after] == ',') return true;
    }
    at = end + 1;
  }
  return false;
}

const char* version() { return KEEPLESS_VERSION; }

int print_version(const char* tool) {
  std::printf("%s %s\n", tool, version());
  return std::fflush(stdout) == 0 ? 0 : 1;
}

std::string unknown_option(std::string_view arg) { return "unknown option '" + std::string(arg) + "'"; }

std::string needs_value(std::string_view flag) { return "option '" + std::string(flag) + "' needs a value"; }

int usage_error(const char* tool, const std::string& message) {
  std::fprintf(stderr, "%s: %s; see '%s --help'\n", tool, message.c_str(), tool);
  return kExitUsage;
}

Arg next(const std::vector<Flag>& flags, int argc, char** argv, int* i, const Flag** flag, const char** value,
         std::string* error) {
  const std::string_view arg = argv[*i];
  if (arg == "--help" || arg == "-h") return Arg::kHelp;
  if (arg == "--version") return Arg::kVersion;
  *flag = find(flags, arg);
  *value = nullptr;
  if (*flag == nullptr) {
    *error = unknown_option(arg);
    return Arg::kError;
  }
  if ((*flag)->value != nullptr) {
    if (*i + 1 >= argc) {
      *error = needs_value(arg);
      return Arg::kError;
    }
    *value = argv[++*i];
  }
  return Arg::kFlag;
}

bool next_flag(const char* tool, const std::string& usage_text, const std::vector<Flag>& flags, int argc,
               char** argv, int* i, const Flag** flag, const char** value, int* exit_status) {
  std::string error;
  switch (next(flags, argc, argv, i, flag, value, &error)) {
    case Arg::kFlag: return true;
    case Arg::kHelp:
      std::fputs(usage_text.c_str(), stdout);
      *exit_status = 0;
      return false;
    case Arg::kVersion: *exit_status = print_version(tool); return false;
    case Arg::kError: break;
  }
  *exit_status = usage_error(tool, error);
  return false;
}

}  // namespace keepless::cli
