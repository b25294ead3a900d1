"""Convergence benchmark: error against wall time for Lantern's path tracer, Lantern's bidirectional
path tracer and Cycles on the same scenes.

Run inside Blender (bench/run_convergence.sh does the build and the call):

    LANTERN_LIBRARY=build-bench/liblantern.so blender -b --factory-startup --python-exit-code 1 \
        --python bench/convergence.py -- [--quick] [--out bench/results] [--scenes door,caustic]

What it does, per scene ("door", "door_bounce", "caustic", "cornell_area" of
scenes/build_scenes.py, at 160x120, --quick: 96x72), in one Blender process, all threads for
every engine:
  * Warm-up: one 1-sample render per method (not recorded).
  * Ladder: each method (Lantern PATH, Lantern BIDIRECTIONAL, Cycles) renders at 4, 8, 16, ...
    samples, a different seed for every render. The methods take turns rung by rung, so a change in
    the machine's load falls on all three alike. A method stops before a rung that would take its
    ladder past --budget seconds (the next rung is predicted as twice the last one).
  * Reference: Lantern BIDIRECTIONAL (the Blender tests check it agrees with Cycles on these scenes)
    rendered as --ref-chunks independent renders (other seeds) of equal samples, about
    --ref-seconds in all, averaged. The spread of the chunks gives the reference's own noise.
  * Error: relMSE = mean over pixels and RGB of (x - ref)^2 / (ref^2 + 1e-2). Because the reference
    is noisy too, the expected measured relMSE is the true one plus the reference's noise term
    mean(Var(ref) / (ref^2 + 1e-2)) (the "floor"); relmse_corrected subtracts that estimate.
  * Time: wall time of the render operator (render_utils.render: .seconds), which includes export
    and writing the image, as a user waits for it. CPU time of the process is recorded too.
  * Ratios at equal time: each method's log relMSE is interpolated linearly in log time at the
    largest time all three methods reached; the ratios are taken there (from relmse_corrected).
    The JSON also has them against CPU time of the process (on a machine shared with other jobs
    the steadier time base; both engines keep 2 threads busy when the machine is idle), from a 1/t
    fit of the last rungs (fit_inverse_time), and from the trimmed relMSE: the same without the
    0.1 % of pixels of largest error. On "caustic" a few fireflies (light seen through the glass,
    the caustic seen through the glass) move one render's relMSE by orders of magnitude; the
    trimmed figure is steadier there but favours the methods whose error is fireflies (it drops
    them) while they are fewer than 0.1 % of the pixels.
Output: OUT/convergence.json, OUT/convergence_<scene>.png (log-log plot, needs matplotlib),
OUT/convergence_<scene>_reference.png and OUT/convergence_<scene>_images.png (reference, then each
method's rung nearest the equal time; all with the exposure given in the JSON).
Nothing asserts: it prints figures and writes them.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import bpy
import numpy as np

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
sys.path.insert(0, BENCH)
sys.path.insert(0, os.path.join(REPO, "addon"))
sys.path.insert(0, os.path.join(REPO, "scenes"))

import build_scenes  # noqa: E402  (the test scenes' builders)
from curves import EPS, interp_loglog, pixel_errors, reference_from_chunks, rgb  # noqa: E402
from machine import cpu_model  # noqa: E402
import lantern  # noqa: E402
import render_utils  # noqa: E402  (render to EXR and read back; PNG writer)
from lantern import core as lt_core  # noqa: E402

TRIM = 1e-3  # the trimmed relMSE leaves out this fraction of pixels, those of largest error
SCENES = ("door", "door_bounce", "caustic", "cornell_area")
# name: (engine, Lantern integrator, Lantern sample pattern); --independent adds the last two
# (the sampler's gain: the same integrators with independent random numbers).
METHODS = {
    "PATH": ("LANTERN", "PATH", "SOBOL_OWEN"),
    "BIDIRECTIONAL": ("LANTERN", "BIDIRECTIONAL", "SOBOL_OWEN"),
    "CYCLES": ("CYCLES", "PATH", None),
}
INDEPENDENT_METHODS = {
    "PATH_INDEPENDENT": ("LANTERN", "PATH", "INDEPENDENT"),
    "BIDIRECTIONAL_INDEPENDENT": ("LANTERN", "BIDIRECTIONAL", "INDEPENDENT"),
}
COLOURS = {"PATH": "tab:blue", "BIDIRECTIONAL": "tab:red", "CYCLES": "tab:green",
           "PATH_INDEPENDENT": "tab:cyan", "BIDIRECTIONAL_INDEPENDENT": "tab:orange",
           "PATH_POWER": "tab:purple"}
# --power-pick adds Lantern's path tracer with next-event estimation picking lights by power, the
# selection before the light tree (LANTERN_LIGHT_SELECTION=power, read when the scene is committed).
POWER_PICK = {"PATH_POWER": ("LANTERN", "PATH", "SOBOL_OWEN")}
# Seeds: method j's rung i uses LADDER_SEED0 + 100 j + i (PATH and BIDIRECTIONAL share their camera
# paths' random numbers at equal seeds); reference chunk k uses seed 1 + k.
LADDER_SEED0 = 1000


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="convergence.py")
    p.add_argument("--quick", action="store_true",
                   help="96x72, short budgets: for debugging the script, figures are rough")
    p.add_argument("--out", default=os.path.join(BENCH, "results"))
    p.add_argument("--scenes", default=",".join(SCENES), help="comma-separated")
    p.add_argument("--width", type=int, default=None, help="default 160 (quick: 96)")
    p.add_argument("--height", type=int, default=None, help="default 120 (quick: 72)")
    p.add_argument("--budget", type=float, default=None,
                   help="seconds of ladder per method and scene (default 60, quick 8)")
    p.add_argument("--ref-seconds", type=float, default=None,
                   help="seconds of reference per scene (default 180, quick 16)")
    p.add_argument("--ref-chunks", type=int, default=4)
    p.add_argument("--min-samples", type=int, default=4)
    p.add_argument("--threads", type=int, default=0, help="0: all cores")
    p.add_argument("--independent", action="store_true",
                   help="also render PATH and BIDIRECTIONAL with independent random numbers")
    p.add_argument("--power-pick", action="store_true",
                   help="also PATH_POWER: the path tracer with the power pick instead of the light tree")
    p.add_argument("--analyse-only", action="store_true",
                   help="render nothing: recompute figures and plots from OUT/convergence.json")
    a = p.parse_args(argv)
    a.width = a.width or (96 if a.quick else 160)
    a.height = a.height or (72 if a.quick else 120)
    a.budget = a.budget or (8.0 if a.quick else 60.0)
    a.ref_seconds = a.ref_seconds or (16.0 if a.quick else 180.0)
    a.threads = a.threads or os.cpu_count()
    return a


def git_describe():
    try:
        return subprocess.run(["git", "-C", REPO, "describe", "--always", "--dirty"],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def trimmed_mean(e, floor_map, fraction=TRIM):
    """Mean of the per-pixel errors minus the reference's noise, over the pixels left when the
    largest `fraction` of the errors (fireflies) is left out."""
    e, f = e.ravel(), floor_map.ravel()
    keep = np.argsort(e, kind="stable")[:e.size - int(math.ceil(fraction * e.size))]
    return float(e[keep].mean() - f[keep].mean())


class Renderer:
    def __init__(self, scene, threads, tmpdir):
        self.scene, self.threads, self.tmpdir = scene, threads, tmpdir
        # In a scene with media the path tracer is the volumetric one (PATH ignores media).
        self.media = render_utils.export(scene)[0].get("media", 0) > 0

    def __call__(self, method, samples, seed):
        engine, integrator, pattern = METHODS[method]
        if pattern:
            self.scene.lantern.sample_pattern = pattern
        if self.media and integrator == "PATH":
            integrator = "VOLPATH"
        power = method in POWER_PICK
        if power:
            os.environ["LANTERN_LIGHT_SELECTION"] = "power"
        c0 = time.process_time()
        try:
            out = render_utils.render(self.scene, engine, samples, seed, threads=self.threads,
                                      outdir=self.tmpdir, integrator=integrator,
                                      tag="%s_%s_s%d_seed%d" % (self.scene.name, method, samples, seed))
        finally:
            if power:
                del os.environ["LANTERN_LIGHT_SELECTION"]
        cpu = time.process_time() - c0
        img = out.combined
        if not np.all(np.isfinite(img)):
            print("bench: WARNING %s %s %d spp: %d non-finite values" % (
                self.scene.name, method, samples, int(np.sum(~np.isfinite(img)))), flush=True)
        return img, out.seconds, cpu


def equal_time(curves, time_key, err_key):
    """Common time (the largest every method reached) and each method's error there."""
    t = min(max(r[time_key] for r in rows) for rows in curves.values())
    errs = {}
    for m, rows in curves.items():
        rows = sorted(rows, key=lambda r: r[time_key])
        errs[m] = interp_loglog([r[time_key] for r in rows], [r[err_key] for r in rows], t)
    return t, errs


