#!/bin/sh
# The motion bias along the fitted path (`eventlfm track --motion-along-path`,
# default on; elfm_smooth.h motion_along_path): each view's lead taken along
# the motion a delay before the frame, and the way back along the path.
#  - flow_random 100 ms seed 1 (beads turning at 1-2 um/ms^2 where they
#    slow down): alpha at least 0.005 above --motion-along-path off
#    (0.7847 -> 0.7930 when it came; seeds 1-30 +0.0071 +- 0.0002, every
#    one up, docs/tracker.md "The lead along the path");
#  - summary.json says true, and false when turned off;
#  - a value other than on or off is a usage error.
# Usage: track_along_path.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--motion-along-path 1" "--motion-along-path yes"
simulate_or_skip "$tmp/r" flow_random 100 1
track_score "$tmp/r" "$tmp/off" "$tmp/off.json" --motion-along-path off
track_score "$tmp/r" "$tmp/on" "$tmp/on.json"
a0=$(key "$tmp/off.json" alpha); a1=$(key "$tmp/on.json" alpha)
echo "flow_random seed 1: alpha $a0 with the lead along the present motion, $a1 along the path"
expect_gain "$a0" "$a1" 0.005 "the lead along the path gains < 0.005 alpha ($a0 -> $a1)"
[ "$(key "$tmp/on/summary.json" motion_along_path)" = true ] ||
  { echo "FAIL: motion_along_path not true in summary.json"; fail=$((fail+1)); }
[ "$(key "$tmp/off/summary.json" motion_along_path)" = false ] ||
  { echo "FAIL: motion_along_path not false with --motion-along-path off"; fail=$((fail+1)); }
[ $fail -eq 0 ] && echo "track_along_path: all passed" || echo "track_along_path: $fail failed"
[ $fail -eq 0 ]
