#!/usr/bin/env bash
# Builds everything (scripts/setup.sh), checks the style (scripts/check_style.sh) and runs the whole
# test suite: the add-on's pytest suite inside `blender -b` beside, on the other core, the native
# GoogleTest suite under ctest and then the sanitizer builds and bounded fuzzing
# (scripts/run_sanitizers.sh). Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
echo "== style (scripts/check_style.sh) =="
bash scripts/check_style.sh
BUILD_DIR=${LANTERN_BUILD_DIR:-build}

echo "== Blender tests (pytest inside blender -b) beside the native tests, sanitizers and fuzzing =="
# Side by side: the Blender suite keeps about one core busy on average (scene building, export,
# Python and Cycles' sync between its renders: measured 21 CPU minutes in 20 wall minutes on the
# 2-core machine), so the native suite, then the sanitizers, run in the rest. The Blender suite's
# output is shown when all are done.
# The tests use this checkout's add-on and library, not an installed copy.
export LANTERN_LIBRARY="$PWD/$BUILD_DIR/liblantern.so"
export LANTERN_TEST_VDB_DIR="$PWD/$BUILD_DIR/test_vdb"  # .vdb files the build generates
BLENDER_LOG="$BUILD_DIR/blender_tests.log"
blender -b --factory-startup --python-exit-code 1 --python tests/blender/run_pytest.py -- -q --durations=25 >"$BLENDER_LOG" 2>&1 &
blender_pid=$!
echo "== native tests (ctest) =="
native=0
(cd "$BUILD_DIR" && ctest --output-on-failure -j2 "$@") || native=$?
echo "== sanitizers and fuzzing (scripts/run_sanitizers.sh) =="
sanitizers=0
bash scripts/run_sanitizers.sh || sanitizers=$?
blender=0
wait "$blender_pid" || blender=$?
echo "== Blender tests (pytest inside blender -b; $BLENDER_LOG) =="
cat "$BLENDER_LOG"
if [ "$native" -ne 0 ] || [ "$sanitizers" -ne 0 ] || [ "$blender" -ne 0 ]; then
  echo "native tests exit $native, sanitizers exit $sanitizers, Blender tests exit $blender" >&2
  exit 1
fi