def fit_inverse_time(rows, t_common, time_key, err_key):
    """C of relMSE ≈ C / t: the mean of relMSE·t over the rungs with t >= t_common / 8 (the
    converged end of the curve, where error falls as 1/t). It averages 3-4 independent renders, so
    it is steadier than the interpolation between two, and, being an arithmetic mean, it keeps the
    weight of rare fireflies (the expected error includes them)."""
    vals = [r[err_key] * r[time_key] for r in rows
            if r[time_key] >= t_common / 8 and r[err_key] is not None and r[err_key] > 0]
    return sum(vals) / len(vals) if vals else None


def ratio(a, b):
    return a / b if a is not None and b is not None and b > 0 else None


def auto_exposure(ref):
    """Exposure (stops) putting the 97th percentile of the reference's luminance at 0.8."""
    lum = ref @ np.array([0.2126, 0.7152, 0.0722])
    p = float(np.percentile(lum, 97))
    return 0.0 if p <= 0 else round(math.log2(0.8 / p) * 2) / 2


def montage(images, gap=2):
    h = images[0].shape[0]
    pad = np.ones((h, gap, 3)) * 0.5
    parts = []
    for im in images:
        parts += [rgb(im), pad]
    return np.concatenate(parts[:-1], axis=1)


def run_scene(name, args, tmpdir):
    build_scenes.reset_file()
    scene = build_scenes.build(name, resolution=(args.width, args.height))
    render = Renderer(scene, args.threads, tmpdir)
    load_before = os.getloadavg()
    t_scene = time.perf_counter()
    print("bench: ==== %s %dx%d, %d threads, ladder budget %.0f s per method, reference %.0f s" % (
        name, args.width, args.height, args.threads, args.budget, args.ref_seconds), flush=True)
    for m in METHODS:  # warm-up: library loading, kernels, first-use costs
        render(m, 1, 0)

    # Ladder, the methods taking turns rung by rung.
    rows = {m: [] for m in METHODS}
    images = {m: [] for m in METHODS}
    spent = {m: 0.0 for m in METHODS}
    active = list(METHODS)
    rung = 0
    while active:
        samples = args.min_samples << rung
        for j, m in enumerate(METHODS):
            if m not in active:
                continue
            seed = LADDER_SEED0 + 100 * j + rung
            if rows[m] and spent[m] + 2.0 * rows[m][-1]["seconds"] > args.budget:
                active.remove(m)
                continue
            img, sec, cpu = render(m, samples, seed)
            spent[m] += sec
            rows[m].append({"samples": samples, "seed": seed, "seconds": sec, "cpu_seconds": cpu})
            images[m].append(img)
            print("bench: %-13s %6d spp: %7.2f s (CPU %7.2f s)" % (m, samples, sec, cpu), flush=True)
        rung += 1

    # Reference: BDPT, equal chunks of other seeds, about ref_seconds in all on an otherwise idle
    # machine: sized by the CPU time of BDPT's last rung (threads x wall time when idle), which
    # other processes disturb much less than its wall time.
    last = rows["BIDIRECTIONAL"][-1]
    per_sample = max(last["cpu_seconds"] / args.threads, 1e-6) / last["samples"]
    chunk_samples = max(last["samples"],
                        int(round(args.ref_seconds / args.ref_chunks / per_sample / 16.0)) * 16)
    chunks, ref_secs, ref_cpu = [], 0.0, 0.0
    for k in range(args.ref_chunks):
        img, sec, cpu = render("BIDIRECTIONAL", chunk_samples, 1 + k)
        chunks.append(img)
        ref_secs += sec
        ref_cpu += cpu
        print("bench: reference chunk %d: %d spp, %.2f s" % (k + 1, chunk_samples, sec), flush=True)
    ref, floor_map, floor = reference_from_chunks(chunks)
    K = args.ref_chunks

    for m in METHODS:
        for r, img in zip(rows[m], images[m]):
            e = pixel_errors(img, ref)
            r["relmse"] = float(e.mean())
            r["relmse_corrected"] = r["relmse"] - floor if r["relmse"] > floor else None
            t = trimmed_mean(e, floor_map)
            r["relmse_trimmed"] = t if t > 0 else None

    res = {"width": args.width, "height": args.height, "methods": rows,
           "path_integrator": "VOLPATH" if render.media else "PATH"}
    analyse(res)
    t_eq = res["equal_time"]["seconds"]

    exposure = auto_exposure(ref)
    out_ref = os.path.join(args.out, "convergence_%s_reference.png" % name)
    render_utils.write_png(out_ref, ref, exposure)
    shown = {}
    for m in METHODS:  # each method's rung whose time is nearest the equal time (in log)
        i = min(range(len(rows[m])), key=lambda j: abs(math.log(rows[m][j]["seconds"] / t_eq)))
        shown[m] = {"samples": rows[m][i]["samples"], "seconds": rows[m][i]["seconds"]}
        images[m] = images[m][i]
    out_img = os.path.join(args.out, "convergence_%s_images.png" % name)
    render_utils.write_png(out_img, montage([ref] + [images[m] for m in METHODS]), exposure)

    res.update({
        "reference": {"method": "BIDIRECTIONAL", "chunks": K, "samples_per_chunk": chunk_samples,
                      "samples": K * chunk_samples, "seeds": list(range(1, K + 1)),
                      "seconds": ref_secs, "cpu_seconds": ref_cpu,
                      "noise_floor_relmse": floor,
                      "mean_rgb": [float(x) for x in ref.reshape(-1, 3).mean(axis=0)]},
        "images": {"exposure": exposure, "reference_png": os.path.basename(out_ref),
                   "montage_png": os.path.basename(out_img),
                   "montage_order": ["reference"] + list(METHODS), "montage_rungs": shown},
        "loadavg_before": load_before, "loadavg_after": os.getloadavg(),
        "scene_seconds": time.perf_counter() - t_scene,
    })
    res["plot_png"] = plot(name, res, args)
    print("bench: %s: reference %d spp (%.0f s), noise floor %.3g; at equal wall time %.2f s "
          "relMSE %s" % (name, K * chunk_samples, ref_secs, floor, t_eq,
                         {m: fmt(v) for m, v in res["equal_time"]["relmse"].items()}), flush=True)
    return res


