"""Issue 15's motion blur in the add-on (export/motion.py): what the scene sends to the core (the
core counts it in its render report), that a scene without motion pays nothing, and bad input.
Agreement with Cycles is in test_agreement.py (scene motion_blur)."""
import math
import re

import numpy as np
import pytest

import build_scenes
import render_utils as ru
from lantern import engine


def _motion_line():
    report = engine.LAST_RENDER.get("report", "")
    m = re.search(r"motion blur: (\d+) moving object\(s\), (\d+) deforming mesh\(es\), "
                  r"(\d+) moving Volume object\(s\), camera (still|moving, \d+ steps)", report)
    return (int(m.group(1)), int(m.group(2)), int(m.group(3)), m.group(4)) if m else None, report


def test_moving_scene_sends_its_motion_and_restores_the_frame(scene_factory):
    """The translating and rotating boxes move, the grid deforms, the camera pans (3 steps each,
    Cycles' default of 1 motion step); the floor, the wall and the light stay still; the frame
    being rendered is restored after sampling the shutter, for each shutter position."""
    scene = scene_factory("motion_blur", resolution=(24, 16))
    for position in ("CENTER", "START", "END"):
        scene.cycles.motion_blur_position = position
        out = ru.render(scene, ru.LANTERN, 2, seed=0)
        assert np.isfinite(out.combined).all()
        line, report = _motion_line()
        assert line == (2, 1, 0, "moving, 3 steps"), report
        assert (scene.frame_current, scene.frame_subframe) == (1, 0.0)
    # Cycles' 2^steps + 1 time steps; an object with motion blur off does not move.
    scene.camera.cycles.motion_steps = 2
    scene.objects["Rotating"].cycles.use_motion_blur = False
    scene.objects["Deforming"].cycles.use_deform_motion = False
    ru.render(scene, ru.LANTERN, 1, seed=0)
    line, report = _motion_line()
    assert line == (1, 0, 0, "moving, 5 steps"), report


def test_scene_without_motion_sends_none_and_renders_the_same_bits(scene_factory):
    """Motion blur on, nothing moving: the core gets no motion (counted) and the image is
    bit-identical to the render with motion blur off (no time is drawn: the samples' random
    numbers are unchanged)."""
    scene = scene_factory("cornell_area", resolution=(24, 24))
    off = ru.render(scene, ru.LANTERN, 4, seed=3).combined
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 0.5
    on = ru.render(scene, ru.LANTERN, 4, seed=3).combined
    line, report = _motion_line()
    assert line == (0, 0, 0, "still"), report
    assert np.array_equal(off, on)


def test_bad_shutters_and_changing_topology_are_defined(scene_factory):
    """A closed shutter (0) renders without motion; a shutter of 1000 frames samples frames 500
    away (as Cycles; the keys hold their values there), finite; a mesh whose topology changes
    over the shutter (a Build modifier adding faces) gets no deformation blur, with a warning;
    an object that appears mid-shutter keeps its centre transform where it is missing, with a
    warning; one that exists only off-centre is not rendered (Cycles' rules)."""
    scene = scene_factory("motion_blur", resolution=(24, 16))
    scene.render.motion_blur_shutter = 0.0
    assert np.isfinite(ru.render(scene, ru.LANTERN, 1, seed=0).combined).all()
    assert _motion_line()[0] is None
    scene.render.motion_blur_shutter = 1000.0
    assert np.isfinite(ru.render(scene, ru.LANTERN, 1, seed=0).combined).all()
    line, report = _motion_line()
    assert line is not None and line[0] == 2, report
    scene.render.motion_blur_shutter = 1.0
    # Faces appear one frame at a time: the Build modifier changes the topology every frame.
    grid = scene.objects["Deforming"]
    build = grid.modifiers.new("Build", 'BUILD')
    build.frame_start, build.frame_duration = 0.0, 3.0
    # Appears at the centre (hidden before it), and one visible only before the centre.
    late = build_scenes.add_object(scene, "Late", build_scenes.mesh_box("Late", (0.3, 0.3, 0.3)), (0.5, -1, 0))
    early = build_scenes.add_object(scene, "Early", build_scenes.mesh_box("Early", (0.3, 0.3, 0.3)), (-0.5, -1, 0))
    for obj, hidden in ((late, (True, False)), (early, (False, True))):
        for frame, value in zip((0.0, 1.0), hidden):
            obj.hide_render = value
            obj.keyframe_insert("hide_render", frame=frame)
        obj.location.x += 0.2
        obj.keyframe_insert("location", frame=2)
    out = ru.render(scene, ru.LANTERN, 1, seed=0)
    assert np.isfinite(out.combined).all()
    line, report = _motion_line()
    assert "Object 'Deforming': its mesh's topology changes over the shutter" in report, report
    assert "Object 'Late' does not exist at every motion step" in report, report
    assert "Early" not in report, report
    assert line is not None and line[1] == 0, report


