#!/bin/sh
# Long tracks in bounded memory (`eventlfm track --piece-points N`): once a
# live track has N + N/4 points of its own, its oldest N are smoothed with
# N/8 points of context on each side and written (tracks.csv, and held for
# the XML files in a scratch file), and the live track drops them. The
# default (1024) is longer than any scene we simulate, so here a 0.5 s
# worm (250 frames at 500 Hz) is cut into pieces of 128 points (16 of
# context) and compared with the same run on whole tracks. Asked: pieces
# were taken; tracks.csv has the same (track, frame) rows, each once; the
# same tracks and points in summary.json, the ISBI and the TrackMate files;
# no scratch file left; alpha within 0.01 (seed 1: 0.937 whole, 0.933 in
# 12 pieces; pieces of 64, 24 of them, with the Cauchy loss 0.926). And the
# progress line says how far through the file the run is and what is left.
# Usage: track_pieces.sh BINARY
bin=$1
. "$(dirname "$0")/track_lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_usage_errors "--piece-points 10" "--piece-points -1" "--piece-points x"
simulate_or_skip "$tmp/w" worm 500 1
# the whole-track run shows its progress (stderr): how far through the file
# and the time left, "12 % (~3 s left)"
"$bin" track --calib "$tmp/w/calib.json" --events "$tmp/w/events.raw" --out "$tmp/whole" \
  --dt-us 2000 --repr integral --piece-points 0 2> "$tmp/whole.err" || { echo "FAIL: track whole"; fail=$((fail+1)); }
tr '\r' '\n' < "$tmp/whole.err" | grep -Eq 'recording, [0-9]+ % \(~[0-9]+ (s|min) left\)' ||
  { echo "FAIL: no progress with the time left:"; tr '\r' '\n' < "$tmp/whole.err" | head -3; fail=$((fail+1)); }
"$bin" score --truth "$tmp/w/truth.csv" --tracks "$tmp/whole/tracks.csv" --detections "$tmp/whole/detections.csv" \
  --calib "$tmp/w/calib.json" --json > "$tmp/whole.json" || { echo "FAIL: score whole"; fail=$((fail+1)); }
track_score "$tmp/w" "$tmp/cut" "$tmp/cut.json" --dt-us 2000 --repr integral --piece-points 128
a0=$(key "$tmp/whole.json" alpha); a1=$(key "$tmp/cut.json" alpha)
np=$(key "$tmp/cut/summary.json" track_pieces)
echo "worm 0.5 s seed 1: alpha $a0 on whole tracks, $a1 in $np pieces of 128 points"
[ -n "$np" ] && [ "$np" -ge 5 ] || { echo "FAIL: only '$np' pieces taken"; fail=$((fail+1)); }
[ "$(key "$tmp/whole/summary.json" track_pieces)" = 0 ] || { echo "FAIL: pieces with --piece-points 0"; fail=$((fail+1)); }
expect_gain "$a0" "$a1" -0.01 "pieces cost more than 0.01 alpha ($a0 -> $a1)"
rows() { tail -n +2 "$1/tracks.csv" | cut -d, -f1,2 | sort; }
rows "$tmp/whole" > "$tmp/rows.whole"
rows "$tmp/cut" > "$tmp/rows.cut"
cmp -s "$tmp/rows.whole" "$tmp/rows.cut" ||
  { echo "FAIL: tracks.csv rows (track, frame) differ: $(wc -l < "$tmp/rows.whole") whole, $(wc -l < "$tmp/rows.cut") in pieces"; fail=$((fail+1)); }
[ -z "$(uniq -d "$tmp/rows.cut")" ] || { echo "FAIL: a frame written twice for a track"; fail=$((fail+1)); }
for k in tracks track_points; do
  [ "$(key "$tmp/whole/summary.json" $k)" = "$(key "$tmp/cut/summary.json" $k)" ] ||
    { echo "FAIL: summary.json $k differ"; fail=$((fail+1)); }
done
nt=$(key "$tmp/cut/summary.json" tracks); npts=$(key "$tmp/cut/summary.json" track_points)
[ "$(grep -c '<particle>' "$tmp/cut/tracks_isbi.xml")" = "$nt" ] &&
  [ "$(grep -c '<detection ' "$tmp/cut/tracks_isbi.xml")" = "$npts" ] ||
  { echo "FAIL: ISBI XML: not one particle per track, one detection per point"; fail=$((fail+1)); }
[ "$(grep -c '<Track ' "$tmp/cut/tracks_trackmate.xml")" = "$nt" ] &&
  [ "$(grep -c '<Spot ' "$tmp/cut/tracks_trackmate.xml")" = "$npts" ] &&
  [ "$(grep -c '<Edge ' "$tmp/cut/tracks_trackmate.xml")" = $((npts - nt)) ] ||
  { echo "FAIL: TrackMate XML: not one track per track, one spot per point, edges between"; fail=$((fail+1)); }
grep -q '"pieces"' "$tmp/cut/summary.json" || { echo "FAIL: no track lists its pieces"; fail=$((fail+1)); }
[ -z "$(ls -A "$tmp/cut" | grep tmp)" ] || { echo "FAIL: scratch file left: $(ls -A "$tmp/cut")"; fail=$((fail+1)); }
[ $fail -eq 0 ] && echo "track_pieces: all passed" || echo "track_pieces: $fail failed"
[ $fail -eq 0 ]
