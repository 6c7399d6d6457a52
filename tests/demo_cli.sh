#!/bin/sh
# The README's main command, `eventlfm demo`: it simulates, tracks and
# scores, and its table must say what `eventlfm score` says of the same
# files (alpha; recall within 20 um of focus from --by-depth), with the
# depth line that shows where out of focus the run can be trusted.
# Usage: demo_cli.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
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

# the whole depth line: each band's recall / alpha as score's, the 60+
# band pooled over score's bands from 60 um by their truth points (a mean
# left unweighted passed every test until a mutation sweep)
want=$(grep -o '"depth_bands":\[[^]]*\]' "$tmp/score.json" | sed 's/},{/\n/g' |
  awk '{ lo = $0; sub(/.*"z_lo_um":/, "", lo); lo += 0
         n = $0; sub(/.*"n_truth_points":/, "", n); n += 0
         tp = $0; sub(/.*"n_true_positives":/, "", tp); tp += 0
         al = $0; sub(/.*"alpha_tracks":/, "", al); al += 0
         k = lo < 60 ? lo / 20 : 3; N[k] += n; T[k] += tp; A[k] += n * al }
       END { for (k = 0; k < 4; k++) printf "%.4f %.4f ", N[k] ? T[k] / N[k] : -1, N[k] ? A[k] / N[k] : -1 }')
got=$(grep -F "recall / alpha by |z| (um)" "$tmp/out.txt" | sed 's/.*(um)//; s/[0-9]*-[0-9]*//g; s/60+//; s/\// /g')
echo "depth line: demo '$got', from score '$want'"
echo "$got $want" | awk '{ if (NF != 16) exit 1; for (k = 1; k <= 8; k++) { d = $k - $(k + 8); if (d < 0) d = -d; if (d > 0.006) exit 1 } }' ||
  bad "the demo's depth line '$got' is not score's '$want'"
# the real-time factor is the recording's span (its first to its last
# event, `eventlfm info`'s duration_us: the sensor's latency takes it a little past
# the 100 ms simulated) over the tracking time; the time is printed to
# 0.01 s and the factor to 0.001, so their product is the span within
# 0.005 r + 0.0005 t (slow machines and sanitizer builds give small factors)
"$bin" info "$tmp/d/sim/events.raw" --json > "$tmp/info.json" || bad "info exited non-zero"
span_us=$(key "$tmp/info.json" duration_us)
rtf=$(sed -n 's/.*real-time factor (span \/ wall) *\([0-9.]*\).*/\1/p' "$tmp/out.txt")
trk=$(sed -n 's/.*tracking (events -> tracks files) *\([0-9.]*\) s.*/\1/p' "$tmp/out.txt")
awk -v r="$rtf" -v t="$trk" -v sp_us="$span_us" 'BEGIN { s = r * t; sp = sp_us * 1e-6; e = 0.005 * r + 0.0005 * t + 1e-6
  exit !(t > 0 && sp > 0.09 && (s - sp) ^ 2 <= e * e) }' ||
  bad "real-time factor $rtf x tracking $trk s is not the recording's span ('$span_us' us)"

# a duration out of range is a usage error (exit 2), nothing written
"$bin" demo --out "$tmp/e" --duration-ms 5 > /dev/null 2>&1; rc=$?
[ $rc -eq 2 ] || bad "--duration-ms 5 exited $rc, not 2"
[ ! -e "$tmp/e" ] || bad "--duration-ms 5 wrote $tmp/e"

[ $fail -eq 0 ] && echo "demo_cli: the demo's table agrees with eventlfm score (alpha $alpha, in-focus recall $r0)"
exit $fail
