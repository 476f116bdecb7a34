#!/usr/bin/env bash
# Compress a COLMAP model with keepless_sparsify and look at the result.
#   examples/colmap.sh [KEEPLESS_SPARSIFY] [MODEL_DIR] [OUT_DIR]
# Defaults: build/bin/keepless_sparsify, the KITTI 06 model of the shared data
# folder (../shared/data/colmap_kitti06_first51/sparse, or $KEEPLESS_DATA/...),
# a fresh temporary folder. Exits 77 (ctest: skipped), naming the path, when
# the model is not there.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
sparsify=${1:-$root/build/bin/keepless_sparsify}
data=${KEEPLESS_DATA:-$root/../shared/data}
model=${2:-$data/colmap_kitti06_first51/sparse}
if [ ! -f "$model/cameras.bin" ] && [ ! -f "$model/cameras.txt" ]; then
  echo "colmap.sh: skipped: no COLMAP model at $model (set KEEPLESS_DATA or pass MODEL_DIR)" >&2
  exit 77
fi
if [ -n "${3:-}" ]; then
  out=$3
  mkdir -p "$out"
else
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi

# snippet-begin: sparsify
"$sparsify" --colmap "$model" --out "$out/sparse" --M 200 --min-obs-per-image 30 | tail -n 1 > "$out/summary.json"
# snippet-end: sparsify
ls -l "$out/sparse"
python3 - "$out/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"kept {s['points_kept']} of {s['model_points']} points ({100 * s['kept_fraction']:.1f} %), "
      f"observations per image min {s['min_obs_per_image']} median {s['median_obs_per_image']}")
assert 0 < s['points_kept'] < s['model_points'], "nothing was culled"
assert s['min_obs_per_image'] >= 30, "an image fell below the floor"
PY
