#!/bin/sh
# Output directories and the length of their files' paths, for every command
# that writes into --out (simulate, recon, traces, demo; track's own cases
# are in track_cli.sh). A directory as long as the system takes (PATH_MAX,
# 4096 with its NUL) less the longest file name is written whole; a longer
# one exits 1 with a message naming --out and the limit, and leaves no
# directory behind. Before, simulate refused anything over 1000 characters
# (after making the directories) and recon made a tree cut at 4095
# characters before failing on its first file.
# Usage: long_out_cli.sh BINARY
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
. "$(dirname "$0")/track_lib.sh"  # check
# long ROOT CHARS: ROOT/abcdefghi/... of at least CHARS characters
long() {
  d=$1
  while [ ${#d} -lt "$2" ]; do d="$d/abcdefghi"; done
  echo "$d"
}
# refused NAME COMMAND...: exit 1 naming --out, and nothing made under NAME
refused() {
  name=$1; shift
  check 1 "out: .*too long for its files' paths (at most" "$@"
  [ -e "$tmp/$name" ] && { echo "FAIL: $name: a refused --out left directories behind"; fail=$((fail+1)); }
  rm -rf "${tmp:?}/$name"
}
cd "$tmp" || exit 1  # relative paths: their length is what the command is given

check 0 "" "$bin" simulate flow --out sim --duration-ms 4 --seed 2 --quiet
# simulate: 1200 characters written whole (refused before); over the limit refused
d=$(long sim_ok 1200)
check 0 "" "$bin" simulate flow --out "$d" --duration-ms 4 --seed 2 --quiet
cmp -s sim/events.raw "$d/events.raw" || { echo "FAIL: simulate to ${#d} characters: other events"; fail=$((fail+1)); }
d=$(long sim_no 4083)  # + /stimulus.csv is past 4095
refused sim_no "$bin" simulate flow --out "$d" --duration-ms 4 --quiet
refused sim_no "$bin" simulate flow --out "$(long sim_no 5000)" --duration-ms 4 --quiet

# recon: with --save-volumes the longest name is /volumes/vol_NNNNNN.exr (23)
d=$(long recon_ok 4060)
[ $((${#d} + 23)) -le 4095 ] || d=${d%/abcdefghi}
check 0 "" "$bin" recon --calib sim/calib.json --events sim/events.raw --out "$d" --save-volumes --save-mips --quiet
[ -s "$d/volumes/vol_000000.exr" ] && [ -s "$d/mips/mip_000000.png" ] && [ -s "$d/summary.json" ] ||
  { echo "FAIL: recon to ${#d} characters wrote no volume, MIP or summary"; fail=$((fail+1)); }
refused recon_no "$bin" recon --calib sim/calib.json --events sim/events.raw --out "$(long recon_no 4080)" --save-volumes --quiet
refused recon_no "$bin" recon --calib sim/calib.json --events sim/events.raw --out "$(long recon_no 5000)" --quiet
# with MIPs only the longest is /mips/mip_NNNNNN.png (20): 4078 characters
# are refused there, and written without them (/summary.json, 13)
d=$(long recon_mp 4078)
refused recon_mp "$bin" recon --calib sim/calib.json --events sim/events.raw --out "$d" --save-mips --quiet
check 0 "" "$bin" recon --calib sim/calib.json --events sim/events.raw --out "$d" --quiet
[ -s "$d/summary.json" ] || { echo "FAIL: recon to ${#d} characters wrote no summary"; fail=$((fail+1)); }
# without volumes the longest is /summary.json: the same 4080 fits
d=$(long recon_no 4080)
[ $((${#d} + 13)) -le 4095 ] || d=${d%/abcdefghi}
check 0 "" "$bin" recon --calib sim/calib.json --events sim/events.raw --out "$d" --quiet
[ -s "$d/frames.csv" ] || { echo "FAIL: recon to ${#d} characters wrote no frames.csv"; fail=$((fail+1)); }

# traces (the longest name: /traces_summary.json, 20)
check 0 "" "$bin" track --calib sim/calib.json --events sim/events.raw --out trk -q
d=$(long traces_ok 4070)
[ $((${#d} + 20)) -le 4095 ] || d=${d%/abcdefghi}
check 0 "" "$bin" traces --calib sim/calib.json --events sim/events.raw --tracks trk/tracks.csv --out "$d" --quiet
[ -s "$d/traces.csv" ] && [ -s "$d/traces_summary.json" ] ||
  { echo "FAIL: traces to ${#d} characters wrote no traces"; fail=$((fail+1)); }
refused traces_no "$bin" traces --calib sim/calib.json --events sim/events.raw --tracks trk/tracks.csv \
  --out "$(long traces_no 4080)" --quiet

# demo: refused before it simulates anything
refused demo_no "$bin" demo --out "$(long demo_no 4075)"

[ $fail -eq 0 ] && echo "long_out_cli: all cases behave"
exit $fail
