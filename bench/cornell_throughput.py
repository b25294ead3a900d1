"""Throughput benchmark: Lantern against Cycles and against raw Embree on the Cornell box.

Run inside Blender (bench/run_throughput.sh does the build and the call):

    LANTERN_LIBRARY=build-bench/liblantern.so blender -b --factory-startup --python-exit-code 1 \
        --python bench/cornell_throughput.py -- [--width 320] [--height 320] [--samples 64] \
        [--repeats 3] [--embree-raw build-bench/bench/embree_raw] [--out bench/results/throughput.json]

What it measures (one process, one run; ratios are taken between renders of this same run):
  * Cycles (CPU, all threads) and Lantern (path tracer, all threads) render the test scene
    `cornell_area` of scenes/build_scenes.py at equal resolution, samples, bounce limits,
    pixel filter and clamping (none). Each engine is warmed up once (1 sample), then rendered
    `--repeats` times alternately; the best (smallest) time is used for the ratios, since other
    processes only ever add time (medians are in the JSON too). Per render: wall time of
    bpy.ops.render.render (time.perf_counter), Blender's own render time (the "Time:" of Blender's
    last render-stats line, which it prints to stdout), and for Lantern the add-on's export time,
    the core's scene commit (BVH build) time, the core's render time and its ray count (from the
    render status the add-on polls; the script wraps core.Render.poll to see it).
    CPU time of the Blender process (time.process_time, all threads) is reported beside wall
    time: on a machine shared with other jobs it is the less disturbed figure.
  * The scene's world-space triangles, camera and light are dumped to a binary file and
    bench/embree_raw traces as many rays as Lantern traced (primary + cosine bounce rays with
    rtcIntersect1, one shadow ray per hit with rtcOccluded1; see embree_raw.cpp) on the same number
    of threads, `--repeats` times per variant (best run kept). Lantern's rays/s (rays / core render
    time) and rays per CPU second are divided by raw Embree's.
Nothing here asserts on time: it prints figures and writes them to JSON.
"""
import argparse
import contextlib
import ctypes
import json
import os
import re
import statistics
import struct
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

import build_scenes  # noqa: E402  (the test scenes' builders: the same Cornell box as the tests)
from machine import cpu_model  # noqa: E402
import lantern  # noqa: E402
from lantern import core as lt_core  # noqa: E402
from lantern import engine as lt_engine  # noqa: E402

SCENE = "cornell_area"


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="cornell_throughput.py")
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--height", type=int, default=320)
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--threads", type=int, default=0, help="0: all cores (both engines)")
    p.add_argument("--embree-raw", default=os.path.join(REPO, "build-bench", "bench", "embree_raw"))
    p.add_argument("--out", default=os.path.join(BENCH, "results", "throughput.json"))
    p.add_argument("--lantern-only", action="store_true",
                   help="render with Lantern only, once, print its figures and stop (profiling)")
    return p.parse_args(argv)


# ---- Lantern instrumentation: wrap the add-on's calls, change nothing they do ------------------

LANTERN_STATS = {}


def instrument_lantern():
    export_scene = lt_engine.export_scene
    commit = lt_core.Scene.commit
    start = lt_core.Render.start
    poll = lt_core.Render.poll

    def timed_export(*a, **k):
        t = time.perf_counter()
        summary = export_scene(*a, **k)
        LANTERN_STATS["export_seconds"] = time.perf_counter() - t
        LANTERN_STATS["export_summary"] = {k: v for k, v in summary.items()
                                           if isinstance(v, (int, float, str))}
        return summary

    def timed_commit(self):
        t = time.perf_counter()
        commit(self)
        LANTERN_STATS["commit_seconds"] = time.perf_counter() - t

    def timed_start(self):
        LANTERN_STATS["start_time"] = time.perf_counter()
        return start(self)

    def recording_poll(self):
        st = poll(self)
        LANTERN_STATS.update(state=st.state, samples_done=st.samples_done,
                             core_seconds=st.elapsed_seconds, rays=int(st.rays),
                             nan_samples=int(st.nan_samples))
        return st

    lt_engine.export_scene = timed_export
    lt_core.Scene.commit = timed_commit
    lt_core.Render.start = timed_start
    lt_core.Render.poll = recording_poll


