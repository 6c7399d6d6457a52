#!/bin/bash
# measure_scenes.sh — the per-scene table of the README: simulate, track
# (/usr/bin/time -v), score. EVENTLFM=path/to/eventlfm OUT=dir to change.
# LONG=1: each scene at its own length (flow and stage 1 s, blink and worm
# 0.5 s; `eventlfm simulate --list`) instead of the table's 100-200 ms:
# every track has more encounters to survive (docs/tracker.md "Longer
# recordings").
set -u
B=${EVENTLFM:-$(cd "$(dirname "$0")/.." && pwd)/build/eventlfm}
M=${OUT:-/tmp/eventlfm_measure}; rm -rf "$M"; mkdir -p "$M"
cd "$M"
TIME="/usr/bin/time -v"; [ -x /usr/bin/time ] || TIME=""   # Debian package "time"
for sc in "flow 100 1" "flow 100 2" "stage 200 1" "blink 200 1" "worm 200 1"; do
  set -- $sc; scene=$1; ms=$2; seed=$3; d=$M/${scene}_s${seed}
  dur="--duration-ms $ms"; [ "${LONG:-0}" = 1 ] && dur=""
  "$B" simulate $scene --out $d $dur --seed $seed --quiet 2>$d.sim.txt
  extra=""; [ $scene = worm ] && extra="--dt-us 2000 --repr integral"
  [ $scene = stage ] && extra="--motion stage"
  [ $scene = blink ] && extra="--start each-trigger"   # a window per LED pulse (README)
  $TIME "$B" track --calib $d/calib.json --events $d/events.raw --out $d/t $extra 2> $d.track.txt
  sv=""; [ $scene = stage ] && sv="--stage-velocity-um-per-ms 0,2.5,0"
  "$B" score --truth $d/truth.csv --tracks $d/t/tracks.csv --detections $d/t/detections.csv --calib $d/calib.json $sv > $d.score.txt 2>&1
  label="$sc"; [ "${LONG:-0}" = 1 ] && label="$scene (its own length) $seed"
  echo "== $label"; tail -1 $d.track.txt | head -1; grep -E "eventlfm track:|Elapsed|Maximum resident" $d.track.txt | tail -3; cat $d.score.txt
  # blinking objects: also with the frame list and the window rule (an object
  # counts when lit for half of the frame's own window, docs/bench.md), beside
  # SPEC 7 as written above
  if [ $scene = blink ]; then
    echo "-- with --frames run --window-us run"
    "$B" score --truth $d/truth.csv --tracks $d/t/tracks.csv --detections $d/t/detections.csv --calib $d/calib.json --frames run --window-us run 2>&1
  fi
done
