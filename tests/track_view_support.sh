#!/bin/sh
# The view-support test of `eventlfm track` (a peak needs signal in a
# fraction of the views sampling its voxel) on simulator truth: at a low
# threshold that lets ghosts through, turning it on rejects peaks and raises
# the detection precision without costing more than a little recall; a
# value outside 0..1 is a usage error. Usage: track_view_support.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--view-support 1.5"
simulate_or_skip "$tmp/sim" flow 40 3
run() {  # tag view-support
  track_score "$tmp/sim" "$tmp/$1" "$tmp/$1.json" --threshold-abs 25 --threshold-low 15 --view-support "$2"
}
run off 0
run on 0.3
p0=$(key "$tmp/off.json" precision); p1=$(key "$tmp/on.json" precision)
r0=$(key "$tmp/off.json" recall); r1=$(key "$tmp/on.json" recall)
rej0=$(key "$tmp/off/summary.json" peaks_rejected_view_support)
rej1=$(key "$tmp/on/summary.json" peaks_rejected_view_support)
echo "threshold 25: view support off: precision $p0 recall $r0 (rejected $rej0); 0.3: precision $p1 recall $r1 (rejected $rej1)"
[ "$rej0" = 0 ] || { echo "FAIL: peaks rejected with the test off"; fail=$((fail+1)); }
awk -v a="$rej1" 'BEGIN { exit !(a > 50) }' || { echo "FAIL: the test rejected only $rej1 peaks"; fail=$((fail+1)); }
expect_gain "$p0" "$p1" 0.1 "precision $p0 -> $p1"
expect_gain "$r0" "$r1" -0.05 "recall $r0 -> $r1"
[ $fail -eq 0 ] && echo "1 passed, 0 failed" || echo "0 passed, $fail failed"
exit $fail