# ---- Blender's own render time: the last stats line it prints to stdout ---------------------

_TIME_RE = re.compile(r"Time:(?:(\d+):)?(\d+):(\d+(?:\.\d+)?)")


@contextlib.contextmanager
def captured_stdout(sink):
    """Captures what C code writes to fd 1 (Blender's stats lines) into sink[0]."""
    libc = ctypes.CDLL(None)
    sys.stdout.flush()
    libc.fflush(None)
    saved = os.dup(1)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 1)
        try:
            yield
        finally:
            sys.stdout.flush()
            libc.fflush(None)
            os.dup2(saved, 1)
            os.close(saved)
            tmp.seek(0)
            sink.append(tmp.read().decode("utf-8", "replace"))


def blender_time(text):
    """Seconds of the last 'Time:' in Blender's stats output, or None."""
    last = None
    for m in _TIME_RE.finditer(text):
        h, mnt, s = m.groups()
        last = (int(h or 0) * 60 + int(mnt)) * 60 + float(s)
    return last


# ---- scene --------------------------------------------------------------------------------------

def make_scene(args):
    scene = build_scenes.build(SCENE, scene_name="bench_" + SCENE,
                               resolution=(args.width, args.height), samples=args.samples)
    r = scene.render
    r.use_compositing = False
    r.use_sequencer = False
    r.use_persistent_data = False
    r.threads_mode = "AUTO" if args.threads == 0 else "FIXED"
    if args.threads:
        r.threads = args.threads
    c = scene.cycles
    c.device = "CPU"
    c.use_denoising = False
    c.use_adaptive_sampling = False
    c.time_limit = 0.0
    c.samples = args.samples
    lt = scene.lantern
    lt.samples = args.samples
    lt.seed = 0
    lt.integrator = "PATH"
    # Equal bounce limits and clamping (build_scenes sets Cycles' to the unbiased reference).
    lt.max_bounces = c.max_bounces
    lt.diffuse_bounces = c.diffuse_bounces
    lt.glossy_bounces = c.glossy_bounces
    lt.transmission_bounces = c.transmission_bounces
    lt.transparent_bounces = c.transparent_max_bounces
    lt.clamp_direct = c.sample_clamp_direct
    lt.clamp_indirect = c.sample_clamp_indirect
    return scene


def render_once(scene, engine, samples):
    scene.render.engine = engine
    scene.cycles.samples = samples
    scene.lantern.samples = samples
    LANTERN_STATS.clear()
    out = []
    with captured_stdout(out):
        cpu = time.process_time()
        t = time.perf_counter()
        bpy.ops.render.render(scene=scene.name)
        wall = time.perf_counter() - t
        cpu = time.process_time() - cpu
    rec = {"wall_seconds": wall, "cpu_seconds": cpu, "blender_seconds": blender_time(out[0]),
           "blender_last_stats": (out[0].strip().splitlines() or [""])[-1][:300]}
    if engine == "LANTERN":
        rec.update({k: v for k, v in LANTERN_STATS.items() if k != "start_time"})
    return rec


