#!/bin/sh
# test_sim_cli.sh — eventlfm simulate / calib from the command line: outputs,
# exit codes (0 ok, 1 failure, 2 usage) and messages naming what is wrong.
bin=$1
dir=${2:-.}/sim_cli_out
rm -rf "$dir"
fail=0
check() { # check NAME EXPECTED_RC COMMAND...
  name=$1; want=$2; shift 2
  "$@" >"$dir.out" 2>"$dir.err"; rc=$?
  if [ "$rc" -ne "$want" ]; then
    echo "FAIL: $name: exit $rc, want $want"; cat "$dir.err"; fail=$((fail+1))
  fi
}
mkdir -p "$dir"
check list 0 "$bin" simulate --list
[ "$(wc -l <"$dir.out")" -eq 9 ] || { echo "FAIL: --list gave $(wc -l <"$dir.out") scenes"; fail=$((fail+1)); }
grep -qx flow_random "$dir.out" || { echo "FAIL: --list lacks flow_random"; fail=$((fail+1)); }
check run 0 "$bin" simulate blink --out "$dir/blink" --duration-ms 20 --seed 3 --quiet
for f in events.raw truth.csv calib.json stimulus.csv; do
  [ -s "$dir/blink/$f" ] || { echo "FAIL: blink: no $f"; fail=$((fail+1)); }
done
grep -q "Mev/s" "$dir.err" || { echo "FAIL: no event rate on stderr"; fail=$((fail+1)); }
# the line's numbers agree: rate = events / span, events = light + noise
# (a rate 1000 times too high passed every test until a mutation sweep)
awk '/^simulate: scene/ { for (k = 1; k <= NF; k++) {
       if ($(k + 1) == "events" && $(k + 2) == "in") e = $k
       if ($(k + 1) == "s" && $k + 0 > 0 && d == "") d = $k
       if ($(k + 1) == "Mev/s:") { r = $k; sub(/^\(/, "", r) }
       if ($(k + 1) == "from") l = $k
       if ($(k + 1) == "noise),") n = $k } }
     END { exit !(e > 0 && d == 0.020 && (r - e / d * 1e-6) ^ 2 < 0.005 ^ 2 && l + n == e) }' "$dir.err" ||
  { echo "FAIL: simulate's rate line does not add up: $(cat "$dir.err")"; fail=$((fail+1)); }
check info 0 "$bin" info "$dir/blink/events.raw"
check calib-of-scene 0 "$bin" calib show "$dir/blink/calib.json"
# --out in folders that do not exist yet: made, as by mkdir -p
check param 0 "$bin" simulate stage --out "$dir/new/run/stage" --duration-ms 3 --param objects.count=2 --quiet
[ -s "$dir/new/run/stage/events.raw" ] || { echo "FAIL: no events.raw under --out's new folders"; fail=$((fail+1)); }
[ ! -e "$dir/new/run/stage/stimulus.csv" ] || { echo "FAIL: stage wrote stimulus.csv"; fail=$((fail+1)); }
check no-out 2 "$bin" simulate stage
check bad-seed 2 "$bin" simulate stage --out "$dir/x" --seed abc
check bad-duration 2 "$bin" simulate stage --out "$dir/x" --duration-ms -5
check no-scene 1 "$bin" simulate no_such_scene --out "$dir/x"
grep -q "no_such_scene" "$dir.err" || { echo "FAIL: unknown scene not named"; fail=$((fail+1)); }
check bad-param 1 "$bin" simulate stage --out "$dir/x" --param sensor.nosuch=1
grep -q "sensor.nosuch" "$dir.err" || { echo "FAIL: bad --param key not named"; fail=$((fail+1)); }
printf '{"name": "x"}' >"$dir/bad.json"
check bad-scene 1 "$bin" simulate "$dir/bad.json" --out "$dir/x"
grep -q "bad.json" "$dir.err" && grep -q "description" "$dir.err" || { echo "FAIL: bad scene file/key not named"; cat "$dir.err"; fail=$((fail+1)); }
# The pixel model's threshold-mismatch ratchet (docs/simulator.md, "A dim
# object fades"): one deep (z 80 um), dim bead at rest, a 1 ms pulse every
# 3 ms, no noise. Its images change a pixel by a little more than one
# threshold; each ON/OFF pair moves the reference by (ON - OFF threshold),
# so with per-pixel mismatch (sigma 0.03) the pixels fall silent one by
# one (ON events in the second 30 ms against the first, measured: 232 / 790),
# and without it every pulse fires alike (2300 / 2070).
for sg in 0.03 0; do
  check "ratchet-$sg" 0 "$bin" simulate blink --out "$dir/r$sg" --duration-ms 60 --seed 1 --quiet \
    --param objects.count=1 --param 'objects.flux_hz=[30000,30000]' --param motion.z_min_um=80 \
    --param motion.z_max_um=80 --param motion.place_radius_um=5 \
    --param 'illumination={"type":"periodic","pulse_us":1000,"period_us":3000}' \
    --param sensor.threshold_sigma=$sg --param sensor.shot_noise_hz=0 --param sensor.leak_hz=0 \
    --param sensor.hot_pixels=0
  check "ratchet-csv-$sg" 0 "$bin" convert "$dir/r$sg/events.raw" "$dir/r$sg/ev.csv"
