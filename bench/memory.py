"""Peak memory of a render, Lantern against Cycles, in the same run (issue 18).

    python3 bench/memory.py --library build/liblantern.so [--sizes 1920x1080,4000x4000,8000x8000]
        [--texture 8192] [--texture-formats png,exr,jpg,hdr] [--interpolation Linear]
        [--out bench/results/memory.json]

Each measurement is a fresh `blender -b --factory-startup` process (this script is its own worker):
it builds `cornell_area` from scenes/build_scenes.py, sets the resolution, 1 sample, and
renders with bpy.ops.render.render (Cycles on the CPU, or Lantern through this checkout's add-on).
The parent takes the process's peak resident set size from os.wait4 (ru_maxrss, the kernel's
high-water mark of the whole process, Blender included). A run that builds the scene and does not
render gives the baseline; bytes per pixel = (peak - baseline) / pixels: everything a render
adds (film, Blender's RenderResult, the add-on's buffers).

"default" passes are the view layer's defaults (Combined, Depth); "all" also enables Normal and, for
Cycles, its Denoising Data and Debug Sample Count passes, for Lantern the Albedo, Variance and Sample
Count passes (View Layer > Passes, lantern_extra_passes).

Textures: a plane with an N x N image (generated once into bench/results/ by Blender: an 8-bit sRGB
PNG, a 32-bit float OpenEXR, an 8-bit sRGB JPEG and a Radiance HDR; --texture-formats), rendered at
256 x 256, 1 sample; bytes per texel = (peak - peak of the same
scene with a 64 x 64 image) / (N^2 - 64^2), so it counts every copy of the image (Blender's own
included, where the engine makes Blender load it). Nothing asserts on memory or time.
"""
import argparse
import json
import os
import subprocess
import sys
import time

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
RESULTS = os.path.join(BENCH, "results")


# The texture files' formats by extension, and those Blender reads as float (scene linear).
_FILE_FORMATS = {"png": "PNG", "exr": "OPEN_EXR", "jpg": "JPEG", "hdr": "HDR"}
_FLOAT_FORMATS = {"exr", "hdr"}


def _parse_size(s):
    w, h = s.lower().split("x")
    return int(w), int(h)


# ---- worker (inside Blender) ------------------------------------------------------------------
def worker(args):
    import bpy
    import numpy as np
    sys.path[:0] = [os.path.join(REPO, "addon"), os.path.join(REPO, "scenes")]
    import build_scenes
    import lantern
    lantern.register()
    if args.make_image:
        n = args.make_image_size
        path = args.make_image
        ext = os.path.splitext(path)[1][1:]
        is_float = ext in _FLOAT_FORMATS
        img = bpy.data.images.new("gen", n, n, alpha=False, float_buffer=is_float)
        ramp = np.linspace(0.0, 1.0, n, dtype=np.float32)
        px = np.empty((n, n, 4), np.float32)
        px[..., 0] = ramp[None, :]
        px[..., 1] = ramp[:, None]
        px[..., 2] = 0.5
        px[..., 3] = 1.0
        img.pixels.foreach_set(px.ravel())
        del px
        img.filepath_raw = path
        img.file_format = _FILE_FORMATS[ext]
        if ext == "exr":
            img.use_half_precision = False  # 32-bit float EXR
        img.save()
        return
    build_scenes.reset_file()
    scene = build_scenes.build("cornell_area")
    if args.image:
        img = bpy.data.images.load(args.image)
        img.colorspace_settings.name = "Linear" if os.path.splitext(args.image)[1][1:] in _FLOAT_FORMATS else "sRGB"
        floor = scene.objects["Floor"]
        floor.data.materials.clear()
        mat = build_scenes.image_material("Tex", img)
        for n in mat.node_tree.nodes:
            if n.type == 'TEX_IMAGE':
                n.interpolation = args.interpolation
        floor.data.materials.append(mat)
    w, h = _parse_size(args.size)
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.engine = "LANTERN" if args.engine == "lantern" else "CYCLES"
    scene.cycles.samples = 1
    scene.lantern.samples = 1
    layer = scene.view_layers[0]
    if args.passes == "all":
        layer.use_pass_normal = True
        layer.cycles.denoising_store_passes = True
        layer.cycles.pass_debug_sample_count = True
        layer.lantern_extra_passes = True
    if not args.no_render:
        t0 = time.perf_counter()
        bpy.ops.render.render(scene=scene.name)
        print("MEMBENCH render_seconds %.3f" % (time.perf_counter() - t0))
        report = getattr(lantern.engine, "LAST_RENDER", {}).get("report")
        if report and args.engine == "lantern":
            for line in report.splitlines():
                if "memory" in line.lower():
                    print("MEMBENCH report " + line.strip())


