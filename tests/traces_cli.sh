#!/bin/sh
# eventlfm traces on bad input: usage errors exit 2 naming the option; a
# missing or malformed tracks/detections file exits 1 naming the file (and
# column or line); a recording cut halfway exits 1 naming the file and byte,
# and the traces of the frames read before it are kept. Usage: traces_cli.sh BINARY
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
. "$(dirname "$0")/track_lib.sh"  # check
check 0 "" "$bin" traces --help
grep -q "detections.csv" "$tmp/out" || { echo "FAIL: --help says nothing of detections.csv"; fail=$((fail+1)); }
check 2 "required" "$bin" traces
check 2 "required" "$bin" traces --calib a --events b --out c
check 2 "required" "$bin" traces --calib a --events b --out c --tracks t --detections d
check 2 "hold" "$bin" traces --calib a --events b --out c --detections d --hold
check 2 "cluster-um" "$bin" traces --calib a --events b --out c --detections d --cluster-um 0
check 2 "cluster-kz" "$bin" traces --calib a --events b --out c --detections d --cluster-kz -1
check 2 "min-detections" "$bin" traces --calib a --events b --out c --detections d --min-detections 0
check 2 "dt-us" "$bin" traces --calib a --events b --out c --detections d --dt-us 10
check 2 "unknown option" "$bin" traces --calib a --events b --out c --detections d --bogus

"$bin" simulate slice --out "$tmp/sim" --duration-ms 150 --quiet >/dev/null 2>&1 || { echo "SKIP: simulate failed"; exit 77; }
check 0 "" "$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/trk" -q
check 1 "missing.csv" "$bin" traces --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/o1" --tracks "$tmp/missing.csv" --quiet
printf 'track_id,t_us,x_um,y_um\n1,1000,0,0\n' > "$tmp/noz.csv"
check 1 "noz.csv:1: no column 'z_um'" "$bin" traces --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/o1" --tracks "$tmp/noz.csv" --quiet
printf 't_us,x_um,y_um,z_um,intensity\n1000,0,0,0,5\n\n2000,nan,0,0,5\n' > "$tmp/nan.csv"
check 1 "nan.csv:4:" "$bin" traces --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/o1" --detections "$tmp/nan.csv" --quiet
: > "$tmp/empty.csv"
check 1 "empty.csv:1: empty file" "$bin" traces --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/o1" --detections "$tmp/empty.csv" --quiet
# no detections at all: objects.csv and traces.csv hold the header only
printf 'frame,t_us,x_um,y_um,z_um,intensity\n' > "$tmp/none.csv"
check 0 "" "$bin" traces --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/o2" --detections "$tmp/none.csv" --quiet
[ "$(wc -l < "$tmp/o2/traces.csv")" -eq 1 ] && [ "$(wc -l < "$tmp/o2/objects.csv")" -eq 1 ] ||
  { echo "FAIL: no objects: expected header-only outputs"; fail=$((fail+1)); }
# a recording cut inside a word halfway: exit 1 naming file and byte, the
# rows of the frames before the cut kept (one per object and frame)
size=$(wc -c < "$tmp/sim/events.raw")
half=$((size / 2))
head -c "$half" "$tmp/sim/events.raw" > "$tmp/half.raw"
if "$bin" info "$tmp/half.raw" >/dev/null 2>&1; then
  head -c $((half + 1)) "$tmp/sim/events.raw" > "$tmp/half.raw"
fi
check 1 "half.raw: byte" "$bin" traces --calib "$tmp/sim/calib.json" --events "$tmp/half.raw" --out "$tmp/o3" --detections "$tmp/trk/detections.csv" --quiet
objs=$(($(wc -l < "$tmp/o3/objects.csv" 2>/dev/null || echo 1) - 1))
rows=$(($(wc -l < "$tmp/o3/traces.csv" 2>/dev/null || echo 1) - 1))
[ "$objs" -gt 0 ] && [ "$rows" -ge $((objs * 40)) ] ||
  { echo "FAIL: truncated input kept $rows rows for $objs objects (want >= 40 frames each)"; fail=$((fail+1)); }
grep -q '"input_error"' "$tmp/o3/traces_summary.json" 2>/dev/null ||
  { echo "FAIL: traces_summary.json does not record the input error"; fail=$((fail+1)); }
# the same frames as track's: with --tracks every track's detections are marked detected
# into track's own directory: its summary.json stays track's
cp "$tmp/trk/summary.json" "$tmp/track_summary.json"
check 0 "" "$bin" traces --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/trk" --tracks "$tmp/trk/tracks.csv" --hold --quiet
tr -d ' \t\n' < "$tmp/trk/traces_summary.json" 2>/dev/null | grep -q '"objects":"tracks","hold":true' ||
  { echo "FAIL: traces_summary.json lacks the objects' source"; fail=$((fail+1)); }
cmp -s "$tmp/trk/summary.json" "$tmp/track_summary.json" ||
  { echo "FAIL: traces overwrote track's summary.json"; fail=$((fail+1)); }
# On moving beads (the slice's neurons do not move, and make no tracks):
# the rows' times are track's frames' (frames.csv: frame, t_us), and each
# object's first and last time its track's first and last row's (tracks.csv:
# track_id, frame, t_us); a window's start written as its time, or the last
# time as the first, passed every test until a mutation sweep
"$bin" simulate flow --out "$tmp/fl" --duration-ms 30 --quiet >/dev/null 2>&1 || { echo "SKIP: simulate flow failed"; exit 77; }
check 0 "" "$bin" track --calib "$tmp/fl/calib.json" --events "$tmp/fl/events.raw" --out "$tmp/flt" -q
check 0 "" "$bin" traces --calib "$tmp/fl/calib.json" --events "$tmp/fl/events.raw" --out "$tmp/flt" --tracks "$tmp/flt/tracks.csv" --quiet
bad=$(awk -F, 'FNR == 1 { f++; next } f == 1 { t[$1] = $2; next } { n++; if (!($2 in t) || t[$2] != $3) b++ }
  END { print (n > 0 ? b + 0 : "no rows") }' "$tmp/flt/frames.csv" "$tmp/flt/traces.csv")
[ "$bad" = 0 ] || { echo "FAIL: traces.csv rows off their frame's t_us: $bad"; fail=$((fail+1)); }
bad=$(awk -F, 'FNR == 1 { f++; next }
  f == 1 { if (!($1 in lo) || $3 < lo[$1]) lo[$1] = $3; if (!($1 in hi) || $3 > hi[$1]) hi[$1] = $3; next }
  { n++; if (lo[$1] != $7 || hi[$1] != $8) b++ }
  END { print (n > 0 ? b + 0 : "no objects") }' "$tmp/flt/tracks.csv" "$tmp/flt/objects.csv")
[ "$bad" = 0 ] || { echo "FAIL: objects.csv first/last t_us not their tracks': $bad"; fail=$((fail+1)); }
[ "$fail" -eq 0 ] && echo "traces_cli: all passed"
exit $((fail > 0))
