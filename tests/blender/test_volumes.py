"""Volumes: export of volume materials and Volume objects, and agreement with Cycles.

Agreement uses test_agreement.py's rule (two seeds per engine, 16x16 tile means within a
Bonferroni-corrected z bound of both engines' noise). Lantern's volume_bounces is copied from
scene.cycles.volume_bounces (render_utils.configure); the media here are homogeneous, which Cycles
integrates exactly as Lantern does.
"""
import os

import bpy
import numpy as np
import pytest

import render_utils as ru
from lantern import core
from lantern.export import export_scene

VOLUME_SCENES = ["smoke_box", "thin_fog", "dense_fog"]
SAMPLES = 128
TILE = 16
ROUNDING = 1e-5


def _export(scene):
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    reports = []
    core_scene = core.Scene()
    try:
        summary = export_scene(depsgraph, core_scene, lambda level, message: reports.append(message))
        core_scene.commit()
    finally:
        core_scene.close()
    return summary, "\n".join(reports)


@pytest.mark.parametrize("name", VOLUME_SCENES)
@pytest.mark.parametrize("volume_bounces", [0, 2])
def test_volume_agrees_with_cycles(name, volume_bounces, scene_factory, outdir):
    scene = scene_factory(name)
    scene.cycles.volume_bounces = volume_bounces
    runs = {}
    for engine in (ru.CYCLES, ru.LANTERN):
        runs[engine] = [ru.render(scene, engine, SAMPLES, seed=s, integrator="VOLPATH").combined
                        for s in (0, 1)]
    for img in runs[ru.LANTERN]:
        assert np.isfinite(img).all()
    mean_c, se2_c = ru.tile_mean_and_se2(*runs[ru.CYCLES], TILE)
    mean_l, se2_l = ru.tile_mean_and_se2(*runs[ru.LANTERN], TILE)
    z = ru.bonferroni_z(mean_c.size)
    bound = z * np.sqrt(se2_c + se2_l) + ROUNDING * np.abs(mean_c)
    diff = np.abs(mean_l - mean_c)
    if not (diff <= bound).all():
        tag = "%s_vb%d" % (name, volume_bounces)
        ru.write_png(os.path.join(outdir, tag + "_lantern.png"), 0.5 * sum(runs[ru.LANTERN]))
        ru.write_png(os.path.join(outdir, tag + "_cycles.png"), 0.5 * sum(runs[ru.CYCLES]))
        i = int(np.argmax(diff / np.maximum(bound, 1e-30)))
        pytest.fail("%s: worst tile value Lantern %.5f Cycles %.5f bound %.5f (images in %s)"
                    % (tag, mean_l.ravel()[i], mean_c.ravel()[i], bound.ravel()[i], outdir))


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


def test_volume_debug_view_renders(scene_factory):
    scene = scene_factory("smoke_box")
    img = ru.render(scene, ru.LANTERN, 4, seed=0, integrator="VOLUME_DEBUG").combined
    assert np.isfinite(img).all()
    assert img[..., :3].min() >= 0.0
    assert img[..., :3].max() > 1.0, "the distance panels hold metres from the camera"
