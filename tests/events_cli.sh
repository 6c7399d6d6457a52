#!/bin/sh
# eventlfm info / convert through the command line: bad input gives exit 1
# and a message naming the file and byte offset (or line); usage errors
# exit 2; convert round trips the shared recordings (when present) and,
# on an input error, leaves a valid output holding the events before it.
bin=$1
shared=$2
fail=0
tmp=$(mktemp -d /tmp/elfm_events_cli.XXXXXX) || exit 1
trap 'rm -rf "$tmp"' EXIT

# expect CODE PATTERN CMD... : exit code CODE and PATTERN in stderr
expect() {
  code=$1; pat=$2; shift 2
  "$@" >"$tmp/out" 2>"$tmp/err"
  rc=$?
  if [ $rc -ne "$code" ]; then echo "FAIL: $* exited $rc, wanted $code"; cat "$tmp/err"; fail=$((fail+1)); return; fi
  if [ -n "$pat" ] && ! grep -q -- "$pat" "$tmp/err"; then
    echo "FAIL: $*: stderr lacks '$pat':"; cat "$tmp/err"; fail=$((fail+1))
  fi
}

: > "$tmp/empty.raw"
expect 1 "empty.raw: byte 0: empty file" "$bin" info "$tmp/empty.raw"
printf '%% evt 3.0\n%% geometry 1280x720\n%% end\n' > "$tmp/hdr.raw"
expect 1 "no events" "$bin" info "$tmp/hdr.raw"
head -c 3000 /dev/urandom | tr '%t' 'xy' > "$tmp/random.bin"
expect 1 "random.bin: byte 0: not an event file" "$bin" info "$tmp/random.bin"
# EVT3: TIME_HIGH 1, ADDR_Y 10, ADDR_X 1300 (outside 1280)
{ printf '%% evt 3.0\n%% geometry 1280x720\n%% end\n'; printf '\001\200\012\000\024\045'; } > "$tmp/xout.raw"
expect 1 "xout.raw: byte 40: EVT3 ADDR_X x=1300" "$bin" info "$tmp/xout.raw"
# truncated: TIME_HIGH then one byte
{ printf '%% evt 3.0\n%% geometry 1280x720\n%% end\n'; printf '\001\200\012'; } > "$tmp/trunc.raw"
expect 1 "trunc.raw: byte 38: file ends inside a 2-byte word" "$bin" info "$tmp/trunc.raw"
printf '%% evt 3.0\n%% geometry 2147483648x2147483648\n%% end\n' > "$tmp/absurd.raw"
expect 1 "absurd.raw: byte 10: bad geometry" "$bin" info "$tmp/absurd.raw"
printf '%% evt 3.0\n%% format EVT3;height=720;width=99999\n%% end\n' > "$tmp/absurd2.raw"
expect 1 "absurd2.raw: byte 0: geometry 99999x720" "$bin" info "$tmp/absurd2.raw"
printf 't_us,x,y,p\n5,1,1,1\n3,1,1,0\n' > "$tmp/unsorted.csv"
# info counts backward steps instead of failing; convert refuses them
expect 0 "" "$bin" info "$tmp/unsorted.csv" --json
grep -q '"non_monotonic_steps":1' "$tmp/out" || { echo "FAIL: info did not count the backward step"; fail=$((fail+1)); }
expect 1 "unsorted.csv:3: rows not sorted" "$bin" convert "$tmp/unsorted.csv" "$tmp/u.raw" --geometry 10x10
printf 't_us,x,y,p\n5,1,1,1\n6,1,x,0\n' > "$tmp/bad.csv"
expect 1 "bad.csv:3:" "$bin" info "$tmp/bad.csv"
expect 1 "cannot open" "$bin" info "$tmp/nonexistent.raw"
expect 2 "" "$bin" info
expect 2 "" "$bin" info --geometry 12 "$tmp/bad.csv"
expect 2 "" "$bin" convert "$tmp/bad.csv"
expect 2 "output format" "$bin" convert "$tmp/bad.csv" "$tmp/out.xyz"
expect 2 "" "$bin" convert "$tmp/bad.csv" "$tmp/o.csv" --from-us 10 --to-us 5

