#!/bin/sh
# Slow beads: where the first peaks' tracks move at 1.2-2.5 um/ms (early
# speeds at 1 ms; faster than cells, slower than the usual flow's 3.7-4.2)
# on a time surface with neither --dt-us nor --tau-us given, the run starts
# again with --dt-us 1500 --tau-us 1500: a bead at 0.3-2 mm/s fires few of
# its pixels in 1 ms (cmd_track_auto.h TRACK_SLOW_BEADS_*; docs/tracker.md
# "Windows for slow beads"). Checked: flow at 0.6-1 mm/s (150 ms, seed 1:
# alpha 0.683 at 1 ms, where its faint peaks got the blur, 0.792 by
# default) must gain 0.05; --dt-us or --tau-us given keeps the window; the
# usual flow is untouched (100 ms seed 1 at 1 ms).
# Usage: track_slow_beads.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

simulate_or_skip "$tmp/f" flow 150 1 --param 'motion.speed_mm_per_s=[0.6,1.0]'
track_score "$tmp/f" "$tmp/fa" "$tmp/fa.json"
track_score "$tmp/f" "$tmp/f1" "$tmp/f1.json" --dt-us 1000
a=$(key "$tmp/fa.json" alpha); a1=$(key "$tmp/f1.json" alpha)
echo "flow at 0.6-1 mm/s, 150 ms seed 1: alpha $a1 at 1 ms, $a by default (--dt-us $(key "$tmp/fa/summary.json" dt_us))"
expect_gain "$a1" "$a" 0.05 "slow beads: alpha $a1 -> $a, not 0.05 better"
expect_key dt_us "$tmp/fa/summary.json" 1500
expect_key tau_us "$tmp/fa/summary.json" 1500
expect_key blur_px "$tmp/fa/summary.json" 0
expect_key dt_us "$tmp/f1/summary.json" 1000
"$bin" track --calib "$tmp/f/calib.json" --events "$tmp/f/events.raw" --out "$tmp/ft" -q --tau-us 1000 ||
  { echo "FAIL: track --tau-us"; fail=$((fail+1)); }
expect_key dt_us "$tmp/ft/summary.json" 1000

simulate_or_skip "$tmp/u" flow 100 1
"$bin" track --calib "$tmp/u/calib.json" --events "$tmp/u/events.raw" --out "$tmp/ua" -q ||
  { echo "FAIL: track flow"; fail=$((fail+1)); }
expect_key dt_us "$tmp/ua/summary.json" 1000
expect_key tau_us "$tmp/ua/summary.json" 1000
[ "$fail" -eq 0 ] && echo "track_slow_beads: all checks passed"
exit $([ "$fail" -eq 0 ] && echo 0 || echo 1)
