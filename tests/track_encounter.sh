#!/bin/sh
# The encounter review (elfm_link.h step 7; `eventlfm track --encounter-um`,
# default 5): flow 100 ms seed 7, beads 14 and 17 at frame 54 pass 3 um
# apart laterally and 10 um in z, inside the axial blur. The view fit finds
# bead 17 twice, both tracks take a point there without a gap (so the swap
# review of gap closings never sees it) and the next frame each leaves on
# the other's bead. The review joins each track's head to the tail it fits:
# alpha 0.759 -> 0.804 when it came. This test asks for a gain of at least
# 0.03, that summary.json records the setting, and that bad values are
# usage errors.
# Usage: track_encounter.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--encounter-um -1" "--encounter-um x" "--encounter-ratio 0" \
  "--encounter-ratio 1.5" "--encounter-pad -1"
simulate_or_skip "$tmp/flow" flow 100 7
track_score "$tmp/flow" "$tmp/off" "$tmp/off.json" --encounter-um 0
track_score "$tmp/flow" "$tmp/on" "$tmp/on.json"
a0=$(key "$tmp/off.json" alpha); a1=$(key "$tmp/on.json" alpha)
echo "flow seed 7: alpha $a0 without the encounter review, $a1 with it"
expect_gain "$a0" "$a1" 0.03 "the encounter review gains < 0.03 alpha ($a0 -> $a1)"
[ "$(key "$tmp/on/summary.json" encounter_um)" = 5 ] ||
  { echo "FAIL: encounter_um not 5 in summary.json"; fail=$((fail+1)); }
[ $fail -eq 0 ] && echo "track_encounter: all passed" || echo "track_encounter: $fail failed"
[ $fail -eq 0 ]
