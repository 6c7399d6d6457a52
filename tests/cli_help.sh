#!/bin/sh
# Every subcommand answers --help with usage on stdout and exit 0; an unknown
# command exits 2.
bin=$1
fail=0
for c in info convert calib simulate recon track traces score view bench demo; do
  out=$("$bin" "$c" --help 2>/dev/null) || { echo "FAIL: $c --help exited non-zero"; fail=$((fail+1)); continue; }
  case "$out" in *usage*|*Usage*) ;; *) echo "FAIL: $c --help printed no usage"; fail=$((fail+1)) ;; esac
done
"$bin" no-such-command >/dev/null 2>&1; [ $? -eq 2 ] || { echo "FAIL: unknown command did not exit 2"; fail=$((fail+1)); }
"$bin" --help | grep -q simulate || { echo "FAIL: top-level help lists no commands"; fail=$((fail+1)); }
[ $fail -eq 0 ] && echo "cli_help: all subcommands answer --help"
exit $fail
