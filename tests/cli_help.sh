#!/bin/sh
# Every subcommand answers --help with usage on stdout and exit 0; an unknown
# command exits 2; a stdout that cannot be written is an error (exit non-zero);
# every long option is named in its command's help (with the source folder
# as $2).
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
# Every long option a command's parser takes (its getopt table, read from
# the source, $2) is named in its --help: an option added without a line
# there, or a line renamed, is an option no user finds (view's --colour,
# an alias, was missing until the sixty-ninth session)
src=${2:-}
if [ -n "$src" ] && [ -d "$src/cli" ]; then
  named() { # command words ..., --, source files
    cmd=""
    while [ "$1" != "--" ]; do cmd="$cmd $1"; shift; done
    shift
    # shellcheck disable=SC2086 # cmd: the command's words
    help=$("$bin" $cmd --help 2>/dev/null)
    # (option names are single words: a loop over words is a loop over lines)
    # shellcheck disable=SC2013
    for o in $(cat "$@" | grep -o '{"[a-z0-9-]*", *[a-z]*_argument' | sed 's/{"\([a-z0-9-]*\)".*/\1/' | sort -u); do
      [ "$o" = help ] && continue
      printf '%s\n' "$help" | grep -q -e "--$o\b" ||
        { echo "FAIL: eventlfm$cmd --help does not name --$o"; fail=$((fail+1)); }
    done
  }
  named track -- "$src/cli/cmd_track_opts.c" "$src/cli/cli.h"
  named recon -- "$src/cli/cmd_recon.c" "$src/cli/cli.h"
  named calib refine -- "$src/cli/cmd_calib_refine.c" "$src/cli/cli.h"
  named calib from-optics -- "$src/cli/cmd_calib.c"
  for c in score simulate traces view bench convert info demo; do named $c -- "$src/cli/cmd_$c.c"; done
  # the table was read: track has dozens of options
  n=$(grep -o '{"[a-z0-9-]*", *[a-z]*_argument' "$src/cli/cmd_track_opts.c" | wc -l)
  [ "$n" -gt 50 ] || { echo "FAIL: $n options read from cmd_track_opts.c"; fail=$((fail+1)); }
else
  echo "SKIP the options' check: no source folder given"
fi
[ $fail -eq 0 ] && echo "cli_help: all subcommands answer --help"
exit $fail
