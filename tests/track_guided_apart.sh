#!/bin/sh
# A guided view fit that lands on another detection's object is dropped
# (--guided-apart-um, cli/cmd_track_guided.c). Where a track predicts its
# bead and no peak lies near, the view fit starts from the prediction; a
# fit that lands beside another detection most often found that object,
# and then two tracks hold one bead. On random flow 150 ms (seed 1, pair
# fits off so that every weak view fit in detections.csv is a guided fit):
# with the rule off, 12 guided fits lie within 3 um (dz / 1.5) of a
# detection the frame already had when it was linked (nearest_um set; gap
# fills, written later, have none), at the positions as measured; with the
# default 3 um, none, and summary.json counts the fits dropped. (Made a
# no-op, the rule leaves 12 and the test fails.)
# Usage: track_guided_apart.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
simulate_or_skip "$tmp/sim" flow_random 150 1

# near DETECTIONS D KZ: the weak view fits within D um (dz / KZ) of a
# detection of their frame that has nearest_um (present when linked), at
# the positions as measured (raw_x/y/z_um; x/y/z_um are moved back by
# their track's motion bias afterwards)
near() {
  awk -F, -v D="$2" -v KZ="$3" '
    function flush(  i, j, dx, dy, dz) {
      for (i = 1; i <= n; i++) {
        if (!g[i]) continue
        for (j = 1; j <= n; j++) {
          if (j == i || !lk[j]) continue
          dx = x[i] - x[j]; dy = y[i] - y[j]; dz = (z[i] - z[j]) / KZ
          if (dx * dx + dy * dy + dz * dz < D * D) { c++; break }
        }
      }
    }
    NR == 1 {
      for (k = 1; k <= NF; k++) col[$k] = k
      if (!col["view_fit"] || !col["weak"] || !col["nearest_um"] || !col["raw_z_um"]) { print "no columns"; exit 1 }
      next
    }
    {
      if ($1 != f) { flush(); f = $1; n = 0 }
      n++; x[n] = $col["raw_x_um"]; y[n] = $col["raw_y_um"]; z[n] = $col["raw_z_um"]
      g[n] = ($col["view_fit"] == 1 && $col["weak"] == 1); lk[n] = ($col["nearest_um"] != "")
    }
    END { flush(); print c + 0 }' "$1"
}

for d in 0 3; do
  "$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/g$d" -q \
    --pair-fit-um 0 --guided-apart-um "$d" || { echo "FAIL: track --guided-apart-um $d"; fail=$((fail+1)); }
done
off=$(near "$tmp/g0/detections.csv" 3 1.5)
on=$(near "$tmp/g3/detections.csv" 3 1.5)
echo "guided fits within 3 um of a linked detection: $off with the rule off, $on with it"
[ "$off" -gt 0 ] 2>/dev/null || { echo "FAIL: none with the rule off ($off): the test sees nothing"; fail=$((fail+1)); }
[ "$on" = 0 ] || { echo "FAIL: $on guided fits beside another detection at --guided-apart-um 3"; fail=$((fail+1)); }
expect_key guided_apart_um "$tmp/g3/summary.json" 3
expect_key guided_fits_beside "$tmp/g0/summary.json" 0
below 0 1 "$(key "$tmp/g3/summary.json" guided_fits_beside)" ||
  { echo "FAIL: summary.json counts no guided fit dropped"; fail=$((fail+1)); }
# the default is the rule at 3 um: the same files as given
"$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/def" -q \
  --pair-fit-um 0 || { echo "FAIL: track at the default"; fail=$((fail+1)); }
cmp -s "$tmp/def/tracks.csv" "$tmp/g3/tracks.csv" ||
  { echo "FAIL: the default's tracks differ from --guided-apart-um 3"; fail=$((fail+1)); }
expect_usage_errors "--guided-apart-um -1" "--guided-apart-um 101" "--guided-apart-um x"
[ $fail -eq 0 ] && echo "track_guided_apart: all passed"
exit $fail