done
r=$(awk -F, 'NR > 1 && $4 == 1 { if ($1 < 30000) a++; else b++ } END { printf "%.3f", b / (a ? a : 1) }' "$dir/r0.03/ev.csv")
r0=$(awk -F, 'NR > 1 && $4 == 1 { if ($1 < 30000) a++; else b++ } END { printf "%.3f", b / (a ? a : 1) }' "$dir/r0/ev.csv")
echo "ratchet: ON events second / first 30 ms: $r (threshold sigma 0.03), $r0 (sigma 0)"
awk -v r="$r" -v r0="$r0" 'BEGIN { exit !(r < 0.5 && r0 > 0.9) }' ||
  { echo "FAIL: ratchet ratios $r, $r0"; fail=$((fail+1)); }
# fields that must agree change together: a stage at 1 mm/s needs v0 and v1
# both (one alone is refused: unequal speeds need an acceleration)
check stage-speed 0 "$bin" simulate stage --out "$dir/st1" --duration-ms 5 --quiet \
  --param motion.v0_mm_per_s=1 --param motion.v1_mm_per_s=1
check stage-speed-half 1 "$bin" simulate stage --out "$dir/st2" --duration-ms 5 --quiet \
  --param motion.v0_mm_per_s=1
grep -q "accel_mm_per_s2" "$dir.err" || { echo "FAIL: stage-speed-half: $(cat "$dir.err")"; fail=$((fail+1)); }
check from-optics 0 "$bin" calib from-optics --na 0.5 --out "$dir/c.json"
check show 0 "$bin" calib show "$dir/c.json"
grep -q "view" "$dir.out" || { echo "FAIL: calib show printed no views"; fail=$((fail+1)); }
# the views' grid and the optics' (600 um lenslets x relay 1.25 / 4.86 um
# pixels = 154.32 px), which part when a sweep has taken another relay
grep -q "^views' grid 154.32 px apart (the lenslets' 600 um x the relay's 1.2500 over the pixels: 154.32 px)$" "$dir.out" ||
  { echo "FAIL: calib show's grid: $(grep grid "$dir.out")"; fail=$((fail+1)); }
# each view's line: its shift per um of depth points along its place in
# the grid, x with i and y with j (0 on the middle column or row), and the
# views (i, j) and (j, i) have their shifts swapped (a y shift printed
# from x passed every test until a mutation sweep)
awk '/^view / { i = $0; sub(/.*\(i=/, "", i); sub(/,.*/, "", i); j = $0; sub(/.*, j=/, "", j); sub(/\).*/, "", j)
       i += 0; j += 0
       s = $0; sub(/.*shift \(/, "", s); sub(/\) px.*/, "", s); split(s, d, ", ")
       n++; dx[i "," j] = d[1] + 0; dy[i "," j] = d[2] + 0
       if ((i > 0) != (d[1] > 0) || (i < 0) != (d[1] < 0) || (j > 0) != (d[2] > 0) || (j < 0) != (d[2] < 0)) bad++ }
     END { for (k in dx) { split(k, ij, ","); t = ij[2] "," ij[1]
             if (!(t in dx) || dx[k] != dy[t] || dy[k] != dx[t]) bad++ }
           exit !(n == 25 && bad == 0) }' "$dir.out" ||
  { echo "FAIL: calib show's shifts do not follow the views' places: $(sed -n 3,5p "$dir.out")"; fail=$((fail+1)); }
