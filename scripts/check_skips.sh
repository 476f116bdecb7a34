#!/usr/bin/env bash
# check_skips.sh LOG [ALLOWED...]: the tests a ctest log lists as not run
# ("The following tests did not run"), minus ALLOWED names (deliberate skips
# that say why in their own output). Any other skip did not check anything:
# under CI (CI set) that fails (exit 1); elsewhere it is reported.
set -euo pipefail
log=$1
shift
# The list below is read in a process substitution, whose failure set -e does not see.
[ -f "$log" ] && [ -r "$log" ] || { echo "check_skips: $log: no such log (did ctest run?)" >&2; exit 1; }
allowed=" $* "
bad=()
while read -r name; do
  [[ "$allowed" == *" $name "* ]] || bad+=("$name")
done < <(sed -n '/The following tests did not run/,/^$/p' "$log" | sed -nE 's/^[[:space:]]+[0-9]+ - ([^ ]+) .*/\1/p')
((${#bad[@]} == 0)) && exit 0
echo "check_skips: ${#bad[@]} test(s) skipped (each says why above): ${bad[*]}" >&2
[[ -z "${CI:-}" ]] || exit 1
