"""Child Blender for test_cancel.py: renders with Lantern and presses Esc the background-mode way.

    blender -b --factory-startup --python-exit-code 1 --python blender_cancel_child.py -- AFTER

In background mode Blender turns the first SIGINT into an internal break (G.is_break, which
RenderEngine.test_break() reports) and kills itself on the second, so this runs in its own
process. Prints one line "RESULT {json}".
"""
import json
import os
import signal
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
for path in (os.path.join(REPO, "scenes"), HERE, os.path.join(REPO, "addon")):
    if path not in sys.path:
        sys.path.insert(0, path)

import numpy as np  # noqa: E402

import build_scenes  # noqa: E402
import lantern  # noqa: E402
import render_utils as ru  # noqa: E402

after = float(sys.argv[sys.argv.index("--") + 1])
lantern.register()
scene = build_scenes.build("cornell_area")
scene.view_layers[0].lantern_extra_passes = True  # the Sample Count pass
total = 1 << 20
state = {}


def esc():
    state["esc"] = time.monotonic()
    os.kill(os.getpid(), signal.SIGINT)


threading.Timer(after, esc).start()
out = ru.render(scene, ru.LANTERN, total, seed=0)
done = time.monotonic()
combined = out.combined
counts = out["Sample Count"][..., 0] if "Sample Count" in out else np.zeros(1)
print("RESULT " + json.dumps({
    "status": sorted(out.status),
    "stopped_after_esc": done - state.get("esc", done),
    "samples_total": total,
    "samples_min": float(counts.min()),
    "samples_max": float(counts.max()),
    "finite": bool(np.isfinite(combined).all()),
    "mean": float(combined[..., :3].mean()),
}), flush=True)
