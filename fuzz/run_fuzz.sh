#!/bin/sh
# Runs the given fuzz targets one after another, each for $SECS seconds, at lowest priority.
# Usage: ./run_fuzz.sh SECS target...
SECS=$1; shift
cd "$(dirname "$0")"
mkdir -p fuzzlogs
for t in "$@"; do
  echo "start $t $(date -u +%H:%M:%S)" >> fuzzlogs/runs.txt
  nice -n 19 cargo +nightly fuzz run "$t" -a -- -max_total_time="$SECS" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    > "fuzzlogs/$t.log" 2>&1
  echo "end $t rc=$? $(date -u +%H:%M:%S)" >> fuzzlogs/runs.txt
done
