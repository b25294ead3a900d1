"""scene.lantern.sample_offset reaches the core, and the Merge Images operator (lantern.merge_images)
merges sample-split parts into the full render and refuses overlapping parts without writing."""
import os

import numpy as np
import pytest

import bpy

import render_utils
from lantern import core, engine
from lantern.export import export_scene


def _render_part(scene, offset, samples, path):
    scene.lantern.samples = samples
    scene.lantern.sample_offset = offset
    width, height, border = engine.frame_size(scene.render)
    settings = engine.render_settings(scene, width, height, border)
    assert settings["sample_offset"] == offset
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    with core.Scene() as cs:
        export_scene(depsgraph, cs, lambda level, msg: None)
        cs.commit()
        with core.Render(cs, settings) as r:
            r.start()
            r.wait()
            r.write_exr(path, {"lantern/scene": "operator test"})


def test_merge_images_operator(scene_factory, tmp_path):
    scene = scene_factory("cornell_area", resolution=(24, 24), samples=16)
    scene.render.engine = "LANTERN"
    scene.lantern.integrator = "BIDIRECTIONAL"
    d = str(tmp_path)
    _render_part(scene, 0, 16, os.path.join(d, "full.exr"))
    _render_part(scene, 0, 8, os.path.join(d, "a.exr"))
    _render_part(scene, 8, 8, os.path.join(d, "b.exr"))
    _render_part(scene, 4, 8, os.path.join(d, "overlap.exr"))
    out = os.path.join(d, "merged.exr")

    with pytest.raises(RuntimeError, match="sample ranges overlap"):
        bpy.ops.lantern.merge_images(directory=d, files=[{"name": "a.exr"}, {"name": "overlap.exr"}],
                                     output_filepath=out)
    assert not os.path.exists(out)

    assert bpy.ops.lantern.merge_images(directory=d, files=[{"name": "a.exr"}, {"name": "b.exr"}],
                                        output_filepath=out) == {'FINISHED'}
    merged, full = render_utils.read_exr(out), render_utils.read_exr(os.path.join(d, "full.exr"))
    part = render_utils.read_exr(os.path.join(d, "a.exr"))
    assert np.all(merged["SampleCount.X"] == 16)
    for c in "RGB":
        assert np.all(np.abs(merged[c] - full[c]) <= 1e-5 * np.abs(full[c])), c
    assert np.any(part["R"] != full["R"])  # the parts differ from the whole: the check says something
