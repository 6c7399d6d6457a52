#!/bin/sh
# eventlfm track on bad input: clear message naming the file, non-zero exit,
# no crash; usage errors exit 2. Usage: track_cli.sh BINARY
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
. "$(dirname "$0")/track_lib.sh"  # check
check 2 "required" "$bin" track
check 2 "unknown option" "$bin" track --calib a --events b --out c --bogus
check 2 "motion" "$bin" track --calib a --events b --out c --motion sideways
check 2 "stage-velocity" "$bin" track --calib a --events b --out c --stage-velocity-um-per-ms 1,2
check 2 "batch" "$bin" track --calib a --events b --out c --batch -1
check 2 "max-outlier-frac" "$bin" track --calib a --events b --out c --max-outlier-frac 2
check 2 "priority-points" "$bin" track --calib a --events b --out c --priority-points -1
check 2 "priority-points" "$bin" track --calib a --events b --out c --priority-points x
check 2 "gcv-gamma" "$bin" track --calib a --events b --out c --gcv-gamma 0.5
check 2 "spline-order" "$bin" track --calib a --events b --out c --spline-order 4
# The recon options track shares with recon (cli_parse_recon_option): each
# bad value is a usage error naming the option, with the same message from
# both commands.
for bad in "--dt-us 10" "--dt-us x" "--stride-us -1" "--stride-us 2000" "--tau-us 0" \
           "--repr dots" "--polarity up" "--median 4" "--path fast" "--ghost bogus" \
           "--ghost frac" "--ghost frac:2" "--ghost mad:-1" "--ghost agree:2" "--ghost mad:3," \
           "--ghost-value 3" "--ghost-value -1" "--agree 1.5" "--threads -1" "--threads 5000" \
           "--batch 5000" "--from-us x" "--from-us 5 --to-us 5" "--to-us" "--z-step-um 0" \
           "--z-min-um x" "--z-max-um 2e4"; do
  opt=${bad%% *}
  [ "$bad" = "--from-us 5 --to-us 5" ] && opt=--from-us
  # shellcheck disable=SC2086  # $bad is an option and its value
  check 2 "$opt" "$bin" track --calib a --events b --out c $bad
  cp "$tmp/err" "$tmp/err.track"
  # shellcheck disable=SC2086
  check 2 "$opt" "$bin" recon --calib a --events b --out c $bad
  if [ "$(sed 's/^eventlfm recon: //' "$tmp/err")" != "$(sed 's/^eventlfm track: //' "$tmp/err.track")" ]; then
    echo "FAIL: recon and track say different things for $bad:"; cat "$tmp/err.track" "$tmp/err"
    fail=$((fail+1))
  fi
done
check 1 "$tmp/nope.json" "$bin" track --calib "$tmp/nope.json" --events "$tmp/e.raw" --out "$tmp/o" -q
# a valid calibration, then broken event files
"$bin" calib from-optics --out "$tmp/calib.json" >/dev/null 2>&1 || { echo "SKIP: calib from-optics failed"; exit 77; }
check 1 "$tmp/missing.raw" "$bin" track --calib "$tmp/calib.json" --events "$tmp/missing.raw" --out "$tmp/o1" -q
printf 't_us,x,y,p\n100,5,5,1\n200,5,5,notanumber\n' > "$tmp/bad.csv"
check 1 "bad.csv" "$bin" track --calib "$tmp/calib.json" --events "$tmp/bad.csv" --out "$tmp/o2" -q
printf '%% evt 3.0\n%% geometry 1280x720\n%% end\n' > "$tmp/trunc.raw"
printf '\001\002\003' >> "$tmp/trunc.raw"
check 1 "trunc.raw: byte" "$bin" track --calib "$tmp/calib.json" --events "$tmp/trunc.raw" --out "$tmp/o3" -q
# planes that the calibration's make impossible (min above its max): a
# usage error naming the options and the calibration, from both commands
check 2 "calib.json's planes" "$bin" track --calib "$tmp/calib.json" --events "$tmp/missing.raw" --out "$tmp/o1" -q --z-min-um 150
check 2 "calib.json's planes" "$bin" recon --calib "$tmp/calib.json" --events "$tmp/missing.raw" --out "$tmp/o1" --quiet --z-step-um 0.01
# a recording cut inside a word halfway: exit 1 naming file and byte, and
# nothing already read is lost: the tracks of the first half are written
"$bin" simulate flow --out "$tmp/sim" --duration-ms 30 --quiet >/dev/null 2>&1 || { echo "SKIP: simulate failed"; exit 77; }
size=$(wc -c < "$tmp/sim/events.raw")
half=$((size / 2))
head -c "$half" "$tmp/sim/events.raw" > "$tmp/half.raw"
# data words are 2 bytes after a text header of either parity: move the cut
# by one byte if it fell between two words
if "$bin" info "$tmp/half.raw" >/dev/null 2>&1; then
  head -c $((half + 1)) "$tmp/sim/events.raw" > "$tmp/half.raw"
