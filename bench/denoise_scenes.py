"""The denoiser's trade on the test scenes (issue 16): relMSE against a reference of the noisy and
the denoised image over a range of sample counts, at equal CPU time, and the image mean's shift.

denoise.cpp measures the core's Cornell box and the denoiser's time per megapixel; this measures
the Blender test scenes of scenes/build_scenes.py through the add-on, as a user renders them.

    LANTERN_LIBRARY=$PWD/build/liblantern.so blender -b --factory-startup --python-exit-code 1 \\
        --python bench/denoise_scenes.py -- [--out bench/results] [--scenes cornell_area,smoke_box]

Per scene (SCENES: the scene and its best integrator; 160x120, 2 threads, one Blender process):
  * Warm-up: one 2-sample render with and one without denoising (not recorded).
  * Ladder: 4, 8, 16, ... samples, each rung a seed of its own, rendered twice with that seed:
    without denoising (the noisy image and its time) and with it (Render > Denoise: the denoised
    Combined, whose time includes the denoiser's, and the Noisy Image pass, checked to be the same
    bits as the first render's Combined). The ladder stops before a rung that would take it past
    --budget CPU seconds (the next rung predicted as twice the last).
  * Reference: the same integrator, --ref-chunks renders of other seeds, about --ref-cpu CPU
    seconds in all (sized from the last noisy rung), averaged; their spread gives its own noise.
  * Error: relMSE (curves.pixel_errors, epsilon 1e-2) minus the reference's noise term.
  * Time: CPU time of the Blender process around the render operator (export, render, denoise,
    writing the EXR; all threads), the time base to trust on a shared machine; the wall time and
    the core's denoise_seconds (wall) are recorded too.
  * Equal time: the noisy curve's log relMSE interpolated in log CPU time at each denoised rung's
    CPU time (curves.interp_loglog); the ratio noisy / denoised there (> 1: denoising pays).
  * Mean shift: per rung and channel, render_utils.denoise_mean_shift (the denoised minus the noisy
    image mean in standard errors of the noisy mean, from the Variance pass; the tests' bound is 5).
Output: OUT/denoise_scenes.json, OUT/denoise_scenes.png (relMSE against CPU time, a panel per
scene). Nothing asserts.
"""
import argparse
import json
import os
import sys
import tempfile
import time

import bpy
import numpy as np

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
for _p in (BENCH, os.path.join(REPO, "addon"), os.path.join(REPO, "scenes")):
    if _p not in sys.path:
        sys.path.insert(0, _p)

import build_scenes  # noqa: E402
from curves import EPS, interp_loglog, pixel_errors, reference_from_chunks, rgb  # noqa: E402
from machine import cpu_model  # noqa: E402
import lantern  # noqa: E402
import render_utils  # noqa: E402
from lantern import core as lt_core  # noqa: E402
from lantern import engine as lt_engine  # noqa: E402

# The scene and its best integrator (bench/README.md, the convergence section: BDPT on the doors).
SCENES = {
    "cornell_area": "PATH",
    "textured": "PATH",
    "door_slabs": "BIDIRECTIONAL",
    "door_bounce": "BIDIRECTIONAL",
    "smoke_box": "VOLPATH",
}
LADDER_SEED0 = 1000  # rung i: seed LADDER_SEED0 + i; reference chunk k: seed 1 + k


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="denoise_scenes.py")
    p.add_argument("--out", default=os.path.join(BENCH, "results"))
    p.add_argument("--scenes", default=",".join(SCENES), help="comma-separated, of SCENES")
    p.add_argument("--width", type=int, default=160)
    p.add_argument("--height", type=int, default=120)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--budget", type=float, default=60.0, help="CPU seconds of ladder per scene")
    p.add_argument("--ref-cpu", type=float, default=150.0, help="CPU seconds of reference per scene")
    p.add_argument("--ref-chunks", type=int, default=4)
    p.add_argument("--max-samples", type=int, default=1024)
    return p.parse_args(argv)


class Renderer:
    def __init__(self, scene, integrator, threads, tmpdir):
        self.scene, self.integrator, self.threads, self.tmpdir = scene, integrator, threads, tmpdir
        scene.view_layers[0].lantern_extra_passes = True  # Variance, for the mean's standard error

    def __call__(self, samples, seed, denoise):
        self.scene.lantern.use_denoising = denoise
        c0 = time.process_time()
        out = render_utils.render(self.scene, render_utils.LANTERN, samples, seed, threads=self.threads,
                                  outdir=self.tmpdir, integrator=self.integrator,
                                  tag="%s_s%d_seed%d_d%d" % (self.scene.name, samples, seed, denoise))
        cpu = time.process_time() - c0
        st = lt_engine.LAST_RENDER["stats"]
        if bool(st.denoised) != denoise:
            raise RuntimeError("%s %d spp: denoised %s, asked %s" % (self.scene.name, samples, st.denoised, denoise))
        for name in ("Combined", "Noisy Image") if denoise else ("Combined",):
            bad = int(np.sum(~np.isfinite(out[name][..., :3])))
            if bad:
                print("bench: WARNING %s %d spp: %d non-finite values in %s" % (
                    self.scene.name, samples, bad, name), flush=True)
        return out, {"seconds": out.seconds, "cpu_seconds": cpu,
                     "denoise_seconds": float(st.denoise_seconds) if denoise else 0.0}


