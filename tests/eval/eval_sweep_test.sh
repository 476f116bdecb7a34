#!/usr/bin/env bash
# scripts/eval_sweep.sh end to end on a small slice (KITTI 06 frames 0-15 at two
# fractions, the synthetic TUM group at 12 keyframes and one fraction, one
# seed, every variant but maturity and defer): every job exits 0, each variant has its Budget sweep
# table with every method it runs at its fractions, runs.csv rows for them, the
# SVG, its flags.txt, and jobs.tsv's CPU column; track skips the synthetic
# back end; scripts/sweep_table.py labels each variant's rows with its flags.
# Exits 77 (skipped), naming the path, without the data.
#   tests/eval/eval_sweep_test.sh BIN_DIR DATA_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=$1
data=$2
for need in kitti06_first51_niconielsen/calib.txt evo/freiburg1_xyz-groundtruth.txt; do
  if [ ! -f "$data/$need" ]; then
    echo "eval_sweep_test: skipped: no $data/$need" >&2
    exit 77
  fi
done
out=$(mktemp -d)
size="--frames 0:15 --max-keyframes 12 --keypoints 300"  # --eval-flags: every variant's flags.txt records them
trap 'rm -rf "$out"' EXIT
"$root/scripts/eval_sweep.sh" --bin "$bin" --data-root "$data" --only kitti06,synthetic_tum --seeds 1 \
  --fractions 0.2,0.4 --synthetic-fractions 0.4 --variants paper,track,authors,information,floor \
  --eval-flags "$size" -j 2 --out "$out"

fail() { echo "eval_sweep_test: $*" >&2; exit 1; }
# Every variant on both inputs but track, on KITTI 06 only.
[ "$(awk -F'\t' 'NR > 1' "$out/jobs.tsv" | wc -l)" = 9 ] || fail "jobs.tsv should list 9 jobs"
awk -F'\t' 'NR > 1 && ($6 != 0 || $5 !~ /^[0-9]+$/) { exit 1 }' "$out/jobs.tsv" || fail "a job failed or has no CPU figure"
for variant in paper track authors information floor; do
  tables=$out/$variant/tables.md
  grep -q "^#### Budget sweep: kitti06_first51_niconielsen" "$tables" || fail "$variant: no Budget sweep table"
  ls "$out/$variant"/sweep_*.svg > /dev/null || fail "$variant: no sweep SVG"
  for f in 0.20 0.40; do
    grep -q "^| $f | ours |" "$tables" || fail "$variant: no row for ours at F = $f"
  done
  [ -f "$out/$variant/flags.txt" ] || fail "$variant: no flags.txt"
done
# The synthetic group runs at its own fraction only.
for variant in paper authors information floor; do
  fractions=$(awk -F, 'NR > 1 && $2 == "fr1_xyz" { print $9 }' "$out/$variant/runs.csv" | sort -u | tr '\n' ' ')
  [ "$fractions" = "0.400 " ] || fail "$variant: fr1_xyz at F = '$fractions', want 0.400 only"
done
[ -f "$out/track/runs.csv" ] || fail "track: no runs.csv"
if grep -q ",fr1_xyz," "$out/track/runs.csv"; then fail "track: ran the synthetic back end"; fi
# The paper variant runs every baseline; the others here run keepless only.
for method in random "longest track" "ANMS (SSC)"; do
  grep -q "^| 0.20 | $method |" "$out/paper/tables.md" || fail "paper: no $method row"
  for variant in track authors information floor; do
    if grep -q "^| 0.20 | $method |" "$out/$variant/tables.md"; then fail "$variant: has a $method row"; fi
  done
done
for cost in track authors information; do
  grep -q "cost $cost" "$out/$cost/meta.txt" || fail "$cost: meta.txt does not say cost $cost"
done
grep -q "coverage floor 30" "$out/floor/meta.txt" || fail "floor: meta.txt does not say coverage floor 30"
grep -qx "eval: --floor 30 --no-baselines $size" "$out/floor/flags.txt" || fail "floor: flags.txt does not hold its flags"
grep -qx "eval: $size" "$out/paper/flags.txt" || fail "paper: flags.txt does not hold the --eval-flags"
# sweep_table.py labels the rows from flags.txt: floor's keepless rows, no baseline of its own.
full=$("$root/scripts/sweep_table.py" "$out")
grep -q "^ATE against local-BA observations, .*: correlation of the logs -\?[0-9.]* over [0-9]* runs.$" <<< "$full" ||
  fail "sweep_table: no correlation line"
condensed=$("$root/scripts/sweep_table.py" "$out" --condensed)
floor="\`--floor 30 $size\`"
grep -q "^| $floor | 0.4 | " <<< "$condensed" || fail "sweep_table: no --floor 30 row"
grep -q "^| $floor | .* | – | – | – |$" <<< "$condensed" || fail "sweep_table: floor has baseline cells"
grep -q "^| fr1_xyz (tum) | [0-9.e-]* | $floor | 0.4 | " <<< "$condensed" ||
  fail "sweep_table: no synthetic fr1_xyz row for floor"
echo "eval_sweep_test: ok"
