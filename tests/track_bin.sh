#!/bin/sh
# track --bin-px: the peaks found in volumes refocused from the frames
# binned 2 x 2 (recon/pipeline.c), each refined again on the full-sampled
# voxels around it (cli/cmd_track_bin.c) and placed by the view fit on the
# full frame (docs/tracker.md "Peaks found in a binned volume"). On flow
# 100 ms seed 1, against the same run at --bin-px 1 (the default):
#  - alpha and F1 no more than 0.01 lower, the lateral RMSE no more than
#    10 % higher (measured: alpha 0.891 -> 0.893, F1 0.972 -> 0.975);
#  - the in-focus peaks' median width, from which the motion lead is
#    taken, within 0.05 um of the full-sampled one (0.85 both; the binned
#    volume's own peaks are ~35 % wider: 1.12 against 0.82 um on flow 1 s,
#    and the lead grew with them, alpha 0.793 -> 0.754);
#  - summary.json says the binning; --bin-px 3 runs too;
#  - bad values and --resolution with it (whose widths would be the
#    binned volume's) are usage errors.
# Usage: track_bin.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

simulate_or_skip "$tmp/f" flow 100 1
track_score "$tmp/f" "$tmp/t1" "$tmp/t1.json" --bin-px 1
track_score "$tmp/f" "$tmp/t2" "$tmp/t2.json" --bin-px 2
a1=$(key "$tmp/t1.json" alpha); a2=$(key "$tmp/t2.json" alpha)
f1=$(key "$tmp/t1.json" f1); f2=$(key "$tmp/t2.json" f1)
echo "flow 100 ms seed 1: alpha $a1 -> $a2, F1 $f1 -> $f2 with --bin-px 2"
expect_gain "$a1" "$a2" -0.01 "alpha $a1 -> $a2 with --bin-px 2"
expect_gain "$f1" "$f2" -0.01 "F1 $f1 -> $f2 with --bin-px 2"
for ax in x y; do
  r1=$(key "$tmp/t1.json" "rmse_${ax}_um"); r2=$(key "$tmp/t2.json" "rmse_${ax}_um")
  below "$r2" 1.1 "$r1" || { echo "FAIL: RMSE $ax $r1 -> $r2 with --bin-px 2"; fail=$((fail+1)); }
done
w1=$(key "$tmp/t1/summary.json" peak_width_median_um)
w2=$(key "$tmp/t2/summary.json" peak_width_median_um)
echo "in-focus peaks' median width $w1 -> $w2 um"
awk -v a="$w1" -v b="$w2" "$AWK_NUM"' BEGIN { exit !(num(a) && num(b) && b - a <= 0.05 && a - b <= 0.05) }' ||
  { echo "FAIL: the binned run's widths $w2 um, the full-sampled $w1"; fail=$((fail+1)); }
expect_key bin_px "$tmp/t1/summary.json" 1
expect_key bin_px "$tmp/t2/summary.json" 2
track_score "$tmp/f" "$tmp/t3" "$tmp/t3.json" --bin-px 3 --to-us 40000
expect_key bin_px "$tmp/t3/summary.json" 3
f3=$(key "$tmp/t3.json" f1)
at_least "$f3" 0.9 || { echo "FAIL: F1 $f3 with --bin-px 3 over 40 ms"; fail=$((fail+1)); }
expect_usage_errors "--bin-px 0" "--bin-px 5" "--bin-px x" "--bin-px 2 --resolution"
[ "$fail" -eq 0 ] && echo "track_bin: all checks passed"
exit $([ "$fail" -eq 0 ] && echo 0 || echo 1)
