#!/bin/sh
# Builds the library and embree_raw (Release, build-bench/) and runs the throughput benchmark in
# Blender; writes bench/results/throughput.json and bench/results/throughput.log.
# Extra arguments go to cornell_throughput.py, e.g.: bench/run_throughput.sh --samples 128
set -eu
REPO=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${LANTERN_BENCH_BUILD:-$REPO/build-bench}
BLENDER=${BLENDER:-blender}
RESULTS=$REPO/bench/results
cmake -S "$REPO" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DLANTERN_BUILD_BENCH=ON >/dev/null
cmake --build "$BUILD" -j2 --target lantern_shared embree_raw
mkdir -p "$RESULTS"
LANTERN_LIBRARY="$BUILD/liblantern.so" "$BLENDER" -b --factory-startup --python-exit-code 1 \
  --python "$REPO/bench/cornell_throughput.py" -- \
  --embree-raw "$BUILD/bench/embree_raw" --out "$RESULTS/throughput.json" "$@" \
  2>&1 | tee "$RESULTS/throughput.log" | grep -E '^(bench:|====|Cycles|Lantern|Ratio|Raw|Goals|Load|Wrote|Error|Traceback|  )'
