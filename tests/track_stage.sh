#!/bin/sh
# --motion stage without --stage-velocity-um-per-ms: the microscopist who
# checks the stage's speed does not tell the tracker what it is. A track
# that does not move with the stage (a hot pixel's or noise's track at
# rest, a ghost's joined across gaps) biased the tracks' velocity, the
# SPEC's stage error; with a known velocity such tracks were always dropped.
# Now the tracks themselves give the velocity: finished tracks wait until 5
# of 20 points or more agree, then each is tested against the weighted
# median of the newest 32 long ones' (along the stage at 1/4 to 4x its
# speed, across it within 25 % + 0.1 um/ms). Dim stage (0.3 of the flux,
# 200 ms) seeds 1-3: stage error 0.72 / 1.53 / 0.39 % -> 0.21 / 0.38 / 0.39 %
# (0.21 / 0.38 / 0.26 with the velocity given); the usual stage, seeds
# 1-11: mean 0.17 -> 0.14 %, max 0.43 -> 0.23 %; stage_accel unchanged
# (docs/tracker.md "The stage's velocity from its tracks").
# A stage whose beads lie 20-90 um from focus (seed 11): fewer than 50
# peaks within 20 um of focus gave the lead no width, and it stayed at the
# flow beads' 1.25 um against these brighter beads' ~1.8 (alpha 0.710); the
# peaks within 40 um give it now (alpha 0.800).
# Checked: the dim stage seed 3 drops a track that does not move with the
# stage and is within 1 %; an accelerating stage (0.1 -> 0.6 um/ms in 200
# ms), whose tracks differ 2x in mean speed, loses none.
# Forty-second session: the simulator's events no longer lag by half a
# time step (docs/simulator.md "Time steps"), which changed every scene's
# events, and with a stage the linker predicts dark tracks straight at the
# tracks' common velocity (elfm_link.h straight_gaps). Seed 2 was the case
# (its track running against the stage dropped); it now has no track off
# the stage (stage error 0.50 %). Now seed 3: 1 track dropped (a bead 83
# um deep at the field's edge, x 56 um, whose detections in frames 49-56
# drift across the stage, about -0.6 um/ms in x and -0.7 in z), stage
# error 0.25 % (0.25 % with the velocity given), summary speed 2.494,
# pooled vy 2.498 um/ms. Dim stage seeds 1-40: 10 drop 1-2 tracks; all
# are within 0.65 %. Seed 11 now: 0 peaks within 20 um of focus, 119
# within 40 um, lead 1.82 um, alpha 0.863.
# Usage: track_stage.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
simulate_or_skip "$tmp/dim" stage 200 3 --param 'objects.flux_hz=[8000,10000]'
score_args="--stage-velocity-um-per-ms 0,2.5,0"
track_score "$tmp/dim" "$tmp/d" "$tmp/d.json" --motion stage
n=$(key "$tmp/d/summary.json" tracks_rejected_off_stage)
e=$(key "$tmp/d.json" stage_velocity_rel_error)
echo "dim stage 200 ms seed 3: $n track(s) off the stage, stage error $e"
[ -n "$n" ] && [ "$n" -ge 1 ] || { echo "FAIL: no track off the stage ('$n')"; fail=$((fail+1)); }
[ -n "$e" ] && below "$e" 1 0.01 || { echo "FAIL: stage error '$e' not below 1 %"; fail=$((fail+1)); }
# the summary's velocity is the kept tracks' own
sp=$(key "$tmp/d/summary.json" speed_um_per_ms)
awk -v v="$sp" 'BEGIN { exit !(v > 2.475 && v < 2.525) }' || { echo "FAIL: summary speed '$sp' not within 1 % of 2.5"; fail=$((fail+1)); }
# and the pooled velocity (each track by the spread of its times over its
# points' scatter), in y
py=$(tr -d ' \n\t' < "$tmp/d/summary.json" | sed -n 's/.*"velocity_pooled_um_per_ms":\[\([^]]*\)\].*/\1/p' | cut -d, -f2)
echo "dim stage 200 ms seed 3: pooled vy $py um/ms"
awk -v v="$py" 'BEGIN { exit !(v > 2.475 && v < 2.525) }' || { echo "FAIL: pooled vy '$py' not within 1 % of 2.5"; fail=$((fail+1)); }
# the spreads: the sample standard deviations of the listed tracks' mean
# velocities (per axis) and speeds, recomputed here from the summary's
# own "tracks" (a speed_sd written as the speed passed every test until a
# mutation sweep)
flat=$(tr -d ' \n\t' < "$tmp/d/summary.json")
want=$(echo "$flat" | grep -o '"mean_velocity_um_per_ms":\[[^]]*\]' | sed 's/.*\[//; s/\]//' |
  awk -F, '$1 != "null" { n++; s = sqrt($1*$1 + $2*$2 + $3*$3); sp += s; sp2 += s*s
             for (a = 1; a <= 3; a++) { u[a] += $a; q[a] += $a*$a } }
           END { m = sp / n; printf "%.6e", sqrt((sp2 - n*m*m) / (n - 1))
                 for (a = 1; a <= 3; a++) { mu = u[a] / n; printf " %.6e", sqrt((q[a] - n*mu*mu) / (n - 1)) } }')
