"""Animation renders (issue 15): the seed per frame, the scene kept between frames."""
import bpy
import numpy as np

import build_scenes
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


def _check_kept_between_frames(scene, tmp_path, transform_updates):
    """`blender -b -a` over the scene's frames with Persistent Data: one export, then the moves
    as instance transforms (each frame one more top-level BVH build and no mesh's: builds counted
    by the core), and each frame equal to the frame rendered on its own."""
    ru.configure(scene, ru.LANTERN, 4, 7)
    ru._exr_settings(scene)
    scene.render.use_persistent_data = True
    scene.render.filepath = str(tmp_path / "anim_")
    syncs = []

    def written(*_):
        syncs.append(engine.LAST_RENDER["scene_sync"])
    bpy.app.handlers.render_write.append(written)
    try:
        bpy.ops.render.render(animation=True, scene=scene.name)
    finally:
        bpy.app.handlers.render_write.remove(written)
    sync = syncs[-1]
    assert sync["full_exports"] == 1 and sync["transform_updates"] == transform_updates, sync
    assert [s["mesh_bvh_builds"] for s in syncs] == [syncs[0]["mesh_bvh_builds"]] * len(syncs), syncs
    assert [s["top_bvh_builds"] - syncs[0]["top_bvh_builds"] for s in syncs] == list(range(len(syncs))), syncs
    scene.render.use_persistent_data = False
    bpy.context.window.scene = scene  # see _frame
    for frame in range(scene.frame_start, scene.frame_end + 1):
        animated = ru.read_multilayer_exr(str(tmp_path / ("anim_%04d.exr" % frame)))["Combined"]
        scene.frame_set(frame)
        alone = ru.render(scene, ru.LANTERN, 4, seed=7).combined
        assert engine.LAST_RENDER["scene_sync"] is None
        assert np.abs(animated - alone).max() < 1e-4, frame


def test_persistent_data_animation_reuses_the_scene_and_equals_single_frames(scene_factory, tmp_path):
    """The box's moves are instance transforms: one export for three frames."""
    _check_kept_between_frames(_animated_scene(scene_factory), tmp_path, transform_updates=2)


def _moving_every_frame(scene, names):
    for name in names:
        build_scenes.extrapolate_motion(scene.objects[name])
    scene.frame_start, scene.frame_end = 1, 3
    scene.render.resolution_x = scene.render.resolution_y = 32


def test_persistent_data_keeps_hair_curves_and_points(scene_factory, tmp_path):
    """A scene with particle hair, a Curves object and point clouds is kept too (each of them an
    instance export_scene records: the emitter's hair apart from the emitter). hair_motion with
    the hair ball held still (a moving emitter re-evaluates its particles: Blender flags a
    geometry update, and a new scene is exported) and the Curves object moving; point_cloud with a cloud
    moving. Before, every frame of such a scene was a full export."""
    scene = scene_factory("hair_motion")
    scene.render.use_motion_blur = False
    scene.objects["Ball"].animation_data_clear()
    _moving_every_frame(scene, ["RandomCurves"])
    _check_kept_between_frames(scene, tmp_path / "hair", transform_updates=2)

    scene = scene_factory("point_cloud")
    cloud = scene.objects["Cloud0"]
    cloud.keyframe_insert("location", frame=1)
    cloud.location.z += 0.2
    cloud.keyframe_insert("location", frame=2)
    _moving_every_frame(scene, ["Cloud0"])
    _check_kept_between_frames(scene, tmp_path / "points", transform_updates=2)
