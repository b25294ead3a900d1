#!/bin/sh
# Builds the library (Release, build-bench/) and runs the convergence benchmark in Blender; writes
# bench/results/convergence.json, convergence_<scene>*.png and convergence.log (or into --out DIR).
# Extra arguments go to convergence.py, e.g.: bench/run_convergence.sh --quick
# Installs Debian's python3-matplotlib (Blender's Python sees it) for the plots when it is missing.
set -eu
REPO=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${LANTERN_BENCH_BUILD:-$REPO/build-bench}
BLENDER=${BLENDER:-blender}
RESULTS=$REPO/bench/results
bash "$REPO/scripts/install_packages.sh" python3-matplotlib
cmake -S "$REPO" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD" -j2 --target lantern_shared
OUT=$RESULTS  # convergence.py's --out, if given, also takes the log
prev=
for a in "$@"; do
  [ "$prev" = "--out" ] && OUT=$a
  prev=$a
done
mkdir -p "$OUT"
LANTERN_LIBRARY="$BUILD/liblantern.so" "$BLENDER" -b --factory-startup --python-exit-code 1 \
  --python "$REPO/bench/convergence.py" -- --out "$RESULTS" "$@" \
  2>&1 | tee "$OUT/convergence.log" | grep --line-buffered -E '^(bench:|====|scene |[a-z_]+ +(wall|cpu)_|Goal|Load|Wrote|Error|Traceback|  )'
