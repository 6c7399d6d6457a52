#!/bin/sh
# `eventlfm track` on microscopes unlike the paper's, each at its defaults,
# scored against the simulator's truth: flow 40 ms, seed 3, with
#  - a 640 x 480 sensor (the views' grid overhangs it: views cropped or lost),
#  - a 7 x 7 lens array (49 smaller views),
#  - the lens array turned 3 degrees against the sensor's rows,
#  - a single bead (nothing for the linker to choose between).
# Each run exits 0, pairs every bead of the truth with a track and scores
# alpha >= 0.7 (measured when written, fifty-ninth session: 0.810, 0.913,
# 0.908, 0.916; the paper's own optics give 0.88-0.94 on flow). Under the
# sanitizers (CI) the same runs also check memory and arithmetic on
# geometries the other tests do not use.
# Usage: track_optics.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

# one NAME SIMULATE-OPTIONS...: simulate, track, score, check
one() {
  on=$1; shift
  simulate_or_skip "$tmp/$on" flow 40 3 "$@"
  track_score "$tmp/$on" "$tmp/$on.out" "$tmp/$on.json"
  oa=$(key "$tmp/$on.json" alpha)
  om=$(key "$tmp/$on.json" n_missed_tracks)
  ot=$(key "$tmp/$on.json" n_truth_tracks)
  echo "$on: alpha $oa, $om of $ot beads without a track"
  awk -v a="$oa" 'BEGIN { exit !(a != "" && a >= 0.7) }' || { echo "FAIL: $on: alpha '$oa' < 0.7"; fail=$((fail+1)); }
  [ "$om" = 0 ] && [ "${ot:-0}" -gt 0 ] 2>/dev/null || { echo "FAIL: $on: $om of $ot beads missed"; fail=$((fail+1)); }
}

one vga --param sensor.width=640 --param sensor.height=480
one lenses7 --param optics.lenslets_per_side=7
one turned --param optics.mla_rotation_deg=3
one single --param objects.count=1

[ "$fail" -eq 0 ] && echo "track_optics: OK"
exit "$fail"
