"""Farm overhead: the fixed cost of one farm task (Blender start-up and .blend load, export, BVH
build, EXR write) against its rendering time, per example scene, and from them the parallel
efficiency of splitting a 4096-sample 1080p render into N tasks on N machines.

    python3 bench/farm_overhead.py [--build build] [--scenes a05_box,door] [--samples 16]

Each scene of examples.blend runs as a farm task does (`blender -b --factory-startup examples.blend
--scene S --python build/lantern_task.py -- --offset O --samples K --timing`): four times with K = 1,
then with K = --samples. From the last run: render time per sample r (the core's render stage / K)
and the fixed cost F = wall time - render time (everything a task pays whatever its sample count).
The merge cost per part m: (`lantern merge` of all five parts - that of one) / 4, best of 3 each.
Model for S = 4096 samples at 1920x1080 (render and
EXR write scaled by the pixel count; start-up, export and build do not depend on it):
    T(1) = F + S r,   T(N) = F + (S / N) r + M(N)
where M(N) is the merge after all tasks as `lantern farm` runs it: N m + w (one merge; w: writing
the merged EXR) up to 16 tasks, else groups of g = ceil(sqrt(N)) parts merged in parallel and then
their results, (g + ceil(N / g)) m + 2 w. Speedup T(1) / T(N), efficiency speedup / N; the table
gives the first N where it falls below 50% and, for comparison, where the fixed cost alone would
put it, (S r + 2 F) / F.
Slurm's own scheduling and launch (about 2 s per batch of tasks, see the farm note) come on top.
Writes bench/results/farm_overhead.json and prints the table. Nothing asserts on time.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
SCENES = ["a05_box", "glossy_glass", "door", "caustic", "a05_smoke_debug", "a05_cloud_march",
          "a05_cloud_track", "a05_smoke_interior"]
TARGET_PIXELS, TARGET_SAMPLES, TASKS = 1920 * 1080, 4096, (4, 16, 100, 1000)
RESULTS = os.path.join(HERE, "results", "farm_overhead.json")
TIMING = re.compile(r"lantern task timing: startup ([\d.]+) export ([\d.]+) build ([\d.]+) "
                    r"render ([\d.]+) write ([\d.]+)")


def task(env, blend, scene, offset, samples, out, build):
    cmd = ["blender", "-b", "--factory-startup", blend, "--scene", scene, "--python-exit-code", "1",
           "--python", os.path.join(build, "lantern_task.py"), "--", "--offset", str(offset),
           "--samples", str(samples), "--out", out, "--timing"]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    m = TIMING.search(p.stdout)
    if p.returncode != 0 or not m:
        sys.exit("task failed for %s:\n%s%s" % (scene, p.stdout[-2000:], p.stderr[-2000:]))
    startup, export, bvh, render, write = map(float, m.groups())
    # Start-up as the task sees it: process launch and .blend load (before the script) plus the
    # script's own imports and frame_set.
    return {"wall": wall, "startup": wall - (export + bvh + render + write), "export": export,
            "build": bvh, "render": render, "write": write}


def exr_size(path):
    import struct
    with open(path, "rb") as f:
        data = f.read(65536)
    i = data.index(b"dataWindow\0box2i\0")
    x0, y0, x1, y1 = struct.unpack_from("<4i", data, i + len(b"dataWindow\0box2i\0") + 4)
    return x1 - x0 + 1, y1 - y0 + 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=os.path.join(REPO, "build"))
    ap.add_argument("--blend", default=os.path.join(REPO, "examples.blend"))
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--tables", action="store_true", help="only print the tables of the last results")
    args = ap.parse_args()
    if args.tables:
        with open(RESULTS) as f:
            rows = json.load(f)["rows"]
        print_tables([dict(r, **model(r)) for r in rows])
        return
    build = os.path.abspath(args.build)
    work = tempfile.mkdtemp(prefix="lantern_farm_bench_")
    try:
        # examples.blend reads its .vdb files from //assets/ (scripts/render_examples.sh)...
        blend = os.path.join(work, "examples.blend")
        shutil.copy(args.blend, blend)
        os.makedirs(os.path.join(work, "assets"))
        for vdb in ("cloud.vdb", "smoke.vdb"):
            shutil.copy(os.path.join(build, "test_vdb", vdb), os.path.join(work, "assets"))
        # and the cathedral's textures from //models/ (README: Example scenes).
        os.symlink(os.path.join(REPO, "models"), os.path.join(work, "models"))
        env = dict(os.environ, LANTERN_ADDON_DIR=os.path.join(REPO, "addon"),
                   LANTERN_LIBRARY=os.path.join(build, "liblantern.so"))
        # Blender's embedded Python takes its prefix from the first python3 on PATH: not this one's
        # (a pyenv interpreter would hide Debian's numpy from the add-on).
        own = os.path.dirname(sys.executable)
        env["PATH"] = os.pathsep.join(p for p in env["PATH"].split(os.pathsep) if p != own)
        rows = []
        for scene in args.scenes.split(","):
            # Four 1-sample parts (the first also warms the file cache), then the timed task.
            small = [os.path.join(work, "%s_%d.exr" % (scene, k)) for k in range(4)]
            for k, part in enumerate(small):
                task(env, blend, scene, k, 1, part, build)
            hi = os.path.join(work, scene + "_hi.exr")
            t = task(env, blend, scene, 4, args.samples, hi, build)
            w, h = exr_size(hi)
            # Merge cost per part: (merge of all 5 parts - merge of 1) / 4, best of 3 each.
            merge_times = []
            for parts in (small + [hi], [hi]):
                best = float("inf")
                for _ in range(3):
                    t0 = time.perf_counter()
                    p = subprocess.run([os.path.join(build, "lantern"), "merge", os.path.join(work, "m.exr")] + parts,
                                       capture_output=True, text=True)
                    best = min(best, time.perf_counter() - t0)
                    if p.returncode != 0:
                        sys.exit("merge failed: " + p.stderr)
                merge_times.append(best)
            merge = max(0.0, (merge_times[0] - merge_times[1]) / 4)
            row = {"scene": scene, "resolution": [w, h], "samples": args.samples, "task": t,
                   "fixed_seconds": t["wall"] - t["render"], "render_seconds_per_sample": t["render"] / args.samples,
                   "merge_seconds_per_part": merge}
            row.update(model(row))
            rows.append(row)
            print("%s done: fixed %.2f s, %.4f s/sample at %dx%d" % (
                scene, row["fixed_seconds"], row["render_seconds_per_sample"], w, h), flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    with open(RESULTS, "w") as f:
        json.dump({"cpus": os.cpu_count(), "rows": rows}, f, indent=1)
    print_tables(rows)


def merge_seconds(n, m, write):
    """`lantern farm`'s merge of n parts: one merge up to 16 tasks, else groups of g = ceil(sqrt(n))
    merged in parallel on separate nodes, then one merge of the group results."""
    if n <= 16:
        return n * m + write
    g = math.ceil(math.sqrt(n))
    return g * m + write + math.ceil(n / g) * m + write


def model(row):
    """The 4096-sample 1080p split model (module docstring) from one scene's measurements."""
    t = row["task"]
    w, h = row["resolution"]
    scale = TARGET_PIXELS / (w * h)
    f = t["startup"] + t["export"] + t["build"] + t["write"] * scale
    r, m = row["render_seconds_per_sample"] * scale, row["merge_seconds_per_part"] * scale
    sr = TARGET_SAMPLES * r
    t1 = f + sr
    write = t["write"] * scale  # each merge job writes one 1080p EXR, like a task

    def t_n(n):
        return f + sr / n + merge_seconds(n, m, write)

    split = {n: {"seconds": t_n(n), "speedup": t1 / t_n(n), "efficiency": t1 / t_n(n) / n} for n in TASKS}
    n50 = next((n for n in range(1, 1 << 20) if t1 / t_n(n) / n < 0.5), None)
    return {"fixed_seconds_1080p": f, "render_seconds_per_sample_1080p": r, "merge_seconds_per_part_1080p": m,
            "one_machine_seconds_1080p_4096": t1, "split": split, "tasks_at_50_percent": n50,
            "tasks_at_50_percent_fixed_cost_only": (sr + 2 * f) / f}


