#!/bin/sh
# Beads that turn beyond prediction (`eventlfm simulate flow_random`, seed
# 33, 100 ms; no setting was chosen on it): each path a sum of sinusoids
# with periods of 8-30 ms, so a 1 ms step leaves the linker's prediction by
# ~2-3 um where the helical `flow` leaves it by ~1-1.5 um
# (elfm_link_last_miss_um). `eventlfm track` judges the first peaks'
# tracks, says so, and starts again with the same 1 ms windows twice as
# often (--stride-us 500): the same outputs as --stride-us 500 given, and
# alpha at least 0.05 above --stride-us 1000 given (0.557 -> 0.651 when it
# came). The helical flow keeps its rate and says nothing.
# docs/tracker.md "Frames twice as often for turning beads".
# Every run here is without the deep window (--deep-window-us 0), where the
# case was measured; docs/tracker.md "A longer window for deep beads" gives
# its figures with it.
# Usage: track_turning.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
simulate_or_skip "$tmp/fr" flow_random 100 33
"$bin" track --calib "$tmp/fr/calib.json" --events "$tmp/fr/events.raw" --out "$tmp/a" --deep-window-us 0 \
  >/dev/null 2>"$tmp/a.err" || { echo "FAIL: track on the random flow"; fail=$((fail+1)); }
n_again=$(grep -c "the tracks turn beyond prediction ([0-9]* detections lay a median [0-9.]* um from where their tracks predicted them): starting again with --stride-us 500" "$tmp/a.err")
[ "$n_again" = 1 ] || { echo "FAIL: the rate's restart said $n_again times: $(tail -c 400 "$tmp/a.err")"; fail=$((fail+1)); }
expect_key stride_us "$tmp/a/summary.json" 500
expect_key dt_us "$tmp/a/summary.json" 1000
miss=$(key "$tmp/a/summary.json" auto_prediction_miss_um)
at_least "$miss" 1.8 || { echo "FAIL: judged miss '$miss' below 1.8 um"; fail=$((fail+1)); }
track_score "$tmp/fr" "$tmp/g" "$tmp/g.json" --stride-us 500 --deep-window-us 0
for f in tracks.csv detections.csv frames.csv; do
  cmp -s "$tmp/a/$f" "$tmp/g/$f" || { echo "FAIL: auto's $f differs from --stride-us 500's"; fail=$((fail+1)); }
done
track_score "$tmp/fr" "$tmp/k" "$tmp/k.json" --stride-us 1000 --deep-window-us 0
expect_key stride_us "$tmp/k/summary.json" 1000
a1=$(key "$tmp/k.json" alpha); a2=$(key "$tmp/g.json" alpha)
echo "random flow: alpha $a1 at 1 ms frames, $a2 at the automatic 0.5 ms stride (judged miss $miss um)"
expect_gain "$a1" "$a2" 0.05 "the stride of 0.5 ms gains < 0.05 alpha ($a1 -> $a2)"

simulate_or_skip "$tmp/flow" flow 60 1
"$bin" track --calib "$tmp/flow/calib.json" --events "$tmp/flow/events.raw" --out "$tmp/d" --deep-window-us 0 \
  >/dev/null 2>"$tmp/d.err" || { echo "FAIL: track on the default flow"; fail=$((fail+1)); }
grep -q "starting again" "$tmp/d.err" && { echo "FAIL: the helical flow started again: $(tail -c 300 "$tmp/d.err")"; fail=$((fail+1)); }
expect_key stride_us "$tmp/d/summary.json" 1000
dm=$(key "$tmp/d/summary.json" auto_prediction_miss_um)
[ -n "$dm" ] && below "$dm" 1 1.8 || { echo "FAIL: the helical flow's judged miss '$dm' not below 1.8 um"; fail=$((fail+1)); }

[ $fail -eq 0 ] && echo "track_turning: all passed" || echo "track_turning: $fail failed"
[ $fail -eq 0 ]
