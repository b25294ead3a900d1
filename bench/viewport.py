"""Viewport benchmark: time to the first viewport image, to 8 and to 32 samples, time per
refinement, and update latency after a camera move and an object move, on every scene of
examples.blend, through the add-on's ViewportSession with the settings view_draw gives it
(engine.viewport_settings; the code view_update / view_draw run, without the GPU upload).

Run from the repository root (the volume examples read ./assets/*.vdb, which
scripts/render_examples.sh copies from <build>/test_vdb):

    LANTERN_LIBRARY=$PWD/build/liblantern.so blender -b --factory-startup examples.blend \\
        --python-exit-code 1 --python bench/viewport.py -- \\
        [--size 640x360] [--threads 2] [--samples 32] [--viewport-integrator FAST|RENDER] \\
        [--scenes a05_box,door] [--integrator PATH] [--out bench/results]

Per scene, the viewport looks through the scene camera at --size (Blender's own projection
matrix for that size, as a camera view gives view_draw):
  * first image: full export + BVH build + the first pass (1/4 resolution, 1 sample)
  * to 8 and to --samples samples: from the same start (export included) to the full-resolution
    image of that many samples (Sampling > Viewport > Samples = --samples)
  * refinement: seconds per full-resolution sample pass (mean between the first and the last)
  * camera move: the view turned by 1 degree, 5 times, each as soon as the previous move's first
    full-resolution pass is shown -> median time to the first image (reduced resolution, chosen
    by the session from the measured pass cost) and to the first full-resolution pass; full
    exports and BVH builds counted before and after (goal: no re-export)
  * object move: the largest mesh instance moved by 1 cm through the incremental path ->
    first image; mesh BVH builds counted (goal: none)
Times are wall-clock from the change to the image being read back by the session (polled every
millisecond). Output: OUT/viewport.json and a table on stdout. Nothing asserts.
"""
import argparse
import json
import math
import os
import sys
import time
import types

import bpy
import numpy as np
from mathutils import Matrix

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, "addon"))
import lantern  # noqa: E402
from lantern import engine  # noqa: E402
from lantern.viewport import ViewportSession, view_camera  # noqa: E402

POLL = 0.001
MOVES = 5


def camera_view(cam, depsgraph, w, h, turn=0.0):
    world = Matrix.Rotation(turn, 4, 'Z') @ cam.matrix_world if turn else cam.matrix_world
    return types.SimpleNamespace(window_matrix=cam.calc_matrix_camera(depsgraph, x=w, y=h),
                                 view_matrix=world.inverted(), is_perspective=cam.data.type != 'ORTHO')


def until(session, settings, condition, timeout=300.0):
    t0 = time.perf_counter()
    while not condition():
        session.update(settings)
        if time.perf_counter() - t0 > timeout:
            raise TimeoutError("no image within %.0f s" % timeout)
        time.sleep(POLL)
    return time.perf_counter() - t0