# A good CSV -> EVT3 -> CSV round trip, with a time range.
printf 't_us,x,y,p\n' > "$tmp/good.csv"
i=0; while [ $i -lt 300 ]; do echo "$((913000000 + i * 97)),$((i % 640)),$((i % 480)),$((i % 2))" >> "$tmp/good.csv"; i=$((i+1)); done
expect 0 "" "$bin" convert "$tmp/good.csv" "$tmp/good.raw" --geometry 640x480
expect 0 "" "$bin" convert "$tmp/good.raw" "$tmp/back.csv"
cmp -s "$tmp/good.csv" "$tmp/back.csv" || { echo "FAIL: CSV -> EVT3 -> CSV changed the events"; fail=$((fail+1)); }
# info's rates against the CSV's own: events over the span in ms, and the
# most events in one 1 ms bin of the clock (t_us / 1000); a burst of 40
# events in one millisecond makes the peak. (A mean rate 10 times too high
# passed every test until a mutation sweep.)
{ cat "$tmp/good.csv"; i=0; while [ $i -lt 40 ]; do echo "$((913040000 + i * 20)),5,6,1"; i=$((i+1)); done; } > "$tmp/burst.csv"
for f in good.csv burst.csv; do
  want=$(awk -F, 'NR > 1 { n++; if (n == 1) t0 = $1; t1 = $1; b = int($1 / 1000); c[b]++; if (c[b] > pk) pk = c[b] }
    END { d = t1 - t0; printf "%.6f %d", n / (d > 1000 ? d / 1000 : 1), pk }' "$tmp/$f")
  expect 0 "" "$bin" info --json "$tmp/$f"
  got=$(sed 's/.*"mean_rate_per_ms":\([0-9.e+-]*\).*"peak_rate_per_ms":\([0-9]*\).*/\1 \2/' "$tmp/out" |
    awk '{ printf "%.6f %d", $1, $2 }')
  [ "$got" = "$want" ] || { echo "FAIL: info $f: mean and peak rate '$got', wanted '$want'"; fail=$((fail+1)); }
done
grep -q '"peak_rate_per_ms":40,' "$tmp/out" || { echo "FAIL: the burst's 40 events in one ms are not the peak"; cat "$tmp/out"; fail=$((fail+1)); }
expect 0 "" "$bin" convert "$tmp/good.raw" "$tmp/part.csv" --from-us 913000970 --to-us 913001940
n=$(($(wc -l < "$tmp/part.csv") - 1))
[ "$n" -eq 10 ] || { echo "FAIL: time range kept $n events, wanted 10"; fail=$((fail+1)); }

# Input error mid-file: exit 1, and what was written stays a valid file.
{ cat "$tmp/good.csv"; echo "1,1,1,1"; } > "$tmp/late_error.csv"
expect 1 "late_error.csv:302:" "$bin" convert "$tmp/late_error.csv" "$tmp/partial.raw" --geometry 640x480
expect 0 "" "$bin" info --json "$tmp/partial.raw"
grep -q '"events":300' "$tmp/out" || { echo "FAIL: partial output does not hold the 300 good events"; cat "$tmp/out"; fail=$((fail+1)); }
# A recording cut short: info describes the events before the damage (the
# same count as the file cut on the word boundary), names the byte, exit 1.
sz=$(wc -c < "$tmp/good.raw")
head -c $((sz - 1)) "$tmp/good.raw" > "$tmp/cut1.raw"
head -c $((sz - 2)) "$tmp/good.raw" > "$tmp/cut2.raw"
for f in cut1 cut2; do "$bin" info --json "$tmp/$f.raw" > "$tmp/$f.json" 2> "$tmp/$f.err"; echo $? > "$tmp/$f.rc"; done
bad=cut1; good=cut2
[ "$(cat "$tmp/cut1.rc")" = 0 ] && { bad=cut2; good=cut1; }
[ "$(cat "$tmp/$good.rc")" = 0 ] && [ "$(cat "$tmp/$bad.rc")" = 1 ] ||
  { echo "FAIL: cuts a byte apart exited $(cat "$tmp/cut1.rc") and $(cat "$tmp/cut2.rc"), wanted 0 and 1"; fail=$((fail+1)); }
grep -q "$bad.raw: byte [0-9]*: file ends inside" "$tmp/$bad.err" ||
  { echo "FAIL: info on $bad.raw does not name the byte:"; cat "$tmp/$bad.err"; fail=$((fail+1)); }
nb=$(sed -n 's/.*"events":\([0-9]*\).*/\1/p' "$tmp/$bad.json")
ng=$(sed -n 's/.*"events":\([0-9]*\).*/\1/p' "$tmp/$good.json")
[ -n "$nb" ] && [ "$nb" = "$ng" ] && grep -q '"error":' "$tmp/$bad.json" ||
  { echo "FAIL: info on a cut recording: '$nb' events with an error key, the clean cut '$ng'"; fail=$((fail+1)); }

# The shared recordings: info --json figures equal reference.jsonl, and
# they survive convert to EVT3.
if [ -f "$shared/data/events/reference.jsonl" ]; then
  while read -r line; do
    f=$(echo "$line" | sed 's/.*"file": "\([^"]*\)".*/\1/')
    "$bin" info --json "$shared/data/events/$f" > "$tmp/info.json" || { echo "FAIL: info $f"; fail=$((fail+1)); continue; }
    "$bin" convert "$shared/data/events/$f" "$tmp/conv.raw" 2>/dev/null || { echo "FAIL: convert $f"; fail=$((fail+1)); continue; }
    "$bin" info --json "$tmp/conv.raw" > "$tmp/conv.json"
    for k in events t_first_us t_last_us sum_t sum_x sum_y on_events max_x max_y non_monotonic_steps; do
      want=$(echo "$line" | sed "s/.*\"$k\": \([0-9-]*\).*/\1/")
      for j in info conv; do
        got=$(sed "s/.*\"$k\":\([0-9-]*\).*/\1/" "$tmp/$j.json")
        [ "$got" = "$want" ] || { echo "FAIL: $f ($j) $k = $got, wanted $want"; fail=$((fail+1)); }
      done
    done
  done < "$shared/data/events/reference.jsonl"
else
  echo "note: $shared/data/events absent, reference part skipped"
fi

[ $fail -eq 0 ] && echo "events_cli: all checks passed"
exit $fail
