#pragma once
// What every keepless tool does with its command line, as GNU tools do:
// --help prints the usage on stdout (a usage line, then one described line
// per flag, aligned) and exits 0; --version prints "<tool> <version>" and
// exits 0; an unknown option or a flag without its value is named on stderr
// in one line with a pointer to --help, exit 2.

#include <string>
#include <string_view>
#include <vector>

namespace keepless::cli {

constexpr int kExitUsage = 2;

struct Flag {
  const char* name;   // "--M"
  const char* value;  // "N"; nullptr for a switch
  const char* help;   // one line; '\n' continues it under the description column
};

// `synopsis` (its lines as given, the first starting "usage: "), a blank
// line, the flags in order, then --help and --version, then `epilogue`.
std::string usage(std::string_view synopsis, const std::vector<Flag>& flags, std::string_view epilogue = {});

const Flag* find(const std::vector<Flag>& flags, std::string_view name);

// The value of the last "`flag` VALUE" in argv, or nullptr: for a flag
// applied before the others wherever it stands (--use), so they refine it.
const char* last_value(int argc, char** argv, std::string_view flag);

// A usage text documents `flag` when a line starts with two blanks and the
// flag, followed by a blank, a comma or the line's end.
bool documents(std::string_view usage_text, std::string_view flag);

const char* version();                 // the project's version (CMake PROJECT_VERSION)
int print_version(const char* tool);   // "<tool> <version>" on stdout; returns 0

std::string unknown_option(std::string_view arg);  // "unknown option '--bogus'"
std::string needs_value(std::string_view flag);    // "option '--M' needs a value"

// "<tool>: <message>; see '<tool> --help'" on stderr (one line); returns kExitUsage.
int usage_error(const char* tool, const std::string& message);

// The head of a parse loop over a flag table, for argv[*i]:
//   kHelp / kVersion: --help or -h / --version;
//   kError: not in `flags` (unknown_option) or its value is missing (needs_value);
//   kFlag: *flag is the entry; for a flag with a value, *value is argv[*i + 1] and *i advanced.
enum class Arg { kFlag, kHelp, kVersion, kError };
Arg next(const std::vector<Flag>& flags, int argc, char** argv, int* i, const Flag** flag, const char** value,
         std::string* error);

// next() with what every tool does with the rest: --help prints `usage_text`
// on stdout and --version "<tool> <version>" (exit status 0); an unknown
// option or a missing value goes through usage_error. True for a flag of
// `flags` (*flag and *value as next() sets them); false with *exit_status
// for main() to return.
bool next_flag(const char* tool, const std::string& usage_text, const std::vector<Flag>& flags, int argc,
               char** argv, int* i, const Flag** flag, const char** value, int* exit_status);

}  // namespace keepless::cli
