"""Cost of depth of field: the cornell_dof scene (scenes/build_scenes.py: F/0.05, 6 blades,
anamorphic) against the same scene with depth of field off, at equal samples, for PATH and
BIDIRECTIONAL, in one run.

    LANTERN_LIBRARY=build/liblantern.so blender -b --factory-startup --python bench/dof_cost.py -- \
        [--repeats 3] [--width 160] [--height 160] [--samples 64] [--out bench/results/dof_cost.json]

Each configuration exports the scene with this checkout's add-on and renders through core.Render
(2 threads); the two cameras alternate, `--repeats` renders each, and the ratio uses the best
time of each (other processes only add time), both wall time and CPU time of the render. With a
lens every camera ray draws one more 2D sample and BDPT's light tracing one per connection; the
rays themselves are as many, but blurred pixels make incoherent rays. Nothing asserts on time.
"""
import argparse
import json
import os
import resource
import sys

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
sys.path[:0] = [os.path.join(REPO, "addon"), os.path.join(REPO, "scenes")]


def render_once(scene, integrator, args):
    from lantern import core, engine
    from lantern.export import export_scene
    scene.lantern.integrator = integrator
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    cs = core.Scene()
    export_scene(depsgraph, cs, lambda level, msg: None)
    cs.commit()
    settings = engine.render_settings(scene, args.width, args.height, [0, 0, 0, 0])
    settings.update(samples=args.samples, threads=2)
    cpu0 = resource.getrusage(resource.RUSAGE_SELF)
    r = core.Render(cs, settings).start()
    r.wait()
    cpu1 = resource.getrusage(resource.RUSAGE_SELF)
    st = r.poll()
    r.close()
    cs.close()
    assert st.samples_done == args.samples, (st.samples_done, args.samples)
    return st.elapsed_seconds, (cpu1.ru_utime + cpu1.ru_stime) - (cpu0.ru_utime + cpu0.ru_stime)


def main(args):
    import build_scenes
    import lantern
    lantern.register()
    build_scenes.reset_file()
    scene = build_scenes.build("cornell_dof")
    results = []
    for integrator in ("PATH", "BIDIRECTIONAL"):
        times = {"dof": [], "pinhole": []}
        for _ in range(args.repeats):
            for key in ("dof", "pinhole"):
                scene.camera.data.dof.use_dof = key == "dof"
                times[key].append(render_once(scene, integrator, args))
        best = {k: (min(t[0] for t in v), min(t[1] for t in v)) for k, v in times.items()}
        row = dict(integrator=integrator, runs=times, best=best,
                   wall_ratio=best["dof"][0] / best["pinhole"][0], cpu_ratio=best["dof"][1] / best["pinhole"][1])
        results.append(row)
        print("%-13s depth of field / pinhole: wall %.3f (%.2f s / %.2f s), CPU %.3f (%.2f s / %.2f s)"
              % (integrator, row["wall_ratio"], best["dof"][0], best["pinhole"][0], row["cpu_ratio"],
                 best["dof"][1], best["pinhole"][1]))
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            json.dump(dict(width=args.width, height=args.height, samples=args.samples, results=results), f, indent=1)


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--width", type=int, default=160)
    p.add_argument("--height", type=int, default=160)
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--out", default=os.path.join(BENCH, "results", "dof_cost.json"))
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    main(p.parse_args(argv))