def print_tables(rows):
    print("\nPer task, measured (scene resolution, %d samples):\n" % rows[0]["samples"])
    print("| scene | resolution | start-up + load | export | BVH build | EXR write | fixed cost F | "
          "render per sample | merge per part |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        t = r["task"]
        print("| %s | %dx%d | %.2f s | %.3f s | %.3f s | %.3f s | %.2f s | %.3f s | %.3f s |" % (
            r["scene"], r["resolution"][0], r["resolution"][1], t["startup"], t["export"], t["build"], t["write"],
            r["fixed_seconds"], r["render_seconds_per_sample"], r["merge_seconds_per_part"]))
    print("\nModel, 4096 samples at 1920x1080 on N machines (efficiency = speedup / N):\n")
    print("| scene | F | render per sample | merge per part | 1 machine | N = 4 | N = 16 | N = 100 | N = 1000 | "
          "50% at N = | (fixed cost alone) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %.1f s | %.2f s | %.2f s | %.1f h | %s | %.0f | %.0f |" % (
            r["scene"], r["fixed_seconds_1080p"], r["render_seconds_per_sample_1080p"],
            r["merge_seconds_per_part_1080p"], r["one_machine_seconds_1080p_4096"] / 3600,
            " | ".join("%.0f%%" % (100 * r["split"][n]["efficiency"]) for n in TASKS),
            r["tasks_at_50_percent"], r["tasks_at_50_percent_fixed_cost_only"]))


if __name__ == "__main__":
    main()
