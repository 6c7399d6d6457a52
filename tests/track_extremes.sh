#!/bin/sh
# Options at the far ends of what they take run to the end, with every
# output written. Two that did not (docs/tracker.md "Frames microseconds
# apart"):
# - --stride-us 1, windows 1 us apart: a track's spline refit ended the run
#   with "smooth: no model could be fitted (153 points)", exit 1 and no
#   summary.json. GCV's grid of spline weights was in ms^3 for frames ~1 ms
#   apart, and on frames 1 us apart its smallest weight was already beyond
#   what the banded factorisation holds; the grid now moves with the
#   states' spacing (elfm_spline_lambda_unit, test_smooth_timescale).
# - --tau-us 1e300, a surface that never decays: the motion bias's delay
#   (the weighted events' mean age) came out -inf, "motion bias out of
#   range"; it is now the window's half, its limit (plus 20 us).
# Usage: track_extremes.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
simulate_or_skip "$tmp/flow" flow 10 1
sc=$tmp/flow
# 1500 windows, 1 us apart, over 8.0-9.5 ms (where the refit failed)
check 0 "" "$bin" track --calib "$sc/calib.json" --events "$sc/events.raw" --out "$tmp/s1" -q \
  --stride-us 1 --from-us 8000 --to-us 9500
[ -s "$tmp/s1/summary.json" ] || { echo "FAIL: stride 1 us: no summary.json"; fail=$((fail+1)); }
n=$(key "$tmp/s1/summary.json" tracks)
below 9 1 "${n:-0}" || { echo "FAIL: stride 1 us: $n tracks, want 10 or more"; fail=$((fail+1)); }
check 0 "" "$bin" track --calib "$sc/calib.json" --events "$sc/events.raw" --out "$tmp/t" -q \
  --tau-us 1e300
expect_key motion_delay_us "$tmp/t/summary.json" 520
[ $fail -eq 0 ] && echo "track_extremes: all passed" || echo "track_extremes: $fail failed"
[ $fail -eq 0 ]
