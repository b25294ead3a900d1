"""Animation renders (issue 15): the seed per frame, the scene kept between frames."""
import bpy
import numpy as np

import render_utils as ru
from lantern import engine


def _frame(scene, frame, animated):
    # A still render of a scene that is not the window's renders the window scene's frame.
    bpy.context.window.scene = scene
    scene.lantern.use_animated_seed = animated
    scene.frame_set(frame)
    out = ru.render(scene, ru.LANTERN, 8, seed=3).combined[..., :3]
    return out, engine.LAST_RENDER["settings"].seed


def test_animated_seed_gives_each_frame_its_own_noise(scene_factory):
    """Off: a still scene renders the same noise at every frame. On (Cycles' Animated Seed): each
    frame has its own seed, so the noise differs, and the image is the same in the mean."""
    scene = scene_factory("cornell_area")
    scene.render.resolution_x = scene.render.resolution_y = 32
    a, seed_a = _frame(scene, 1, False)
    b, seed_b = _frame(scene, 2, False)
    assert seed_a == seed_b == 3
    assert np.abs(a - b).max() < 1e-3  # same numbers (summation order may differ by rounding)
    c, seed_c = _frame(scene, 1, True)
    d, seed_d = _frame(scene, 2, True)
    assert len({seed_c, seed_d, 3}) == 3
    assert np.abs(c - d).max() > 0.05  # independent noise
    # The same image in the mean: within 5 standard errors of the difference of two renders.
    diff = (c - d).mean(axis=-1)
    se = diff.std() / np.sqrt(diff.size)
    assert abs(diff.mean()) < 5 * se, (diff.mean(), se)


def _animated_scene(scene_factory):
    """cornell_area whose tall box slides over frames 1-3."""
    scene = scene_factory("cornell_area")
    scene.render.resolution_x = scene.render.resolution_y = 32
    box = next(o for o in scene.objects if o.type == 'MESH' and "box" in o.name.lower())
    box.keyframe_insert("location", frame=1)
    box.location.x += 0.3
    box.keyframe_insert("location", frame=3)
    scene.frame_start, scene.frame_end = 1, 3
    return scene


def test_persistent_data_animation_reuses_the_scene_and_equals_single_frames(scene_factory, tmp_path):
    """`blender -b -a` with Persistent Data: one export for three frames (the box's moves are
    instance transforms), and each frame equals the frame rendered on its own."""
    scene = _animated_scene(scene_factory)
    ru.configure(scene, ru.LANTERN, 4, 7)
    ru._exr_settings(scene)
    scene.render.use_persistent_data = True
    scene.render.filepath = str(tmp_path / "anim_")
    bpy.ops.render.render(animation=True, scene=scene.name)
    sync = engine.LAST_RENDER["scene_sync"]
    assert sync["full_exports"] == 1 and sync["transform_updates"] == 2, sync
    scene.render.use_persistent_data = False
    bpy.context.window.scene = scene  # see _frame
    for frame in (1, 2, 3):
        animated = ru.read_multilayer_exr(str(tmp_path / ("anim_%04d.exr" % frame)))["Combined"]
        scene.frame_set(frame)
        alone = ru.render(scene, ru.LANTERN, 4, seed=7).combined
        assert engine.LAST_RENDER["scene_sync"] is None
        assert np.abs(animated - alone).max() < 1e-4, frame
