"""Frame-to-frame time of an animation render (as `blender -b -a`) with Persistent Data, which keeps
the native scene between frames and applies each frame's moves as edits (addon/lantern/scene_sync.py),
against a full re-export of every frame; Cycles' own Persistent Data beside it.

    blender -b --factory-startup --python bench/animation.py -- \
        [--scene sponza|sponza_blur|hair|hair_moving|hair_colour] [--strands 100000] \
        [--frames 6] [--samples 16] [--width 200] [--height 150] [--threads 2] [--engines LANTERN,CYCLES] \
        [--out FILE]

Scenes (scenes/build_scenes.py), every F-curve extrapolated so that each frame moves something:
- sponza: sponza_motion (the Sponza model from ../shared/assets, a box sliding, a box turning and
  the camera panning) with motion blur off and the bulging grid's shape key held still: a deforming
  mesh is a geometry change, which makes Lantern export a new scene.
- sponza_blur: the same with motion blur on (a shutter of 1 frame): each frame samples its
  shutter's sub-frames, then the kept scene takes the frame's motion steps as edits.
- hair: the hair ball with --strands strands (a quarter parents, 4 children each, as
  bench/hair_export.py) and the camera panning 4 degrees a frame: a heavy export kept.
- hair_moving: the same hair ball, the camera still and the ball (the emitter) moving 0.05 m and
  turning 10 degrees a frame: Blender flags each move of an emitter as a geometry update, and
  Lantern keeps the scene when the emitter's mesh and hair read as exported (scene_sync.py).
- hair_colour: the same hair ball, nothing moving, the ball's Object colour (what Object Info's
  Color reads) changing a little each frame: set on the kept instances in place.
Each engine renders frames 1 .. --frames with Persistent Data on, then off, then on and off again
(frame_set and the output's write included, PNG files in a temporary folder); a frame's time is
from the previous frame's write to its own (render_write handlers). Reported per engine and
setting: the first frame (the export every render pays) and the median of the later frames'
times over both runs, and for Lantern the median of the core's render time in them
(lt_render_status.elapsed) and of each frame's time beside it: the export or the edits, the BVH
builds, the frame change and the write. Nothing asserts on time (bench/README.md, animation
renders).
"""
import argparse
import json
import os
import statistics
import sys
import tempfile
import time

BENCH = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(BENCH)
sys.path[:0] = [os.path.join(REPO, "addon"), os.path.join(REPO, "scenes")]


def animate_every_frame(scene):
    """Extrapolates every object's F-curves linearly and holds the shape keys still."""
    import build_scenes
    for ob in scene.objects:
        build_scenes.extrapolate_motion(ob)
        keys = getattr(getattr(ob, "data", None), "shape_keys", None)
        if keys is not None and keys.animation_data:
            keys.animation_data_clear()


def render_animation(scene, engine_name, persistent, args):
    """Renders the frames; returns each frame's wall time and, for Lantern, its core render time and
    the scene_sync counters of the last frame."""
    import bpy
    import render_utils as ru
    from lantern import engine
    ru.configure(scene, engine_name, args.samples, seed=0, threads=args.threads)
    scene.render.image_settings.file_format = "PNG"
    scene.render.use_persistent_data = persistent
    scene.frame_start, scene.frame_end = 1, args.frames
    marks, core = [], []

    def on_pre(_scene, *_):
        if not marks:
            marks.append(time.monotonic())

    def on_write(_scene, *_):
        marks.append(time.monotonic())
        if engine_name == ru.LANTERN:
            core.append(engine.LAST_RENDER["stats"].elapsed_seconds)
    bpy.app.handlers.render_pre.append(on_pre)
    bpy.app.handlers.render_write.append(on_write)
    try:
        with tempfile.TemporaryDirectory(prefix="lantern_anim_") as out:
            scene.render.filepath = os.path.join(out, "frame_")
            bpy.ops.render.render(animation=True, scene=scene.name)
    finally:
        bpy.app.handlers.render_pre.remove(on_pre)
        bpy.app.handlers.render_write.remove(on_write)
        scene.render.use_persistent_data = False
    assert len(marks) == args.frames + 1, (len(marks), args.frames)
    frames = [b - a for a, b in zip(marks, marks[1:])]
    sync = engine.LAST_RENDER.get("scene_sync") if engine_name == ru.LANTERN else None
    return dict(frames=frames, core=core, scene_sync=sync)


def main(args):
    import build_scenes
    import lantern
    lantern.register()
    build_scenes.reset_file()
    if args.scene in ("sponza", "sponza_blur"):
        scene = build_scenes.build("sponza_motion", resolution=(args.width, args.height))
        scene.render.use_motion_blur = args.scene == "sponza_blur"
    else:
        scene = build_scenes.new_scene("hair_animation", (args.width, args.height), args.samples)
        build_scenes.build_hair_ball(scene, strands=args.strands // 4, children=4)
        ball = scene.objects["Ball"]
        if args.scene == "hair":
            build_scenes.pan_camera(scene.camera, 4.0)
        elif args.scene == "hair_moving":
            build_scenes.move_and_turn(ball, 0.05, 10.0)
        else:
            build_scenes._keyframes(ball, "color", [(0.2, 0.4, 0.6, 1.0), (0.3, 0.4, 0.6, 1.0)])
    animate_every_frame(scene)
    results = []
    for engine_name in args.engines.split(","):
        runs = {True: [], False: []}
        for _ in range(2):
            for persistent in (True, False):
                runs[persistent].append(render_animation(scene, engine_name, persistent, args))
        for persistent in (True, False):
            rs = runs[persistent]
            later = [t for r in rs for t in r["frames"][1:]]
            row = dict(engine=engine_name, persistent=persistent, runs=rs,
                       first=min(r["frames"][0] for r in rs), later_median=statistics.median(later))
            text = ""
            if engine_name == "LANTERN":
                row["later_core_median"] = statistics.median(c for r in rs for c in r["core"][1:])
                row["later_beside_median"] = statistics.median(
                    t - c for r in rs for t, c in zip(r["frames"][1:], r["core"][1:]))
                text = ", the core's render %.3f s, beside it %.3f s" % (row["later_core_median"],
                                                                       row["later_beside_median"])
            if rs[-1]["scene_sync"]:
                text += ", scene_sync %s" % rs[-1]["scene_sync"]
            results.append(row)
            print("%-8s persistent %-5s first frame %.2f s, later frames %.3f s (median of %d)%s"
                  % (engine_name, persistent, row["first"], row["later_median"], len(later), text))
        on, off = (next(r for r in results if r["engine"] == engine_name and r["persistent"] == p)
                   for p in (True, False))
        print("%-8s later frames: full re-export / Persistent Data %.2f"
              % (engine_name, off["later_median"] / on["later_median"]))
    out = args.out or os.path.join(BENCH, "results", "animation_%s.json" % args.scene)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        json.dump(dict(scene=args.scene, strands=args.strands if args.scene.startswith("hair") else None,
                       frames=args.frames, samples=args.samples, width=args.width, height=args.height,
                       threads=args.threads, results=results), f, indent=1)


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--scene", choices=("sponza", "sponza_blur", "hair", "hair_moving", "hair_colour"),
                   default="sponza")
    p.add_argument("--strands", type=int, default=100000)
    p.add_argument("--frames", type=int, default=6)
    p.add_argument("--samples", type=int, default=16)
    p.add_argument("--width", type=int, default=200)
    p.add_argument("--height", type=int, default=150)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--engines", default="LANTERN,CYCLES")
    p.add_argument("--out", default=None)
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    main(p.parse_args(argv))