def test_viewport_ignores_motion_blur_as_cycles(scene_factory):
    """The viewport's export (export_scene without a render engine's frame_set, as viewport.py
    calls it) sends no motion, as Cycles' viewport renders none, and changes no frame."""
    scene = scene_factory("motion_blur", resolution=(24, 16))
    summary, reports = ru.export(scene)
    stats = summary["stats"]
    assert (stats["motion_instances"], stats["motion_meshes"], stats["camera_motion_steps"]) == (0, 0, 0)
    assert (scene.frame_current, scene.frame_subframe) == (1, 0.0)


@pytest.mark.parametrize("name, motion", [("motion_blur_one", (1, 0, 0, "still")),
                                          ("motion_blur_sliding", (1, 1, 0, "moving, 3 steps"))])
def test_partly_moving_scenes_agree_with_cycles(scene_factory, outdir, name, motion):
    """Per tile and the image mean against Cycles, PATH and BIDIRECTIONAL, on the two ways the core
    gives Embree part of motion_blur. motion_blur_one (only the turning box animated): a scene's one
    moving object, as one Embree instance per motion segment (geometry.cpp, attach_moving; alone,
    Embree would trace it with no bounds test at all). motion_blur_sliding (all but the turning box):
    objects moving without turning, baked into world-space triangles at each motion step
    (bakes_motion), beside a deforming grid and a panning camera."""
    from test_agreement import ROUNDING, TILE
    scene = scene_factory(name)
    spp = build_scenes.SCENES[name][2]
    cycles = [ru.render(scene, ru.CYCLES, spp, seed=seed).combined for seed in (0, 1)]
    for integrator in ("PATH", "BIDIRECTIONAL"):
        lantern = [ru.render(scene, ru.LANTERN, spp, seed=seed, integrator=integrator).combined for seed in (0, 1)]
        assert _motion_line()[0] == motion, _motion_line()[1]
        report, _ = ru.agreement_report(name + "_" + integrator.lower(), lantern, cycles, outdir, TILE, ROUNDING)
        assert report == "", report


def test_curves_and_text_deform_over_the_shutter_as_cycles(scene_factory, outdir):
    """A curve whose Bevel Depth and a text whose Extrude grow in the shutter's second half (at its
    centre, the frame, the ring is a thin tube and the letter thin): their evaluated meshes reach the
    depsgraph as instances of themselves (export/motion.py's own_geometry), which deform as an
    object's mesh does. Before, their deformation blur was dropped (the frame's shapes rendered).
    Per tile and the image mean against Cycles (PATH)."""
    import bpy
    from test_agreement import ROUNDING, TILE
    scene = scene_factory("cornell_area", resolution=(48, 48))
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0
    curve = bpy.data.curves.new("Ring", 'CURVE')
    spline = curve.splines.new('BEZIER')
    spline.bezier_points.add(3)
    for p, (x, z) in zip(spline.bezier_points, ((-0.4, 1.0), (0.0, 1.4), (0.4, 1.0), (0.0, 0.6))):
        p.co = (x, 0.0, z)
        p.handle_left_type = p.handle_right_type = 'AUTO'
    spline.use_cyclic_u = True
    text = bpy.data.curves.new("Word", 'FONT')
    text.body = "L"
    text.size = 0.5
    for data, path, values in ((curve, "bevel_depth", (0.01, 0.3)), (text, "extrude", (0.02, 0.4))):
        for frame, value in zip((1, 1.5), values):
            setattr(data, path, value)
            data.keyframe_insert(path, frame=frame)
        for fc in data.animation_data.action.fcurves:
            for k in fc.keyframe_points:
                k.interpolation = 'LINEAR'
    build_scenes.add_object(scene, "Ring", curve, (0.0, 0.0, 0.0))
    build_scenes.add_object(scene, "Word", text, (0.3, -0.3, 0.3), (90, 0, -20))
    scene.frame_set(1)
    cycles = [ru.render(scene, ru.CYCLES, 64, seed=seed).combined for seed in (0, 1)]
    lantern = [ru.render(scene, ru.LANTERN, 64, seed=seed).combined for seed in (0, 1)]
    assert _motion_line()[0] == (0, 2, 0, "still"), _motion_line()[1]
    report, _ = ru.agreement_report("curve_deform", lantern, cycles, outdir, TILE, ROUNDING)
    assert report == "", report


