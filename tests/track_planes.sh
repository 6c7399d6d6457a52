#!/bin/sh
# The planes `eventlfm track` refocuses on when --z-step-um is not given:
# every m-th of the calibration's planes, m the largest that moves the
# outermost view <= --plane-shift-px (1.5) px between planes (where it does
# not divide the planes' span, the range is centred); the default absolute
# thresholds fall by what the wider
# sampling costs a peak (exp(-((h/2)^2 - (h0/2)^2) / (2 x 5^2))); a given
# step, a given threshold and --plane-shift-px 0 are taken as they are. On
# simulator truth the coarser planes keep the accuracy of every plane.
# Usage: track_planes.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--plane-shift-px -1" "--plane-shift-px 101" "--plane-shift-px x"
simulate_or_skip "$tmp/sim" flow 60 3

# The paper's optics, 2 um planes: the outer views move 0.358 px per um,
# so 4 um (1.43 px) is the coarsest within 1.5 px.
track_score "$tmp/sim" "$tmp/auto" "$tmp/auto.json"
track_score "$tmp/sim" "$tmp/all" "$tmp/all.json" --plane-shift-px 0
s=$tmp/auto/summary.json
expect_key nz "$s" 51
expect_key z_step_um "$s" 4
expect_key calib_planes_per_plane "$s" 2
expect_key fit_half_z "$s" 2
# 45, 30 and 30 x exp(-(2^2 - 1^2) / 50)
expect_key threshold_abs "$s" 42.3794
expect_key threshold_low "$s" 28.2529
expect_key threshold_min "$s" 28.2529
s=$tmp/all/summary.json
expect_key nz "$s" 101
expect_key z_step_um "$s" 2
expect_key calib_planes_per_plane "$s" 1
expect_key fit_half_z "$s" 3
expect_key threshold_abs "$s" 45
expect_key threshold_low "$s" 30

# The choice is said on stderr (not with every plane).
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/say" \
  2>"$tmp/say.err" >/dev/null || { echo "FAIL: track (not quiet)"; fail=$((fail+1)); }
grep -q "51 planes -100..100 um, 4 um apart: every 2nd of" "$tmp/say.err" ||
  { echo "FAIL: stderr does not name the planes: $(head -c 300 "$tmp/say.err")"; fail=$((fail+1)); }
# the usual flux: no note of faint peaks (track_dim.sh has the dim ones)
grep -q "peaks are faint" "$tmp/say.err" && { echo "FAIL: faint-peaks note on flow"; fail=$((fail+1)); }
# ... so --blur-px auto judged them and kept going without the blur
expect_key blur_px "$tmp/say/summary.json" 0
[ "$(key "$tmp/say/summary.json" blur_auto)" = true ] || { echo "FAIL: blur_auto not on by default"; fail=$((fail+1)); }
ra=$(key "$tmp/say/summary.json" auto_height_ratio)
at_least "$ra" 2.15 || { echo "FAIL: flow's auto_height_ratio '$ra' below 2.15"; fail=$((fail+1)); }
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/say0" \
  --plane-shift-px 0 2>"$tmp/say0.err" >/dev/null
grep -q "apart: every" "$tmp/say0.err" && { echo "FAIL: planes named with every plane"; fail=$((fail+1)); }

# A spacing that does not divide the range (3 planes of 2 um: 2.15 px within
# 2.2): the 100 steps take 33 of 6 um, centred on the range, -99..99 um.
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/six" \
  --plane-shift-px 2.2 2>"$tmp/six.err" >/dev/null || { echo "FAIL: track --plane-shift-px 2.2"; fail=$((fail+1)); }
s=$tmp/six/summary.json
expect_key nz "$s" 34
expect_key z_step_um "$s" 6
expect_key z_min_um "$s" -99
expect_key calib_planes_per_plane "$s" 3
expect_key fit_half_z "$s" 1
# 45 x exp(-(3^2 - 1^2) / 50)
expect_key threshold_abs "$s" 38.3465
grep -q "34 planes -99..99 um, 6 um apart: centred" "$tmp/six.err" ||
  { echo "FAIL: the centred planes not named: $(head -c 300 "$tmp/six.err")"; fail=$((fail+1)); }

# Given values stay: the step, and a threshold (the others still scale).
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/step" -q \
  --z-step-um 2 || { echo "FAIL: track --z-step-um 2"; fail=$((fail+1)); }
expect_key nz "$tmp/step/summary.json" 101
expect_key threshold_abs "$tmp/step/summary.json" 45
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/thr" -q \
  --threshold-abs 45 || { echo "FAIL: track --threshold-abs 45"; fail=$((fail+1)); }
expect_key nz "$tmp/thr/summary.json" 51
expect_key threshold_abs "$tmp/thr/summary.json" 45

# Other calibrations of the same sensor (the planes only: the events are
# the paper's): 1 um planes -> every 4th; a span of 99 steps of 2 um
# (-99..99), which 2 does not divide -> every 2nd, centred: 49 steps of 4 um,
# -98..98 (every plane before the fifty-third session); 40x optics, whose
# outer views move 1.75 px per um -> every plane.
# planes CALIB_OPTIONS NZ STEP EVERY
planes() {
  pl_n=$((pl_n+1))
  # shellcheck disable=SC2086
  "$bin" calib from-optics $1 --out "$tmp/c$pl_n.json" >/dev/null 2>&1 ||
    { echo "FAIL: calib from-optics $1"; fail=$((fail+1)); return; }
  "$bin" track --calib "$tmp/c$pl_n.json" --events "$tmp/sim/events.raw" --out "$tmp/p$pl_n" -q || { echo "FAIL: track with calib from-optics $1"; fail=$((fail+1)); return; }
  expect_key nz "$tmp/p$pl_n/summary.json" "$2"
  expect_key z_step_um "$tmp/p$pl_n/summary.json" "$3"
  expect_key calib_planes_per_plane "$tmp/p$pl_n/summary.json" "$4"
}
pl_n=0
planes "--z-step-um 1" 51 4 4
planes "--z-min-um -99 --z-max-um 99 --z-step-um 2" 50 4 2
expect_key z_min_um "$tmp/p2/summary.json" -98
planes "--magnification 40" 101 2 1

# Accuracy: the coarser planes lose no more than a little alpha and recall
# (flow 100 ms seeds 1-20: alpha 0.8505 with every plane; docs/tracker.md
# "Planes 4 um apart").
a0=$(key "$tmp/all.json" alpha); a1=$(key "$tmp/auto.json" alpha)
r0=$(key "$tmp/all.json" recall); r1=$(key "$tmp/auto.json" recall)
echo "flow 60 ms seed 3: every plane alpha $a0 recall $r0; every 2nd alpha $a1 recall $r1"
expect_gain "$a0" "$a1" -0.03 "alpha $a0 -> $a1"
expect_gain "$r0" "$r1" -0.02 "recall $r0 -> $r1"
[ $fail -eq 0 ] && echo "1 passed, 0 failed" || echo "0 passed, $fail failed"
exit $fail
