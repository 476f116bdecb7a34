#!/usr/bin/env bash
# The budget sweep: every method at every kept fraction on the real sequences
# (7-Scenes RGB-D 600 frames, KITTI 00 200, KITTI 06 51), on the synthetic
# back end's trajectory groups (synthetic_tum, synthetic_euroc, synthetic_kitti:
# keepless_eval --data-root's trajectories; --only synthetic selects all three)
# at their own fractions and, with keepless_maps_bench, the COLMAP fixture. One
# keepless_eval process per (input, seed) with every fraction (the original runs
# once per seed), N at a time (-j), each into
# OUT/runs/NAME_seedS; then `keepless_eval --report` merges them
# into OUT/tables.md (with a "Budget sweep" table and the failures per
# sequence), OUT/runs.csv and OUT/sweep_NAME.svg (ATE against local-BA
# observations, one curve per method, failed seeds ringed). Each job's wall
# time is in OUT/jobs.tsv.
#
# A variant is a keepless configuration run through the same sweep (every
# selector alike where the flag applies to all); with several, each goes to
# OUT/VARIANT. paper: the paper's network (default); maturity: tracking-safe
# culling, --maturity 2 --scope newest (every selector decides the keyframe
# that just became 2 old); track: --cost track, keepless only (the baselines
# are paper's); defer: deferred culling, --defer 2; window: deferred culling
# with refined excluded points, every selector deciding the whole local window
# (--defer 2 --defer-refine --decide window); keepkf: window with the VO's
# keyframe culling off (--no-keyframe-culling); countkf: window with that
# culling counting the points a selector deleted (--keyframe-culling
# count-culled); authors, information: the authors' and the information cost
# model, floor: a coverage floor of 30 points per keyframe (ORB-SLAM2's minimum
# inliers), keepless only. Each variant's flags go to OUT/[VARIANT/]flags.txt
# (scripts/sweep_table.py reads them). track, defer, window, keepkf and countkf
# do not run on the synthetic back end (it sends no point quality and has no
# deferred culling).
#
#   scripts/eval_sweep.sh [--data-root DIR] [--fractions 0.1,0.2,0.3,0.4,0.6] [--seeds 5] [-j 2]
#                         [--out DIR] [--only 7scenes,kitti00,kitti06,synthetic,colmap] [--bin DIR]
#                         [--synthetic-fractions 0.2,0.4]
#                         [--variants paper,maturity,track,defer,window,keepkf,countkf,authors,information,floor]
#                         [--eval-flags "FLAGS"] [--resume]
#
# --resume keeps OUT's finished jobs (a run directory with its runs.csv, the
# COLMAP rows with their JSON line, each run with the same flags: its .job file)
# and runs the rest.
set -euo pipefail
# The defaults are the repository's; paths given on the command line are the caller's.
root=$(cd "$(dirname "$0")/.." && pwd)

data=$root/../shared/data
fractions=0.1,0.2,0.3,0.4,0.6
synthetic_fractions=0.2,0.4
seeds=5
jobs=2
out=$root/sweep_out
only=7scenes,kitti00,kitti06,colmap
bin=$root/build/bin
variants=paper
extra=
resume=0
while (($#)); do
  case "$1" in
    --data-root) data=$2; shift 2 ;;
    --fractions) fractions=$2; shift 2 ;;
    --synthetic-fractions) synthetic_fractions=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    -j) jobs=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    --bin) bin=$2; shift 2 ;;
    --variants) variants=$2; shift 2 ;;
    --eval-flags) extra=$2; shift 2 ;;
    --resume) resume=1; shift ;;
    -h|--help) sed -n 2,40p "$0"; exit 0 ;;
    *) echo "eval_sweep: unknown option $1" >&2; exit 2 ;;
  esac