def test_particles_born_within_the_shutter_are_hidden_as_cycles(scene_factory):
    """Cycles hides a particle instance missing at any motion step (Object::update_motion with
    hide_on_missing_motion, which it sets for particle instances): of a box's particles, the 20 born
    after the shutter opens are not rendered, with a note, and the 10 born before it are."""
    import bpy
    scene = scene_factory("cornell_area", resolution=(24, 24))
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0  # frame 5: 4.5 to 5.5
    pebble = build_scenes.add_object(scene, "Pebble", build_scenes.mesh_box("Pebble", (0.05, 0.05, 0.05)),
                                     (0, 0, -5))
    box = scene.objects["ShortBox"]
    for name, count, born in (("Late", 20, 4.7), ("Early", 10, 1.0)):
        box.modifiers.new(name, 'PARTICLE_SYSTEM')
        settings = box.particle_systems[-1].settings
        settings.count, settings.frame_start, settings.frame_end, settings.lifetime = count, born, born + 0.1, 50
        settings.normal_factor, settings.effector_weights.gravity = 0.5, 0.0
        settings.render_type, settings.instance_object = 'OBJECT', pebble
    bpy.context.window.scene = scene
    scene.frame_set(5)
    assert np.isfinite(ru.render(scene, ru.LANTERN, 1, seed=0).combined).all()
    line, report = _motion_line()
    assert "20 particle instance(s) born or dying within the shutter are not rendered" in report, report
    assert line is not None and line[0] == 10, report


def test_a_zoom_blurs_as_cycles(scene_factory, outdir):
    """A focal length animated from 25 to 75 mm over frames 0 to 2 (50 mm at frame 1): Cycles blurs
    a perspective camera's zoom (its fov at the shutter's opening and closing, the view plane
    interpolated between them), and so does Lantern (lt_camera_desc.zoom_pre and zoom_post; the
    render report says the camera zooms). Per tile and the image mean against Cycles, PATH and
    BIDIRECTIONAL (t = 1 projects through the view plane at the sample's time). Before, the frame's
    focal length alone rendered."""
    from test_agreement import ROUNDING, TILE
    scene = scene_factory("cornell_area", resolution=(48, 48))
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0
    cam = scene.camera.data
    for frame, lens in ((0, 25.0), (2, 75.0)):
        cam.lens = lens
        cam.keyframe_insert("lens", frame=frame)
    for k in cam.animation_data.action.fcurves[0].keyframe_points:
        k.interpolation = 'LINEAR'
    scene.frame_set(1)
    cycles = [ru.render(scene, ru.CYCLES, 64, seed=seed).combined for seed in (0, 1)]
    for integrator in ("PATH", "BIDIRECTIONAL"):
        lantern = [ru.render(scene, ru.LANTERN, 64, seed=seed, integrator=integrator).combined for seed in (0, 1)]
        assert _motion_line()[0] == (0, 0, 0, "still"), _motion_line()[1]
        assert "camera still, zooming" in engine.LAST_RENDER["report"], engine.LAST_RENDER["report"]
        report, _ = ru.agreement_report("zoom_" + integrator.lower(), lantern, cycles, outdir, TILE, ROUNDING)
        assert report == "", report


def test_a_moving_volume_object_blurs_as_cycles(scene_factory, outdir):
    """vdb_cloud's cloud (a Volume object) keyed sliding 1.2 m and turning 60 degrees about z over
    the shutter: each ray looks the grid up at its time (Medium::set_motion), per tile and in the
    image mean against Cycles 3.4, which blurs it, for VOLPATH and BIDIRECTIONAL. The same rule
    tells the cloud rendered at the shutter's centre (motion blur off) from Cycles' blurred one."""
    from test_agreement import ROUNDING, TILE
    scene = scene_factory("vdb_cloud", resolution=(64, 48))
    cloud = scene.objects["Cloud"]
    x, y, z = cloud.location
    for frame, dx, turn in ((0, -0.6, -30.0), (2, 0.6, 30.0)):
        cloud.location = (x + dx, y, z)
        cloud.rotation_euler = (0.0, 0.0, math.radians(turn))
        cloud.keyframe_insert("location", frame=frame)
        cloud.keyframe_insert("rotation_euler", frame=frame)
    scene.frame_set(1)
    scene.render.motion_blur_shutter = 1.0
    scene.render.use_motion_blur = True
    spp = 64
    cycles = [ru.render(scene, ru.CYCLES, spp, seed=seed).combined for seed in (0, 1)]
    for integrator in ("VOLPATH", "BIDIRECTIONAL"):
        lantern = [ru.render(scene, ru.LANTERN, spp, seed=seed, integrator=integrator).combined for seed in (0, 1)]
        assert _motion_line()[0] == (0, 0, 1, "still"), _motion_line()[1]
        report, _ = ru.agreement_report("moving_cloud_" + integrator.lower(), lantern, cycles, outdir, TILE, ROUNDING)
        assert report == "", report
    scene.render.use_motion_blur = False
    still = [ru.render(scene, ru.LANTERN, spp, seed=seed, integrator="VOLPATH").combined for seed in (0, 1)]
    assert ru.agreement_report("still_cloud", still, cycles, outdir, TILE, ROUNDING)[0] != ""