# Equal-time comparisons: time base (JSON key of the rows) x error (JSON key of the rows).
TIME_BASES = {"wall": "seconds", "cpu": "cpu_seconds"}
ERRORS = {"relmse": "relmse_corrected", "trimmed": "relmse_trimmed"}


def ratios(e):
    best = [e[m] for m in ("PATH", "BIDIRECTIONAL") if e.get(m) is not None]
    return {"cycles_over_bdpt": ratio(e["CYCLES"], e["BIDIRECTIONAL"]),
            "bdpt_over_path": ratio(e["BIDIRECTIONAL"], e["PATH"]),
            "cycles_over_path": ratio(e["CYCLES"], e["PATH"]),
            "cycles_over_best": ratio(e["CYCLES"], min(best) if best else None),
            # > 1: Sobol-Owen beats independent numbers at equal time (--independent)
            "path_independent_over_path": ratio(e.get("PATH_INDEPENDENT"), e["PATH"]),
            "bdpt_independent_over_bdpt": ratio(e.get("BIDIRECTIONAL_INDEPENDENT"), e["BIDIRECTIONAL"]),
            # --power-pick: > 1, the light tree beats the power pick
            "power_over_tree": ratio(e.get("PATH_POWER"), e["PATH"]),
            "cycles_over_power": ratio(e["CYCLES"], e.get("PATH_POWER"))}


