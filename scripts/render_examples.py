"""Renders every scene of the open .blend with Lantern: <out>/<scene>.exr and <out>/<scene>.png.

Run as: blender -b examples.blend --python-exit-code 1 --python scripts/render_examples.py -- OUTDIR
"""
import os
import sys
import time

import addon_utils
import bpy

out_dir = sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv else os.path.join(os.getcwd(), "renders")
os.makedirs(out_dir, exist_ok=True)
addon_utils.enable("lantern", default_set=True)

written = []
for scene in bpy.data.scenes:
    scene.render.engine = "LANTERN"
    t0, c0 = time.perf_counter(), time.process_time()
    bpy.ops.render.render(write_still=False, scene=scene.name)
    print("lantern: %s rendered in %.1f s (export and render; %.1f s of CPU time on all threads)"
          % (scene.name, time.perf_counter() - t0, time.process_time() - c0), flush=True)
    image = bpy.data.images["Render Result"]
    settings = scene.render.image_settings
    # The same render saved twice: scene-referred 32-bit float EXR, display-referred PNG.
    for file_format, depth, ext in (("OPEN_EXR", "32", "exr"), ("PNG", "8", "png")):
        settings.file_format = file_format
        settings.color_depth = depth
        settings.color_mode = "RGBA"
        path = os.path.join(out_dir, f"{scene.name}.{ext}")
        image.save_render(path, scene=scene)
        written.append(path)

print("lantern: wrote")
for p in written:
    print("  " + p)
