#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh), then renders every scene of examples.blend with Lantern in
# `blender -b`, writing renders/<scene>.exr (32-bit float) and renders/<scene>.png.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p renders
# The volume examples read small .vdb files the build generates, from ./assets next to the .blend.
mkdir -p assets
cp "${LANTERN_BUILD_DIR:-build}"/test_vdb/cloud.vdb "${LANTERN_BUILD_DIR:-build}"/test_vdb/smoke.vdb assets/
blender -b examples.blend --python-exit-code 1 --python scripts/render_examples.py -- "$PWD/renders"