def per_sample(rows):
    """Error per sample (relMSE x spp) and cost per sample (CPU s / spp), means over the last
    three rungs: which of the two moved."""
    rows = [r for r in rows if r.get("relmse_corrected") is not None][-3:]
    if not rows:
        return None
    return {"relmse_x_spp": sum(r["relmse_corrected"] * r["samples"] for r in rows) / len(rows),
            "cpu_s_per_spp": sum(r["cpu_seconds"] / r["samples"] for r in rows) / len(rows)}


def analyse(res):
    """Fills res["equal_time"] from the rows in res["methods"]. The headline (seconds, relmse,
    ratios) is wall time and relMSE minus the reference's noise; "variants" has every
    combination of wall/CPU time and relMSE/trimmed relMSE, each by interpolation and by the
    1/t fit."""
    variants = {}
    for tb, tkey in TIME_BASES.items():
        for eb, ekey in ERRORS.items():
            curves = {m: [r for r in rows if r.get(ekey) is not None]
                      for m, rows in res["methods"].items()}
            t, e = equal_time(curves, tkey, ekey)
            fit = {m: fit_inverse_time(rows, t, tkey, ekey) for m, rows in curves.items()}
            variants["%s_%s" % (tb, eb)] = {
                "time": t, "relmse": e, "ratios": ratios(e),
                "fit_inverse_time": {"C": fit, "ratios": ratios(fit)}}
    head = variants["wall_relmse"]
    res["equal_time"] = {"seconds": head["time"], "relmse": head["relmse"],
                         "ratios": head["ratios"], "variants": variants,
                         "trim_fraction": TRIM}
    res["per_sample"] = {m: per_sample(rows) for m, rows in res["methods"].items()}


