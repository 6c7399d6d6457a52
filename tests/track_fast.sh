#!/bin/sh
# Fast beads (`eventlfm simulate flow --param motion.speed_mm_per_s=[5,8]`,
# seed 33, 100 ms; no setting was chosen on it): at 1 ms frames they move
# ~5 um between frames, where the linker loses them between frames (alpha
# 0.36). `eventlfm track` measures the tracks' median speed and notes that
# shorter windows follow them, naming the --dt-us to use; following the note
# must raise alpha by 0.15 or more (0.364 -> 0.660 when it came). On the
# default flow scene (2.5-4 mm/s, ~2.7 um per frame, where --dt-us 500
# loses 0.05 alpha on average, seeds 1-4) there is no such note.
# Usage: track_fast.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
simulate_or_skip "$tmp/fast" flow 100 33 --param "motion.speed_mm_per_s=[5,8]"
"$bin" track --calib "$tmp/fast/calib.json" --events "$tmp/fast/events.raw" --out "$tmp/f1" \
  >/dev/null 2>"$tmp/f1.err" || { echo "FAIL: track on the fast scene"; fail=$((fail+1)); }
"$bin" score --truth "$tmp/fast/truth.csv" --tracks "$tmp/f1/tracks.csv" \
  --detections "$tmp/f1/detections.csv" --calib "$tmp/fast/calib.json" --json >"$tmp/f1.json" ||
  { echo "FAIL: score on the fast scene"; fail=$((fail+1)); }
grep -q "note: the tracks move fast.*--dt-us 500" "$tmp/f1.err" ||
  { echo "FAIL: no note naming --dt-us 500 on the fast scene"; cat "$tmp/f1.err"; fail=$((fail+1)); }
track_score "$tmp/fast" "$tmp/f2" "$tmp/f2.json" --dt-us 500
a1=$(key "$tmp/f1.json" alpha); a2=$(key "$tmp/f2.json" alpha)
echo "fast flow (5-8 mm/s): alpha $a1 at 1 ms frames, $a2 at 0.5 ms (the note's advice)"
expect_gain "$a1" "$a2" 0.15 "following the note gains < 0.15 alpha ($a1 -> $a2)"

simulate_or_skip "$tmp/flow" flow 60 1
"$bin" track --calib "$tmp/flow/calib.json" --events "$tmp/flow/events.raw" --out "$tmp/d" \
  >/dev/null 2>"$tmp/d.err" || { echo "FAIL: track on the default flow"; fail=$((fail+1)); }
grep -q "note: the tracks move fast" "$tmp/d.err" && { echo "FAIL: the fast note on the default flow"; fail=$((fail+1)); }

[ $fail -eq 0 ] && echo "track_fast: all passed" || echo "track_fast: $fail failed"
[ $fail -eq 0 ]
