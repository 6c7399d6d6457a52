#!/bin/bash
# measure_memory.sh — peak memory of `eventlfm track` against the length of
# the recording, with long tracks written in pieces (the default,
# --piece-points 1024) and whole (--piece-points 0): docs/tracker.md "Long
# tracks in bounded memory". A 20 s worm (10,000 frames at 500 Hz, 12
# neurons; the scene's crawl slowed so that the worms stay in the field),
# tracked on one thread up to 5, 10 and 20 s (/usr/bin/time -v), then
# scored. ~15 minutes here. EVENTLFM=path/to/eventlfm OUT=dir to change;
# SECONDS_LIST="5 20" for fewer lengths.
set -eu
B=${EVENTLFM:-$(cd "$(dirname "$0")/.." && pwd)/build/eventlfm}
M=${OUT:-/tmp/eventlfm_memory}; mkdir -p "$M"
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (Debian package \"time\")"; exit 1; }
d=$M/worm20s
[ -s "$d/events.raw" ] ||
  "$B" simulate worm --seed 1 --duration-ms 20000 --param motion.crawl_mm_per_s=0.002 --out "$d" --quiet
t0=$("$B" info "$d/events.raw" | awk '$1 == "first" { print $3 }')   # the first event, us
printf "%-14s %8s %12s %10s\n" pieces seconds peak_rss_mb alpha
for pp in 1024 0; do
  for s in ${SECONDS_LIST:-5 10 20}; do
    o=$M/t_pp${pp}_${s}s
    /usr/bin/time -v "$B" track --calib "$d/calib.json" --events "$d/events.raw" --out "$o" \
      --dt-us 2000 --repr integral --threads 1 --quiet --piece-points $pp \
      --to-us $((t0 + s * 1000000)) 2> "$o.time"
    rss=$(awk '/Maximum resident/ { printf "%.1f", $NF / 1024 }' "$o.time")
    a=-
    if [ "$s" = 20 ]; then
      a=$("$B" score --truth "$d/truth.csv" --tracks "$o/tracks.csv" --calib "$d/calib.json" --json |
        tr ',' '\n' | sed -n 's/.*"alpha":\([0-9.]*\).*/\1/p')
    fi
    printf "%-14s %8s %12s %10s\n" "$pp" "$s" "$rss" "$a"
  done
done
