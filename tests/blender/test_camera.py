"""Issue 15's cameras in the add-on: the focus distance as Cycles takes it from a focus object,
what Lantern reports for camera settings it cannot render, and the panels it shows."""
import math
import types

import bpy
import numpy as np
from mathutils import Vector

import render_utils as ru
from lantern import ui
from lantern.export.camera import focus_distance


def test_focus_object_distance_is_along_the_view_axis(scene_factory):
    """Cycles' blender_camera_focal_distance: |view axis . (camera - target)|, so an object off
    the axis focuses at its depth, and one behind the camera at the same distance in front."""
    scene = scene_factory("cornell_dof")
    cam = scene.camera
    depsgraph = scene.view_layers[0].depsgraph
    target = scene.objects["ShortBox"]
    forward = (cam.matrix_world.to_3x3() @ Vector((0, 0, -1))).normalized()
    right = (cam.matrix_world.to_3x3() @ Vector((1, 0, 0))).normalized()
    for offset, depth in ((forward * 2.5 + right * 1.2, 2.5), (-forward * 1.5 + right * 0.3, 1.5)):
        target.location = cam.matrix_world.translation + offset
        depsgraph.update()
        assert math.isclose(focus_distance(depsgraph, cam), depth, rel_tol=1e-5), (offset, depth)
    cam.data.dof.focus_object = None
    cam.data.dof.focus_distance = 3.25
    assert focus_distance(depsgraph, cam) == 3.25


def test_camera_settings_lantern_cannot_render_are_reported(scene_factory):
    """A focus distance of 0 (the plane in focus at the lens) renders without depth of field, with
    a warning naming the camera, and a finite image; an equiangular cubemap face renders as itself,
    with no warning."""
    scene = scene_factory("cornell_dof", resolution=(24, 24))
    cam = scene.camera.data
    cam.dof.focus_object = None
    cam.dof.focus_distance = 0.0
    reports = ru.export(scene)[1]
    assert any("Camera" in r and "focus distance is 0" in r for r in reports), reports
    cam.dof.use_dof = False
    cam.type = 'PANO'
    cam.cycles.panorama_type = 'EQUIANGULAR_CUBEMAP_FACE'
    reports = ru.export(scene)[1]
    assert not any("Camera" in r for r in reports), reports
    assert np.isfinite(ru.render(scene, ru.LANTERN, 2, seed=0).combined).all()


def test_depth_of_field_and_panorama_panels_show_for_lantern(scene_factory):
    """Blender's Depth of Field panels (Cycles shows them; Blender lists only EEVEE and Workbench)
    and Lantern's Panorama panel, which draws Cycles' panorama settings for panoramic cameras."""
    scene = scene_factory("pano_fisheye_equisolid")
    for name in ("DATA_PT_camera_dof", "DATA_PT_camera_dof_aperture"):
        assert 'LANTERN' in getattr(bpy.types, name).COMPAT_ENGINES, name
    panel = ui.LANTERN_CAMERA_PT_panorama
    cam = scene.camera.data
    for engine_id, kind, visible in (('LANTERN', 'PANO', True), ('LANTERN', 'PERSP', False),
                                     ('CYCLES', 'PANO', False)):
        cam.type = kind
        assert bool(panel.poll(types.SimpleNamespace(engine=engine_id, camera=cam))) == visible
    cam.type = 'PANO'
    for kind in ('EQUIRECTANGULAR', 'FISHEYE_EQUIDISTANT', 'FISHEYE_EQUISOLID', 'FISHEYE_LENS_POLYNOMIAL',
                 'EQUIANGULAR_CUBEMAP_FACE', 'MIRRORBALL'):
        cam.cycles.panorama_type = kind
        drawn = []

        class Layout:
            def prop(self, data, name, **kw):
                drawn.append((data, name))

            def __getattr__(self, name):
                return lambda *a, **kw: Layout()
        panel.draw(types.SimpleNamespace(layout=Layout()), types.SimpleNamespace(camera=cam))
        assert "panorama_type" in [n for _, n in drawn], (kind, drawn)
        assert len(drawn) >= 2 or kind in ('EQUIANGULAR_CUBEMAP_FACE', 'MIRRORBALL'), (kind, drawn)
        for data, name in drawn:
            assert name in data.bl_rna.properties, name


def test_film_outside_a_fisheye_is_black_and_opaque_as_in_cycles(scene_factory):
    """With Film > Transparent, the film a fisheye does not see is black with alpha 1 in Cycles
    (it skips those samples) and in Lantern; inside, both see the box (alpha 1, some light)."""
    scene = scene_factory("pano_fisheye_equidistant", resolution=(24, 24))
    scene.render.film_transparent = True
    for engine in (ru.CYCLES, ru.LANTERN):
        img = ru.render(scene, engine, 4, seed=0).combined
        for corner in (img[0, 0], img[0, -1], img[-1, 0], img[-1, -1]):
            assert list(corner) == [0.0, 0.0, 0.0, 1.0], (engine, corner)
        assert img[12, 12, 3] == 1.0 and img[8:16, 8:16, :3].mean() > 0, engine


def test_orthographic_depth_of_field_focuses_past_the_clip_start_as_cycles(scene_factory, tmp_path):
    """Cycles' orthographic rays start on the near clip plane and aim at the focus distance from
    there (camera_sample_orthographic): with Clip Start 2 m the plane in focus is 2 m beyond the
    short box, the focus object. Lantern agrees with Cycles (8-pixel tiles and the image mean, two
    seeds each) for PATH and BIDIRECTIONAL (BDPT's t = 1 connects to the near plane too); with the
    focus at the box (Lantern before), the box's edges and the walls' differ."""
    scene = scene_factory("cornell_dof", resolution=(48, 48))
    cam = scene.camera.data
    cam.type = 'ORTHO'
    cam.ortho_scale = 2.4
    cam.clip_start = 2.0
    cam.dof.aperture_fstop = 2.0  # an orthographic aperture radius of 1 / (2 F-stop): 25 cm
    cycles = [ru.render(scene, ru.CYCLES, 64, seed=s).combined for s in (0, 1)]
    for integrator in ("PATH", "BIDIRECTIONAL"):
        lantern = [ru.render(scene, ru.LANTERN, 64, seed=s, integrator=integrator).combined for s in (0, 1)]
        report, _ = ru.agreement_report("ortho_dof_" + integrator, lantern, cycles, str(tmp_path), tile=8)
        assert report == "", report
