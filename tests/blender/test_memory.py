"""Bounded memory through Blender (issue 18): a render that cannot fit is refused before it
allocates, with a message Blender shows, and Blender goes on (no abort, no kill)."""
import json
import os
import subprocess

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))


def _child(width, height, limit_mib):
    proc = subprocess.run(
        [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
         "--python", os.path.join(HERE, "blender_memory_child.py"), "--",
         str(width), str(height), str(limit_mib)],
        capture_output=True, text=True, timeout=300, env=dict(os.environ))
    # Blender exits with 1 after an operator's error report even when the script ran through: the
    # RESULT line (printed last) tells that it did; a signal (abort, kill) gives a negative code.
    lines = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
    assert proc.returncode in (0, 1) and lines, "exit %d\n%s\n%s" % (
        proc.returncode, proc.stdout[-3000:], proc.stderr[-3000:])
    errors = [l for l in proc.stdout.splitlines() if l.startswith("Lantern: error: ")]
    return errors, json.loads(lines[-1][len("RESULT "):])


def test_render_too_large_for_the_address_space_is_refused_with_a_message():
    # 8000 x 8000 with the default passes needs about 5.5 GiB (film, Blender's RenderResult and
    # the add-on's buffer); the child may allocate 1 GiB more than it holds.
    errors, r = _child(8000, 8000, 1024)
    assert errors, r
    assert "8000x8000 render needs about" in errors[0] and "is available" in errors[0], errors
    assert "needs about" in r["raised"], r  # what Blender shows: the operator's error report
    # The same cap leaves room for a frame that fits.
    errors, r = _child(64, 64, 1024)
    assert not errors and "result:" in r["result"], (errors, r)


def test_byte_images_are_kept_at_8_bits_and_reported(scene_factory):
    """The textured scene's two packed 8-bit images (sRGB and Non-Color) reach the core as
    Blender's b / 255 values and are kept as 3 bytes a texel (alpha dropped); the report says so."""
    import render_utils as ru
    from lantern import engine
    scene = scene_factory("textured")
    ru.render(scene, ru.LANTERN, 1, seed=0)
    line = [l for l in engine.LAST_RENDER["report"].splitlines() if l.startswith("texture memory:")]
    assert line == ["texture memory: 0.0 MiB for 2 image(s), 2 of them 8-bit, 0 read from their files "
                    "(3.00 bytes per texel)"], line