fi
check 1 "half.raw: byte" "$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/half.raw" --out "$tmp/o5" -q
rows=$(($(wc -l < "$tmp/o5/tracks.csv" 2>/dev/null || echo 1) - 1))
[ "$rows" -gt 10 ] || { echo "FAIL: truncated input lost the tracks read before the error ($rows rows)"; fail=$((fail+1)); }
grep -q '"input_error"' "$tmp/o5/summary.json" 2>/dev/null || { echo "FAIL: summary.json does not record the input error"; fail=$((fail+1)); }
[ -s "$tmp/o5/tracks_isbi.xml" ] || { echo "FAIL: truncated input left no ISBI XML"; fail=$((fail+1)); }
# other planes than the calibration's: the summary says which were used
check 0 "" "$bin" track --calib "$tmp/sim/calib.json" --events "$tmp/sim/events.raw" --out "$tmp/o6" -q \
  --z-min-um -60 --z-max-um 60 --z-step-um 4
tr -d ' \t\n' < "$tmp/o6/summary.json" 2>/dev/null | grep -q '"nz":31,"um_per_px":[0-9.]*,"z_min_um":-60,"z_step_um":4' ||
  { echo "FAIL: track --z-*-um: summary.json lacks the 31 planes -60..60 step 4"; fail=$((fail+1)); }
# the outputs written as tracks end agree: one ISBI particle and one
# TrackMate track per summary.json track, one spot per kept point, each
# file whole, and no scratch file left behind (also after the input error)
for o in o5 o6; do
  d="$tmp/$o"
  [ -f "$d/summary.json" ] || continue
  nt=$(tr -d ' \t\n' < "$d/summary.json" | sed -n 's/.*"tracks":\([0-9]*\),.*/\1/p')
  np=$(tr -d ' \t\n' < "$d/summary.json" | sed -n 's/.*"track_points":\([0-9]*\),.*/\1/p')
  ni=$(grep -c '<particle>' "$d/tracks_isbi.xml" 2>/dev/null)
  nm=$(grep -c '<Track ' "$d/tracks_trackmate.xml" 2>/dev/null)
  ns=$(grep -c '<Spot ' "$d/tracks_trackmate.xml" 2>/dev/null)
  nc=$(tail -n +2 "$d/tracks.csv" | cut -d, -f1 | sort -u | wc -l)
  if [ -z "$nt" ] || [ "$nt" -lt 1 ] || [ "$ni" != "$nt" ] || [ "$nm" != "$nt" ] || [ "$nc" != "$nt" ] ||
     [ "$ns" != "$np" ]; then
    echo "FAIL: $o: tracks summary/isbi/trackmate/csv $nt/$ni/$nm/$nc, spots $ns of $np points"
    fail=$((fail+1))
  fi
  [ -n "$VERBOSE" ] && echo "$o: $nt tracks, $ns spots"
  tail -1 "$d/tracks_isbi.xml" | grep -q '</root>' || { echo "FAIL: $o: ISBI XML not closed"; fail=$((fail+1)); }
  tail -1 "$d/tracks_trackmate.xml" | grep -q '</TrackMate>' || { echo "FAIL: $o: TrackMate XML not closed"; fail=$((fail+1)); }
  ls "$d" | grep -q 'tmp' && { echo "FAIL: $o: scratch file left: $(ls "$d")"; fail=$((fail+1)); }
  # the timing's figures are what their names say (SPEC 5): the real-time
  # factor the recording's span over the wall time, volumes per second the
  # volumes over it
  js=$(tr -d ' \t\n' < "$d/summary.json")
  num() { printf '%s' "$js" | sed -n "s/.*\"$1\":\([-0-9.eE+]*\)[,}].*/\1/p"; }
  if ! awk -v w="$(num wall_s)" -v s="$(num span_s)" -v r="$(num realtime_factor)" \
         -v vps="$(num volumes_per_s)" -v nv="$(num volumes)" 'BEGIN {
         exit !(w > 0 && s > 0 && nv > 0 &&
                (r - s / w) ^ 2 <= (1e-9 * r) ^ 2 && (vps - nv / w) ^ 2 <= (1e-9 * vps) ^ 2) }'; then
    echo "FAIL: $o: timing wall $(num wall_s) s, span $(num span_s) s, realtime_factor $(num realtime_factor), volumes $(num volumes), volumes_per_s $(num volumes_per_s)"
    fail=$((fail+1))
  fi
