#!/bin/sh
# The encounter review (elfm_link.h step 7; `eventlfm track --encounter-um`,
# default 5): flow 100 ms seed 7, beads 14 and 17 at frame 54 pass 3 um
# apart laterally and 10 um in z, inside the axial blur. The view fit finds
# bead 17 twice, both tracks take a point there without a gap (so the swap
# review of gap closings never sees it) and the next frame each leaves on
# the other's bead. The review joins each track's head to the tail it fits:
# alpha 0.759 -> 0.804 when it came. This test asks for a gain of at least
# 0.03, that summary.json records the setting, and that bad values are
# usage errors. Since the next frame's circle (--circle-next-path-um,
# thirty-sixth session) the two tracks keep their beads through that
# crossing without the review (0.850 either way); the test runs without the
# next frame's circle, which keeps the case.
# The reviews' join limit (--review-join-factor, default 2 x the gate):
# on flow seed 23 (held out when it was chosen) the reviews without it
# exchanged a 28-frame gap closing on joins 20 um off (RMS) and an
# encounter on joins 100 um off; with the limit both are left as linked:
# alpha 0.751 -> 0.773 when it came. Asked: a gain of 0.01. Since the
# circle fit (--circle-points 15) that gap is closed on the right bead and
# the limit has nothing left to refuse there (0.830 either way); the test
# runs without the circle, which keeps the case. Since the ghost test of
# bright peaks (--explain-brighter, twenty-fifth session) the encounter is
# not reached either (0.7805 either way), so it runs without that too;
# over flow seeds 1-20 with both the limit still gains: 0.8490 -> 0.8505.
# Since the fits beside a gap's prediction (--fill-retry-um, thirty-eighth
# session) seed 23's tracks meet neither case (0.8065 -> 0.8072); without
# them the case stands as before.
# Since the neighbours' light is taken out of the view fits on time
# surfaces too (--localize-near-um 12, fortieth session), neither seed 7's
# nor seed 23's tracks reach their case (0.866 / 0.825 either way); both
# run without it (0), which keeps them. Over flow 100 ms seeds 1-20 at the
# new defaults the review and the limit still gain: --encounter-um 0 /
# --review-join-factor 0 0.8765 / 0.8759 against 0.8786.
# Forty-second session: the simulator's events no longer lag by half a time
# step (docs/simulator.md "Time steps"), which changed every scene's events;
# both cases are gone (seed 7: 0.785 either way with the options above;
# seed 23: 0.788 either way). Over flow 100 ms seeds 1-40 with the same
# options, the clearest cases now need none of them, so both run at the
# defaults. The review: seed 12, beads 2 and 19 pass 3 um apart laterally
# and 6.5 um in z at frame 19, beads 1 and 10 0.5 um and 5 um at frame 61;
# without the review each pair's tracks leave on the other's bead, with it
# all four keep theirs: alpha 0.8394 -> 0.8960. The limit: seed 27, where
# the reviews without it passed the tracks of beads 18, 10 and 15 among
# each other (frames 25, 39, 71) on joins 10-24 um off; with the limit the
# three keep their beads: alpha 0.8644 -> 0.9203. Over seeds 1-20 at the
# defaults: --encounter-um 0 / --review-join-factor 0 0.8739 / 0.8735
# against 0.8782.
# Straight lines at rest (--encounter-line-ratio, default 0.5): worm 500 ms
# seed 1 (--repr integral), neurons 2 and 6 crossing 10 um apart in z and
# 0.3 um laterally merge for ~30 frames, and neurons 1 and 5 later; the
# 8-point quadratic junctions decided neither, the 20-point lines both
# (and the first stays exchanged now that the same pair's nested encounters
# are not reviewed again): alpha 0.847 -> 0.913 when it came. Asked: a
# gain of 0.03.
# Frames apart within an encounter (--encounter-apart, default 4): worm
# 200 ms seed 5 at 500 Hz (--repr integral), neurons 4 and 5 at z -57 um,
# whose images merge: their fits met at frames 9-11, parted for two frames
# and crossed at 14-17. Reviewed as one encounter, the crossing is undone
# (and two other pairs' swaps): alpha 0.786 -> 0.828 when it came. Asked:
# a gain of 0.02. Since then the integral's defaults changed (bright levels
# leak more slowly, threshold 25, lead -0.05 um) and seed 5's pairs no
# longer cross; the test runs with the settings of the time (one leak,
# threshold 20, lead 0.1 um), which keep the case (0.785 -> 0.826).
# Pair fits (--pair-fit-um, fifty-fourth session) split the merged peaks
# of seed 12 and of both worm cases, and the cases change: seed 12 0.884
# without the review and 0.903 with it; worm seed 5 0.923 either way (0.925
# with the review before); worm seed 1 0.919 -> 0.939 (0.920 before). Those
# three run without the pair fits, which keeps the cases.
# Usage: track_encounter.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--encounter-um -1" "--encounter-um x" "--encounter-ratio 0" \
  "--encounter-ratio 1.5" "--encounter-pad -1" "--review-join-factor -1" "--encounter-apart -1" \
  "--encounter-apart x" "--encounter-circle-ratio -0.1" "--encounter-circle-ratio 1.5" \
  "--encounter-circle-ratio x" "--encounter-line-ratio -0.1" "--encounter-line-ratio 1.5" \
  "--encounter-line-ratio x"
