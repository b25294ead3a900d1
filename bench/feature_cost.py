"""Cost of a camera feature at equal samples, for PATH and BIDIRECTIONAL, in one run: the scene
rendered with the feature on against the same scene with it off.

    LANTERN_LIBRARY=build/liblantern.so blender -b --factory-startup --python bench/feature_cost.py -- \
        --feature dof|motion|motion_one|motion_sliding|motion_sponza [--repeats 3] [--width W] [--height H] \
        [--samples 64] [--threads 2] [--out FILE]

- dof: cornell_dof (scenes/build_scenes.py: F/0.05, 6 blades, anamorphic) against a pinhole. With
  a lens every camera ray draws one more 2D sample and BDPT's light tracing one per connection;
  the rays are as many, but blurred pixels make incoherent rays.
- motion_one: motion_blur_one (motion_blur with only the rotating box animated): a scene's one
  moving object, which Embree would otherwise trace without any bounds test (geometry.cpp,
  attach_moving).
- motion_sliding: motion_blur_sliding (motion_blur without the turning box's animation): objects
  that move without turning, whose motion the core bakes into world-space triangles (geometry.cpp,
  bakes_motion), and the deforming grid and the camera.
- motion_sponza: sponza_motion (the Sponza model from ../shared/assets under an area lamp, with
  every kind of motion motion_blur has: a sliding and a turning box, a bulging grid, a panning
  camera): a real model's still meshes beside Embree's motion, which the core traces in world
  space (geometry.cpp, flattens_beside_motion).
- motion: motion_blur (a translating and a rotating box, a deforming grid, a panning camera;
  shutter 1 frame, 3 motion steps) against motion blur off (everything at the shutter's centre).
  Every camera sample draws one time, moving instances traverse Embree's motion BVH (quaternion
  interpolation per instance per ray), the deforming grid's triangles are interpolated, and each
  hit on a moving object interpolates its transform for shading.

Each render goes through the engine (bpy.ops.render.render, 2 threads unless --threads: sampling a
shutter needs RenderEngine.frame_set). The ratios use the core's render time (lt_render_status.elapsed, not the
export), the process's CPU time from the core render's start to its end (the figure to trust on a
shared machine) and the whole render's wall time, best of `--repeats` each (other processes only
add time), the two settings alternating, and the median of the on/off pairs' CPU ratios. On this
shared machine a best of 3 moves by about 5 %; to see a change of 1-2 %, pin the render to one core
(`taskset -c 1 setarch -R blender ... -- --threads 1 --repeats 6`: a pair's ratio then spreads by
0.01-0.02; bench/README.md, motion blur). Nothing asserts on time.
"""
import argparse
import json
import os
import resource
import statistics
import sys

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
sys.path[:0] = [os.path.join(REPO, "addon"), os.path.join(REPO, "scenes")]


def _motion_blur(scene, on):
    scene.render.use_motion_blur = on


# feature: (scene, what it is called, switch(scene, on), default resolution)
FEATURES = {
    "dof": ("cornell_dof", "depth of field / pinhole",
            lambda scene, on: setattr(scene.camera.data.dof, "use_dof", on), (160, 160)),
    "motion": ("motion_blur", "motion blur / none", _motion_blur, (160, 107)),
    "motion_one": ("motion_blur_one", "one moving object's blur / none", _motion_blur, (160, 107)),
    "motion_sliding": ("motion_blur_sliding", "blur without turning / none", _motion_blur, (160, 107)),
    "motion_sponza": ("sponza_motion", "motion blur on Sponza / none", _motion_blur, (200, 150)),
}


def _cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def render_once(scene, integrator, args):
    import render_utils as ru
    from lantern import core, engine
    # CPU time from the core render's start (after the export and its frame changes) to the end.
    start, marks = core.Render.start, []

    def timed_start(self, *a, **k):
        marks.append(_cpu())
        return start(self, *a, **k)
    core.Render.start = timed_start
    try:
        out = ru.render(scene, ru.LANTERN, args.samples, seed=0, threads=args.threads, integrator=integrator)
    finally:
        core.Render.start = start
    cpu1 = _cpu()
    st = engine.LAST_RENDER["stats"]
    assert st.samples_done == args.samples, (st.samples_done, args.samples)
    return st.elapsed_seconds, cpu1 - marks[0], out.seconds


def main(args):
    import build_scenes
    import lantern
    lantern.register()
    name, label, switch, resolution = FEATURES[args.feature]
    width, height = args.width or resolution[0], args.height or resolution[1]
    build_scenes.reset_file()
    scene = build_scenes.build(name, resolution=(width, height))
    results = []
    for integrator in ("PATH", "BIDIRECTIONAL"):
        times = {"on": [], "off": []}
        for _ in range(args.repeats):
            for key in ("on", "off"):
                switch(scene, key == "on")
                times[key].append(render_once(scene, integrator, args))
        best = {k: tuple(min(t[i] for t in v) for i in range(3)) for k, v in times.items()}
        pair_ratios = sorted(on[1] / off[1] for on, off in zip(times["on"], times["off"]))
        row = dict(integrator=integrator, runs=times, best=best, pair_cpu_ratio_median=statistics.median(pair_ratios),
                   core_ratio=best["on"][0] / best["off"][0], cpu_ratio=best["on"][1] / best["off"][1],
                   wall_ratio=best["on"][2] / best["off"][2])
        results.append(row)
        print("%-13s %s: core %.3f (%.2f s / %.2f s), CPU %.3f (%.2f s / %.2f s), whole render %.3f, "
              "CPU pairs' median %.3f"
              % (integrator, label, row["core_ratio"], best["on"][0], best["off"][0], row["cpu_ratio"],
                 best["on"][1], best["off"][1], row["wall_ratio"], row["pair_cpu_ratio_median"]))
    out = args.out or os.path.join(BENCH, "results", "%s_cost.json" % args.feature)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        json.dump(dict(feature=args.feature, width=width, height=height, samples=args.samples, threads=args.threads,
                   results=results),
                  f, indent=1)


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--feature", choices=sorted(FEATURES), required=True)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--width", type=int, default=0)
    p.add_argument("--height", type=int, default=0)
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default=None)
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    main(p.parse_args(argv))
