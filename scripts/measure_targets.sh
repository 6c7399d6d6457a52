#!/bin/bash
# measure_targets.sh — the README's "Against the targets" table, measured
# again in one go on the build at hand: each scene simulated over the seeds
# the README quotes, tracked by `eventlfm track` at its defaults (it picks
# the worm's, the stage's and the LED's settings itself) on one thread, and
# scored against the simulator's truth (`eventlfm score --json`, SPEC 7).
# Prints one Markdown row per set of recordings: the means over its seeds.
#
#   scripts/measure_targets.sh [SET ...]       (default: every set but flow_1s)
#
# Sets: flow, flow_heldout, flow_1s (20 recordings of 1 s: ~4 min on 2 cores),
# flow_random, worm, stage, stage_accel, blink, blink_moving.
# EVENTLFM=path/to/eventlfm, OUT=dir (default /tmp/eventlfm_targets),
# JOBS=N recordings at once (default 2), TRACK_ARGS="..." options given to
# every `track` (an option's effect on the targets: run twice, with and
# without, in two OUT folders). Each recording's files stay in
# OUT/SET/sSEED (sim.txt, track.txt, score.json) for a closer look.
set -u
B=${EVENTLFM:-$(cd "$(dirname "$0")/.." && pwd)/build/eventlfm}
M=${OUT:-/tmp/eventlfm_targets}
JOBS=${JOBS:-2}
SELF=$(realpath "$0")

# scene, length (ms), first and last seed, what `score` adds
set_def() {
  case "$1" in
  flow) echo "flow 100 1 20" ;;
  flow_heldout) echo "flow 100 21 32" ;;
  flow_1s) echo "flow 1000 1 20" ;;
  flow_random) echo "flow_random 100 1 30" ;;
  worm) echo "worm 200 1 8" ;;
  stage) echo "stage 200 1 9" ;;
  stage_accel) echo "stage_accel 300 1 1" ;;
  blink) echo "blink 200 1 4" ;;
  blink_moving) echo "blink_moving 200 1 10" ;;
  *) return 1 ;;
  esac
}

# One recording: simulate, track, score; a failed step leaves its file.
one() {
  local set=$1 scene=$2 ms=$3 seed=$4 d=$M/$1/s$4
  mkdir -p "$d"
  "$B" simulate "$scene" --out "$d/sim" --duration-ms "$ms" --seed "$seed" --quiet \
    >"$d/sim.txt" 2>&1 || { echo "$set seed $seed: simulate failed ($d/sim.txt)" >&2; return 1; }
  # shellcheck disable=SC2086 # TRACK_ARGS: several options
  "$B" track --threads 1 --calib "$d/sim/calib.json" --events "$d/sim/events.raw" --out "$d/t" \
    ${TRACK_ARGS:-} >"$d/track.txt" 2>&1 || { echo "$set seed $seed: track failed ($d/track.txt)" >&2; return 1; }
  local extra=""
  case "$scene" in
  stage) extra="--stage-velocity-um-per-ms 0,2.5,0" ;;   # the scene's stage (docs/simulator.md)
  blink | blink_moving) extra="--frames run --window-us run" ;;   # a frame per LED pulse
  esac
  "$B" score --truth "$d/sim/truth.csv" --tracks "$d/t/tracks.csv" --detections "$d/t/detections.csv" \
    --calib "$d/sim/calib.json" $extra --json >"$d/score.json" 2>"$d/score.txt" ||
    { echo "$set seed $seed: score failed ($d/score.txt)" >&2; return 1; }
  echo "$set seed $seed done" >&2
}

if [ "${1:-}" = --one ]; then
  shift
  one "$@"
  exit
fi

sets=("$@")
[ ${#sets[@]} -eq 0 ] && sets=(flow flow_heldout flow_random worm stage stage_accel blink blink_moving)
for s in "${sets[@]}"; do
  set_def "$s" >/dev/null || { echo "measure_targets.sh: unknown set '$s'" >&2; exit 2; }
done
[ -x "$B" ] || { echo "measure_targets.sh: no $B (build first, or set EVENTLFM)" >&2; exit 2; }

# a flat JSON object's number for key $2 in file $1 ("-" when absent)
num() {
  local v
  v=$(sed -n "s/.*\"$2\":\([-0-9.eE+]*\).*/\1/p" "$1")
  echo "${v:--}"
}

echo "| set | recordings | alpha | F1 | recall | precision | RMSE x / y / z um | objects paired / truth, spurious tracks | other |"
echo "|---|---:|---:|---:|---:|---:|---|---|---|"
status=0
for s in "${sets[@]}"; do
  read -r scene ms first last <<<"$(set_def "$s")"
  rm -rf "${M:?}/$s"
  mkdir -p "$M/$s"
  seq "$first" "$last" | xargs -P "$JOBS" -I{} "$SELF" --one "$s" "$scene" "$ms" {} || status=1
  n=0
  rows=""
  for seed in $(seq "$first" "$last"); do
    f=$M/$s/s$seed/score.json
    [ -s "$f" ] || continue
    n=$((n + 1))
    acc=""
    if [ "$scene" = stage_accel ]; then
      # the fitted stage's acceleration along y (the scene's 0.0025 um/ms^2)
      acc=$(sed -n 's/.*"acceleration_um_per_ms2":[^,]*, *\([-0-9.eE+]*\),.*/\1/p' "$M/$s/s$seed/t/summary.json")
    fi
    rows+="$(num "$f" alpha) $(num "$f" f1) $(num "$f" recall) $(num "$f" precision) $(num "$f" rmse_x_um)"
    rows+=" $(num "$f" rmse_y_um) $(num "$f" rmse_z_um) $(num "$f" n_paired_tracks) $(num "$f" n_truth_tracks)"
    rows+=" $(num "$f" n_spurious_tracks) $(num "$f" stage_velocity_rel_error) ${acc:--}"$'\n'
  done
  [ "$n" -eq "$(($last - $first + 1))" ] || status=1
  printf '%s' "$rows" | awk -v set="$s ($scene, $ms ms, seeds $first-$last)" -v n="$n" '
    NF >= 12 { for (i = 1; i <= 10; i++) m[i] += $i
               if ($11 != "-") { se += $11; sn++; if ($11 > smax) smax = $11 }
               if ($12 != "-") a = $12 }
    END {
      if (n == 0) { printf "| %s | 0 | | | | | | | |\n", set; exit }
      other = ""
      if (sn > 0) other = sprintf("stage velocity error %.2f %% (largest %.2f %%; the vector, which bounds the speed error)", 100 * se / sn, 100 * smax)
      if (a != "") other = sprintf("fitted acceleration %.5f um/ms^2 (truth 0.0025, %.1f %%)", a, 100 * (a - 0.0025) / 0.0025)
      printf "| %s | %d | %.3f | %.3f | %.3f | %.3f | %.2f / %.2f / %.2f | %d / %d, %d | %s |\n", set, n,
             m[1] / n, m[2] / n, m[3] / n, m[4] / n, m[5] / n, m[6] / n, m[7] / n, m[8], m[9], m[10], other
    }'
done
exit $status
