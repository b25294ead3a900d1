#!/usr/bin/env bash
# Builds everything (scripts/setup.sh), checks the style (scripts/check_style.sh) and runs the whole
# test suite: the native GoogleTest suite under ctest, then the add-on's pytest suite inside
# `blender -b`, then the sanitizer builds and bounded fuzzing (scripts/run_sanitizers.sh). Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
echo "== style (scripts/check_style.sh) =="
bash scripts/check_style.sh
BUILD_DIR=${LANTERN_BUILD_DIR:-build}

echo "== native tests (ctest) =="
(cd "$BUILD_DIR" && ctest --output-on-failure -j2 "$@")

echo "== Blender tests (pytest inside blender -b) =="
# The tests use this checkout's add-on and library, not an installed copy.
export LANTERN_LIBRARY="$PWD/$BUILD_DIR/liblantern.so"
export LANTERN_TEST_VDB_DIR="$PWD/$BUILD_DIR/test_vdb"  # .vdb files the build generates
blender -b --factory-startup --python-exit-code 1 --python tests/blender/run_pytest.py -- -q

echo "== sanitizers and fuzzing (scripts/run_sanitizers.sh) =="
bash scripts/run_sanitizers.sh