def run_scene(name, args, tmpdir):
    build_scenes.reset_file()
    scene = build_scenes.build(name, resolution=(args.width, args.height))
    integrator = SCENES[name]
    render = Renderer(scene, integrator, args.threads, tmpdir)
    load_before = os.getloadavg()
    print("bench: ==== %s %dx%d, %s, %d threads, ladder budget %.0f CPU s, reference %.0f CPU s" % (
        name, args.width, args.height, integrator, args.threads, args.budget, args.ref_cpu), flush=True)
    render(2, 0, False)  # warm-up
    render(2, 0, True)

    rows, noisy_imgs, denoised_imgs = [], [], []
    spent, samples, rung = 0.0, 4, 0
    while samples <= args.max_samples:
        if rows and spent + 2.0 * (rows[-1]["noisy"]["cpu_seconds"] + rows[-1]["denoised"]["cpu_seconds"]) \
                > args.budget:
            break
        seed = LADDER_SEED0 + rung
        plain, t_noisy = render(samples, seed, False)
        den, t_den = render(samples, seed, True)
        same = bool(np.array_equal(plain.combined[..., :3], den["Noisy Image"][..., :3]))
        shift = render_utils.denoise_mean_shift(den.combined, plain.combined, plain["Variance"])[0]
        rows.append({"samples": samples, "seed": seed, "noisy": t_noisy, "denoised": t_den,
                     "noisy_image_same_bits": same, "mean_shift_sigmas": shift})
        noisy_imgs.append(rgb(plain.combined))
        denoised_imgs.append(rgb(den.combined))
        spent += t_noisy["cpu_seconds"] + t_den["cpu_seconds"]
        print("bench: %5d spp: noisy %.2f CPU s, denoised %.2f CPU s (denoiser %.3f s wall), mean shift %s%s" % (
            samples, t_noisy["cpu_seconds"], t_den["cpu_seconds"], t_den["denoise_seconds"],
            " ".join("%+.2f" % z for z in rows[-1]["mean_shift_sigmas"]),
            "" if same else " NOISY IMAGE DIFFERS from the render without denoising"), flush=True)
        samples *= 2
        rung += 1

    # Reference: sized by the last noisy rung's CPU time per sample.
    last = rows[-1]
    per_sample = last["noisy"]["cpu_seconds"] / last["samples"]
    chunk_samples = max(last["samples"], int(round(args.ref_cpu / args.ref_chunks / per_sample / 16.0)) * 16)
    chunks, ref_cpu, ref_secs = [], 0.0, 0.0
    for k in range(args.ref_chunks):
        out, t = render(chunk_samples, 1 + k, False)
        chunks.append(out.combined)
        ref_cpu += t["cpu_seconds"]
        ref_secs += t["seconds"]
        print("bench: reference chunk %d: %d spp, %.1f CPU s" % (k + 1, chunk_samples, t["cpu_seconds"]), flush=True)
    ref, _, floor = reference_from_chunks(chunks)

    for r, n_img, d_img in zip(rows, noisy_imgs, denoised_imgs):
        for key, img in (("noisy", n_img), ("denoised", d_img)):
            e = float(pixel_errors(img, ref).mean())
            r[key]["relmse"] = e
            r[key]["relmse_corrected"] = e - floor if e > floor else None
    for r in rows:
        n, d = r["noisy"]["relmse_corrected"], r["denoised"]["relmse_corrected"]
        r["ratio_equal_samples"] = n / d if n and d else None
        # The noisy curve at the denoised render's CPU time (None outside the noisy curve's times).
        at = interp_loglog([x["noisy"]["cpu_seconds"] for x in rows],
                           [x["noisy"]["relmse_corrected"] for x in rows], r["denoised"]["cpu_seconds"])
        r["noisy_relmse_at_equal_cpu"] = at
        r["ratio_equal_cpu"] = at / d if at and d else None

    worst = max(abs(z) for r in rows for z in r["mean_shift_sigmas"])
    return {"integrator": integrator, "width": args.width, "height": args.height, "rows": rows,
            "reference": {"integrator": integrator, "chunks": args.ref_chunks, "samples_per_chunk": chunk_samples,
                          "samples": args.ref_chunks * chunk_samples, "cpu_seconds": ref_cpu,
                          "seconds": ref_secs, "noise_floor_relmse": floor,
                          "mean_rgb": [float(x) for x in ref.reshape(-1, 3).mean(axis=0)]},
            "largest_mean_shift_sigmas": worst,
            "loadavg_before": load_before, "loadavg_after": os.getloadavg()}


