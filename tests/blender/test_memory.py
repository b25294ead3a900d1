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
    # 8000 x 8000 with the default passes needs about 4 GiB (film and Blender's RenderResult; the
    # add-on's buffers are a band of rows); the child may allocate 1 GiB more than it holds.
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


def test_8k_png_texture_is_held_once_near_cycles_bytes_per_texel(tmp_path):
    """An 8192 x 8192 8-bit RGB PNG on the floor, measured as bench/memory.py measures it (peak
    resident memory of a fresh blender -b, less that of the same scene with a 64 x 64 image, per
    texel). The core reads the file itself (Blender never loads it) and keeps 3 bytes a texel.
    Cycles 3.4, which also reads files itself, measured 4.0 bytes a texel (bench/README.md);
    Lantern made Blender load the image and copied its float pixels: 22.8. Bound: Cycles' 4.0
    plus 1 byte a texel (64 MiB) for the allocator's state and the process's other noise."""
    import argparse
    import sys

    import numpy as np

    import render_utils as ru
    from lantern import core
    bench = os.path.join(os.path.dirname(os.path.dirname(HERE)), "bench")
    sys.path.insert(0, bench)
    try:
        import memory as membench
    finally:
        sys.path.remove(bench)
    paths = {}
    for n in (64, 8192):
        ramp = np.linspace(0, 255, n).astype(np.uint8)
        rgb = np.empty((n, n, 3), np.uint8)
        rgb[..., 0] = ramp[None, :]
        rgb[..., 1] = ramp[:, None]
        rgb[..., 2] = 128
        paths[n] = str(tmp_path / ("memtex_%d.png" % n))
        ru.write_png_values(paths[n], rgb, level=1)
        del rgb
    args = argparse.Namespace(library=core.library_path())
    small = membench.run(args, engine="lantern", size="256x256", image=paths[64])
    big = membench.run(args, engine="lantern", size="256x256", image=paths[8192])
    per_texel = (big["peak_bytes"] - small["peak_bytes"]) / (8192.0 ** 2 - 64 ** 2)
    assert per_texel <= 4.0 + 1.0, "%.1f bytes a texel (peaks %.2f and %.2f GiB)" % (
        per_texel, big["peak_bytes"] / 2.0 ** 30, small["peak_bytes"] / 2.0 ** 30)
    assert "1 read from their files" in big.get("report", ""), big
