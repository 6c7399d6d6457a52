#!/bin/sh
# The lead on blurred frames: with --blur-px 1 (which track chooses for
# dim beads, "Dim objects") the in-focus peaks are as wide as without it,
# so the lead taken from their widths is the same, but the detections lie
# ~0.3 um further back along the motion; track shortens that lead by 0.3
# um (--motion-blur-lead-um; cmd_track_volume.c track_motion_lead_blur_um;
# docs/tracker.md "The lead on blurred frames"). Checked against the same
# run without it (--motion-blur-lead-um 0, the build before): flow 100 ms
# seed 1 with --blur-px 1 must gain 0.01 of alpha (measured 0.835 ->
# 0.864); summary.json says what was taken off; not on a stage (where the
# shorter lead lost) nor without the blur; bad values are usage errors.
# Usage: track_blur_lead.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

simulate_or_skip "$tmp/f" flow 100 1
track_score "$tmp/f" "$tmp/fb" "$tmp/fb.json" --blur-px 1
track_score "$tmp/f" "$tmp/f0" "$tmp/f0.json" --blur-px 1 --motion-blur-lead-um 0
a=$(key "$tmp/fb.json" alpha); a0=$(key "$tmp/f0.json" alpha)
echo "flow 100 ms seed 1, --blur-px 1: alpha $a0 without the blur's cut, $a with it"
expect_gain "$a0" "$a" 0.01 "flow with the blur: alpha $a0 -> $a, not 0.01 better"
expect_key motion_blur_lead_um "$tmp/fb/summary.json" 0.3
expect_key motion_lead_blur_cut_um "$tmp/fb/summary.json" 0.3
expect_key motion_lead_blur_cut_um "$tmp/f0/summary.json" 0
"$bin" track --calib "$tmp/f/calib.json" --events "$tmp/f/events.raw" --out "$tmp/fn" -q --to-us 40000 ||
  { echo "FAIL: track without the blur"; fail=$((fail+1)); }
expect_key motion_lead_blur_cut_um "$tmp/fn/summary.json" 0
"$bin" track --calib "$tmp/f/calib.json" --events "$tmp/f/events.raw" --out "$tmp/fs" -q --to-us 40000 \
  --blur-px 1 --motion stage || { echo "FAIL: track --motion stage --blur-px 1"; fail=$((fail+1)); }
expect_key motion_lead_blur_cut_um "$tmp/fs/summary.json" 0
expect_usage_errors "--motion-blur-lead-um -1" "--motion-blur-lead-um 11" "--motion-blur-lead-um x"
[ "$fail" -eq 0 ] && echo "track_blur_lead: all checks passed"
exit $([ "$fail" -eq 0 ] && echo 0 || echo 1)
