#!/bin/sh
# The lead of slow beads: on the ON time surface a slow bead's detections
# lie further ahead of it than the lead - delay x speed line (fitted at
# 2.5-5 um/ms) says; track adds 0.17 ms x (3 um/ms - speed) of lead below 3
# um/ms (elfm_smooth.h motion_slow_lead_ms; docs/tracker.md "The lead of
# slow beads"). Checked against the same run without it
# (--motion-slow-lead-ms 0), which is the build before: beads in a flow at
# 0.6-1 mm/s (150 ms, seed 3: alpha 0.689 -> 0.718) and a stage at 1 mm/s
# (200 ms, seed 1: 0.812 -> 0.867; at 1 ms, --dt-us 1000, as a stage this
# slow gets 2.5 ms windows by default, track_stage_slow.sh) must each gain
# 0.01 of alpha. A lead
# given (eventlfm score's regression on a scene like the sample) turns the
# bend off; the options' ranges are checked.
# Usage: track_slow_lead.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

simulate_or_skip "$tmp/f" flow 150 3 --param 'motion.speed_mm_per_s=[0.6,1.0]'
track_score "$tmp/f" "$tmp/fa" "$tmp/fa.json"
track_score "$tmp/f" "$tmp/f0" "$tmp/f0.json" --motion-slow-lead-ms 0
a=$(key "$tmp/fa.json" alpha); a0=$(key "$tmp/f0.json" alpha)
echo "flow at 0.6-1 mm/s, 150 ms seed 3: alpha $a0 without the slow lead, $a with it"
expect_gain "$a0" "$a" 0.01 "flow 0.6-1 mm/s: alpha $a0 -> $a, not 0.01 better"
expect_key motion_slow_lead_ms "$tmp/fa/summary.json" 0.17
expect_key motion_slow_um_per_ms "$tmp/fa/summary.json" 3

simulate_or_skip "$tmp/s" stage 200 1 --param motion.v0_mm_per_s=1 --param motion.v1_mm_per_s=1
track_score "$tmp/s" "$tmp/sa" "$tmp/sa.json" --dt-us 1000
track_score "$tmp/s" "$tmp/s0" "$tmp/s0.json" --dt-us 1000 --motion-slow-lead-ms 0
a=$(key "$tmp/sa.json" alpha); a0=$(key "$tmp/s0.json" alpha)
echo "stage at 1 mm/s, 200 ms seed 1: alpha $a0 without the slow lead, $a with it"
expect_gain "$a0" "$a" 0.01 "stage 1 mm/s: alpha $a0 -> $a, not 0.01 better"

# a lead given stands for the whole line: no bend unless given too
"$bin" track --calib "$tmp/f/calib.json" --events "$tmp/f/events.raw" --out "$tmp/fl" -q \
  --motion-lead-um 1.8 --motion-delay-us 600 || { echo "FAIL: track --motion-lead-um"; fail=$((fail+1)); }
expect_key motion_slow_lead_ms "$tmp/fl/summary.json" 0
"$bin" track --calib "$tmp/f/calib.json" --events "$tmp/f/events.raw" --out "$tmp/fm" -q \
  --motion-lead-um 1.8 --motion-slow-lead-ms 0.2 --motion-slow-um-per-ms 2 ||
  { echo "FAIL: track --motion-slow-lead-ms"; fail=$((fail+1)); }
expect_key motion_slow_lead_ms "$tmp/fm/summary.json" 0.2
expect_key motion_slow_um_per_ms "$tmp/fm/summary.json" 2
expect_usage_errors "--motion-slow-lead-ms -1" "--motion-slow-lead-ms 11" "--motion-slow-um-per-ms x" \
  "--motion-slow-um-per-ms 101"
[ "$fail" -eq 0 ] && echo "track_slow_lead: all checks passed"
exit $([ "$fail" -eq 0 ] && echo 0 || echo 1)
