"""The cost of volume emission's code paths for scenes without emitting grids: renders
"vdb_cloud" (scenes/build_scenes.py; no emission) with Lantern VOLPATH and prints the CPU time of
the Blender process (time.process_time, all threads) and the wall time per render.

Compare two builds by running this script once per build, alternating, each with its own add-on
and library (the scene builder is this tree's):

    git archive main addon | tar -x -C /tmp/base      # the baseline add-on
    LANTERN_LIBRARY=<base build>/liblantern.so LANTERN_TEST_VDB_DIR=$PWD/build/test_vdb \\
        blender -b --factory-startup --python bench/volume_emission_cost.py -- --addon /tmp/base/addon
    LANTERN_LIBRARY=$PWD/build/liblantern.so LANTERN_TEST_VDB_DIR=$PWD/build/test_vdb \\
        blender -b --factory-startup --python bench/volume_emission_cost.py --

Options: --samples (64), --reps (3), --estimator (TRACKING or RAY_MARCHING). Nothing asserts.
"""
import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="volume_emission_cost.py")
    p.add_argument("--addon", default=os.path.join(REPO, "addon"))
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--reps", type=int, default=3)
    p.add_argument("--estimator", default="TRACKING")
    args = p.parse_args(argv)
    for path in (args.addon, os.path.join(REPO, "scenes")):
        sys.path.insert(0, path)
    import bpy
    import lantern
    import build_scenes
    import render_utils as ru
    if not hasattr(bpy.types.Scene, "lantern"):
        lantern.register()
    build_scenes.reset_file()
    scene = build_scenes.build("vdb_cloud")
    scene.lantern.volume_estimator = args.estimator
    ru.render(scene, ru.LANTERN, 1, seed=0, integrator="VOLPATH")  # warm-up
    runs = []
    for rep in range(args.reps):
        c0, w0 = time.process_time(), time.perf_counter()
        img = ru.render(scene, ru.LANTERN, args.samples, seed=rep, integrator="VOLPATH").combined
        runs.append(dict(cpu=time.process_time() - c0, wall=time.perf_counter() - w0,
                         mean=[float(v) for v in img[..., :3].mean(axis=(0, 1))]))
    print("emission_cost:", json.dumps(dict(addon=args.addon, library=os.environ.get("LANTERN_LIBRARY"),
                                            samples=args.samples, estimator=args.estimator, runs=runs)))


main()
