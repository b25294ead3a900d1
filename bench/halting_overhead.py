"""Overhead of the error estimate's bookkeeping: this checkout's library against a baseline library
built without it (e.g. the commit before halting landed), same scene, same settings.

    python3 bench/halting_overhead.py --library build/liblantern.so --baseline OLD/liblantern.so \
        [--repeats 3] [--out bench/results/halting_overhead.json]

The script is its own worker: each render runs in a fresh `blender -b` process that builds the test
scene (scenes/build_scenes.py), exports it with this checkout's add-on and renders through
core.Render with the given library (no halting, no adaptive sampling: only the always-on half image
and the per-pass estimate differ), printing the core's render time. Renders of the two libraries
alternate, `--repeats` each per configuration; ratios use the best time of each (other processes
only add time), both wall time and CPU time of the render (all threads; steadier on a shared
machine). Nothing asserts on time.
"""
import argparse
import json
import os
import subprocess
import sys

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
CONFIGS = [  # (scene, integrator, width, height, samples)
    ("cornell_area", "PATH", 160, 160, 64),
    ("cornell_area", "BIDIRECTIONAL", 96, 96, 16),
]


def worker(args):
    sys.path[:0] = [os.path.join(REPO, "addon"), os.path.join(REPO, "scenes")]
    import build_scenes
    import lantern
    from lantern import core, engine
    lantern.register()
    from lantern.export import export_scene
    if args.abi:
        core.ABI_VERSION = args.abi  # a baseline from before the ABI grew: it reads the prefix
        core.CHECK_LAYOUT = False  # and has no lt_abi_layout (ABI < 6)
    build_scenes.reset_file()
    scene = build_scenes.build(args.scene)
    scene.lantern.integrator = args.integrator
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    cs = core.Scene()
    export_scene(depsgraph, cs, lambda level, msg: None)
    cs.commit()
    settings = engine.render_settings(scene, args.width, args.height, [0, 0, 0, 0])
    settings.update(samples=args.samples, threads=2)
    import resource
    cpu0 = resource.getrusage(resource.RUSAGE_SELF)
    r = core.Render(cs, settings).start()
    r.wait()
    cpu1 = resource.getrusage(resource.RUSAGE_SELF)
    st = r.poll()
    cpu = (cpu1.ru_utime + cpu1.ru_stime) - (cpu0.ru_utime + cpu0.ru_stime)
    print("RESULT %.6f %.6f %d" % (st.elapsed_seconds, cpu, st.samples_done))
    r.close()
    cs.close()


def run_one(library, abi, config):
    scene, integrator, w, h, spp = config
    cmd = ["blender", "-b", "--factory-startup", "--python-exit-code", "1", "--python", __file__, "--",
           "--worker", "--scene", scene, "--integrator", integrator, "--width", str(w), "--height", str(h),
           "--samples", str(spp), "--abi", str(abi)]
    # Blender's embedded (Debian) Python must not see a pyenv interpreter this script may run under.
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYENV")}
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if ".pyenv" not in p)
    env["LANTERN_LIBRARY"] = library
    out = subprocess.run(cmd, env=env, capture_output=True, text=True)
    for line in out.stdout.splitlines():
        if line.startswith("RESULT "):
            return float(line.split()[1]), float(line.split()[2])
    raise RuntimeError("worker failed:\n" + out.stdout[-2000:] + out.stderr[-2000:])


def main(args):
    results = []
    for config in CONFIGS:
        runs = {"library": [], "baseline": []}
        for _ in range(args.repeats):
            runs["baseline"].append(run_one(args.baseline, args.baseline_abi, config))
            runs["library"].append(run_one(args.library, 0, config))
        best = {k: (min(w for w, _ in v), min(c for _, c in v)) for k, v in runs.items()}
        wall_ratio = best["library"][0] / best["baseline"][0]
        cpu_ratio = best["library"][1] / best["baseline"][1]
        results.append(dict(scene=config[0], integrator=config[1], size=config[2:4], samples=config[4],
                            runs_wall_cpu=runs, wall_ratio_best=wall_ratio, cpu_ratio_best=cpu_ratio))
        print("%s %s %dx%d %d spp: best wall %.3f s -> %.3f s (ratio %.3f), best CPU %.3f s -> %.3f s "
              "(ratio %.3f)" % (config[0], config[1], config[2], config[3], config[4], best["baseline"][0],
                                best["library"][0], wall_ratio, best["baseline"][1], best["library"][1],
                                cpu_ratio))
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    p = argparse.ArgumentParser()
    p.add_argument("--worker", action="store_true")
    p.add_argument("--scene")
    p.add_argument("--integrator")
    p.add_argument("--width", type=int)
    p.add_argument("--height", type=int)
    p.add_argument("--samples", type=int)
    p.add_argument("--abi", type=int, default=0)
    p.add_argument("--library", default=os.path.join(REPO, "build", "liblantern.so"))
    p.add_argument("--baseline")
    p.add_argument("--baseline-abi", type=int, default=1)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--out", default=os.path.join(BENCH, "results", "halting_overhead.json"))
    a = p.parse_args(argv)
    worker(a) if a.worker else main(a)
