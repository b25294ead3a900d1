"""Drives Lantern in a real Blender window (run under Xvfb by test_ui_window.py):

    xvfb-run blender --factory-startup --python tests/blender/ui_driver.py -- OUTDIR

Steps, from a bpy.app.timers callback so that the window's event loop keeps running: builds the
Cornell box, selects Lantern, opens the Render properties, turns the 3D view to Rendered shading,
waits for the viewport render, then moves the view, an object, a material and a light and records
what each update did, shows a material preview, and renders with F12. Screenshots of the whole
window go to OUTDIR/*.png, the measurements to OUTDIR/result.json; the test judges them. The
driver itself asserts nothing except that each step happens within its time limit.
"""
import json
import os
import sys
import time
import traceback

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
for path in (os.path.join(REPO, "scenes"), os.path.join(REPO, "addon")):
    if path not in sys.path:
        sys.path.insert(0, path)

import build_scenes  # noqa: E402
import lantern  # noqa: E402

OUT = sys.argv[sys.argv.index("--") + 1]
RESULT = {"steps": [], "screenshots": {}}

if os.environ.get("LANTERN_UI_OPEN_PANELS"):  # for looking at the layout: every panel open
    for cls in lantern.ui.classes:
        cls.bl_options = set(getattr(cls, "bl_options", set())) - {'DEFAULT_CLOSED'}
lantern.register()
bpy.context.preferences.view.show_splash = False


def area(kind):
    win = bpy.context.window_manager.windows[0]
    return next(a for a in win.screen.areas if a.type == kind)


def screenshot(name, window=None, region_of=None):
    """Saves the window as OUTDIR/name.png; returns the pixels (h, w, 4), rows bottom to top,
    cropped to region_of (an Area's WINDOW region) when given."""
    win = window or bpy.context.window_manager.windows[0]
    path = os.path.join(OUT, name + ".png")
    with bpy.context.temp_override(window=win, screen=win.screen, area=win.screen.areas[0]):
        bpy.ops.screen.screenshot(filepath=path)
    img = bpy.data.images.load(path, check_existing=False)
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    px = px.reshape(h, w, 4)
    RESULT["screenshots"][name] = path
    if region_of is not None:
        r = next(r for r in region_of.regions if r.type == 'WINDOW')
        px = px[r.y:r.y + r.height, r.x:r.x + r.width]
    return px


def image_stats(px):
    rgb = px[..., :3]
    lum = rgb.mean(axis=2)
    red = (rgb[..., 0] > 1.5 * rgb[..., 1] + 0.05).mean()
    green = (rgb[..., 1] > 1.3 * rgb[..., 0] + 0.05).mean()
    return dict(mean=float(lum.mean()), std=float(lum.std()), nonblack=float((lum > 0.02).mean()),
                red_fraction=float(red), green_fraction=float(green))


def session():
    sessions = list(lantern.viewport.SESSIONS)
    return sessions[0] if len(sessions) == 1 else None


def wait_until(what, condition, timeout):
    t0 = time.monotonic()
    while not condition():
        if time.monotonic() - t0 > timeout:
            raise TimeoutError("%s: not within %.0f s" % (what, timeout))
        yield 0.02
    RESULT["steps"].append({"step": what, "seconds": round(time.monotonic() - t0, 3)})


def refined(samples):
    s = session()
    return s is not None and s.shown_divider == 1 and s.samples[0] >= samples


def after_change(what, change, timeout=30.0):
    """Applies change(), waits for the session's first image of it; returns (counters before,
    after, seconds to the first image)."""
    s = session()
    before = dict(s.counters)
    version = s.version
    change()
    yield from wait_until(what, lambda: s.first_image_seconds is not None and s.version > version, timeout)
    RESULT[what] = dict(before=before, after=dict(s.counters),
                        first_image_seconds=s.first_image_seconds)


