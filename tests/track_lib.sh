# track_lib.sh — helpers the `eventlfm track` shell tests share (sourced).

# key FILE KEY: the number after "KEY": in a JSON file (summary.json, or
# `eventlfm score --json` output); empty when absent.
key() {
  tr ',{}' '\n\n\n' < "$1" | sed -n "s/^[[:space:]]*\"$2\":[[:space:]]*//p" | head -1
}

# The awk test the comparisons below share: num(x) is 1 when x is a number.
# awk compares a word (a JSON null, an empty key) with a number as text,
# and "null" > "0.9": a null once passed a check (at_least).
AWK_NUM='function num(x) { return x != "" && x == x + 0 }'

# expect_gain A B M MESSAGE: B > A + M (floating point, by awk; a negative
# M: B may fall below A by less than -M), both numbers; otherwise print
# "FAIL: MESSAGE" and count it in $fail.
expect_gain() {
  awk -v a="$1" -v b="$2" -v m="$3" "$AWK_NUM"' BEGIN { exit !(num(a) && num(b) && b > a + m) }' ||
    { echo "FAIL: $4"; fail=$((fail+1)); }
}

# expect_key KEY FILE VALUE: the number KEY in FILE (key, above) is VALUE
# to 1e-3; otherwise print a failure and count it in $fail.
expect_key() {
  ex_v=$(key "$2" "$1")
  awk -v a="$ex_v" -v b="$3" "$AWK_NUM"' BEGIN { exit !(num(a) && a - b < 1e-3 && b - a < 1e-3) }' ||
    { echo "FAIL: $1 in $2 is '$ex_v', not $3"; fail=$((fail+1)); }
}

# expect_string FILE KEY VALUE: the JSON string KEY in FILE is "VALUE";
# otherwise print a failure and count it in $fail.
expect_string() {
  [ "$(key "$1" "$2")" = "\"$3\"" ] || { echo "FAIL: $2 in $1 is $(key "$1" "$2"), not $3"; fail=$((fail+1)); }
}

# below A F B: true when A < F x B (floating point, by awk); false when A or
# B is not a number (a JSON null, an empty key).
below() {
  awk -v a="$1" -v f="$2" -v b="$3" "$AWK_NUM"' BEGIN { exit !(num(a) && num(b) && a < f * b) }'
}

# at_least A B: true when A is a number >= B (not `! below`, which a JSON
# null or an empty key passed: track_turning's judged miss written as null
# went unseen until a mutation sweep).
at_least() {
  awk -v a="$1" -v b="$2" "$AWK_NUM"' BEGIN { exit !(num(a) && a >= b) }'
}

# simulate_or_skip DIR SCENE MS SEED [simulate options...]: `eventlfm
# simulate SCENE` for MS ms into DIR; the test is skipped (exit 77) when
# that fails. Uses $bin.
simulate_or_skip() {
  sos_dir=$1; sos_scene=$2; sos_ms=$3; sos_seed=$4; shift 4
  "$bin" simulate "$sos_scene" --out "$sos_dir" --duration-ms "$sos_ms" --seed "$sos_seed" --quiet "$@" >/dev/null 2>&1 ||
    { echo "SKIP: simulate $sos_scene failed"; exit 77; }
}

# track_score SCENE OUT JSON [track options...]: `eventlfm track` on the
# simulated scene in directory SCENE into OUT, then `eventlfm score --json`
# of OUT's tracks and detections into JSON, with the score options in
# $score_args when set (e.g. the window rule for blinking objects). Uses
# $bin; a failure is printed and counted in $fail.
track_score() {
  ts_sc=$1; ts_out=$2; ts_json=$3; shift 3
  "$bin" track --calib "$ts_sc/calib.json" --events "$ts_sc/events.raw" --out "$ts_out" -q "$@" ||
    { echo "FAIL: track $ts_out"; fail=$((fail+1)); }
  # shellcheck disable=SC2086
  "$bin" score --truth "$ts_sc/truth.csv" --tracks "$ts_out/tracks.csv" \
    --detections "$ts_out/detections.csv" --calib "$ts_sc/calib.json" ${score_args:-} --json \
    > "$ts_json" || { echo "FAIL: score $ts_out"; fail=$((fail+1)); }
}

# expect_usage_errors OPTION_VALUE...: each "--option value" given alone to
# `eventlfm track` exits 2 with a message naming the option. Uses $bin and
# $tmp; a failure is printed and counted in $fail.
expect_usage_errors() {
  for eu_bad in "$@"; do
    # shellcheck disable=SC2086
    "$bin" track --calib a --events b --out c $eu_bad >/dev/null 2>"$tmp/err"
    [ $? -eq 2 ] && grep -q -e "${eu_bad%% *}" "$tmp/err" ||
      { echo "FAIL: $eu_bad not a usage error"; fail=$((fail+1)); }
  done
}

# check EXIT PATTERN COMMAND...: COMMAND exits EXIT and, when PATTERN is not
# empty, its stderr holds it (grep); otherwise the command (its first 300
# characters: long_out_cli.sh's paths run to 5000) and its stderr are
# printed and the failure counted in $fail. COMMAND's output is left in
# $tmp/out and $tmp/err.
check() {
  ck_want=$1; ck_pat=$2; shift 2
  "$@" >"$tmp/out" 2>"$tmp/err"; ck_rc=$?
  if [ $ck_rc -ne "$ck_want" ]; then
    echo "FAIL: exit $ck_rc (want $ck_want): $(printf '%s' "$*" | cut -c1-300)"; head -c 2000 "$tmp/err"; echo
    fail=$((fail+1)); return
  fi
  if [ -n "$ck_pat" ] && ! grep -q -- "$ck_pat" "$tmp/err"; then
    echo "FAIL: stderr lacks '$ck_pat': $(printf '%s' "$*" | cut -c1-300)"; head -c 2000 "$tmp/err"; echo
    fail=$((fail+1))
  fi
}
