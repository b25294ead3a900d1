"""Volume benchmarks: error against time for the volume estimators and Cycles, the cost of the
volumetric integrator on a scene without media, and the memory of a loaded VDB.

Run inside Blender from the repository root, after a build with the tests (make_test_vdb writes
<build>/test_vdb/*.vdb, lantern_tests prints the VDB memory):

    LANTERN_LIBRARY=$PWD/build/liblantern.so LANTERN_TEST_VDB_DIR=$PWD/build/test_vdb \\
        blender -b --factory-startup --python-exit-code 1 --python bench/volumes.py -- \\
        [--out bench/results] [--tests build/lantern_tests] [--threads 2]

What it does (all renders 64x64, --threads threads, one Blender process):
  * Error against time on "vdb_cloud" and "smoke_box" (scenes/build_scenes.py), integrator
    VOLPATH. Methods: ray marching at step = voxel x {1, 1/2, 1/4} (vdb_cloud only: smoke_box is
    homogeneous, where every estimator uses the closed forms), delta/ratio tracking, and Cycles
    (which ray-marches at voxel x volume_step_rate). Each renders 16, 64, 256 samples (other seeds
    per rung). Reference: Lantern tracking (unbiased; agrees with Cycles in tests/blender) at
    --ref-samples in two renders of different seeds. relMSE = mean over pixels and RGB of
    (x - ref)^2 / (ref^2 + 1e-2) minus the reference's own noise term (estimated from its two
    halves). Ray marching converges to its biased image, so its curve flattens at its bias.
    Equal time: log relMSE interpolated linearly in log time at the largest time all methods reach.
  * VOLPATH against PATH on "cornell_area" (no media): 96x96, 256 samples, --reps (5) renders each,
    alternating; the ratio of the minimum wall times (goal <= 1.02).
  * Memory: lantern_tests --gtest_filter=VdbLoad.CloudAndSmokeMemory prints, per .vdb, the active
    voxel count, the NanoVDB buffer and the majorant grid in bytes.
Output: OUT/volumes.json and, if matplotlib is importable, OUT/volumes_<scene>.png (log-log).
Nothing asserts.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
for p in (HERE, os.path.join(REPO, "scenes"), os.path.join(REPO, "addon")):
    if p not in sys.path:
        sys.path.insert(0, p)

import numpy as np  # noqa: E402

import build_scenes  # noqa: E402
import render_utils as ru  # noqa: E402
from curves import interp_loglog  # noqa: E402  (None outside a curve's times: no extrapolation)

RUNGS = (16, 64, 256)


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="volumes.py")
    p.add_argument("--out", default=os.path.join(REPO, "bench", "results"))
    p.add_argument("--tests", default=os.path.join(REPO, "build", "lantern_tests"))
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--ref-samples", type=int, default=1024)
    p.add_argument("--reps", type=int, default=5)
    return p.parse_args(argv)


def rgb(img):
    return np.asarray(img, np.float64)[..., :3]


def methods_for(name):
    ms = []
    if name == "vdb_cloud":
        voxel = 0.04
        for f in (1.0, 0.5, 0.25):
            ms.append(("march_%g" % f, ru.LANTERN, dict(volume_estimator="RAY_MARCHING",
                                                        volume_step=voxel * f)))
    ms.append(("tracking", ru.LANTERN, dict(volume_estimator="TRACKING")))
    ms.append(("cycles", ru.CYCLES, {}))
    return ms


def render(scene, engine, settings, spp, seed, threads):
    for k, v in settings.items():
        setattr(scene.lantern, k, v)
    out = ru.render(scene, engine, spp, seed=seed, threads=threads, integrator="VOLPATH")
    return rgb(out.combined), out.seconds


def run_scene(name, args):
    build_scenes.reset_file()
    scene = build_scenes.build(name)
    scene.render.resolution_x = scene.render.resolution_y = 64
    # warm-up (not recorded)
    for _, engine, settings in methods_for(name):
        render(scene, engine, settings, 1, 99, args.threads)
    t0 = time.perf_counter()
    half = args.ref_samples // 2
    ra, _ = render(scene, ru.LANTERN, dict(volume_estimator="TRACKING"), half, 1000, args.threads)
    rb, _ = render(scene, ru.LANTERN, dict(volume_estimator="TRACKING"), half, 1001, args.threads)
    ref = 0.5 * (ra + rb)
    denom = ref ** 2 + 1e-2
    floor_map = ((ra - rb) ** 2 / 4.0) / denom
    ref_seconds = time.perf_counter() - t0
    curves = {}
    seed = 0
    for spp in RUNGS:  # methods take turns rung by rung
        for m, engine, settings in methods_for(name):
            seed += 1
            img, secs = render(scene, engine, settings, spp, seed, args.threads)
            err = float(np.mean((img - ref) ** 2 / denom))
            corrected = max(err - float(np.mean(floor_map)), 1e-12)
            curves.setdefault(m, []).append(dict(samples=spp, seconds=secs, relmse=err,
                                                 relmse_corrected=corrected,
                                                 mean=float(img.mean())))
            print("bench: %-10s %-10s %4d spp %7.2f s relMSE %.3e (corrected %.3e)"
                  % (name, m, spp, secs, err, corrected), flush=True)
    t_common = min(c[-1]["seconds"] for c in curves.values())
    at = {m: interp_loglog([r["seconds"] for r in c], [r["relmse_corrected"] for r in c], t_common)
          for m, c in curves.items()}
    res = dict(scene=name, resolution=[64, 64], threads=args.threads,
               reference=dict(samples=args.ref_samples, seconds=ref_seconds,
                              floor=float(np.mean(floor_map)), mean=float(ref.mean())),
               curves=curves, equal_time=dict(seconds=t_common, relmse_corrected=at),
               tracking_over_cycles=None if None in (at["tracking"], at["cycles"]) else at["tracking"] / at["cycles"])
    print("bench: %s at %.2f s: %s; tracking/cycles %.3f" % (
        name, t_common, ", ".join("%s %s" % (m, "--" if e is None else "%.3e" % e) for m, e in at.items()),
        res["tracking_over_cycles"] or float("nan")))
    return res


def volpath_overhead(args):
    build_scenes.reset_file()
    scene = build_scenes.build("cornell_area")
    times = {"PATH": [], "VOLPATH": []}
    for integ in times:  # warm-up
        ru.render(scene, ru.LANTERN, 4, seed=0, threads=args.threads, integrator=integ)
    for rep in range(args.reps):
        for integ in times:
            out = ru.render(scene, ru.LANTERN, 256, seed=rep, threads=args.threads, integrator=integ)
            times[integ].append(out.seconds)
    ratio = min(times["VOLPATH"]) / min(times["PATH"])
    print("bench: cornell_area 96x96 256 spp: PATH %s s, VOLPATH %s s, ratio of minima %.3f"
          % (["%.2f" % t for t in times["PATH"]], ["%.2f" % t for t in times["VOLPATH"]], ratio))
    return dict(scene="cornell_area", samples=256, seconds=times, ratio_of_minima=ratio, goal=1.02)


def vdb_memory(args):
    if not os.path.exists(args.tests):
        print("bench: %s not found, memory skipped" % args.tests)
        return None
    out = subprocess.run([args.tests, "--gtest_filter=VdbLoad.CloudAndSmokeMemory"],
                         capture_output=True, text=True).stdout
    rows = []
    pat = re.compile(r"vdb memory (\S+): (\d+) active voxels, NanoVDB (\d+) bytes, majorant (\d+) "
                     r"bytes, file (\d+) bytes")
    for m in pat.finditer(out):
        name, voxels, nano, maj, size = m.group(1), *map(int, m.groups()[1:])
        rows.append(dict(file=name, active_voxels=voxels, nanovdb_bytes=nano, majorant_bytes=maj,
                         file_bytes=size, bytes_per_active_voxel=(nano + maj) / voxels))
        print("bench: %s: %d active voxels, NanoVDB %d B + majorant %d B = %.2f B/voxel (file %d B)"
              % (name, voxels, nano, maj, (nano + maj) / voxels, size))
    return rows


def plot(res, out_dir):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("bench: matplotlib not importable, no plot")
        return None
    fig, ax = plt.subplots(figsize=(5, 4))
    for m, c in res["curves"].items():
        ax.loglog([r["seconds"] for r in c], [r["relmse_corrected"] for r in c], "o-", label=m)
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("relMSE (reference noise subtracted)")
    ax.set_title(res["scene"])
    ax.legend()
    path = os.path.join(out_dir, "volumes_%s.png" % res["scene"])
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return os.path.basename(path)


def main():
    args = parse_args()
    os.makedirs(args.out, exist_ok=True)
    import bpy
    import lantern
    if not hasattr(bpy.types.Scene, "lantern"):
        lantern.register()
    results = dict(date=time.strftime("%Y-%m-%d %H:%M:%S"), scenes={})
    for name in ("vdb_cloud", "smoke_box"):
        res = run_scene(name, args)
        res["plot_png"] = plot(res, args.out)
        results["scenes"][name] = res
    results["volpath_overhead"] = volpath_overhead(args)
    results["vdb_memory"] = vdb_memory(args)
    path = os.path.join(args.out, "volumes.json")
    with open(path, "w") as f:
        json.dump(results, f, indent=1)
    print("bench: wrote", path)


main()
