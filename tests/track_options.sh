#!/bin/sh
# The detector's, linker's and smoother's options out of range are usage
# errors (exit 2) naming the option and what it takes, before anything is
# read. Before, most reached the libraries, which refused them with exit 1
# and one list of every option's range ("link: options out of range (gate >
# 0, kz > 0, ...)"), or took them: --threshold-min -5 ran.
# Usage: track_options.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--gate-um 0" "--gate-um -1" "--gate-um x" "--link-kz 0" "--max-gap -1" \
  "--min-points 0" "--stitch-points 3" "--stitch-points -1" "--swap-points 2" "--rescue-factor -1" \
  "--stitch-gate-um -1" "--weak-gate-um -1" "--radius-xy-um 0" "--radius-z-um 0" \
  "--min-separation-um -1" "--threshold-rel 2" "--threshold-rel -0.5" "--threshold-low -1" \
  "--threshold-min -5" "--threshold-depth-um -1" "--threshold-k -1" "--threshold-abs -1" \
  "--views-exponent -1" "--views-exponent 5" "--spline-weight-ms3 -1" "--stitch-late-points -1" \
  "--stitch-late-points x"
# the message says what the option takes
"$bin" track --calib a --events b --out c --stitch-points 3 2>"$tmp/err" >/dev/null
grep -q -- "--stitch-points must be 0 (off) or 4..100000, not 3" "$tmp/err" ||
  { echo "FAIL: --stitch-points message: $(cat "$tmp/err")"; fail=$((fail+1)); }
"$bin" track --calib a --events b --out c --gate-um 0 2>"$tmp/err" >/dev/null
grep -q -- "--gate-um must be > 0 and <= 10000, not '0'" "$tmp/err" ||
  { echo "FAIL: --gate-um message: $(cat "$tmp/err")"; fail=$((fail+1)); }
# the edges of the ranges are taken (the command then fails on the missing
# files, exit 1, not 2)
for ok in "--stitch-points 0" "--stitch-points 4" "--stitch-late-points 0" "--stitch-late-points 3" "--swap-points 0" "--threshold-rel 1" "--max-gap 0" \
  "--rescue-factor 0" "--weak-gate-um 0" "--spline-weight-ms3 0" "--views-exponent 4"; do
  # shellcheck disable=SC2086
  "$bin" track --calib "$tmp/none.json" --events b --out "$tmp/o" $ok >/dev/null 2>"$tmp/err"
  [ $? -eq 1 ] || { echo "FAIL: $ok refused: $(cat "$tmp/err")"; fail=$((fail+1)); }
done
# Options given land where they act: summary.json's parameters say each
# value given, in one short run (--threshold-abs and --link-kz stored in
# other fields passed every test until a mutation sweep)
simulate_or_skip "$tmp/f" flow 20 1
set -- threshold_abs:--threshold-abs:37 threshold_low:--threshold-low:11 link_kz:--link-kz:3.5 \
  gate_um:--gate-um:5.5 fill_gate_um:--fill-gate-um:2.5 radius_xy_um:--radius-xy-um:2.25 \
  radius_z_um:--radius-z-um:7.5 min_separation_um:--min-separation-um:3.25 \
  threshold_k_sigma:--threshold-k:4.5 threshold_rel:--threshold-rel:0.125
args=""
for g in "$@"; do args="$args ${g#*:}"; done
args=$(echo "$args" | sed 's/:/ /g')
# shellcheck disable=SC2086
"$bin" track --calib "$tmp/f/calib.json" --events "$tmp/f/events.raw" --out "$tmp/p" $args \
  2>"$tmp/p.err" >/dev/null || { echo "FAIL: track$args: $(tail -n 2 "$tmp/p.err")"; fail=$((fail+1)); }
for g in "$@"; do
  k=${g%%:*}; v=${g##*:}
  got=$(key "$tmp/p/summary.json" "$k")
  awk -v a="$got" -v b="$v" 'BEGIN { exit !(a != "" && a + 0 == b + 0) }' ||
    { echo "FAIL: $(echo "${g#*:}" | tr : " ") gave parameters.$k '$got'"; fail=$((fail+1)); }
done
# and the closing line's realtime factor is the span over its own time
# (both printed to 0.01)
line=$(tr '\r' '\n' < "$tmp/p.err" | grep "realtime factor")
span=$(key "$tmp/p/summary.json" span_s)
echo "$line" | sed 's/.* in \([0-9.]*\) s (.*realtime factor \([0-9.]*\)).*/\1 \2/' |
  awk -v s="$span" '{ t = $1; r = $2; e = 0.005 + s * 0.005 / (t * t) + 1e-9
    exit !(t > 0 && s > 0 && (r - s / t) ^ 2 <= e * e) }' ||
  { echo "FAIL: closing line '$line' (span $span s)"; fail=$((fail+1)); }
[ $fail -eq 0 ] && echo "track_options: all passed" || echo "track_options: $fail failed"
[ $fail -eq 0 ]
