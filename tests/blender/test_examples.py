"""examples.blend as committed: one scene per entry of build_scenes.EXAMPLES with its Lantern
settings, every file it reads found from a clone (the models' textures in models/), and small
enough for the repository. Nothing is rendered (scripts/render_examples.sh renders them)."""
import os

import bpy
import build_scenes as bs

EXAMPLES_BLEND = bs.EXAMPLES_PATH


def test_examples_blend_matches_the_example_list():
    assert os.path.getsize(EXAMPLES_BLEND) < 5 * 1024 * 1024  # the repository's file size limit
    bpy.ops.wm.open_mainfile(filepath=EXAMPLES_BLEND, load_ui=False)
    try:
        assert sorted(s.name for s in bpy.data.scenes) == sorted(bs.EXAMPLES)
        for name, (_, res, spp, integrator, *extra) in bs.EXAMPLES.items():
            scene = bpy.data.scenes[name]
            assert scene.render.engine == "LANTERN", name
            assert (scene.render.resolution_x, scene.render.resolution_y) == res, name
            assert scene.lantern.samples == spp, name
            assert scene.lantern.integrator == integrator, name
            for key, value in (extra[0] if extra else {}).items():
                assert getattr(scene.lantern, key) == value, (name, key)
        # Image files are read relative to the .blend (the cathedral's textures in models/), the
        # .vdb files from //assets/, which scripts/render_examples.sh fills from the build.
        images = [i for i in bpy.data.images if i.source == "FILE" and not i.packed_file]
        assert images, "the cathedral's textures"
        for image in images:
            assert image.filepath.startswith("//models/"), image.filepath
            assert os.path.isfile(bpy.path.abspath(image.filepath)), image.filepath
        for volume in bpy.data.volumes:
            assert volume.filepath.startswith(bs.EXAMPLE_ASSETS), volume.filepath
    finally:
        bs.reset_file()