done
for n in "--seeds $seeds" "-j $jobs"; do
  [[ ${n#* } =~ ^[1-9][0-9]*$ ]] || { echo "eval_sweep: ${n%% *}: expected a positive integer, got '${n#* }'" >&2; exit 2; }
done
IFS=, read -r -a only_list <<< "$only"
for o in "${only_list[@]}"; do
  case "$o" in
    7scenes|kitti00|kitti06|synthetic|synthetic_tum|synthetic_euroc|synthetic_kitti|colmap) ;;
    *) echo "eval_sweep: --only: unknown input '$o' (7scenes, kitti00, kitti06, synthetic, synthetic_tum," \
            "synthetic_euroc, synthetic_kitti, colmap)" >&2
       exit 2 ;;
  esac
done
for b in keepless_eval keepless_maps_bench; do
  [ -x "$bin/$b" ] || { echo "eval_sweep: $bin/$b is missing: cmake --build build --target $b" >&2; exit 1; }
done
data=$(cd "$data" && pwd)
mkdir -p "$out"
out=$(cd "$out" && pwd)
bin=$(cd "$bin" && pwd)
cd "$root"

# name|keepless_eval input flags. The synthetic groups are --data-root's
# trajectories given one by one: --data-root would add its image tracks, named
# like the real KITTI 06 (the report would merge the two), and a BAL problem.
synthetic() {  # FORMAT FILE...: the synthetic back end on each trajectory, no ablation
  local format=$1
  shift
  printf -- '--no-ablation'
  for t; do printf -- ' --trajectory %q --format %s' "$t" "$format"; done
}
euroc=$data/orbslam3_euroc_left_cam_gt
# The flags are shell words (run_job splits them with eval): a data root with blanks stays one word.
q=$(printf '%q' "$data")
inputs=(
  "7scenes|--rgbd $q/7scenes_redkitchen_first600"
  "kitti00|--images $q/kitti00_first200_vamr/image_0 --calib $q/kitti00_first200_vamr/K.txt --poses $q/kitti00_first200_vamr/poses.txt"
  "kitti06|--images $q/kitti06_first51_niconielsen/image_l --calib $q/kitti06_first51_niconielsen/calib.txt --poses $q/kitti06_first51_niconielsen/poses.txt"
  "synthetic_tum|$(synthetic tum "$data/evo/freiburg1_xyz-groundtruth.txt")"
  "synthetic_euroc|$(synthetic euroc "$euroc/MH01_GT.txt" "$euroc/MH03_GT.txt" "$euroc/V102_GT.txt" "$euroc/V201_GT.txt")"
  "synthetic_kitti|$(synthetic kitti "$data/evo/KITTI_00_gt.txt" "$data/kitti_odom_eval/gt_poses/06.txt" "$data/kitti_odom_eval/gt_poses/09.txt")"
)
# An input is selected by its name or, for synthetic_GROUP, by "synthetic".
selected() { [[ ",$only," == *",$1,"* || ($1 == synthetic_* && ",$only," == *",synthetic,"*) ]]; }

# variant|keepless_eval flags|keepless_maps_bench flags ("-": no COLMAP run, the bench has no such
# option)|inputs it skips. --no-baselines: keepless only, the baselines are paper's.
variant_flags() {
  case "$1" in
    paper) echo "|||" ;;
    maturity) echo "|--maturity 2 --scope newest|-|" ;;
    track) echo "|--cost track --no-baselines|--cost track|synthetic" ;;
    defer) echo "|--defer 2|-|synthetic" ;;
    window) echo "|--defer 2 --defer-refine --decide window|-|synthetic" ;;
    keepkf) echo "|--defer 2 --defer-refine --decide window --no-keyframe-culling|-|synthetic" ;;
    countkf) echo "|--defer 2 --defer-refine --decide window --keyframe-culling count-culled|-|synthetic" ;;
    authors) echo "|--cost authors --no-baselines|--cost authors|" ;;
    information) echo "|--cost information --no-baselines|--cost information|" ;;
    floor) echo "|--floor 30 --no-baselines|-|" ;;
    *) echo "eval_sweep: unknown variant $1 (paper, maturity, track, defer, window, keepkf, countkf, authors, information, floor)" >&2
       return 1 ;;
  esac
}