# ---- parent -------------------------------------------------------------------------------------
def run(args, **kw):
    cmd = ["blender", "-b", "--factory-startup", "--python-exit-code", "1", "--python",
           os.path.abspath(__file__), "--", "--worker"]
    for k, v in kw.items():
        if v is True:
            cmd.append("--" + k.replace("_", "-"))
        elif v not in (None, False):
            cmd += ["--" + k.replace("_", "-"), str(v)]
    # Blender's embedded (Debian) Python must not see a pyenv interpreter this script may run under.
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYENV")}
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if ".pyenv" not in p)
    env["LANTERN_LIBRARY"] = os.path.abspath(args.library)
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    out = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.stderr.write(out[-4000:])
        raise SystemExit("worker failed (%d): %s" % (p.returncode, kw))
    info = {"peak_bytes": usage.ru_maxrss * 1024}
    for line in out.splitlines():
        if line.startswith("MEMBENCH "):
            key, _, value = line[len("MEMBENCH "):].partition(" ")
            info[key] = value
    return info


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--worker", action="store_true")
    ap.add_argument("--library", default=os.path.join(REPO, "build", "liblantern.so"))
    ap.add_argument("--sizes", default="1920x1080,4000x4000,8000x8000")
    ap.add_argument("--texture", type=int, default=8192)
    ap.add_argument("--texture-formats", default="png,exr,jpg,hdr")
    ap.add_argument("--engines", default="cycles,lantern")
    ap.add_argument("--passes-sets", default="default,all")
    ap.add_argument("--interpolation", default="Linear", help="the texture's: Linear, Closest, Cubic, Smart")
    ap.add_argument("--out", default=os.path.join(RESULTS, "memory.json"))
    # worker arguments
    ap.add_argument("--engine")
    ap.add_argument("--size", default="64x64")
    ap.add_argument("--passes", default="default")
    ap.add_argument("--image")
    ap.add_argument("--no-render", action="store_true")
    ap.add_argument("--make-image")
    ap.add_argument("--make-image-size", type=int, default=0)
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    args = ap.parse_args(argv)
    if args.worker:
        return worker(args)
    os.makedirs(RESULTS, exist_ok=True)
    results = {"library": os.path.abspath(args.library), "film": [], "texture": []}
    gib = 1024.0 ** 3
    engines = args.engines.split(",")
    for engine in engines:
        base = run(args, engine=engine, no_render=True)["peak_bytes"]
        for passes in args.passes_sets.split(","):
            for size in filter(None, args.sizes.split(",")):
                w, h = _parse_size(size)
                info = run(args, engine=engine, size=size, passes=passes)
                row = dict(engine=engine, passes=passes, width=w, height=h, baseline_bytes=base,
                           bytes_per_pixel=(info["peak_bytes"] - base) / (w * h), **info)
                results["film"].append(row)
                print("%-8s %-8s %5dx%-5d peak %6.2f GiB  %6.1f B/px  %s" % (
                    engine, passes, w, h, info["peak_bytes"] / gib, row["bytes_per_pixel"],
                    info.get("report", "")), flush=True)
    if args.texture:
        n = args.texture
        for ext in args.texture_formats.split(","):
            paths = {}
            for size in (64, n):
                paths[size] = os.path.join(RESULTS, "memtex_%d.%s" % (size, ext))
                if not os.path.exists(paths[size]):
                    run(args, make_image=paths[size], make_image_size=size)
            for engine in engines:
                small = run(args, engine=engine, size="256x256", image=paths[64],
                            interpolation=args.interpolation)["peak_bytes"]
                info = run(args, engine=engine, size="256x256", image=paths[n], interpolation=args.interpolation)
                row = dict(engine=engine, format=ext, interpolation=args.interpolation, texels=n * n,
                           small_peak_bytes=small,
                           bytes_per_texel=(info["peak_bytes"] - small) / (n * n - 64 * 64), **info)
                results["texture"].append(row)
                print("%-8s %s %dx%d texture: peak %6.2f GiB  %5.1f B/texel  %s" % (
                    engine, ext, n, n, info["peak_bytes"] / gib, row["bytes_per_texel"],
                    info.get("report", "")), flush=True)
    with open(args.out, "w") as f:
        json.dump(results, f, indent=1)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
