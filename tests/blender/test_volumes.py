"""Volumes: export of volume materials and Volume objects, and agreement with Cycles.

Agreement uses test_agreement.py's rule (two seeds per engine, 16x16 tile means within a
Bonferroni-corrected z bound of both engines' noise). Lantern's volume_bounces is copied from
scene.cycles.volume_bounces (render_utils.configure); the mesh media are homogeneous, which Cycles
integrates exactly as Lantern does; vdb_cloud (a Volume object) is discussed in its test.
"""
import os

import bpy
import numpy as np
import pytest

import render_utils as ru

VOLUME_SCENES = ["smoke_box", "thin_fog", "dense_fog", "world_fog"]
SAMPLES = 128
TILE = 16
ROUNDING = 1e-5


def _export(scene):
    summary, reports = ru.export(scene)
    return summary, "\n".join(reports)


@pytest.mark.parametrize("name", VOLUME_SCENES)
@pytest.mark.parametrize("volume_bounces", [0, 2])
def test_volume_agrees_with_cycles(name, volume_bounces, scene_factory, outdir):
    scene = scene_factory(name)
    scene.cycles.volume_bounces = volume_bounces
    report, _ = ru.two_seed_agreement(scene, SAMPLES, "VOLPATH", "%s_vb%d" % (name, volume_bounces), outdir,
                                      TILE, ROUNDING)
    assert report == "", report


def test_volume_only_material_is_an_invisible_boundary(scene_factory):
    scene = scene_factory("smoke_box")
    summary, text = _export(scene)
    assert "Smoke" not in text, text
    # With PATH the boundary is Transparent: the smoke is invisible, the image equals the box's.
    img = ru.render(scene, ru.LANTERN, 4, seed=0, integrator="PATH").combined
    assert np.isfinite(img).all()


def test_unsupported_volume_node_is_reported(scene_factory):
    scene = scene_factory("smoke_box")
    mat = bpy.data.materials["Smoke"]
    nt = mat.node_tree
    out = nt.get_output_node('CYCLES')
    emission = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(emission.outputs[0], out.inputs["Volume"])
    _, text = _export(scene)
    assert "Smoke" in text and "Emission" in text, text


def test_volume_object_with_missing_file_is_reported(scene_factory, tmp_path):
    scene = scene_factory("smoke_box")
    vol = bpy.data.volumes.new("MissingCloud")
    vol.filepath = str(tmp_path / "no_such_cloud.vdb")
    obj = bpy.data.objects.new("MissingCloud", vol)
    scene.collection.objects.link(obj)
    summary, text = _export(scene)
    assert "MissingCloud" in text and "no_such_cloud.vdb" in text, text
    assert summary["volumes"] == 0
    img = ru.render(scene, ru.LANTERN, 2, seed=0, integrator="VOLPATH").combined
    assert np.isfinite(img).all()


# ---- OpenVDB ---------------------------------------------------------------------------------
def _need_vdb(filename):
    import build_scenes
    path = build_scenes.test_vdb_path(filename)
    if not os.path.exists(path):
        pytest.skip("%s not generated (build the make_test_vdb target; LANTERN_TEST_VDB_DIR)" % path)
    return path


@pytest.mark.parametrize("estimator", ["TRACKING"])
def test_vdb_cloud_agrees_with_cycles(estimator, scene_factory, outdir):
    """vdb_cloud (tests/scenes/build_scenes.py): a Volume object reading cloud.vdb, white Principled
    Volume of density 5, sun and world, two volume bounces; Lantern's unbiased delta/ratio
    tracking against Cycles, same rule as above.

    Residual bias: Cycles 3.4 ray-marches the grid (step = voxel size x volume_step_rate = 4 cm x
    0.25 = 1 cm, jittered per ray): its transmittance is the mean of exp(-sum sigma_t h) over the
    jitter, biased by O(h^2) curvature and Jensen terms. With sigma_t <= 5 /m the optical depth per
    step is <= 0.05 and the density varies over several voxels, so the bias is far below 1e-3
    relative; measured: Lantern's image mean is +0.06% of Cycles' at 64 spp (noise-level), max tile
    |d|/bound 0.54. The tolerance (z of a 1e-3 family-wise rate on 128 spp tiles, ~1% of a tile) is
    an order of magnitude above that bias. Cycles places voxel i at index i + 0.5; the add-on shifts
    grids by half a voxel to match (export/volume.py): without it this test fails (|d|/bound 3.1).
    """
    _need_vdb("cloud.vdb")
    scene = scene_factory("vdb_cloud")
    scene.lantern.volume_estimator = estimator
    report, mean_l = ru.two_seed_agreement(scene, SAMPLES, "VOLPATH", "vdb_cloud_%s" % estimator.lower(), outdir,
                                           TILE, ROUNDING)
    assert mean_l.max() > 1.2 * mean_l.min()  # the cloud is there: its tiles differ from the world's
    assert report == "", report


@pytest.mark.parametrize("space", ["OBJECT", "WORLD"])
def test_scaled_volume_object_agrees_with_cycles(space, scene_factory, outdir):
    """vdb_cloud_scaled: the cloud grid in a Volume object scaled by (0.8, 0.5, 0.3), read through
    the Principled Volume's Density Attribute 'cloud' (the file's 'density' grid is another shape).
    Render space Object (Blender's default) keeps density per object-space unit: Cycles divides it
    by |M n| for n the unit diagonal (1.75 here); World keeps it per metre. The same rule as above.
    Fails with the render space ignored (Object: image mean ratio Lantern / Cycles 0.981, which
    only the global mean check sees) or with the 'density' grid read (0.955)."""
    _need_vdb("two_grids.vdb")
    scene = scene_factory("vdb_cloud_scaled")
    scene.objects["Cloud"].data.render.space = space
    report, mean_l = ru.two_seed_agreement(scene, SAMPLES, "VOLPATH", "vdb_cloud_scaled_%s" % space.lower(),
                                           outdir, TILE, ROUNDING)
    assert mean_l.max() > 1.2 * mean_l.min()
    assert report == "", report


