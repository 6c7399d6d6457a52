#!/bin/sh
# Twins at a track's end in `eventlfm track` (tracker/link_repair.c, step 8;
# docs/tracker.md "Twins at a track's end"), on simulator truth, flow seed 1,
# the first 450 ms: bead 10's track (22) loses the bead at frame 355 while a
# second track (34), born at 311 and walked back to 295 by the gap filling,
# holds it; at frame 407 track 22 would end, and by default goes on as 34:
#  - alpha above --twin-um 0 (0.8411 -> 0.8500 when it came), one track
#    fewer, and summary.json counts the join and records the settings;
#  - out-of-range values are usage errors.
# Usage: track_twins.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--twin-um -1" "--twin-um x" "--twin-points 0" "--twin-points 1001" \
                    "--twin-points x"

simulate_or_skip "$tmp/flow" flow 450 1
track_score "$tmp/flow" "$tmp/off" "$tmp/off.json" --twin-um 0
track_score "$tmp/flow" "$tmp/def" "$tmp/def.json"
a0=$(key "$tmp/off.json" alpha); a1=$(key "$tmp/def.json" alpha)
j0=$(key "$tmp/off/summary.json" tracks_joined_twins); j1=$(key "$tmp/def/summary.json" tracks_joined_twins)
n0=$(key "$tmp/off/summary.json" tracks); n1=$(key "$tmp/def/summary.json" tracks)
echo "flow seed 1, 450 ms: alpha $a0 -> $a1, twins joined $j0 -> $j1, tracks $n0 -> $n1"
expect_gain "$a0" "$a1" 0.004 "alpha gain < 0.004"
[ "$j0" = 0 ] && [ "${j1:-0}" -ge 1 ] || { echo "FAIL: tracks_joined_twins $j0 / $j1"; fail=$((fail+1)); }
[ -n "$n0" ] && [ -n "$n1" ] && [ "$n1" -lt "$n0" ] || { echo "FAIL: tracks $n0 -> $n1"; fail=$((fail+1)); }
expect_key twin_um "$tmp/def/summary.json" 2
expect_key twin_points "$tmp/def/summary.json" 5
expect_key twin_um "$tmp/off/summary.json" 0
[ $fail -eq 0 ] && echo "track_twins: all passed" || echo "track_twins: $fail failed"
[ $fail -eq 0 ]
