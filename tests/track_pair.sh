#!/bin/sh
# Pair fits (`eventlfm track --pair-fit-um D`, default 4; cmd_track_guided.c):
# where two established tracks predict their beads within D um laterally and
# one detection alone lies within the weak gate of either, and half the
# views or more see their images 3 px apart or more, each bead is
# fitted from its own track's prediction with the other's light taken out
# of the views, and the two fits replace the merged detection. The case:
# flow 100 ms seed 6, beads 1 and 6 pass within 0.6-1.3 um laterally at
# frames 77-80, 13-33 um apart in z (bead 1 at -55 to -65 um). Their images
# merge into one peak of the volume, but not in the outer views. Without
# the pair fits the two tracks exchange the beads at frames 80-81 (alpha
# 0.8835); with them each keeps its bead (0.9111). The test asks for a gain
# of 0.015, for pair fits counted in summary.json and none with the option
# at 0, for the setting recorded, and for bad values to be usage errors.
# The views' test: worm 150 ms seed 5 at 500 Hz (track_integral.sh's
# worm), whose neuron pairs meet at one depth, where no view parts their
# images. Splitting every merged peak there gave alpha 0.925 -> 0.862; with
# the test 0.920. Asked: within 0.01 of the run without pair fits.
# Every run here is without the deep window (--deep-window-us 0), where the
# case was measured; docs/tracker.md "A longer window for deep beads" gives
# its figures with it.
# And without the guided fits' distance from other detections
# (--guided-apart-um 0, fifty-eighth session): with that rule the seed
# gives 0.879 without the pair fits and 0.887 with them, because at frame
# 74 it drops bead 1's guided fit beside bead 1's own peak, which no other
# track expected. With the deep window (the default) the seed gives 0.887
# with the rule and without it (docs/tracker.md "A guided fit on
# another's bead").
# Usage: track_pair.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--pair-fit-um -1" "--pair-fit-um x" "--pair-fit-um 101" "--pair-fit-um nan"
simulate_or_skip "$tmp/f" flow 100 6
track_score "$tmp/f" "$tmp/off" "$tmp/off.json" --pair-fit-um 0 --deep-window-us 0 --guided-apart-um 0
track_score "$tmp/f" "$tmp/on" "$tmp/on.json" --deep-window-us 0 --guided-apart-um 0
a0=$(key "$tmp/off.json" alpha); a1=$(key "$tmp/on.json" alpha)
echo "flow seed 6: alpha $a0 without the pair fits, $a1 with them"
expect_gain "$a0" "$a1" 0.015 "the pair fits gain < 0.015 alpha ($a0 -> $a1)"
expect_key pair_fit_um "$tmp/on/summary.json" 4
expect_key pair_fit_um "$tmp/off/summary.json" 0
expect_key pair_fits "$tmp/off/summary.json" 0
n=$(key "$tmp/on/summary.json" pair_fits)
awk -v n="$n" 'BEGIN { exit !(n > 0) }' || { echo "FAIL: pair_fits '$n' in summary.json"; fail=$((fail+1)); }
simulate_or_skip "$tmp/w" worm 150 5
track_score "$tmp/w" "$tmp/w0" "$tmp/w0.json" --dt-us 2000 --pair-fit-um 0 --deep-window-us 0
track_score "$tmp/w" "$tmp/w1" "$tmp/w1.json" --dt-us 2000 --deep-window-us 0
w0=$(key "$tmp/w0.json" alpha); w1=$(key "$tmp/w1.json" alpha)
echo "worm seed 5: alpha $w0 without the pair fits, $w1 with them"
expect_gain "$w0" "$w1" -0.01 "the pair fits cost the worm > 0.01 alpha ($w0 -> $w1)"
[ $fail -eq 0 ] && echo "track_pair: all passed" || echo "track_pair: $fail failed"
[ $fail -eq 0 ]