# compare SEED OFF_OPTIONS MIN WHAT KEY VALUE: flow 100 ms seed SEED tracked
# with OFF_OPTIONS and with the defaults; the defaults must gain more than
# MIN alpha, and summary.json must record KEY = VALUE.
# SCENE (flow 100 ms unless set; worm 200 ms), MS (the length) and
# TRACK_ARGS (both runs) may be given.
compare() {
  sc=${SCENE:-flow}; ms=100; [ "$sc" = worm ] && ms=200; ms=${MS:-$ms}
  simulate_or_skip "$tmp/f$1" "$sc" $ms "$1"
  # shellcheck disable=SC2086
  track_score "$tmp/f$1" "$tmp/off$1" "$tmp/off$1.json" ${TRACK_ARGS:-} $2
  # shellcheck disable=SC2086
  track_score "$tmp/f$1" "$tmp/on$1" "$tmp/on$1.json" ${TRACK_ARGS:-}
  c0=$(key "$tmp/off$1.json" alpha); c1=$(key "$tmp/on$1.json" alpha)
  echo "$sc seed $1: alpha $c0 without $4, $c1 with it"
  expect_gain "$c0" "$c1" "$3" "$4 gains < $3 alpha ($c0 -> $c1)"
  [ "$(key "$tmp/on$1/summary.json" "$5")" = "$6" ] ||
    { echo "FAIL: $5 not $6 in summary.json"; fail=$((fail+1)); }
}
compare 27 "--review-join-factor 0" 0.01 "the join limit" review_join_factor 2
# (TRACK_ARGS set before a function call may stay set in some shells: the
# cases with options come last, each setting its own)
TRACK_ARGS="--pair-fit-um 0" compare 12 "--encounter-um 0" 0.03 "the encounter review" encounter_um 5
# (on the calibration's planes, where this case was found)
SCENE=worm TRACK_ARGS="--dt-us 2000 --repr integral --tau-bright-us 100000 --threshold-abs 20 --motion-lead-um 0.1 --plane-shift-px 0 --pair-fit-um 0" \
  compare 5 "--encounter-apart 0" 0.02 "frames apart within an encounter" encounter_apart 4
SCENE=worm MS=500 TRACK_ARGS="--dt-us 2000 --repr integral --pair-fit-um 0" \
  compare 1 "--encounter-line-ratio 0" 0.03 "straight lines at rest" encounter_line_ratio 0.5
[ $fail -eq 0 ] && echo "track_encounter: all passed" || echo "track_encounter: $fail failed"
[ $fail -eq 0 ]
