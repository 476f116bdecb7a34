#!/usr/bin/env bash
# The documentation's checks, run by CI after the release tests and by
# `ctest -L docs`:
#   1. README's and docs/'s code snippets equal the examples' marked regions;
#   2. every relative link and #anchor in README.md and docs/ resolves, and no
#      page names internal things (issue numbers, machine paths);
#   3. Doxygen over the public headers (*/include/keepless/**), warnings as errors;
#   4. docs/reference/cli/*.md equal what the built tools print for --help.
#   scripts/check_docs.sh [BUILD_DIR]     (default build; the Doxygen HTML goes to BUILD_DIR/docs)
# Needs python3 and doxygen (scripts/keepless.sh test installs both).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
for tool in python3 doxygen; do
  command -v "$tool" >/dev/null || { echo "check_docs: $tool is not installed (apt-get install $tool)" >&2; exit 1; }
done
status=0
python3 scripts/check_snippets.py . || status=1
python3 scripts/check_links.py . || status=1
mkdir -p "$build/docs"
if KEEPLESS_DOXYGEN_OUT="$build/docs" doxygen docs/Doxyfile; then
  echo "check_docs: doxygen: no warnings ($build/docs/html/index.html)"
else
  echo "check_docs: doxygen warned (treated as errors)" >&2
  status=1
fi
scripts/gen_cli_docs.sh --check "$build" || status=1
[ "$status" = 0 ] && echo "check_docs: all checks passed" || echo "check_docs: FAILED" >&2
exit $status