# each view's crop on the sensor: the paper's 5 x 5 on the EVK4 overhangs
# its 720 rows by 21-22 px top and bottom (rows j = -2, +2 at 85-86 %); on a
# 640 x 480 sensor the corner views keep 1-2 %; on 320 x 240 most are gone
for s in "1280x720:15 of 25 views wholly on the sensor, 10 partly (view 0 least: 85 %), 0 off it" \
         "640x480:9 of 25 views wholly on the sensor, 16 partly (view 0 least: 1 %), 0 off it" \
         "320x240:1 of 25 views wholly on the sensor, 8 partly (view 6 least: 14 %), 16 off it"; do
  check "from-optics-${s%%:*}" 0 "$bin" calib from-optics --sensor "${s%%:*}" --out "$dir/s.json"
  check "show-${s%%:*}" 0 "$bin" calib show "$dir/s.json"
  grep -qxF "${s#*:}" "$dir.out" || { echo "FAIL: calib show ${s%%:*}: $(tail -n 1 "$dir.out")"; fail=$((fail+1)); }
done
grep -q "view 24 .*   0 % on the sensor" "$dir.out" || { echo "FAIL: 320x240 view 24 not off"; fail=$((fail+1)); }
grep -q "view 12 .* 100 % on the sensor" "$dir.out" || { echo "FAIL: 320x240 centre view not whole"; fail=$((fail+1)); }
# a lens array turned 1.5 degrees: calib show reads the turn off the centres and the disparities
check from-optics-turned 0 "$bin" calib from-optics --mla-rotation-deg 1.5 --out "$dir/t.json"
check show-turned 0 "$bin" calib show "$dir/t.json"
grep -qxF "lens array turned +1.500 deg against the sensor's rows (by its centres), +1.500 deg (by its disparities)" "$dir.out" ||
  { echo "FAIL: calib show, turned: $(sed -n 2p "$dir.out")"; fail=$((fail+1)); }
check from-optics-turn-range 1 "$bin" calib from-optics --mla-rotation-deg 50 --out "$dir/t2.json"
check from-optics-no-out 2 "$bin" calib from-optics
check from-optics-bad-na 2 "$bin" calib from-optics --na x --out "$dir/c2.json"
check from-optics-na-range 1 "$bin" calib from-optics --na 1.5 --out "$dir/c2.json"
# A calibration the checks refuse is not written, nor written over one
# there: it was left in OUT (sixty-first session). The message names the
# key and its range, and OUT.
cp "$dir/c.json" "$dir/keep.json"
check from-optics-tiny-na 1 "$bin" calib from-optics --na 1e-300 --out "$dir/keep.json"
grep -q 'keep.json not written): key "optics.na": 1e-300 outside' "$dir.err" ||
  { echo "FAIL: from-optics-tiny-na: $(cat "$dir.err")"; fail=$((fail+1)); }
cmp -s "$dir/c.json" "$dir/keep.json" || { echo "FAIL: from-optics-tiny-na: keep.json changed"; fail=$((fail+1)); }
check from-optics-small-sensor 1 "$bin" calib from-optics --sensor 16x16 --out "$dir/s16.json"
[ ! -e "$dir/s16.json" ] || { echo "FAIL: from-optics-small-sensor wrote s16.json"; fail=$((fail+1)); }
[ -z "$(ls "$dir" | grep '\.tmp$')" ] || { echo "FAIL: from-optics left $(ls "$dir" | grep '\.tmp$')"; fail=$((fail+1)); }
check from-optics-no-dir 1 "$bin" calib from-optics --out "$dir/none/c.json"
grep -q "none/c.json: cannot create" "$dir.err" || { echo "FAIL: from-optics-no-dir: $(cat "$dir.err")"; fail=$((fail+1)); }
check calib-bad-action 2 "$bin" calib frobnicate
check show-missing 1 "$bin" calib show "$dir/none.json"
[ $fail -eq 0 ] && echo "test_sim_cli: all passed"
rm -rf "$dir" "$dir.out" "$dir.err"
exit $fail
