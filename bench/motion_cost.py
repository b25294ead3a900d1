"""Cost of motion blur: the motion_blur scene (scenes/build_scenes.py: a translating and a rotating
box, a deforming grid, a panning camera; shutter 1 frame, 3 motion steps) rendered with motion
blur on against the same scene with it off (everything at the shutter's centre), at equal
samples, for PATH and BIDIRECTIONAL, in one run.

    LANTERN_LIBRARY=build/liblantern.so blender -b --factory-startup --python bench/motion_cost.py -- \
        [--repeats 3] [--width 160] [--height 107] [--samples 64] [--out bench/results/motion_cost.json]

Each render goes through the engine (bpy.ops.render.render, 2 threads), since sampling the shutter
needs RenderEngine.frame_set; the ratios use the core's render time (lt_render_status.elapsed, so
not the export's frame changes), the process's CPU time from the core render's start to the end
(the figure to trust on a shared machine), and the whole render's wall time, best of
`--repeats` each, the two settings alternating. With motion every camera sample draws one time,
moving instances traverse Embree's motion BVH (quaternion interpolation per instance per ray), the
deforming grid's triangles are interpolated, and each hit on a moving object interpolates its
transform for shading. Nothing asserts on time.
"""
import argparse
import json
import os
import resource
import sys

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
sys.path[:0] = [os.path.join(REPO, "addon"), os.path.join(REPO, "scenes")]


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
        out = ru.render(scene, ru.LANTERN, args.samples, seed=0, threads=2, integrator=integrator)
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
    build_scenes.reset_file()
    scene = build_scenes.build("motion_blur", resolution=(args.width, args.height))
    results = []
    for integrator in ("PATH", "BIDIRECTIONAL"):
        times = {"motion": [], "still": []}
        for _ in range(args.repeats):
            for key in ("motion", "still"):
                scene.render.use_motion_blur = key == "motion"
                times[key].append(render_once(scene, integrator, args))
        best = {k: tuple(min(t[i] for t in v) for i in range(3)) for k, v in times.items()}
        row = dict(integrator=integrator, runs=times, best=best,
                   core_ratio=best["motion"][0] / best["still"][0], cpu_ratio=best["motion"][1] / best["still"][1],
                   wall_ratio=best["motion"][2] / best["still"][2])
        results.append(row)
        print("%-13s motion blur / none: core %.3f (%.2f s / %.2f s), CPU %.3f (%.2f s / %.2f s), whole render %.3f"
              % (integrator, row["core_ratio"], best["motion"][0], best["still"][0], row["cpu_ratio"],
                 best["motion"][1], best["still"][1], row["wall_ratio"]))
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            json.dump(dict(width=args.width, height=args.height, samples=args.samples, results=results), f, indent=1)


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--width", type=int, default=160)
    p.add_argument("--height", type=int, default=107)
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--out", default=os.path.join(BENCH, "results", "motion_cost.json"))
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    main(p.parse_args(argv))
