"""Child Blender for test_memory.py: renders a frame too large for a capped address space.

    blender -b --factory-startup --python-exit-code 1 --python blender_memory_child.py -- W H LIMIT_MIB

Caps this process's address space (RLIMIT_AS) at what it uses plus LIMIT_MIB, renders
cornell_area at W x H with Lantern through bpy.ops.render.render, and prints one line
"RESULT {json}"; the engine prints its error ("Lantern: error: ...", also reported to Blender).
Run in its own process: the cap is for good.
"""
import json
import os
import resource
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
for path in (os.path.join(REPO, "scenes"), HERE, os.path.join(REPO, "addon")):
    if path not in sys.path:
        sys.path.insert(0, path)

import bpy  # noqa: E402

import build_scenes  # noqa: E402
import lantern  # noqa: E402

w, h, limit_mib = (int(a) for a in sys.argv[sys.argv.index("--") + 1:][:3])
lantern.register()
scene = build_scenes.build("cornell_area")
scene.render.engine = "LANTERN"
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
scene.lantern.samples = 1
with open("/proc/self/statm") as f:
    in_use = int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
resource.setrlimit(resource.RLIMIT_AS, (in_use + (limit_mib << 20), resource.RLIM_INFINITY))
try:
    bpy.ops.render.render(scene=scene.name)
    raised = ""
except RuntimeError as e:  # an operator that reported an error raises in background mode
    raised = str(e)
print("RESULT " + json.dumps({"raised": raised, "result": lantern.engine.LAST_RENDER.get("report", "")}))
