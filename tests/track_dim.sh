#!/bin/sh
# Dim objects (`--blur-px`): a bead at a quarter of the flow scene's flux
# sends each view about one event per frame, which rarely meet at the voxel
# where its images do. --blur-px 1 spreads each event over the image's size
# (a binomial 3 x 3 on every frame, recon/blur.c) and, unless thresholds
# are given, takes the dim objects' thresholds (8 / 6 / 6, x 0.94 at 4 um
# planes). On simulator truth it finds far more of the dim beads than the
# defaults (flow 100 ms, objects.flux_hz=[3000,4000], seeds 1-10: recall
# 0.28 -> 0.54, alpha 0.21 -> 0.38; docs/tracker.md "Dim objects").
# Usage: track_dim.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--blur-px 3" "--blur-px -1" "--blur-px x"
"$bin" recon --blur-px 5 >/dev/null 2>"$tmp/err"
[ $? -eq 2 ] && grep -q -e "--blur-px" "$tmp/err" || { echo "FAIL: recon --blur-px 5 not a usage error"; fail=$((fail+1)); }
simulate_or_skip "$tmp/sim" flow 60 3 --param 'objects.flux_hz=[3000,4000]'

track_score "$tmp/sim" "$tmp/plain" "$tmp/plain.json"
track_score "$tmp/sim" "$tmp/blur" "$tmp/blur.json" --blur-px 1
# without the blur, the dim thresholds alone (the blur's part of the gain)
track_score "$tmp/sim" "$tmp/low" "$tmp/low.json" --threshold-abs 8 --threshold-low 6 --threshold-min 6
expect_key blur_px "$tmp/blur/summary.json" 1
expect_key blur_px "$tmp/plain/summary.json" 0
# 8 and 6 x exp(-(2^2 - 1^2) / 50) at 4 um planes
expect_key threshold_abs "$tmp/blur/summary.json" 7.5341
expect_key threshold_low "$tmp/blur/summary.json" 5.6506
expect_key threshold_min "$tmp/blur/summary.json" 5.6506
# given thresholds stay as given
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/given" -q \
  --blur-px 1 --threshold-abs 20 || { echo "FAIL: track --blur-px 1 --threshold-abs 20"; fail=$((fail+1)); }
expect_key threshold_abs "$tmp/given/summary.json" 20

# Without the blur, track says the peaks are faint and names the option;
# with it, not (a flow scene of the usual flux: track_planes.sh).
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/say" \
  2>"$tmp/say.err" >/dev/null || { echo "FAIL: track (not quiet)"; fail=$((fail+1)); }
grep -q "note: the peaks are faint (median height .* against the threshold 42.*--blur-px 1" "$tmp/say.err" ||
  { echo "FAIL: no faint-peaks note: $(tail -c 400 "$tmp/say.err")"; fail=$((fail+1)); }
# once: during the run (", so far") once 200 peaks say so, else at the end
n_notes=$(grep -c "peaks are faint" "$tmp/say.err")
[ "$n_notes" = 1 ] || { echo "FAIL: the faint-peaks note came $n_notes times"; fail=$((fail+1)); }
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/say1" \
  --blur-px 1 2>"$tmp/say1.err" >/dev/null
grep -q "peaks are faint" "$tmp/say1.err" && { echo "FAIL: faint-peaks note with --blur-px 1"; fail=$((fail+1)); }
h0=$(key "$tmp/plain/summary.json" peak_height_median)
[ -n "$h0" ] && below "$h0" 2 42.38 ||
  { echo "FAIL: summary.json's median peak height '$h0' not below 2 x 42.38"; fail=$((fail+1)); }

a0=$(key "$tmp/plain.json" alpha); a1=$(key "$tmp/blur.json" alpha); a2=$(key "$tmp/low.json" alpha)
r0=$(key "$tmp/plain.json" recall); r1=$(key "$tmp/blur.json" recall); r2=$(key "$tmp/low.json" recall)
p1=$(key "$tmp/blur.json" precision)
echo "dim flow 60 ms seed 3: defaults alpha $a0 recall $r0; thresholds 8/6/6 alpha $a2 recall $r2; --blur-px 1 alpha $a1 recall $r1 precision $p1"
expect_gain "$r0" "$r1" 0.15 "recall $r0 -> $r1 with --blur-px 1"
expect_gain "$r2" "$r1" 0.08 "recall $r2 (thresholds alone) -> $r1 with the blur"
expect_gain "$a0" "$a1" 0.08 "alpha $a0 -> $a1 with --blur-px 1"
expect_gain 0.9 "$p1" 0 "precision $p1 with --blur-px 1"
[ $fail -eq 0 ] && echo "1 passed, 0 failed" || echo "0 passed, $fail failed"
exit $fail