got="$(printf '%.6e' "$(key "$tmp/d/summary.json" speed_sd_um_per_ms)") $(echo "$flat" |
  sed -n 's/.*"velocity_sd_um_per_ms":\[\([^]]*\)\].*/\1/p' | awk -F, '{ printf "%.6e %.6e %.6e", $1, $2, $3 }')"
echo "dim stage 200 ms seed 3: speed and velocity sd $got"
[ -n "$want" ] && [ "$got" = "$want" ] || { echo "FAIL: summary's speed, velocity sd '$got', from its tracks '$want'"; fail=$((fail+1)); }

# The velocity given: a track is off when its mean velocity lies more than
# 25 % of the stage's speed + 0.1 um/ms from it. Seed 3's drifting track
# (about 0.9 um/ms off) is dropped, and the stage error stays within 1 %
# (a rule loosened to 250 % kept it and passed every test until a
# mutation sweep).
track_score "$tmp/dim" "$tmp/dv" "$tmp/dv.json" --motion stage --stage-velocity-um-per-ms 0,2.5,0
n=$(key "$tmp/dv/summary.json" tracks_rejected_off_stage)
e=$(key "$tmp/dv.json" stage_velocity_rel_error)
echo "dim stage 200 ms seed 3, velocity given: $n track(s) off the stage, stage error $e"
[ -n "$n" ] && [ "$n" -ge 1 ] || { echo "FAIL: velocity given: no track off the stage ('$n')"; fail=$((fail+1)); }
[ -n "$e" ] && below "$e" 1 0.01 || { echo "FAIL: velocity given: stage error '$e' not below 1 %"; fail=$((fail+1)); }

simulate_or_skip "$tmp/acc" stage_accel 200 1
"$bin" track --calib "$tmp/acc/calib.json" --events "$tmp/acc/events.raw" --out "$tmp/a" --motion stage \
  2> "$tmp/a.err" || { echo "FAIL: track stage_accel"; fail=$((fail+1)); }
expect_key tracks_rejected_off_stage "$tmp/a/summary.json" 0
# the stage's velocity said at the end (the pooled one, as in summary.json)
line=$(tr '\r' '\n' < "$tmp/a.err" | grep "the stage moves at")
echo "stage_accel: $line"
[ -n "$line" ] || { echo "FAIL: no stage velocity on stderr"; fail=$((fail+1)); }
case "$line" in *"accelerating at"*) ;; *) echo "FAIL: stage_accel's acceleration not said"; fail=$((fail+1)) ;; esac
px=$(tr -d ' \n\t' < "$tmp/a/summary.json" | sed -n 's/.*"velocity_pooled_um_per_ms":\[\([^]]*\)\].*/\1/p' | cut -d, -f2)
case "$line" in *"$(printf '%.4f' "$px"),"*) ;; *) echo "FAIL: stderr's vy is not summary.json's $px"; fail=$((fail+1)) ;; esac
# the acceleration's spread (over the long tracks' own slopes, which the
# summary does not list; test_analysis bounds it on its own tracks) is a spread,
# not the acceleration again
flat=$(tr -d ' \n\t' < "$tmp/a/summary.json")
acc=$(echo "$flat" | sed -n 's/.*"acceleration_um_per_ms2":\[\([^]]*\)\].*/\1/p')
asd=$(echo "$flat" | sed -n 's/.*"acceleration_sd_um_per_ms2":\[\([^]]*\)\].*/\1/p')
echo "stage_accel: acceleration $acc, sd $asd um/ms^2"
[ -n "$asd" ] && [ "$asd" != "$acc" ] && echo "$asd" | awk -F, '{ exit !($1 >= 0 && $2 >= 0 && $3 >= 0 && $2 < 0.002) }' ||
  { echo "FAIL: stage_accel's acceleration sd '$asd' (acceleration '$acc')"; fail=$((fail+1)); }
simulate_or_skip "$tmp/s11" stage 200 11
score_args=""
track_score "$tmp/s11" "$tmp/s11o" "$tmp/s11.json"
nf=$(key "$tmp/s11o/summary.json" peak_widths_in_focus); nn=$(key "$tmp/s11o/summary.json" peak_widths_near_focus)
ld=$(key "$tmp/s11o/summary.json" motion_lead_um); a=$(key "$tmp/s11.json" alpha)
echo "stage 200 ms seed 11: $nf peaks within 20 um of focus, $nn within 40 um; lead $ld um, alpha $a"
[ -n "$nf" ] && [ "$nf" -lt 50 ] || { echo "FAIL: seed 11 has $nf in-focus peaks (the case needs < 50)"; fail=$((fail+1)); }
awk -v l="$ld" 'BEGIN { exit !(l > 1.5 && l < 2.1) }' || { echo "FAIL: lead '$ld' is not the width's"; fail=$((fail+1)); }
expect_gain 0.77 "$a" 0 "stage seed 11 alpha $a <= 0.77"
[ $fail -eq 0 ] && echo "1 passed, 0 failed" || echo "0 passed, $fail failed"
exit $fail