def fmt(x):
    return "n/a" if x is None else "%.3g" % x


def plot(name, res, args):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        print("bench: no plot for %s (matplotlib: %s; apt-get install python3-matplotlib)" % (name, e))
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), dpi=100, sharey=True)
    eq = res["equal_time"]
    for ax, (tb, tkey) in zip(axes, TIME_BASES.items()):
        for m, rows in res["methods"].items():
            tr = [(r[tkey], r["relmse_trimmed"]) for r in rows if r["relmse_trimmed"]]
            ax.plot([a for a, _ in tr], [b for _, b in tr], "--", color=COLOURS[m], alpha=0.6,
                    lw=1)
            c = [(r[tkey], r["relmse_corrected"]) for r in rows if r["relmse_corrected"]]
            ax.plot([a for a, _ in c], [b for _, b in c], "o-", color=COLOURS[m], ms=4,
                    label="%s (%s spp)" % ("Cycles" if m == "CYCLES" else "Lantern " + m,
                                           "–".join(str(r["samples"]) for r in
                                                    rows[::max(1, len(rows) - 1)])))
        v = eq["variants"][tb + "_relmse"]
        ax.axvline(v["time"], color="grey", lw=0.8)
        ax.axhline(res["reference"]["noise_floor_relmse"], color="grey", ls=":", lw=0.8,
                   label="reference's noise (BDPT %d spp)" % res["reference"]["samples"])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("%s [s] (%d threads)" % ("wall time" if tb == "wall" else
                                               "CPU time of the process", args.threads))
        r, rt = v["ratios"], eq["variants"][tb + "_trimmed"]["ratios"]
        ax.set_title("at %.1f s: Cycles/BDPT %s, BDPT/PATH %s\n(trimmed: %s, %s)" % (
            v["time"], fmt(r["cycles_over_bdpt"]), fmt(r["bdpt_over_path"]),
            fmt(rt["cycles_over_bdpt"]), fmt(rt["bdpt_over_path"])), fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("relMSE = mean (x-ref)² / (ref² + %g)" % EPS)
    axes[0].legend(fontsize=8, title="solid: relMSE; dashed: trimmed (worst %g %% of pixels "
                   "left out);\nboth minus the reference's noise" % (100 * TRIM),
                   title_fontsize=7)
    fig.suptitle("%s %dx%d: relMSE against time" % (name, res["width"], res["height"]),
                 fontsize=11)
    fig.tight_layout()
    path = os.path.join(args.out, "convergence_%s.png" % name)
    fig.savefig(path)
    plt.close(fig)
    return os.path.basename(path)


GOALS = {  # scene: (ratio, comparison, bound)
    "door": [("cycles_over_bdpt", ">=", 5.0)],
    "door_bounce": [("cycles_over_bdpt", ">=", 5.0)],
    "cornell_area": [("bdpt_over_path", "<=", 2.0)],
    "caustic": [],
}


def main():
    args = parse_args()
    if args.independent:
        METHODS.update(INDEPENDENT_METHODS)
    if args.power_pick:
        METHODS.update(POWER_PICK)
    if args.analyse_only:
        return reanalyse(args)
    lantern.register()
    os.makedirs(args.out, exist_ok=True)
    t0 = time.perf_counter()
    result = {
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "command": " ".join(["blender -b --factory-startup --python bench/convergence.py --"]
                            + (sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])),
        "git": git_describe(),
        "machine": {"cpus": os.cpu_count(), "processor": cpu_model(),
                    "blender": bpy.app.version_string, "lantern": lt_core.version(),
                    "loadavg_before": os.getloadavg()},
        "quick": args.quick, "threads": args.threads, "budget_seconds": args.budget,
        "ref_seconds": args.ref_seconds, "relmse": "mean over pixels and RGB of (x-ref)^2/(ref^2+%g)"
        % EPS, "epsilon": EPS, "scenes": {},
    }
    with tempfile.TemporaryDirectory(prefix="lantern_convergence_") as tmp:
        for name in [s for s in args.scenes.split(",") if s]:
            result["scenes"][name] = run_scene(name, args, tmp)
    result["machine"]["loadavg_after"] = os.getloadavg()
    result["total_seconds"] = time.perf_counter() - t0
    finish(result, args)