done
# output directories whose parents do not exist yet are made, parents and
# all (simulate, track, recon); one under a regular file is an error naming it
check 0 "" "$bin" simulate flow --out "$tmp/new/sim/a" --duration-ms 5 --quiet
check 0 "" "$bin" track --calib "$tmp/new/sim/a/calib.json" --events "$tmp/new/sim/a/events.raw" \
  --out "$tmp/new/runs/1" -q
[ -s "$tmp/new/runs/1/tracks.csv" ] && [ -s "$tmp/new/runs/1/summary.json" ] ||
  { echo "FAIL: track --out with new parents wrote no tracks.csv / summary.json"; fail=$((fail+1)); }
check 0 "" "$bin" recon --calib "$tmp/new/sim/a/calib.json" --events "$tmp/new/sim/a/events.raw" \
  --out "$tmp/new/recon/1" --quiet --to-us 3000
[ -d "$tmp/new/recon/1" ] || { echo "FAIL: recon --out with new parents made no directory"; fail=$((fail+1)); }
check 1 "events.raw/x: cannot create directory" "$bin" track --calib "$tmp/new/sim/a/calib.json" \
  --events "$tmp/new/sim/a/events.raw" --out "$tmp/new/sim/a/events.raw/x" -q
# output directories too long for their files' paths (many short parts,
# each of them legal; one past PATH_MAX too): an error naming --out, and no
# directory made. Before, the files' paths were cut to one prefix and
# overwrote one another: a bus error at 4081 characters.
for n in 408 500; do
  long="$tmp/long"; i=0
  while [ $i -lt $n ]; do long="$long/abcdefghi"; i=$((i+1)); done
  check 1 "out: .*too long for its files' paths" "$bin" track --calib "$tmp/new/sim/a/calib.json" \
    --events "$tmp/new/sim/a/events.raw" --out "$long" -q
  [ -e "$tmp/long" ] && { echo "FAIL: a too long --out ($n parts) left directories behind"; fail=$((fail+1)); }
done
# the longest that fits works, parents and all (PATH_MAX 4096 with its
# NUL, less /tracks_trackmate.xml; the limit was 1078 characters before)
long="$tmp/fits"
while [ $((${#long} + 10)) -le $((4095 - 21)) ]; do long="$long/abcdefghi"; done
check 0 "" "$bin" track --calib "$tmp/new/sim/a/calib.json" --events "$tmp/new/sim/a/events.raw" --out "$long" -q
[ -s "$long/tracks_trackmate.xml" ] || { echo "FAIL: an --out of ${#long} characters wrote no TrackMate file"; fail=$((fail+1)); }
# an empty recording: valid outputs with headers only
printf 't_us,x,y,p\n' > "$tmp/empty.csv"
check 0 "" "$bin" track --calib "$tmp/calib.json" --events "$tmp/empty.csv" --out "$tmp/o4" -q
# ... and why there is nothing, on stderr, here and for a range that holds
# no event (sixty-first session); -q keeps it quiet as every note
check 0 "note: $tmp/empty.csv holds no events" "$bin" track --calib "$tmp/calib.json" --events "$tmp/empty.csv" --out "$tmp/o5"
check 0 "note: no event of .* lies in --from-us / --to-us (99999999 us to its end)" "$bin" track \
  --calib "$tmp/new/sim/a/calib.json" --events "$tmp/new/sim/a/events.raw" --out "$tmp/o6" --from-us 99999999
check 0 "no event of .* lies in --from-us / --to-us (its start to -5 us)" "$bin" recon \
  --calib "$tmp/new/sim/a/calib.json" --events "$tmp/new/sim/a/events.raw" --out "$tmp/o7" --to-us -5
head -1 "$tmp/o4/tracks.csv" 2>/dev/null | grep -q '^track_id,frame,t_us,x_um,y_um,z_um' || { echo "FAIL: empty run has no tracks.csv header"; fail=$((fail+1)); }
grep -q '"volumes"' "$tmp/o4/summary.json" 2>/dev/null || { echo "FAIL: empty run has no summary.json"; fail=$((fail+1)); }
[ $fail -eq 0 ] && echo "track_cli: all cases behave"
exit $fail
