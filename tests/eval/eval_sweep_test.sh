#!/usr/bin/env bash
# scripts/eval_sweep.sh end to end on a small slice (KITTI 06 frames 0-15, two
# fractions, one seed, two variants): every job exits 0, each variant has its
# Budget sweep table with every method at both fractions, runs.csv rows for
# them, the SVG, and jobs.tsv's CPU column. Exits 77 (skipped), naming the
# path, without the data.
#   tests/eval/eval_sweep_test.sh BIN_DIR DATA_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=$1
data=$2
seq=$data/kitti06_first51_niconielsen
if [ ! -f "$seq/calib.txt" ]; then
  echo "eval_sweep_test: skipped: no KITTI 06 sequence at $seq" >&2
  exit 77
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$root/scripts/eval_sweep.sh" --bin "$bin" --data-root "$data" --only kitti06 --seeds 1 --fractions 0.2,0.4 \
  --variants paper,track --eval-flags "--frames 0:15" -j 2 --out "$out"

fail() { echo "eval_sweep_test: $*" >&2; exit 1; }
[ "$(awk -F'\t' 'NR > 1' "$out/jobs.tsv" | wc -l)" = 2 ] || fail "jobs.tsv should list 2 jobs"
awk -F'\t' 'NR > 1 && ($6 != 0 || $5 !~ /^[0-9]+$/) { exit 1 }' "$out/jobs.tsv" || fail "a job failed or has no CPU figure"
for variant in paper track; do
  tables=$out/$variant/tables.md
  grep -q "^#### Budget sweep: kitti06_first51_niconielsen" "$tables" || fail "$variant: no Budget sweep table"
  ls "$out/$variant"/sweep_*.svg > /dev/null || fail "$variant: no sweep SVG"
  for f in 0.20 0.40; do
    grep -q "^| $f | ours |" "$tables" || fail "$variant: no row for ours at F = $f"
  done
done
# The paper variant runs every baseline; track runs keepless only.
for method in random "longest track" "ANMS (SSC)"; do
  grep -q "^| 0.20 | $method |" "$out/paper/tables.md" || fail "paper: no $method row"
  if grep -q "^| 0.20 | $method |" "$out/track/tables.md"; then fail "track: has a $method row"; fi
done
grep -q "cost track" "$out/track/meta.txt" || fail "track: meta.txt does not say cost track"
echo "eval_sweep_test: ok"
