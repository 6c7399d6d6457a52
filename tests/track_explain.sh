#!/bin/sh
# The ghost test of `eventlfm track` (--explain-brighter: a peak's views
# that a peak twice as bright explains do not count for its view support)
# on simulator truth: with the flow beads 3 x brighter (flux 36-48 kHz) the
# plain view-support test passes the ghosts a bright bead's images make at
# other depths, and the detection precision falls (0.83 on 100 ms of seed
# 2); with the test it comes back without costing recall; with it off no
# peak is counted as explained. With 60 beads (seed 1, 50 ms) the ghosts of
# many beads overlap: the test lifts precision 0.70 -> 0.90 and alpha 0.72
# -> 0.76 (asked: +0.1 and not lower). Out-of-range values are usage errors.
# Usage: track_explain.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--explain-brighter 1" "--explain-brighter -0.1" "--explain-um 0" "--explain-um nan"
simulate_or_skip "$tmp/sim" flow 100 2 --param 'objects.flux_hz=[36000,48000]'
track_score "$tmp/sim" "$tmp/off" "$tmp/off.json" --explain-brighter 0
track_score "$tmp/sim" "$tmp/on" "$tmp/on.json"
p0=$(key "$tmp/off.json" precision); p1=$(key "$tmp/on.json" precision)
r0=$(key "$tmp/off.json" recall); r1=$(key "$tmp/on.json" recall)
e0=$(key "$tmp/off/summary.json" peaks_explained_by_brighter)
e1=$(key "$tmp/on/summary.json" peaks_explained_by_brighter)
t0=$(key "$tmp/off/summary.json" tracks); t1=$(key "$tmp/on/summary.json" tracks)
echo "beads 3 x brighter: explain off: precision $p0 recall $r0 tracks $t0; on: precision $p1 recall $r1 tracks $t1 ($e1 peaks explained)"
[ "$e0" = 0 ] || { echo "FAIL: $e0 peaks explained with the test off"; fail=$((fail+1)); }
awk -v a="$e1" 'BEGIN { exit !(a > 50) }' || { echo "FAIL: only $e1 peaks explained"; fail=$((fail+1)); }
expect_gain "$p0" "$p1" 0.08 "precision $p0 -> $p1"
expect_gain 0.97 "$p1" 0 "precision $p1 with the test, below 0.97"
expect_gain "$r0" "$r1" -0.01 "recall $r0 -> $r1"
simulate_or_skip "$tmp/dense" flow 50 1 --param objects.count=60
track_score "$tmp/dense" "$tmp/doff" "$tmp/doff.json" --explain-brighter 0
track_score "$tmp/dense" "$tmp/don" "$tmp/don.json"
p0=$(key "$tmp/doff.json" precision); p1=$(key "$tmp/don.json" precision)
a0=$(key "$tmp/doff.json" alpha); a1=$(key "$tmp/don.json" alpha)
echo "60 beads: explain off: precision $p0 alpha $a0; on: precision $p1 alpha $a1"
expect_gain "$p0" "$p1" 0.1 "60 beads: precision $p0 -> $p1"
expect_gain "$a0" "$a1" 0 "60 beads: alpha $a0 -> $a1"
# nearest_um (detections.csv and tracks.csv): each detection's distance to
# the nearest other one of its frame, dz / 1.5. Recomputed here over the
# rows that have one (the linker's inputs but trail and unlinked weak
# peaks; gap fills have none): never below the written value (that was
# over more detections), equal on most rows; and each track row's value is
# its raw point's. claims (how many tracks had the detection within their
# gate when it was linked) is a whole number >= 0 on every row, 2 or more on
# some (60 beads cross), and each track row's is its point's. Both are of
# the detections as measured: detections.csv's raw_x/y/z_um (its x/y/z_um
# are moved back by their track's motion bias)
awk -F, -v kz=1.5 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
  $c["nearest_um"] != "" { n++; f[n] = $1; x[n] = $c["raw_x_um"]; y[n] = $c["raw_y_um"]; z[n] = $c["raw_z_um"]
    w[n] = $c["nearest_um"] }
  END {
    for (i = 1; i <= n; i++) {
      b = 1e18
      for (j = 1; j <= n; j++) if (j != i && f[j] == f[i]) {
        d = (x[j]-x[i])^2 + (y[j]-y[i])^2 + ((z[j]-z[i])/kz)^2; if (d < b) b = d }
      if (b == 1e18) { alone++; continue }
      b = sqrt(b)
      if (b < w[i] - 2e-3) low++
      if (b - w[i] < 2e-3) same++
      m++
    }
    printf "nearest_um: %d rows, %d recomputed the same, %d below, %d alone\n", n, same, low, alone
    exit !(n > 500 && low == 0 && same >= 0.9 * m)
  }' "$tmp/don/detections.csv" || { echo "FAIL: nearest_um in detections.csv"; fail=$((fail+1)); }
awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
  { v = $c["claims"]; n++; if (v !~ /^[0-9]+$/) bad++; else if (v >= 2) two++ }
  END { printf "claims: %d rows, %d with 2 or more, %d not a whole number\n", n, two, bad
        exit !(n > 500 && two > 10 && bad == 0) }' "$tmp/don/detections.csv" ||
  { echo "FAIL: claims in detections.csv"; fail=$((fail+1)); }
awk -F, 'FNR == 1 { for (i = 1; i <= NF; i++) c[FILENAME, $i] = i; next }
  FILENAME == ARGV[1] { if ($c[FILENAME, "nearest_um"] != "") {
      k = $1 "," $c[FILENAME, "raw_x_um"] "," $c[FILENAME, "raw_y_um"]
      v[k] = $c[FILENAME, "nearest_um"]; cl[k] = $c[FILENAME, "claims"] }
    next }
  $c[FILENAME, "raw_x_um"] != "" && $c[FILENAME, "nearest_um"] != "" {
    k = $2 "," $c[FILENAME, "raw_x_um"] "," $c[FILENAME, "raw_y_um"]; t++
    if (!(k in v) || v[k] != $c[FILENAME, "nearest_um"] || cl[k] != $c[FILENAME, "claims"]) bad++ }
  END { printf "tracks.csv: %d rows with nearest_um, %d unlike their detection\n", t, bad; exit !(t > 500 && bad == 0) }' \
  "$tmp/don/detections.csv" "$tmp/don/tracks.csv" || { echo "FAIL: nearest_um in tracks.csv"; fail=$((fail+1)); }
[ $fail -eq 0 ] && echo "1 passed, 0 failed" || echo "0 passed, $fail failed"
exit $fail
