#!/bin/sh
# Fast beads (`eventlfm simulate flow --param motion.speed_mm_per_s=[5,8]`,
# seed 33, 100 ms; no setting was chosen on it), ~4.5-5 um between frames
# at 1 ms:
#  - the linker's acceleration fit over at most 20 um of path
#    (--short-path-um, default 20) keeps them: alpha at least 0.1 above
#    --short-path-um 0, its 8 points over more than a radian of their turn
#    (0.364 -> 0.627 when it came);
#  - `eventlfm track` measures the tracks' median speed and notes that
#    shorter windows follow them better, naming the --dt-us to use;
#    following the note raises alpha (0.627 -> 0.666 when it came);
#  - on the default flow scene (2.5-4 mm/s, ~2.7 um per frame, where
#    --dt-us 500 loses 0.06 alpha on average, seeds 1-4) there is no note;
#  - a negative --short-path-um is a usage error.
# Usage: track_fast.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--short-path-um -1" "--short-path-um x" "--short-path-um 2000"
simulate_or_skip "$tmp/fast" flow 100 33 --param "motion.speed_mm_per_s=[5,8]"
"$bin" track --calib "$tmp/fast/calib.json" --events "$tmp/fast/events.raw" --out "$tmp/f1" \
  >/dev/null 2>"$tmp/f1.err" || { echo "FAIL: track on the fast scene"; fail=$((fail+1)); }
"$bin" score --truth "$tmp/fast/truth.csv" --tracks "$tmp/f1/tracks.csv" \
  --detections "$tmp/f1/detections.csv" --calib "$tmp/fast/calib.json" --json >"$tmp/f1.json" ||
  { echo "FAIL: score on the fast scene"; fail=$((fail+1)); }
grep -q "note: the tracks move fast.*--dt-us 500" "$tmp/f1.err" ||
  { echo "FAIL: no note naming --dt-us 500 on the fast scene"; cat "$tmp/f1.err"; fail=$((fail+1)); }
track_score "$tmp/fast" "$tmp/f0" "$tmp/f0.json" --short-path-um 0
track_score "$tmp/fast" "$tmp/f2" "$tmp/f2.json" --dt-us 500
a0=$(key "$tmp/f0.json" alpha); a1=$(key "$tmp/f1.json" alpha); a2=$(key "$tmp/f2.json" alpha)
echo "fast flow (5-8 mm/s): alpha $a0 with 8-point fits, $a1 at the defaults, $a2 at 0.5 ms (the note's advice)"
expect_gain "$a0" "$a1" 0.1 "the 20 um path cap gains < 0.1 alpha ($a0 -> $a1)"
expect_gain "$a1" "$a2" 0.02 "following the note gains < 0.02 alpha ($a1 -> $a2)"

simulate_or_skip "$tmp/flow" flow 60 1
"$bin" track --calib "$tmp/flow/calib.json" --events "$tmp/flow/events.raw" --out "$tmp/d" \
  >/dev/null 2>"$tmp/d.err" || { echo "FAIL: track on the default flow"; fail=$((fail+1)); }
grep -q "note: the tracks move fast" "$tmp/d.err" && { echo "FAIL: the fast note on the default flow"; fail=$((fail+1)); }
[ "$(key "$tmp/d/summary.json" short_path_um)" = 20 ] || { echo "FAIL: short_path_um not 20 in summary.json"; fail=$((fail+1)); }

[ $fail -eq 0 ] && echo "track_fast: all passed" || echo "track_fast: $fail failed"
[ $fail -eq 0 ]