def finish(result, args):
    """Goals, the JSON and the summary table."""
    goals = {}
    for name, res in result["scenes"].items():
        for key, op, bound in GOALS.get(name, []):
            for variant in ("wall_relmse", "cpu_relmse", "wall_trimmed", "cpu_trimmed"):
                v = res["equal_time"]["variants"][variant]["ratios"][key]
                goals["%s %s %s %g (%s)" % (name, key, op, bound, variant)] = (
                    None if v is None else (v >= bound if op == ">=" else v <= bound))
    result["goals"] = goals
    path = os.path.join(args.out, "convergence.json")
    with open(path, "w") as f:
        json.dump(result, f, indent=2)

    print("\n==== relMSE ratios at equal time (> 1: the second method is better); "
          "interpolated [1/t fit] ====")
    print("%-13s %-13s %9s %17s %17s %17s" % ("scene", "time, error", "at", "Cycles/BDPT",
                                               "BDPT/PATH", "Cycles/PATH"))
    for name, res in result["scenes"].items():
        for variant, v in res["equal_time"]["variants"].items():
            r, rf = v["ratios"], v["fit_inverse_time"]["ratios"]
            print("%-13s %-13s %7.2f s %17s %17s %17s" % (
                name, variant, v["time"], *("%s [%s]" % (fmt(r[k]), fmt(rf[k])) for k in (
                    "cycles_over_bdpt", "bdpt_over_path", "cycles_over_path"))))
    print("\n==== per sample: relMSE x spp, CPU s / spp (last three rungs) ====")
    for name, res in result["scenes"].items():
        print("%-13s %s" % (name, "; ".join(
            "%s %s, %s" % (m, fmt(v["relmse_x_spp"]), fmt(v["cpu_s_per_spp"])) if v else "%s n/a" % m
            for m, v in res.get("per_sample", {}).items())))
    print("\n==== Cycles / best Lantern, Sobol-Owen gain (independent / Sobol-Owen), CPU time ====")
    for name, res in result["scenes"].items():
        r = res["equal_time"]["variants"]["cpu_relmse"]["ratios"]
        print("%-13s Cycles/best %s  PATH gain %s  BDPT gain %s" % (
            name, fmt(r["cycles_over_best"]), fmt(r["path_independent_over_path"]),
            fmt(r["bdpt_independent_over_bdpt"])))
    for k, v in goals.items():
        print("Goal %s: %s" % (k, {True: "met", False: "not met", None: "n/a"}[v]))
    m = result["machine"]
    print("Load average before/after: %s / %s (%d CPUs); total %.0f s" % (
        ", ".join("%.2f" % x for x in m["loadavg_before"]),
        ", ".join("%.2f" % x for x in m.get("loadavg_after", ())), m["cpus"],
        result.get("total_seconds", 0.0)))
    print("Wrote %s" % path)


def reanalyse(args):
    """--analyse-only: recompute the equal-time figures and plots of an existing JSON."""
    path = os.path.join(args.out, "convergence.json")
    with open(path) as f:
        result = json.load(f)
    args.threads = result["threads"]
    for name, res in result["scenes"].items():
        args.width, args.height = res["width"], res["height"]
        analyse(res)
        res["plot_png"] = plot(name, res, args)
    finish(result, args)


main()