def bench_scene(scene, w, h, threads, samples):
    with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
        depsgraph = bpy.context.evaluated_depsgraph_get()  # made for scenes without a window
    scene.lantern.viewport_samples = samples
    settings = engine.viewport_settings(scene, w, h)
    settings.update(threads=threads)
    cam = scene.camera.evaluated_get(depsgraph)
    s = ViewportSession(lambda level, msg: None)
    out = {"integrator": scene.lantern.integrator, "viewport_integrator": engine.viewport_integrator(scene.lantern)}
    try:
        t0 = time.perf_counter()
        s.sync(depsgraph)
        if s.error:
            return {"error": s.error}
        s.set_view(view_camera(camera_view(cam, depsgraph, w, h), w, h), w, h)
        until(s, settings, lambda: s.pixels is not None)
        out["first_image_s"] = time.perf_counter() - t0
        until(s, settings, lambda: s.shown_divider == 1 and s.samples[0] >= 1)
        t1 = time.perf_counter()
        until(s, settings, lambda: s.shown_divider == 1 and s.samples[0] >= min(8, samples))
        out["to_8_samples_s"] = time.perf_counter() - t0
        until(s, settings, lambda: s.shown_divider == 1 and s.samples[0] >= samples)
        out["to_%d_samples_s" % samples] = time.perf_counter() - t0
        out["refinement_s"] = (time.perf_counter() - t1) / max(samples - 1, 1)
        out["first_divider"] = s.first_divider

        stats0, counters0 = s.scene.stats(), dict(s.counters)
        first, full = [], []
        for k in range(MOVES):  # the view turns 1 degree further each time, mid-refinement
            t0 = time.perf_counter()
            s.set_view(view_camera(camera_view(cam, depsgraph, w, h, turn=math.radians(k + 1)), w, h), w, h)
            version = s.version
            until(s, settings, lambda: s.version > version)
            first.append(time.perf_counter() - t0)
            until(s, settings, lambda: s.shown_divider == 1 and s.samples[0] >= 1)
            full.append(time.perf_counter() - t0)
        out["camera_move_first_image_s"] = float(np.median(first))
        out["camera_move_first_image_min_s"] = min(first)
        out["camera_move_first_full_pass_s"] = float(np.median(full))
        out["camera_move_full_exports"] = s.counters["full_exports"] - counters0["full_exports"]
        out["camera_move_bvh_builds"] = {k: s.scene.stats()[k] - stats0[k] for k in stats0}

        # Object move through the incremental path (what view_update does for a transform).
        instances = s.state["instances"]
        entry = next((v for v in instances.values() if v[0] is not None), None)
        if entry is None:
            return out  # no mesh (a Volume object alone)
        core_id, matrix = entry
        moved = matrix.copy()
        moved[:3, 3] += 0.01
        stats0 = s.scene.stats()
        t0 = time.perf_counter()
        s._stop()
        s.scene.set_instance_transform(core_id, moved)
        s.scene.commit()
        s._changed()
        version = s.version
        until(s, settings, lambda: s.version > version)
        out["object_move_first_image_s"] = time.perf_counter() - t0
        out["object_move_bvh_builds"] = {k: s.scene.stats()[k] - stats0[k] for k in stats0}
    finally:
        s.close()
    return out


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", default="640x360")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--samples", type=int, default=32)
    ap.add_argument("--viewport-integrator", default="FAST", choices=("FAST", "RENDER"))
    ap.add_argument("--scenes", default="")
    ap.add_argument("--integrator", default="", help="override every scene's integrator (e.g. PATH)")
    ap.add_argument("--out", default=os.path.join(REPO, "bench", "results"))
    a = ap.parse_args(argv)
    w, h = (int(x) for x in a.size.split("x"))
    lantern.register()
    names = a.scenes.split(",") if a.scenes else [s.name for s in bpy.data.scenes]
    results = {}
    for name in names:
        if a.integrator:
            bpy.data.scenes[name].lantern.integrator = a.integrator
        bpy.data.scenes[name].lantern.viewport_integrator = a.viewport_integrator
        results[name] = bench_scene(bpy.data.scenes[name], w, h, a.threads, a.samples)
        print(name, json.dumps(results[name]), flush=True)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "viewport.json"), "w") as f:
        json.dump(dict(size=[w, h], threads=a.threads, samples=a.samples, viewport_integrator=a.viewport_integrator,
                       results=results), f, indent=1)
    print("\n%-20s %-14s %9s %8s %8s %9s %11s %12s %11s %9s" % (
        "scene", "viewport", "first[ms]", "to 8[s]", "to %d[s]" % a.samples, "pass[ms]", "cam img[ms]",
        "cam pass[ms]", "obj img[ms]", "re-export"))
    for name, r in results.items():
        if "error" in r:
            print("%-20s error: %s" % (name, r["error"]))
            continue
        print("%-20s %-14s %9.1f %8.2f %8.2f %9.1f %11.1f %12.1f %11s %9d" % (
            name, r["viewport_integrator"], 1e3 * r["first_image_s"], r["to_8_samples_s"],
            r["to_%d_samples_s" % a.samples], 1e3 * r["refinement_s"], 1e3 * r["camera_move_first_image_s"],
            1e3 * r["camera_move_first_full_pass_s"],
            "%.1f" % (1e3 * r["object_move_first_image_s"]) if "object_move_first_image_s" in r else "-",
            r["camera_move_full_exports"]))


main()
