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
[ $fail -eq 0 ] && echo "track_options: all passed" || echo "track_options: $fail failed"
[ $fail -eq 0 ]