def image_mean(scene, path):
    """Mean RGB of the Render Result (written as linear EXR): a sanity check of equal work."""
    img_settings = scene.render.image_settings
    img_settings.file_format = "OPEN_EXR"
    img_settings.color_depth = "32"
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    img = bpy.data.images.load(path)
    px = np.empty(len(img.pixels), dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return [float(x) for x in px.reshape(-1, 4)[:, :3].mean(axis=0)]


# ---- geometry dump for embree_raw ---------------------------------------------------------------

def dump_scene(scene, path, width, height):
    """World-space triangles, camera and the area light quad in embree_raw's format."""
    dg = scene.view_layers[0].depsgraph
    dg.update()
    verts, idx, objs = [], [], []
    nv = 0
    cam = light = None
    for k, inst in enumerate(dg.object_instances):
        obj = inst.object
        m = np.array(inst.matrix_world, dtype=np.float64)
        if obj.type == "MESH":
            me = obj.data
            me.calc_loop_triangles()
            co = np.empty(len(me.vertices) * 3, dtype=np.float32)
            me.vertices.foreach_get("co", co)
            co = co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
            tri = np.empty(len(me.loop_triangles) * 3, dtype=np.int32)
            me.loop_triangles.foreach_get("vertices", tri)
            verts.append(co.astype(np.float32))
            idx.append(tri + nv)
            objs.append(np.full(len(tri) // 3, k, dtype=np.int32))
            nv += len(co)
        elif obj.type == "CAMERA" and obj.original == scene.camera:
            # view_frame: top-right, bottom-right, bottom-left, top-left (camera space)
            tr, br, bl, tl = [m @ np.array([*v, 1.0]) for v in obj.data.view_frame(scene=scene)]
            cam = np.concatenate([m[:3, 3], tl[:3], tr[:3], bl[:3], br[:3]])
        elif obj.type == "LIGHT" and obj.data.type == "AREA":
            sx = obj.data.size
            sy = obj.data.size_y if obj.data.shape in ("RECTANGLE", "ELLIPSE") else sx
            corners = [(-sx / 2, -sy / 2), (sx / 2, -sy / 2), (sx / 2, sy / 2), (-sx / 2, sy / 2)]
            light = np.concatenate([(m @ np.array([x, y, 0.0, 1.0]))[:3] for x, y in corners])
    if cam is None or light is None:
        raise RuntimeError("the scene needs a camera and an area light for embree_raw")
    v = np.concatenate(verts)
    i = np.concatenate(idx)
    o = np.concatenate(objs)
    with open(path, "wb") as f:
        f.write(b"LTRB")
        f.write(struct.pack("<5i", 1, len(v), len(i) // 3, width, height))
        f.write(cam.astype("<f4").tobytes())
        f.write(light.astype("<f4").tobytes())
        f.write(v.astype("<f4").tobytes())
        f.write(i.astype("<i4").tobytes())
        f.write(o.astype("<i4").tobytes())
    return {"vertices": int(len(v)), "triangles": int(len(i) // 3)}


def run_embree_raw(exe, path, rays, threads, repeats, *extra):
    """Best of `repeats` runs (highest rays/s; rays per CPU second: its own best)."""
    cmd = [exe, path, "--rays", str(rays), "--threads", str(threads), *extra]
    runs = []
    for _ in range(max(1, repeats)):
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        runs.append(json.loads(out.strip().splitlines()[-1]))
    res = dict(max(runs, key=lambda r: r["rays_per_second"]))
    res["rays_per_cpu_second"] = max(r["rays_per_cpu_second"] for r in runs)
    res["rays_per_second_all"] = [r["rays_per_second"] for r in runs]
    res["rays_per_cpu_second_all"] = [r["rays_per_cpu_second"] for r in runs]
    res["command"] = " ".join(cmd[1:])
    return res


# ---- main ---------------------------------------------------------------------------------------

def best(xs):
    xs = [x for x in xs if x is not None]
    return min(xs) if xs else None


def median(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def main():
    args = parse_args()
    lantern.register()
    instrument_lantern()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    scene = make_scene(args)
    threads = args.threads or os.cpu_count()
    load_before = os.getloadavg()
    pixels = args.width * args.height

    if args.lantern_only:
        rec = render_once(scene, "LANTERN", args.samples)
        print("bench: LANTERN only: %s" % json.dumps(rec))
        return
    for engine in ("CYCLES", "LANTERN"):  # warm-up: kernels, library loading, first-use costs
        render_once(scene, engine, 1)
    runs = {"CYCLES": [], "LANTERN": []}
    for rep in range(args.repeats):
        for engine in ("CYCLES", "LANTERN"):
            rec = render_once(scene, engine, args.samples)
            runs[engine].append(rec)
            print("bench: %-8s run %d: wall %.3f s, Blender time %s s%s" % (
                engine, rep + 1, rec["wall_seconds"], rec["blender_seconds"],
                "" if engine == "CYCLES" else ", core %.3f s, %d rays" % (
                    rec.get("core_seconds", float("nan")), rec.get("rays", 0))), flush=True)
    means = {}
    with tempfile.TemporaryDirectory() as tmp:
        for engine in ("CYCLES", "LANTERN"):  # the images of the last runs, for the sanity check
            render_once(scene, engine, args.samples)
            means[engine] = image_mean(scene, os.path.join(tmp, engine + ".exr"))

    def summary(engine):
        rs = runs[engine]
        s = {"wall_seconds": best([r["wall_seconds"] for r in rs]),
             "wall_seconds_median": median([r["wall_seconds"] for r in rs]),
             "wall_seconds_all": [r["wall_seconds"] for r in rs],
             "cpu_seconds": best([r["cpu_seconds"] for r in rs]),
             "cpu_seconds_all": [r["cpu_seconds"] for r in rs],
             "blender_seconds": best([r["blender_seconds"] for r in rs]),
             "mean_rgb": means[engine]}
        s["samples_per_second"] = pixels * args.samples / s["wall_seconds"]
        if engine == "LANTERN":
            for key in ("export_seconds", "commit_seconds", "core_seconds"):
                s[key] = best([r.get(key) for r in rs])
            s["rays"] = int(median([r.get("rays") for r in rs]))
            s["rays_per_sample"] = s["rays"] / (pixels * args.samples)
            s["rays_per_second_core"] = s["rays"] / s["core_seconds"]
            s["rays_per_second_wall"] = s["rays"] / s["wall_seconds"]
            s["rays_per_cpu_second"] = s["rays"] / s["cpu_seconds"]
            s["samples_per_second_core"] = pixels * args.samples / s["core_seconds"]
            s["nan_samples"] = max(r.get("nan_samples", 0) for r in rs)
        return s

    cy, la = summary("CYCLES"), summary("LANTERN")

    dump = os.path.join(os.path.dirname(os.path.abspath(args.out)), SCENE + "_triangles.bin")
    geo = dump_scene(scene, dump, args.width, args.height)
    raw = {}
    if os.path.isfile(args.embree_raw):
        for name, extra in (("path", ("--mode", "path")),
                            ("path_two_level", ("--mode", "path", "--two-level")),
                            ("closest", ("--mode", "closest"))):
            raw[name] = run_embree_raw(args.embree_raw, dump, la["rays"], threads, args.repeats,
                                       *extra)
    else:
        print("bench: %s not found; build the embree_raw target" % args.embree_raw)

    result = {
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "machine": {"cpus": os.cpu_count(), "processor": cpu_model(),
                    "blender": bpy.app.version_string, "lantern": lt_core.version(),
                    # Other processes on the machine disturb wall times (CPU times less so).
                    "loadavg_before": load_before, "loadavg_after": os.getloadavg()},
        "scene": SCENE, "width": args.width, "height": args.height, "samples": args.samples,
        "threads": threads, "repeats": args.repeats,
        "bounces": {k: getattr(scene.cycles, k) for k in (
            "max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
            "transparent_max_bounces")},
        "geometry": geo, "cycles": cy, "lantern": la, "embree_raw": raw,
        "ratios": {
            "lantern_over_cycles_wall": la["wall_seconds"] / cy["wall_seconds"],
            "lantern_over_cycles_cpu": la["cpu_seconds"] / cy["cpu_seconds"],
            "lantern_over_cycles_blender_time":
                (la["blender_seconds"] / cy["blender_seconds"]
                 if la["blender_seconds"] and cy["blender_seconds"] else None),
        },
    }
    if raw:
        result["ratios"]["lantern_over_embree_raw_rays_per_second"] = (
            la["rays_per_second_core"] / raw["path"]["rays_per_second"])
        result["ratios"]["lantern_over_embree_raw_two_level"] = (
            la["rays_per_second_core"] / raw["path_two_level"]["rays_per_second"])
        result["ratios"]["lantern_over_embree_raw_rays_per_cpu_second"] = (
            la["rays_per_cpu_second"] / raw["path"]["rays_per_cpu_second"])
    goals = result["goals"] = {
        "time_at_equal_samples_le_cycles": result["ratios"]["lantern_over_cycles_wall"] <= 1.0,
        "cpu_time_at_equal_samples_le_cycles": result["ratios"]["lantern_over_cycles_cpu"] <= 1.0}
    if raw:
        goals["rays_per_second_ge_half_raw_embree"] = (
            result["ratios"]["lantern_over_embree_raw_rays_per_second"] >= 0.5)
        goals["rays_per_cpu_second_ge_half_raw_embree"] = (
            result["ratios"]["lantern_over_embree_raw_rays_per_cpu_second"] >= 0.5)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=2)

    rr = result["ratios"]
    print("\n==== Lantern throughput: %s %dx%d, %d spp, %d threads, bounces %s ====" % (
        SCENE, args.width, args.height, args.samples, threads, result["bounces"]))
    print("Cycles : wall %.3f s (Blender time %s s, CPU %.3f s), %.3g samples/s, mean RGB %s" % (
        cy["wall_seconds"], cy["blender_seconds"], cy["cpu_seconds"], cy["samples_per_second"],
        ["%.4f" % x for x in cy["mean_rgb"]]))
    print("Lantern: wall %.3f s (Blender time %s s, CPU %.3f s; export %.3f s, commit/BVH %.3f s, "
          "core render %.3f s), %.3g samples/s, mean RGB %s" % (
              la["wall_seconds"], la["blender_seconds"], la["cpu_seconds"], la["export_seconds"],
              la["commit_seconds"], la["core_seconds"], la["samples_per_second"],
              ["%.4f" % x for x in la["mean_rgb"]]))
    print("Lantern: %d rays (%.2f per sample), %.3g rays/s (core time), %.3g rays/s (wall), "
          "%.3g rays per CPU second" % (la["rays"], la["rays_per_sample"], la["rays_per_second_core"],
                                        la["rays_per_second_wall"], la["rays_per_cpu_second"]))
    print("Ratio Lantern/Cycles wall time: %.3f, CPU time: %.3f%s" % (
        rr["lantern_over_cycles_wall"], rr["lantern_over_cycles_cpu"],
        "" if rr["lantern_over_cycles_blender_time"] is None else
        " (Blender time: %.3f)" % rr["lantern_over_cycles_blender_time"]))
    for name, r in raw.items():
        print("Raw Embree (%s): %d rays (%d intersect + %d occluded) in %.3f s (CPU %.3f s): "
              "%.3g rays/s, %.3g rays per CPU second" % (
                  name, r["rays"], r["intersect_rays"], r["occluded_rays"], r["seconds"],
                  r["cpu_seconds"], r["rays_per_second"], r["rays_per_cpu_second"]))
    if raw:
        print("Ratio Lantern/raw Embree rays/s: %.3f (two-level raw: %.3f; per CPU second: %.3f)" % (
            rr["lantern_over_embree_raw_rays_per_second"], rr["lantern_over_embree_raw_two_level"],
            rr["lantern_over_embree_raw_rays_per_cpu_second"]))
    print("Goals: %s" % goals)
    print("Load average before/after: %s / %s (%d CPUs)" % (
        ", ".join("%.2f" % x for x in load_before),
        ", ".join("%.2f" % x for x in result["machine"]["loadavg_after"]), os.cpu_count()))
    print("Wrote %s" % args.out)


main()
