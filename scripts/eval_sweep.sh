#!/usr/bin/env bash
# The budget sweep: every method at every kept fraction on the real sequences
# (7-Scenes RGB-D 600 frames, KITTI 00 200, KITTI 06 51) and, with keepless_maps_bench,
# the COLMAP fixture. One keepless_eval process per (sequence, seed) with every
# fraction (the original runs once per seed), N at a time (-j), each into
# OUT/runs/NAME_seedS; then `keepless_eval --report` merges them
# into OUT/tables.md (with a "Budget sweep" table and the failures per
# sequence), OUT/runs.csv and OUT/sweep_NAME.svg (ATE against local-BA
# observations, one curve per method, failed seeds ringed). Each job's wall
# time is in OUT/jobs.tsv.
#
#   scripts/eval_sweep.sh [--data-root DIR] [--fractions 0.1,0.2,0.3,0.4,0.6] [--seeds 5] [-j 2]
#                         [--out DIR] [--only 7scenes,kitti00,kitti06,colmap] [--bin DIR]
set -euo pipefail
cd "$(dirname "$0")/.."

data=../shared/data
fractions=0.1,0.2,0.3,0.4,0.6
seeds=5
jobs=2
out=sweep_out
only=7scenes,kitti00,kitti06,colmap
bin=build/bin
while (($#)); do
  case "$1" in
    --data-root) data=$2; shift 2 ;;
    --fractions) fractions=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    -j) jobs=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    --bin) bin=$2; shift 2 ;;
    -h|--help) sed -n 2,13p "$0"; exit 0 ;;
    *) echo "eval_sweep: unknown option $1" >&2; exit 2 ;;
  esac
done
for b in keepless_eval keepless_maps_bench; do
  [ -x "$bin/$b" ] || { echo "eval_sweep: $bin/$b is missing: cmake --build build --target $b" >&2; exit 1; }
done
data=$(cd "$data" && pwd)
mkdir -p "$out/runs"
out=$(cd "$out" && pwd)
bin=$(cd "$bin" && pwd)

# name|keepless_eval input flags
inputs=(
  "7scenes|--rgbd $data/7scenes_redkitchen_first600"
  "kitti00|--images $data/kitti00_first200_vamr/image_0 --calib $data/kitti00_first200_vamr/K.txt --poses $data/kitti00_first200_vamr/poses.txt"
  "kitti06|--images $data/kitti06_first51_niconielsen/image_l --calib $data/kitti06_first51_niconielsen/calib.txt --poses $data/kitti06_first51_niconielsen/poses.txt"
)
selected() { [[ ",$only," == *",$1,"* ]]; }

joblist="$out/jobs.txt"
: > "$joblist"
for entry in "${inputs[@]}"; do
  name=${entry%%|*}
  selected "$name" || continue
  for ((seed = 1; seed <= seeds; ++seed)); do
    echo "$name|$seed|${entry#*|}" >> "$joblist"
  done
done
if selected colmap; then echo "colmap|all|" >> "$joblist"; fi

run_job() {
  IFS='|' read -r name seed flags <<< "$1"
  local start end dir rc=0
  start=$(date +%s)
  if [ "$name" = colmap ]; then
    dir="$out/colmap"
    mkdir -p "$dir/work"
    "$bin/keepless_maps_bench" --data "$data" --keep-fraction "$fractions" --seeds "$seeds" --work "$dir/work" \
      > "$dir/stdout.txt" 2> "$dir/stderr.txt" || rc=$?
  else
    dir="$out/runs/${name}_seed$seed"
    # shellcheck disable=SC2086  # flags are words
    "$bin/keepless_eval" $flags --kept-fraction "$fractions" --seed "$seed" --seeds 1 --out "$dir" \
      > "$dir.stdout" 2> "$dir.stderr" || rc=$?
  fi
  end=$(date +%s)
  printf '%s\t%s\t%d\t%d\n' "$name" "$seed" $((end - start)) "$rc" >> "$out/jobs.tsv"
  echo "eval_sweep: $name seed $seed done in $((end - start)) s (exit $rc)" >&2
}
export -f run_job
export out data bin seeds fractions

printf 'input\tseed\twall_s\texit\n' > "$out/jobs.tsv"
t0=$(date +%s)
tr '\n' '\0' < "$joblist" | xargs -0 -P "$jobs" -I{} bash -c 'run_job "$1"' _ {}

reports=()
for d in "$out"/runs/*/; do [ -f "$d/runs.csv" ] && reports+=(--report "$d"); done
if ((${#reports[@]})); then
  "$bin/keepless_eval" "${reports[@]}" --out "$out" > "$out/report.stdout"
fi
echo "eval_sweep: $(($(date +%s) - t0)) s wall with -j $jobs; tables in $out/tables.md, plots $out/sweep_*.svg," \
     "the COLMAP fixture's rows in $out/colmap/stdout.txt" >&2