def steps():
    win = bpy.context.window_manager.windows[0]
    scene = build_scenes.build("cornell_area", resolution=(320, 240), samples=16)
    win.scene = scene
    scene.render.engine = 'LANTERN'
    scene.lantern.samples = 16
    scene.lantern.viewport_samples = 8
    props = area('PROPERTIES')
    props.spaces[0].context = 'RENDER'
    view = area('VIEW_3D')
    space = view.spaces[0]
    space.region_3d.view_perspective = 'CAMERA'
    space.overlay.show_overlays = False
    yield 1.0
    RESULT["solid"] = image_stats(screenshot("solid", region_of=view))

    space.shading.type = 'RENDERED'
    yield from wait_until("first viewport image", lambda: session() is not None and session().pixels is not None, 60)
    yield from wait_until("viewport refined to 8 samples", lambda: refined(8), 120)
    yield 0.5  # the last redraw reaches the screen
    RESULT["rendered"] = image_stats(screenshot("viewport_rendered", region_of=view))
    s = session()
    RESULT["viewport_pixels"] = image_stats(s.pixels)

    def orbit():
        # A user view a little to the side of the camera, looking into the box.
        from mathutils import Quaternion, Vector
        cam = scene.camera.matrix_world
        rotation = Quaternion((0.0, 0.0, 1.0), 0.12) @ cam.to_quaternion()
        rv3d = space.region_3d
        rv3d.view_perspective = 'PERSP'
        rv3d.view_rotation = rotation
        rv3d.view_distance = 3.0
        rv3d.view_location = cam.translation + rotation @ Vector((0.0, 0.0, -3.0))
    yield from after_change("camera move", orbit)
    yield from wait_until("refined after the camera move", lambda: refined(4), 60)
    yield 0.5
    RESULT["moved_view"] = image_stats(screenshot("viewport_moved_view", region_of=view))

    box = scene.objects["ShortBox"]
    RESULT["moved_object_name"] = box.name

    def move_object():
        box.location.x += 0.15
    yield from after_change("object move", move_object)

    mat = box.active_material

    def edit_material():
        node = next(n for n in mat.node_tree.nodes if n.type in ('BSDF_DIFFUSE', 'BSDF_PRINCIPLED'))
        node.inputs[0].default_value = (0.1, 0.2, 0.9, 1.0)
    RESULT["edited_material"] = mat.name
    yield from after_change("material edit", edit_material)

    light = next(o for o in scene.objects if o.type == 'LIGHT')

    def edit_light():
        light.data.energy *= 2.0
    yield from after_change("light edit", edit_light)
    yield from wait_until("refined after the edits", lambda: refined(4), 60)
    yield 0.5
    RESULT["edited"] = image_stats(screenshot("viewport_edited", region_of=view))
    RESULT["edited_pixels"] = image_stats(session().pixels)

    # Settings change the viewport render: bounces 0 leaves direct light only (darker).
    scene.lantern.max_bounces = 0
    yield from wait_until("refined with no bounces", lambda: refined(8), 120)
    RESULT["no_bounces_pixels"] = image_stats(session().pixels)
    scene.lantern.max_bounces = 12

    # Material preview: the Material tab renders its preview through render() (is_preview).
    engine = lantern.engine
    engine.LAST_RENDER.clear()
    bpy.context.view_layer.objects.active = box
    box.select_set(True)
    yield 0.5
    props.spaces[0].context = 'MATERIAL'
    yield 3.0
    yield from wait_until("material preview", lambda: engine.LAST_RENDER.get("preview"), 60)
    st = engine.LAST_RENDER["stats"]
    RESULT["preview"] = dict(samples_done=st.samples_done, samples_total=st.samples_total,
                             state=st.state)
    yield 1.0
    screenshot("material_preview")

    # F12: the render shows in an Image Editor in the main window; wait for render_complete.
    props.spaces[0].context = 'RENDER'
    bpy.context.preferences.view.render_display_type = 'AREA'
    done = []
    bpy.app.handlers.render_complete.append(lambda *a: done.append(True))
    space.shading.type = 'SOLID'  # leave the CPU to the final render
    with bpy.context.temp_override(window=win, area=view):
        bpy.ops.render.render('INVOKE_DEFAULT')
    yield from wait_until("F12 render", lambda: bool(done), 120)
    yield 1.0
    editor = next(a for a in win.screen.areas if a.type == 'IMAGE_EDITOR')
    region = next(r for r in editor.regions if r.type == 'WINDOW')
    with bpy.context.temp_override(window=win, area=editor, region=region):
        bpy.ops.image.view_all(fit_view=True)
    yield 1.0
    RESULT["f12"] = image_stats(screenshot("f12_render", region_of=editor))
    RESULT["f12_image"] = editor.spaces[0].image.name if editor.spaces[0].image else None
    RESULT["ok"] = True


_gen = steps()


def tick():
    try:
        return next(_gen)
    except StopIteration:
        pass
    except Exception:
        RESULT["error"] = traceback.format_exc()
    with open(os.path.join(OUT, "result.json"), "w") as f:
        json.dump(RESULT, f, indent=1, default=str)
    bpy.ops.wm.quit_blender()
    return None


bpy.app.timers.register(tick, first_interval=1.0)
