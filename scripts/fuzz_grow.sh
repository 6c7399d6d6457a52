#!/bin/bash
# fuzz_grow.sh — grow the fuzz targets' corpora and keep them in
# fuzz/grown_corpus.tar.gz, which .ci/run's short runs start from.
#
# Why: CI gives each target 30 s. From the few hand-made seeds in
# fuzz/corpus/ that is spent rediscovering the formats' structure; from a
# corpus grown for minutes each, the 30 s start where the long run ended.
# The seeds stay as they are (they document the formats); the grown inputs
# live in one archive (a few hundred kB instead of thousands of files).
#
# Usage: scripts/fuzz_grow.sh [SECONDS]   (default 240 per target)
#   needs build-fuzz/ (clang, -DELFM_FUZZ=ON: see .ci/run), runs the
#   targets one after another, each from the seeds, the archive's inputs and
#   what it finds; then keeps only the inputs that add coverage (-merge=1)
#   and writes the archive again (sorted names, fixed times: the same inputs
#   give the same bytes). A crash stops the script with the target's log.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-240}
archive=fuzz/grown_corpus.tar.gz
work=$(mktemp -d /tmp/elfm_fuzz_grow.XXXXXX)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/old" "$work/new"
[ -f "$archive" ] && tar -C "$work/old" -xzf "$archive"
targets=()
for f in build-fuzz/fuzz/fuzz_*; do [ -x "$f" ] && targets+=("$f"); done
[ "${#targets[@]}" -gt 0 ] || { echo "fuzz_grow: no targets in build-fuzz/fuzz (see .ci/run)" >&2; exit 1; }
for f in "${targets[@]}"; do
  name=$(basename "$f")
  mkdir -p "$work/run/$name" "$work/old/$name" "$work/new/$name"
  echo "fuzz_grow: $name for $secs s" >&2
  if ! "$f" -max_total_time="$secs" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
       -artifact_prefix="$work/" "$work/run/$name" "fuzz/corpus/$name" "$work/old/$name" \
       > "$work/$name.log" 2>&1; then
    tail -n 30 "$work/$name.log" >&2
    echo "fuzz_grow: $name failed; the input is in $work (kept)" >&2
    trap - EXIT
    exit 1
  fi
  "$f" -merge=1 -max_len=65536 "$work/new/$name" "fuzz/corpus/$name" "$work/old/$name" \
       "$work/run/$name" > "$work/$name.merge.log" 2>&1
  echo "fuzz_grow: $name: $(ls "$work/new/$name" | wc -l) inputs kept" >&2
done
(cd "$work/new" && tar -czf - --sort=name --mtime=@0 --owner=0 --group=0 --numeric-owner fuzz_*) > "$archive"
echo "fuzz_grow: wrote $archive ($(stat -c %s "$archive") bytes)" >&2
