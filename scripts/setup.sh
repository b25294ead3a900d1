#!/usr/bin/env bash
# Installs what Lantern needs from Debian's apt (when missing), builds the native library, the CLI
# and the tests in Release, and installs the add-on where Blender finds it. Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(blender cmake g++ make libembree-dev libtbb-dev libopenexr-dev libopenimageio-dev libopencolorio-dev libopenvdb-dev libnanovdb-dev
          libboost-iostreams-dev libgtest-dev libbenchmark-dev python3-numpy python3-pytest
          # Pillow: the image-file tests write CMYK JPEG and palette TIFF/TGA files Blender cannot
          python3-pil
          # the farm end-to-end test (tests/blender/test_farm.py)
          slurmctld slurmd slurm-client munge
          # the UI test: a windowed Blender under a virtual X server with Mesa's software OpenGL
          xvfb xauth libgl1-mesa-dri libglx-mesa0 libegl-mesa0)
bash scripts/install_packages.sh "${PACKAGES[@]}"

BUILD_DIR=${LANTERN_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" -j"$(nproc)"

# Install the add-on into the user's Blender scripts folder, with the library beside it, and enable it.
SCRIPTS=$(blender -b --factory-startup --python-expr \
  "import bpy; print('LANTERN_SCRIPTS=' + bpy.utils.user_resource('SCRIPTS'))" 2>/dev/null |
  sed -n 's/^LANTERN_SCRIPTS=//p')
[ -n "$SCRIPTS" ] || { echo "lantern: could not ask Blender for its scripts folder" >&2; exit 1; }
DEST="$SCRIPTS/addons/lantern"
rm -rf "$DEST"
mkdir -p "$DEST"
cp -r addon/lantern/. "$DEST/"
find "$DEST" -name __pycache__ -prune -exec rm -rf {} +
cp "$BUILD_DIR/liblantern.so" "$DEST/"
blender -b --python-expr "import bpy; bpy.ops.preferences.addon_enable(module='lantern'); bpy.ops.wm.save_userpref()" \
  >/dev/null 2>&1
echo "lantern: add-on installed in $DEST and enabled"
