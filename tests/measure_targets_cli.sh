#!/bin/sh
# scripts/measure_targets.sh, the source of the README's "Against the
# targets" table: each row must be the mean of what `eventlfm score` said
# of the set's recordings (alpha, F1, paired / truth objects), the stage's
# acceleration must be summary.json's, TRACK_ARGS must reach `track`, and
# an unknown set must be refused.
# Usage: measure_targets_cli.sh BINARY
bin=$1
script="$(cd "$(dirname "$0")/.." && pwd)/scripts/measure_targets.sh"
. "$(dirname "$0")/track_lib.sh" # key FILE KEY
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
bad() { echo "FAIL: $*"; fail=$((fail+1)); }

EVENTLFM=$bin OUT=$tmp/o JOBS=2 bash "$script" blink stage_accel > "$tmp/table.md" 2> "$tmp/err.txt" ||
  { bad "measure_targets.sh exited non-zero"; cat "$tmp/err.txt"; }
cat "$tmp/table.md"
[ "$(grep -c '^|' "$tmp/table.md")" -eq 4 ] || bad "not a header, a rule and two rows"

# a field of a row (| a | b | ... : field 1 is a)
field() { grep "^| $1 " "$tmp/table.md" | awk -F'|' -v k="$2" '{ gsub(/^ +| +$/, "", $(k + 1)); print $(k + 1) }'; }

# blink: 4 recordings; the row's alpha and F1 are their means
[ "$(field blink 2)" = 4 ] || bad "blink: $(field blink 2) recordings, not 4"
for k in alpha:3 f1:4; do
  name=${k%:*} col=${k#*:}
  want=$(for s in 1 2 3 4; do key "$tmp/o/blink/s$s/score.json" "$name"; done |
    awk '{ s += $1; n++ } END { if (n == 4) printf "%.3f", s / n }')
  got=$(field blink "$col")
  [ -n "$want" ] && [ "$got" = "$want" ] || bad "blink $name: row '$got', scores' mean '$want'"
done
paired=$(for s in 1 2 3 4; do key "$tmp/o/blink/s$s/score.json" n_paired_tracks; done | awk '{ s += $1 } END { print s }')
truth=$(for s in 1 2 3 4; do key "$tmp/o/blink/s$s/score.json" n_truth_tracks; done | awk '{ s += $1 } END { print s }')
case "$(field blink 8)" in
"$paired / $truth, "*) ;;
*) bad "blink objects '$(field blink 8)', scores $paired / $truth" ;;
esac
# the LED's frames scored as the README says (a frame per pulse)
grep -q '"frame_list":true' "$tmp/o/blink/s1/score.json" || bad "blink not scored with --frames run"

# stage_accel: the acceleration is the run's summary.json's, near the truth
acc=$(field stage_accel 9 | sed -n 's/^fitted acceleration \([0-9.]*\) um.*/\1/p')
sum=$(sed -n 's/.*"acceleration_um_per_ms2":[^,]*, *\([-0-9.eE+]*\),.*/\1/p' "$tmp/o/stage_accel/s1/t/summary.json")
[ -n "$acc" ] && [ -n "$sum" ] || bad "no acceleration (row '$acc', summary '$sum')"
awk -v a="$acc" -v s="$sum" 'BEGIN { exit !(a == sprintf("%.5f", s) && a > 0.0025 * 0.95 && a < 0.0025 * 1.05) }' ||
  bad "acceleration: row $acc, summary $sum, truth 0.0025"

# TRACK_ARGS reaches track
EVENTLFM=$bin OUT=$tmp/g TRACK_ARGS="--gate-um 3.5" bash "$script" stage_accel > "$tmp/g.md" 2>&1 ||
  bad "TRACK_ARGS run exited non-zero"
grep -q '"gate_um":[[:space:]]*3.5' "$tmp/g/stage_accel/s1/t/summary.json" || bad "--gate-um 3.5 not in summary.json"

# an unknown set: refused before anything runs
EVENTLFM=$bin OUT=$tmp/u bash "$script" flow nosuchset > "$tmp/u.txt" 2>&1
rc=$?
[ $rc -eq 2 ] || bad "unknown set: exit $rc, not 2"
grep -q "unknown set 'nosuchset'" "$tmp/u.txt" || bad "unknown set: no message"
[ ! -d "$tmp/u/flow" ] || bad "unknown set: flow ran anyway"

[ $fail -eq 0 ] && echo "measure_targets_cli: all checks passed"
exit $((fail > 0))
