#!/usr/bin/env bash
# The libFuzzer harnesses of tests/fuzz (clang-14, ASan + UBSan), in their own
# build dir (build-fuzz/, never the gcc presets).
#
#   scripts/fuzz.sh short        # CI: every harness for FUZZ_SECONDS (default 60) s, one per core at a time
#   scripts/fuzz.sh long [SECS]  # every harness for SECS (default 3600) s; FUZZ_JOBS=N runs N processes each
#
# Each run prints libFuzzer's final stats (executions, corpus, peak RSS).
# A finding leaves crash-*/leak-*/timeout-* in build-fuzz/findings/<harness>/
# and exits non-zero. Reproduce one with: build-fuzz/tests/<harness> <file>.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-short}
case "$mode" in
  short) seconds=${FUZZ_SECONDS:-60} ;;
  long) seconds=${2:-3600} ;;
  *) echo "usage: $0 short|long [SECONDS]" >&2; exit 2 ;;
esac

# The fuzzing toolchain is not in keepless.sh's PACKAGES (the product never
# links it): install it here when missing.
have_fuzzer() {
  command -v clang++-14 >/dev/null && ls /usr/lib/llvm-14/lib/clang/*/lib/linux/libclang_rt.fuzzer-*.a >/dev/null 2>&1
}
if ! have_fuzzer; then
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd=sudo
  $sudo_cmd apt-get update -qq
  $sudo_cmd env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq clang-14 libfuzzer-14-dev libclang-rt-14-dev
fi

build=build-fuzz
export CMAKE_CXX_COMPILER_LAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER:-$(command -v ccache || true)}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER=clang++-14 \
  -DKEEPLESS_FUZZ=ON -DKEEPLESS_BUILD_PERF=OFF -DKEEPLESS_WERROR=OFF \
  "-DCMAKE_CXX_FLAGS=-fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=all -fno-omit-frame-pointer" \
  "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" >/dev/null
cmake --build "$build" -j"${FUZZ_BUILD_JOBS:-2}" --target keepless_fuzzers
mapfile -t harnesses < "$build/tests/fuzz/harnesses.txt"

# One harness per core at a time (FUZZ_PARALLEL; long runs default to one,
# each with FUZZ_JOBS processes): the same time per harness, a shorter wall.
if [ "$mode" = short ]; then parallel_harnesses=${FUZZ_PARALLEL:-$(nproc)}; else parallel_harnesses=${FUZZ_PARALLEL:-1}; fi
fuzz_one() {
  local h=$1 corpus="$build/tests/fuzz/corpus/$1" findings="$build/findings/$1" parallel=()
  mkdir -p "$corpus" "$findings"
  [ "${FUZZ_JOBS:-1}" -gt 1 ] && parallel=(-jobs="$FUZZ_JOBS" -workers="$FUZZ_JOBS")
  "$build/tests/$h" -max_total_time="$seconds" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048 \
    "${parallel[@]}" -artifact_prefix="$findings/" \
    "$corpus" "$build/tests/fuzz/corpus/${h}_seeds" 2>"$findings/log.txt"
}
status=0
for ((first = 0; first < ${#harnesses[@]}; first += parallel_harnesses)); do
  batch=("${harnesses[@]:first:parallel_harnesses}")
  pids=()
  for h in "${batch[@]}"; do
    echo "fuzz: $h for ${seconds}s"
    fuzz_one "$h" &
    pids+=($!)
  done
  for i in "${!batch[@]}"; do
    h=${batch[$i]}
    if ! wait "${pids[$i]}"; then
      status=1
      echo "fuzz: $h FOUND something, see $build/findings/$h/; the end of its log:" >&2
      tail -n 40 "$build/findings/$h/log.txt" | sed "s/^/fuzz: $h: /" >&2  # the oracle's message, the stack
    fi
    grep -E "^stat::(number_of_executed_units|peak_rss_mb|new_units_added)|^#[0-9]+ *DONE" "$build/findings/$h/log.txt" \
      | sed "s/^/fuzz: $h: /" || true
  done
done
exit $status
