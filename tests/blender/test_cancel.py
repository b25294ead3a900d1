"""Esc during a final render in background mode: Blender's own break path, end to end.

The first SIGINT to a background Blender sets its break flag (what the UI's Esc sets), so
RenderEngine.test_break() turns true; the add-on must cancel the core and hand back the partial
image, which Blender still writes. Runs in a child Blender (a second SIGINT would kill this one).
"""
import json
import os
import subprocess

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))


def test_escape_in_background_render_keeps_a_partial_image():
    after = 1.5
    proc = subprocess.run(
        [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
         "--python", os.path.join(HERE, "blender_cancel_child.py"), "--", str(after)],
        capture_output=True, text=True, timeout=120, env=dict(os.environ))
    # A background Blender that received a break exits with status 1 even when its script ran
    # through, so the RESULT line (printed last) is what tells the child succeeded.
    lines = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
    assert lines, "exit %d\n%s\n%s" % (proc.returncode, proc.stdout[-3000:], proc.stderr[-3000:])
    r = json.loads(lines[-1][len("RESULT "):])
    assert r["stopped_after_esc"] < 1.0, r
    assert 0 < r["samples_min"] <= r["samples_max"] < r["samples_total"], r
    assert r["finite"] and r["mean"] > 0.01, r