def fmt(x, f="%.4g"):
    return "n/a" if x is None else f % x


def plot(result, args):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        print("bench: no plot (matplotlib: %s; apt-get install python3-matplotlib)" % e)
        return None
    names = list(result["scenes"])
    fig, axes = plt.subplots(1, len(names), figsize=(3.6 * len(names), 3.8), dpi=100, squeeze=False)
    for ax, name in zip(axes[0], names):
        res = result["scenes"][name]
        for key, colour, label in (("noisy", "tab:blue", "noisy"), ("denoised", "tab:red", "denoised")):
            pts = [(r[key]["cpu_seconds"], r[key]["relmse_corrected"], r["samples"]) for r in res["rows"]
                   if r[key]["relmse_corrected"]]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color=colour, ms=3, label=label)
            if key == "denoised":
                for t, e, s in pts:
                    ax.annotate(str(s), (t, e), fontsize=6, xytext=(2, 2), textcoords="offset points")
        ax.axhline(res["reference"]["noise_floor_relmse"], color="grey", ls=":", lw=0.8,
                   label="reference's noise")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU s (%d threads; denoised: + denoiser)" % args.threads, fontsize=8)
        ax.set_title("%s (%s)" % (name, res["integrator"]), fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel("relMSE (ε %g) minus the reference's noise" % EPS, fontsize=8)
    axes[0][0].legend(fontsize=7)
    fig.suptitle("Lantern's denoiser: relMSE against CPU time, %dx%d (labels: samples)" % (args.width, args.height),
                 fontsize=10)
    fig.tight_layout()
    path = os.path.join(args.out, "denoise_scenes.png")
    fig.savefig(path)
    plt.close(fig)
    return path


def main():
    args = parse_args()
    lantern.register()
    os.makedirs(args.out, exist_ok=True)
    result = {
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "command": " ".join(["blender -b --factory-startup --python bench/denoise_scenes.py --"]
                            + (sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])),
        "machine": {"cpus": os.cpu_count(), "processor": cpu_model(), "blender": bpy.app.version_string,
                    "lantern": lt_core.version(), "loadavg_before": os.getloadavg()},
        "threads": args.threads, "epsilon": EPS, "scenes": {},
    }
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="lantern_denoise_") as tmp:
        for name in [s for s in args.scenes.split(",") if s]:
            result["scenes"][name] = run_scene(name, args, tmp)
    result["machine"]["loadavg_after"] = os.getloadavg()
    result["total_seconds"] = time.perf_counter() - t0
    result["plot_png"] = plot(result, args)
    path = os.path.join(args.out, "denoise_scenes.json")
    with open(path, "w") as f:
        json.dump(result, f, indent=2)

    print("\n| scene | samples | relMSE noisy | relMSE denoised | ratio | CPU s noisy | CPU s denoised "
          "| denoiser s (wall) | ratio at equal CPU time | mean shift (σ, R G B) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, res in result["scenes"].items():
        for r in res["rows"]:
            print("| %s (%s) | %d | %s | %s | %s | %.2f | %.2f | %.3f | %s | %s |" % (
                name, res["integrator"], r["samples"], fmt(r["noisy"]["relmse_corrected"], "%.5f"),
                fmt(r["denoised"]["relmse_corrected"], "%.5f"), fmt(r["ratio_equal_samples"], "%.2f"),
                r["noisy"]["cpu_seconds"], r["denoised"]["cpu_seconds"], r["denoised"]["denoise_seconds"],
                fmt(r["ratio_equal_cpu"], "%.2f"), " ".join("%+.2f" % z for z in r["mean_shift_sigmas"])))
    for name, res in result["scenes"].items():
        ref = res["reference"]
        print("%s: reference %d spp (%d x %d, %.0f CPU s), noise floor %.2g; largest |mean shift| %.2f σ; "
              "load %s -> %s" % (name, ref["samples"], ref["chunks"], ref["samples_per_chunk"], ref["cpu_seconds"],
                                 ref["noise_floor_relmse"], res["largest_mean_shift_sigmas"],
                                 ", ".join("%.1f" % x for x in res["loadavg_before"]),
                                 ", ".join("%.1f" % x for x in res["loadavg_after"])))
    print("Total %.0f s; wrote %s and %s" % (result["total_seconds"], path, result["plot_png"]))


main()
