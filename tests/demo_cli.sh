#!/bin/sh
# The README's main command, `eventlfm demo`: it simulates, tracks and
# scores, and its table must say what `eventlfm score` says of the same
# files (alpha; recall within 20 um of focus from --by-depth), with the
# depth line that shows where out of focus the run can be trusted.
# Usage: demo_cli.sh BINARY
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
bad() { echo "FAIL: $*"; fail=$((fail+1)); }

"$bin" demo --out "$tmp/d" --duration-ms 100 --no-plots > "$tmp/out.txt" 2> "$tmp/err.txt" ||
  { bad "demo exited non-zero"; cat "$tmp/err.txt"; exit 1; }
for want in "detection F1" "ISBI alpha / beta" "recall / alpha by |z| (um)" "real-time factor"; do
  grep -qF "$want" "$tmp/out.txt" || bad "no '$want' in the demo's table"
done
for f in sim/truth.csv sim/calib.json track/tracks.csv track/detections.csv track/summary.json; do
  [ -s "$tmp/d/$f" ] || bad "no $f"
done

# the same figures from score itself
vols=$(sed -n 's/.*"volumes":[[:space:]]*\([0-9]*\).*/\1/p' "$tmp/d/track/summary.json" | head -1)
"$bin" score --truth "$tmp/d/sim/truth.csv" --tracks "$tmp/d/track/tracks.csv" \
  --detections "$tmp/d/track/detections.csv" --calib "$tmp/d/sim/calib.json" \
  --n-frames "$vols" --by-depth 20 --json > "$tmp/score.json" || bad "score exited non-zero"
alpha=$(sed -n 's/^{"alpha":\([0-9.]*\),.*/\1/p' "$tmp/score.json")
shown=$(sed -n 's/.*ISBI alpha \/ beta *\([0-9.]*\) \/.*/\1/p' "$tmp/out.txt")
[ -n "$alpha" ] && [ -n "$shown" ] || bad "alpha not found (score '$alpha', demo '$shown')"
awk -v a="$alpha" -v s="$shown" 'BEGIN { d = a - s; if (d < 0) d = -d; exit !(d < 0.0006 && a > 0.5) }' ||
  bad "demo's alpha $shown is not score's $alpha (or below 0.5)"
# in focus every bead of flow is found: the 0-20 um band's recall
r0=$(sed -n 's/.*"depth_bands":\[{"z_lo_um":0,[^}]*"recall":\([0-9.]*\).*/\1/p' "$tmp/score.json")
shown0=$(sed -n 's/.*0-20 \([0-9.]*\) \/.*/\1/p' "$tmp/out.txt")
awk -v a="$r0" -v s="$shown0" 'BEGIN { d = a - s; if (d < 0) d = -d; exit !(a >= 0.95 && d < 0.006) }' ||
  bad "recall within 20 um of focus: score '$r0', demo '$shown0' (want >= 0.95, the same)"

# a duration out of range is a usage error (exit 2), nothing written
"$bin" demo --out "$tmp/e" --duration-ms 5 > /dev/null 2>&1; rc=$?
[ $rc -eq 2 ] || bad "--duration-ms 5 exited $rc, not 2"
[ ! -e "$tmp/e" ] || bad "--duration-ms 5 wrote $tmp/e"

[ $fail -eq 0 ] && echo "demo_cli: the demo's table agrees with eventlfm score (alpha $alpha, in-focus recall $r0)"
exit $fail