joblist="$out/jobs.txt"
: > "$joblist"
IFS=, read -r -a variant_list <<< "$variants"
# One variant writes into OUT itself, several each into OUT/VARIANT.
variant_dir() { if ((${#variant_list[@]} > 1)); then echo "$out/$1"; else echo "$out"; fi; }
for variant in "${variant_list[@]}"; do
  vf=$(variant_flags "$variant")
  IFS='|' read -r _ eval_flags maps_flags skips <<< "$vf"
  vdir=$(variant_dir "$variant")
  mkdir -p "$vdir/runs"
  # The variant's flags beside its runs (--eval-flags too): the one record of what it is.
  line=$eval_flags
  [ -z "$extra" ] || line="${line:+$line }$extra"
  printf 'eval: %s\ncolmap: %s\n' "$line" "$maps_flags" > "$vdir/flags.txt"
  for entry in "${inputs[@]}"; do
    name=${entry%%|*}
    selected "$name" || continue
    [[ $name == synthetic_* && ",$skips," == *",synthetic,"* ]] && continue
    f=$fractions
    [[ $name == synthetic_* ]] && f=$synthetic_fractions
    for ((seed = 1; seed <= seeds; ++seed)); do
      echo "$variant|$vdir|$name|$seed|$f|${entry#*|} $eval_flags $extra" >> "$joblist"
    done
  done
  if selected colmap && [ "$maps_flags" != - ]; then echo "$variant|$vdir|colmap|all|$fractions|$maps_flags" >> "$joblist"; fi
done

[ -s "$joblist" ] || { echo "eval_sweep: no job: --only $only selects no input the variants $variants run" >&2; exit 2; }

# Each job's wall and CPU seconds (its processes' user + system) go to jobs.tsv.
run_job() {
  IFS='|' read -r variant vdir name seed fractions flags <<< "$1"
  local start end dir rc=0 cpu
  start=$(date +%s)
  if [ "$name" = colmap ]; then
    dir="$vdir/colmap"
    if [ "$resume" = 1 ] && tail -n 1 "$dir/stdout.txt" 2>/dev/null | grep -q '^{' && [ "$(cat "$dir.job" 2>/dev/null)" = "$1" ]; then
      return 0
    fi
    rm -f "$dir.job" "$dir/stdout.txt"  # an earlier run's rows must not outlive a run that fails or is killed
    mkdir -p "$dir/work"
    # shellcheck disable=SC2086  # flags are words
    "$bin/keepless_maps_bench" --data "$data" --keep-fraction "$fractions" --seeds "$seeds" --work "$dir/work" \
      $flags > "$dir/stdout.txt" 2> "$dir/stderr.txt" || rc=$?
  else
    dir="$vdir/runs/${name}_seed$seed"
    # The job's line (input, seed, fractions, flags) in DIR.job: --resume trusts a run of this job only.
    if [ "$resume" = 1 ] && [ -f "$dir/runs.csv" ] && [ "$(cat "$dir.job" 2>/dev/null)" = "$1" ]; then return 0; fi
    rm -rf "$dir" "$dir.job"  # an earlier run's runs.csv must not outlive a run that fails or is killed
    local args
    eval "args=($flags)"  # shell words: the inputs' paths are quoted
    "$bin/keepless_eval" "${args[@]}" --kept-fraction "$fractions" --seed "$seed" --seeds 1 --out "$dir" \
      > "$dir.stdout" 2> "$dir.stderr" || rc=$?
  fi
  end=$(date +%s)
  [ "$rc" != 0 ] || printf '%s\n' "$1" > "$dir.job"
  # `times`' second line: this shell's children, user then system ("1m2.5s");
  # it runs in this shell, not a pipeline's subshell, which has no children.
  times > "$dir.times"
  cpu=$(sed -n 2p "$dir.times" | awk '{ n = 0; for (i = 1; i <= 2; ++i) { split($i, a, /[ms]/); n += a[1] * 60 + a[2] } printf "%.0f", n }')
  printf '%s\t%s\t%s\t%d\t%s\t%d\n' "$variant" "$name" "$seed" $((end - start)) "$cpu" "$rc" >> "$out/jobs.tsv"
  echo "eval_sweep: $variant $name seed $seed done in $((end - start)) s, ${cpu} s CPU (exit $rc)" >&2
}
export -f run_job
export out data bin seeds resume

if [ "$resume" = 0 ] || [ ! -f "$out/jobs.tsv" ]; then
  printf 'variant\tinput\tseed\twall_s\tcpu_s\texit\n' > "$out/jobs.tsv"
fi
t0=$(date +%s)
tr '\n' '\0' < "$joblist" | xargs -0 -P "$jobs" -I{} bash -c 'run_job "$1"' _ {}

failed=0
for variant in "${variant_list[@]}"; do
  vdir=$(variant_dir "$variant")
  reports=()
  # This sweep's jobs only: OUT may hold runs of an earlier sweep (other seeds, inputs or flags).
  while IFS='|' read -r v _ name seed _; do
    d="$vdir/runs/${name}_seed$seed"
    if [ "$v" = "$variant" ] && [ "$name" != colmap ] && [ -f "$d/runs.csv" ]; then reports+=(--report "$d"); fi
  done < "$joblist"
  if ((${#reports[@]})); then
    "$bin/keepless_eval" "${reports[@]}" --out "$vdir" > "$vdir/report.stdout" || failed=1
  fi
done
# The last line per job counts (--resume may have run a job again).
summary=$(awk -F'\t' 'NR > 1 { cpu[$1 FS $2 FS $3] = $5; rc[$1 FS $2 FS $3] = $6 }
  END { for (k in cpu) { total += cpu[k]; if (rc[k] != 0) bad++ } printf "%d %d", total, bad }' "$out/jobs.tsv")
read -r cpu_total bad_jobs <<< "$summary"
echo "eval_sweep: $cpu_total s CPU in all jobs, $bad_jobs failed" >&2
echo "eval_sweep: $(($(date +%s) - t0)) s wall with -j $jobs; tables in $out/[VARIANT/]tables.md, plots" \
     "sweep_*.svg beside them, the COLMAP fixture's rows in colmap/stdout.txt" >&2
if [ "$failed" != 0 ] || [ "$bad_jobs" != 0 ]; then
  echo "eval_sweep: a job or a report failed (exit column of $out/jobs.tsv)" >&2
  exit 1
fi
