#!/bin/sh
# The lead of fast flows: a recording whose beads all move fast leads less
# than its in-focus peaks' widths say, and track shortens the widths' lead
# by 0.13 um per um/ms of the speed it judged on the first peaks above 4.5
# um/ms (--motion-fast-lead-ms, --motion-fast-um-per-ms; cmd_track_volume.c
# track_motion_lead_fast_um; docs/tracker.md "The lead of fast flows").
# Checked against the same run without it (--motion-fast-lead-ms 0, the
# build before): flow at 7-8 mm/s, 100 ms seed 1 (alpha 0.788 -> 0.869
# measured) must gain 0.03 and say in summary.json what it took off; the
# built-in flow (2.5-4 mm/s, judged below 4.5 um/ms) must be left alone,
# and so must a run that judged nothing (window, surface and blur given).
# Usage: track_fast_lead.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

simulate_or_skip "$tmp/f" flow 100 1 --param 'motion.speed_mm_per_s=[7,8]'
track_score "$tmp/f" "$tmp/fa" "$tmp/fa.json"
track_score "$tmp/f" "$tmp/f0" "$tmp/f0.json" --motion-fast-lead-ms 0
a=$(key "$tmp/fa.json" alpha); a0=$(key "$tmp/f0.json" alpha)
cut=$(key "$tmp/fa/summary.json" motion_lead_fast_cut_um)
echo "flow at 7-8 mm/s, 100 ms seed 1: alpha $a0 without the fast lead, $a with it (lead $cut um shorter)"
expect_gain "$a0" "$a" 0.03 "flow 7-8 mm/s: alpha $a0 -> $a, not 0.03 better"
expect_key motion_fast_lead_ms "$tmp/fa/summary.json" 0.13
expect_key motion_fast_um_per_ms "$tmp/fa/summary.json" 4.5
below 0.1 1 "$cut" || { echo "FAIL: the lead taken off ($cut um) is not above 0.1 um"; fail=$((fail+1)); }
expect_key motion_lead_fast_cut_um "$tmp/f0/summary.json" 0

simulate_or_skip "$tmp/n" flow 100 2
"$bin" track --calib "$tmp/n/calib.json" --events "$tmp/n/events.raw" --out "$tmp/na" -q ||
  { echo "FAIL: track (flow seed 2)"; fail=$((fail+1)); }
expect_key motion_lead_fast_cut_um "$tmp/na/summary.json" 0
# nothing judged: no speed to go by
"$bin" track --calib "$tmp/f/calib.json" --events "$tmp/f/events.raw" --out "$tmp/fg" -q \
  --dt-us 500 --repr exp --blur-px 0 || { echo "FAIL: track (all given)"; fail=$((fail+1)); }
expect_key motion_lead_fast_cut_um "$tmp/fg/summary.json" 0
expect_usage_errors "--motion-fast-lead-ms -1" "--motion-fast-lead-ms 11" "--motion-fast-um-per-ms x" \
  "--motion-fast-um-per-ms 101"
[ "$fail" -eq 0 ] && echo "track_fast_lead: all checks passed"
exit $([ "$fail" -eq 0 ] && echo 0 || echo 1)