def test_volume_step_size_follows_render_space(scene_factory):
    """Ray marching with a Volume object's own Step Size: in render space Object the step in
    metres is the smallest of |M (s, s, s)| over the axes (Cycles' compute_volume_step_size), so
    the image is bit for bit the one with the render-wide step set to that length."""
    _need_vdb("two_grids.vdb")
    scene = scene_factory("vdb_cloud_scaled")
    scene.lantern.volume_estimator = "RAY_MARCHING"
    cloud = scene.objects["Cloud"]
    cloud.data.render.step_size = 0.25
    per_object = ru.render(scene, ru.LANTERN, 2, seed=0, integrator="VOLPATH").combined
    cloud.data.render.step_size = 0.0
    images = {}
    for step in (0.25 * 0.3, 0.25 * 0.5):
        scene.lantern.volume_step = step
        images[step] = ru.render(scene, ru.LANTERN, 2, seed=0, integrator="VOLPATH").combined
    assert np.array_equal(per_object, images[0.25 * 0.3])
    assert not np.array_equal(per_object, images[0.25 * 0.5])


def test_vdb_cloud_ray_marching_renders(scene_factory):
    _need_vdb("cloud.vdb")
    scene = scene_factory("vdb_cloud")
    scene.lantern.volume_estimator = "RAY_MARCHING"
    summary, text = _export(scene)
    assert summary["volumes"] == 1, text
    img = ru.render(scene, ru.LANTERN, 4, seed=0, integrator="VOLPATH").combined
    assert np.isfinite(img).all()


def _add_volume_object(scene, name, path):
    vol = bpy.data.volumes.new(name)
    vol.filepath = str(path)
    obj = bpy.data.objects.new(name, vol)
    scene.collection.objects.link(obj)
    return obj


def test_volume_object_with_garbage_file_is_reported(scene_factory, tmp_path):
    """A .vdb that is not an OpenVDB file: the core's LT_ERROR_IO message is in the report. (A file
    with a valid header and a corrupt or truncated body cannot be tested in Blender 3.4: Blender's
    own depsgraph evaluation of the Volume object aborts the process in OpenVDB before the add-on
    runs; the core's handling of those files is covered by the native VDB tests.)"""
    scene = scene_factory("smoke_box")
    path = tmp_path / "garbage.vdb"
    path.write_bytes(b"this is not an OpenVDB file\n" * 20)
    _add_volume_object(scene, "GarbageCloud", path)
    summary, text = _export(scene)
    assert "GarbageCloud" in text and "garbage.vdb" in text, text
    assert summary["volumes"] == 0
    img = ru.render(scene, ru.LANTERN, 2, seed=0, integrator="VOLPATH").combined
    assert np.isfinite(img).all()


def test_volume_object_without_density_grid_is_reported(scene_factory):
    scene = scene_factory("smoke_box")
    _add_volume_object(scene, "NoDensity", _need_vdb("no_density.vdb"))
    summary, text = _export(scene)
    assert "NoDensity" in text and "density" in text, text
    assert "left out" in text, text
    assert summary["volumes"] == 0
    img = ru.render(scene, ru.LANTERN, 2, seed=0, integrator="VOLPATH").combined
    assert np.isfinite(img).all()


def test_volume_debug_view_renders(scene_factory):
    scene = scene_factory("smoke_box")
    img = ru.render(scene, ru.LANTERN, 4, seed=0, integrator="VOLUME_DEBUG").combined
    assert np.isfinite(img).all()
    assert img[..., :3].min() >= 0.0
    assert img[..., :3].max() > 1.0, "the distance panels hold metres from the camera"


def test_render_report_says_which_integrators_render_media(scene_factory):
    """The export counts the smoke and the render report lists it; under PATH it says the media
    are ignored, under VOLPATH and BIDIRECTIONAL it does not."""
    from lantern import engine
    scene = scene_factory("smoke_box")
    for integrator in ("PATH", "VOLPATH", "BIDIRECTIONAL"):
        ru.render(scene, ru.LANTERN, 2, seed=0, integrator=integrator)
        text = engine.LAST_RENDER["report"]
        assert "media: 1 homogeneous" in text, text
        assert ("IGNORED" in text) == (integrator == "PATH"), (integrator, text)


# ---- World volume ------------------------------------------------------------------------------
def test_world_volume_is_exported_and_counted(scene_factory):
    scene = scene_factory("world_fog")
    summary, text = _export(scene)
    assert summary["media"] == 1, summary
    assert text == "", text


def test_world_volume_hides_background_and_sun(scene_factory):
    """Cycles 3.4 hides the background and suns behind a World volume (infinite escape distance);
    Lantern's VOLPATH too: with the point light removed the image is black."""
    scene = scene_factory("world_fog")
    bpy.data.objects["Lamp"].hide_render = True
    img = ru.render(scene, ru.LANTERN, 4, seed=0, integrator="VOLPATH").combined
    assert np.isfinite(img).all()
    assert img[..., :3].max() == 0.0


def test_unsupported_world_volume_node_is_reported(scene_factory):
    scene = scene_factory("world_fog")
    nt = scene.world.node_tree
    emission = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(emission.outputs[0], nt.get_output_node('CYCLES').inputs["Volume"])
    summary, text = _export(scene)
    assert scene.world.name in text and emission.name in text, text
    assert summary["media"] == 0, summary
