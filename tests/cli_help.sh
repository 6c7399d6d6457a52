#!/bin/sh
# Every subcommand answers --help with usage on stdout and exit 0; an unknown
# command exits 2; a stdout that cannot be written is an error (exit non-zero).
bin=$1
fail=0
for c in info convert calib simulate recon track traces score view bench demo; do
  out=$("$bin" "$c" --help 2>/dev/null) || { echo "FAIL: $c --help exited non-zero"; fail=$((fail+1)); continue; }
  case "$out" in *usage*|*Usage*) ;; *) echo "FAIL: $c --help printed no usage"; fail=$((fail+1)) ;; esac
done
"$bin" no-such-command >/dev/null 2>&1; [ $? -eq 2 ] || { echo "FAIL: unknown command did not exit 2"; fail=$((fail+1)); }
"$bin" --help | grep -q simulate || { echo "FAIL: top-level help lists no commands"; fail=$((fail+1)); }
# stdout that cannot be written (a full disk, here /dev/full): a message
# and a non-zero exit, not a silent success (an info table piped to a file
# on a full disk must not look written)
if [ -w /dev/full ]; then
  for args in "--help" "info --help"; do
    # shellcheck disable=SC2086
    "$bin" $args >/dev/full 2>"${TMPDIR:-/tmp}/cli_help.$$"; rc=$?
    [ $rc -ne 0 ] || { echo "FAIL: eventlfm $args to a full stdout exited 0"; fail=$((fail+1)); }
    grep -q "error writing standard output" "${TMPDIR:-/tmp}/cli_help.$$" ||
      { echo "FAIL: eventlfm $args to a full stdout said nothing"; fail=$((fail+1)); }
  done
  rm -f "${TMPDIR:-/tmp}/cli_help.$$"
fi
[ $fail -eq 0 ] && echo "cli_help: all subcommands answer --help"
exit $fail
