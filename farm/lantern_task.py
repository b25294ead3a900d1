"""One farm task: renders samples [offset, offset + samples) of one frame of a .blend with Lantern and
writes the part as a 32-bit float EXR with Lantern's own writer (every pass, the sample range, seed,
resolution and the scene's identity in the header), for `lantern merge`.

    blender -b SCENE.blend --python-exit-code 1 --python lantern_task.py -- \\
        (--offset O --samples S | --samples TOTAL --part K/N) [--frame F] --out PART.exr [--timing]

Any farm that runs `blender -b` (Slurm, Flamenco, Deadline) can run it. The add-on is Blender's
installed `lantern`, or the package under $LANTERN_ADDON_DIR (its library: $LANTERN_LIBRARY or the
one beside it). Fails (exit code 1, message on stderr) on any error: a part is written completely
or not at all.
"""
import argparse
import hashlib
import os
import sys
import time

import bpy

T_START = time.monotonic()


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="lantern_task.py")
    p.add_argument("--offset", type=int, help="first sample index")
    p.add_argument("--samples", type=int, required=True,
                   help="number of samples; with --part, of the whole render")
    p.add_argument("--part", help="K/N: render part K (0 to N-1) of N of the --samples, samples "
                                  "[K S / N, (K + 1) S / N): for farms that number tasks but cannot "
                                  "compute offsets (Deadline's <STARTFRAME>, Flamenco)")
    p.add_argument("--frame", type=int, default=None, help="frame (default: the scene's current)")
    p.add_argument("--out", required=True, help="the part's EXR path")
    p.add_argument("--scene-id", help="the scene's identity for the merge (default: a hash of the .blend "
                                      "file; `lantern farm submit` computes it once for all tasks)")
    p.add_argument("--timing", action="store_true", help="print the time of each stage (bench/)")
    args = p.parse_args(argv)
    if (args.part is None) == (args.offset is None):
        p.error("give either --offset or --part")
    if args.part is not None:
        try:
            k, n = (int(x) for x in args.part.split("/"))
        except ValueError:
            p.error("--part wants K/N, got %r" % args.part)
        if not (0 <= k < n <= args.samples):
            p.error("--part %s: need 0 <= K < N <= --samples (%d)" % (args.part, args.samples))
        args.offset = k * args.samples // n
        args.samples = (k + 1) * args.samples // n - args.offset
    return args


def load_addon():
    addon_dir = os.environ.get("LANTERN_ADDON_DIR")
    if addon_dir:
        sys.path.insert(0, addon_dir)
        import lantern
        if not hasattr(bpy.types.Scene, "lantern"):
            lantern.register()
    else:
        import addon_utils
        addon_utils.enable("lantern", default_set=False)
        import lantern  # noqa: F401
    from lantern import core, engine
    from lantern.export import export_scene
    return core, engine, export_scene


def blend_hash(path):
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()[:20]


def scene_identity(scene_id, frame):
    """Which render a part belongs to: the .blend's content and the frame (lt_merge_exr compares it)."""
    return "%s frame %d" % (scene_id or blend_hash(bpy.data.filepath), frame)


def main():
    args = parse_args()
    if args.samples < 1 or args.offset < 0:
        raise SystemExit("lantern task: need --samples >= 1 and --offset >= 0")
    core, engine, export_scene = load_addon()
    scene = bpy.context.scene
    frame = scene.frame_current if args.frame is None else args.frame
    scene.frame_set(frame)
    t_loaded = time.monotonic()

    width, height, border = engine.frame_size(scene.render)
    settings = engine.render_settings(scene, width, height, border)
    settings.update(samples=args.samples, sample_offset=args.offset)
    # Every pass before the light and data passes (parts need them to merge), and those the view
    # layer enables: default scenes render at the same cost as before them.
    wanted = engine.pass_settings(engine.enabled_passes(scene, bpy.context.view_layer), 0)
    settings["passes"] = ((1 << core.PASS_DIFFUSE_DIRECT) - 1) | wanted["passes"]
    settings["lightgroups"], settings["aovs"] = wanted["lightgroups"], wanted["aovs"]
    settings["pass_alpha_threshold"] = bpy.context.view_layer.pass_alpha_threshold
    crypto, _ = engine.cryptomatte_settings(bpy.context.view_layer, 0)
    settings.update(crypto)
    warnings = []
    core_scene = core.Scene()
    summary = export_scene(bpy.context.evaluated_depsgraph_get(), core_scene,
                           lambda level, msg: warnings.append(msg))
    t_exported = time.monotonic()
    core_scene.commit()
    t_built = time.monotonic()
    for w in warnings + list(core_scene.warnings()):
        print("lantern task: warning: %s" % w, file=sys.stderr)

    render = core.Render(core_scene, settings)
    render.start()
    render.wait()
    st = render.poll()
    if st.state != core.STATE_DONE or st.samples_done != args.samples:
        raise SystemExit("lantern task: render stopped after %d of %d samples (state %d)"
                         % (st.samples_done, args.samples, st.state))
    t_rendered = time.monotonic()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    # Cryptomatte manifests as the specification puts them beside CryptoObject00.r, ...
    attributes = engine.cryptomatte.metadata(summary.get("cryptomatte", {}), "", crypto["cryptomatte"])
    attributes.update({"lantern/scene": scene_identity(args.scene_id, frame), "lantern/frame": str(frame),
                       "lantern/blend": bpy.data.filepath})
    render.write_exr(args.out, attributes)
    render.close()
    core_scene.close()
    print("lantern task: frame %d samples [%d, %d) -> %s" % (frame, args.offset,
                                                             args.offset + args.samples, args.out))
    if args.timing:
        print("lantern task timing: startup %.3f export %.3f build %.3f render %.3f write %.3f" % (
            t_loaded - T_START, t_exported - t_loaded, t_built - t_exported, t_rendered - t_built,
            time.monotonic() - t_rendered))


main()
