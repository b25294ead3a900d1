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


def _kept_animation(scene, tmp_path, samples, seed, integrator="PATH", pass_name="Combined"):
    """`blender -b -a` over the scene's frames with Persistent Data: each frame's scene_sync
    counters and its pass_name pass."""
    ru.configure(scene, ru.LANTERN, samples, seed, integrator=integrator)
    ru._exr_settings(scene)
    scene.render.use_persistent_data = True
    scene.render.filepath = str(tmp_path / ("anim_%d_" % seed))
    syncs = []

    def written(*_):
        syncs.append(engine.LAST_RENDER["scene_sync"])
    bpy.app.handlers.render_write.append(written)
    try:
        bpy.ops.render.render(animation=True, scene=scene.name)
    finally:
        bpy.app.handlers.render_write.remove(written)
    scene.render.use_persistent_data = False
    bpy.context.window.scene = scene  # see _frame
    frames = [ru.read_multilayer_exr(str(tmp_path / ("anim_%d_%04d.exr" % (seed, f))))[pass_name]
              for f in range(scene.frame_start, scene.frame_end + 1)]
    return syncs, frames


def _check_syncs(syncs, transform_updates, full_exports=1, value_updates=0):
    """One export, then the moves as instance transforms (each frame one more top-level BVH build
    and no mesh's: builds counted by the core) and the changed Object Info values set in place (no
    build), or `full_exports` exports."""
    sync = syncs[-1]
    assert (sync["full_exports"], sync["transform_updates"], sync["value_updates"]) == \
        (full_exports, transform_updates, value_updates), sync
    if full_exports == 1:
        assert [s["mesh_bvh_builds"] for s in syncs] == [syncs[0]["mesh_bvh_builds"]] * len(syncs), syncs
        tops = [s["top_bvh_builds"] - syncs[0]["top_bvh_builds"] for s in syncs]
        assert tops == [i if transform_updates else 0 for i in range(len(syncs))], syncs


def _alone(scene, frame, samples, seed, integrator="PATH"):
    scene.frame_set(frame)
    out = ru.render(scene, ru.LANTERN, samples, seed=seed, integrator=integrator).combined
    assert engine.LAST_RENDER["scene_sync"] is None
    return out


def _check_kept_between_frames(scene, tmp_path, transform_updates, full_exports=1, value_updates=0,
                               integrator="PATH"):
    """`blender -b -a` with Persistent Data (_check_syncs), each frame equal to the frame rendered
    on its own."""
    syncs, frames = _kept_animation(scene, tmp_path, 4, 7, integrator)
    _check_syncs(syncs, transform_updates, full_exports, value_updates)
    for frame, animated in zip(range(scene.frame_start, scene.frame_end + 1), frames):
        assert np.abs(animated - _alone(scene, frame, 4, 7, integrator)).max() < 1e-4, frame


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


def test_persistent_data_moves_a_hair_emitter(scene_factory, tmp_path):
    """hair_motion's hair ball (the emitter) translating and turning every frame: Blender flags
    each move of an emitter as a geometry update (its particles are evaluated again), but its mesh
    and hair read as exported, so the kept scene moves it. Blender's path cache holds the keys in
    world space as float32, so the hair read back into object space differs from the export by
    rounding (1e-7 relative): a ray grazing a strand may hit it in one render and not the other, so
    frames agree with frames rendered alone by test_agreement.py's rule (two seeds each side, tiles
    and the image mean), not to the bit."""
    scene = scene_factory("hair_motion")
    scene.render.use_motion_blur = False
    scene.objects["RandomCurves"].animation_data_clear()
    _moving_every_frame(scene, ["Ball"])
    scene.render.resolution_x = scene.render.resolution_y = 64
    kept = [_kept_animation(scene, tmp_path, 64, seed) for seed in (0, 1)]
    for syncs, _ in kept:
        _check_syncs(syncs, transform_updates=2)
    for i, frame in enumerate(range(scene.frame_start, scene.frame_end + 1)):
        alone = [_alone(scene, frame, 64, seed) for seed in (0, 1)]
        report, _ = ru.agreement_report("hair_emitter_frame_%d" % frame, [k[1][i] for k in kept], alone,
                                        str(tmp_path), labels=("kept", "alone"))
        assert report == "", report


def test_persistent_data_exports_an_emitter_whose_geometry_changes(scene_factory, tmp_path):
    """The still hair ball's mesh displaced by a modifier after its particle system, its strength
    animated: the emitter's geometry update is a real one, so each frame is a new export, equal to
    the frame rendered alone (a kept scene would render frame 1's ball). Then the emitter hidden
    (Render > Show Emitter off) and the modifier before the particle system: only the hair changes, and
    each frame is a new export too."""
    scene = scene_factory("hair_motion")
    scene.render.use_motion_blur = False
    for name in ("Ball", "RandomCurves"):
        scene.objects[name].animation_data_clear()
    ball = scene.objects["Ball"]
    displace = ball.modifiers.new("Displace", 'DISPLACE')
    displace.strength = 0.0
    displace.keyframe_insert("strength", frame=1)
    displace.strength = 0.4
    displace.keyframe_insert("strength", frame=3)
    scene.frame_start, scene.frame_end = 1, 3
    scene.render.resolution_x = scene.render.resolution_y = 32
    _check_kept_between_frames(scene, tmp_path / "mesh", transform_updates=0, full_exports=3)

    # Blender evaluates a kept render depsgraph's hair on a deformed emitter differently from a
    # fresh one (Cycles' frames differ the same way): counts only.
    ball.show_instancer_for_render = False
    with bpy.context.temp_override(object=ball):
        bpy.ops.object.modifier_move_to_index(modifier=displace.name, index=0)
    (tmp_path / "hair").mkdir()
    syncs, _ = _kept_animation(scene, tmp_path / "hair", 4, 7)
    _check_syncs(syncs, transform_updates=0, full_exports=3)


def _animated_box_material(scene):
    """cornell_area at 32 x 32 over frames 1-3 with the tall box in a material of its own (the
    default Principled BSDF) that the caller animates: (box, material's node tree, its BSDF)."""
    scene.render.resolution_x = scene.render.resolution_y = 32
    scene.frame_start, scene.frame_end = 1, 3
    box = scene.objects["TallBox"]
    mat = bpy.data.materials.new("Animated")
    mat.use_nodes = True
    box.material_slots[0].material = mat
    return box, mat.node_tree, mat.node_tree.nodes["Principled BSDF"]


def _keyframes(owner, path, values):
    for frame, value in enumerate(values, start=1):
        setattr(owner, path, value)
        owner.keyframe_insert(path, frame=frame)


def test_persistent_data_follows_animated_materials_and_object_values(scene_factory, tmp_path):
    """A keyframed Base Color is a material update: the material translated as the depsgraph
    evaluates it (bpy.data's is the original, which keeps frame 1's colour). Object Info's Color
    and Object Index, ray visibility and a custom property the Attribute node reads, keyframed,
    are set on the core instance in place (as Cycles updates its objects). Each frame equals the
    frame rendered alone (before, the kept scene rendered frame 1's values at every frame)."""
    scene = scene_factory("cornell_area")
    _, _, bsdf = _animated_box_material(scene)
    _keyframes(bsdf.inputs["Base Color"], "default_value", [(1, 0, 0, 1), (0, 1, 0, 1), (0, 0, 1, 1)])
    syncs, frames = _kept_animation(scene, tmp_path / "material", 4, 7)
    assert syncs[-1]["full_exports"] == 1 and syncs[-1]["material_updates"] == 2, syncs[-1]
    for frame, animated in zip((1, 2, 3), frames):
        assert np.abs(animated - _alone(scene, frame, 4, 7)).max() < 1e-4, frame

    def object_info(output):
        scene = scene_factory("cornell_area")
        box, tree, bsdf = _animated_box_material(scene)
        info = tree.nodes.new("ShaderNodeObjectInfo")
        tree.links.new(info.outputs[output], bsdf.inputs["Base Color"])
        return scene, box

    scene, box = object_info("Color")
    _keyframes(box, "color", [(1, 0, 0, 1), (0, 1, 0, 1), (0, 0, 1, 1)])
    _check_kept_between_frames(scene, tmp_path / "color", transform_updates=0, value_updates=2)
    scene, box = object_info("Object Index")  # pass index 0, 1, 0: black, white, black
    _keyframes(box, "pass_index", [0, 1, 0])
    _check_kept_between_frames(scene, tmp_path / "index", transform_updates=0, value_updates=2)
    scene, box = object_info("Color")
    _keyframes(box, "visible_camera", [True, False, True])
    syncs, frames = _kept_animation(scene, tmp_path / "visibility", 4, 7)
    assert (syncs[-1]["full_exports"], syncs[-1]["value_updates"]) == (1, 2), syncs[-1]
    # Each change rebuilds the top level, and no mesh's BVH.
    assert [s["top_bvh_builds"] - syncs[0]["top_bvh_builds"] for s in syncs] == [0, 1, 2], syncs
    assert [s["mesh_bvh_builds"] for s in syncs] == [syncs[0]["mesh_bvh_builds"]] * 3, syncs
    for frame, animated in zip((1, 2, 3), frames):
        assert np.abs(animated - _alone(scene, frame, 4, 7)).max() < 1e-4, frame

    scene = scene_factory("cornell_area")
    box, tree, bsdf = _animated_box_material(scene)
    attribute = tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_type, attribute.attribute_name = 'OBJECT', "tint"
    tree.links.new(attribute.outputs["Color"], bsdf.inputs["Base Color"])
    box["tint"] = 0.0
    for frame, value in enumerate((0.1, 0.9, 0.4), start=1):
        box["tint"] = value
        box.keyframe_insert('["tint"]', frame=frame)
    _check_kept_between_frames(scene, tmp_path / "attribute", transform_updates=0, value_updates=2)


def test_persistent_data_edits_visibility_and_colour_on_sponza(scene_factory, tmp_path):
    """The real model (../shared/assets' Sponza) with a cube coloured by Object Info as a user sets
    it up, its Object colour keyed red, green, blue and Sponza's shadow visibility on, off, on:
    one export, two value updates, and each kept frame the same bits as the frame rendered alone.
    Frame 3 sees every object from every ray again: rendered without Embree's visibility filter,
    as a scene exported so (with the filter still on, pixels differed by up to 0.015)."""
    scene = scene_factory("sponza", resolution=(120, 90))
    sponza = max((o for o in scene.objects if o.type == 'MESH'), key=lambda o: len(o.data.polygons))
    mesh = bpy.data.meshes.new("ColouredCube")
    mesh.from_pydata([(x, y, z) for x in (-0.75, 0.75) for y in (-0.75, 0.75) for z in (0.25, 1.75)], [],
                     [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)])
    cube = bpy.data.objects.new("ColouredCube", mesh)
    scene.collection.objects.link(cube)
    material = bpy.data.materials.new("ObjectColour")
    material.use_nodes = True
    tree = material.node_tree
    info = tree.nodes.new("ShaderNodeObjectInfo")
    tree.links.new(info.outputs["Color"], tree.nodes["Principled BSDF"].inputs["Base Color"])
    mesh.materials.append(material)
    for frame, colour, shadow in ((1, (1, 0, 0, 1), True), (2, (0, 1, 0, 1), False), (3, (0, 0, 1, 1), True)):
        cube.color = colour
        cube.keyframe_insert("color", frame=frame)
        sponza.visible_shadow = shadow
        sponza.keyframe_insert("visible_shadow", frame=frame)
    scene.frame_start, scene.frame_end = 1, 3
    syncs, frames = _kept_animation(scene, tmp_path, 16, 7)
    assert (syncs[-1]["full_exports"], syncs[-1]["value_updates"]) == (1, 2), syncs[-1]
    for frame, kept in zip((1, 2, 3), frames):
        assert np.array_equal(kept, _alone(scene, frame, 16, 7)), frame


def test_persistent_data_exports_a_moving_or_recoloured_volume_object_anew(scene_factory, tmp_path):
    """vdb_cloud's Volume object: its grid's transform and its material's medium are set by its
    export (export/volume.py), so a keyed move, then a keyed Principled Volume density, each make
    every frame a new export, equal to the frame rendered alone (VOLPATH). Before, the kept scene
    rendered the cloud where frame 1 had it, and at frame 1's density."""
    scene = scene_factory("vdb_cloud", resolution=(48, 36))
    scene.frame_start, scene.frame_end = 1, 3
    cloud = scene.objects["Cloud"]
    x, y, z = cloud.location
    for frame, dx in ((1, -0.6), (3, 0.6)):
        cloud.location = (x + dx, y, z)
        cloud.keyframe_insert("location", frame=frame)
    _check_kept_between_frames(scene, tmp_path / "move", transform_updates=0, full_exports=3, integrator="VOLPATH")
    cloud.animation_data_clear()
    density = cloud.active_material.node_tree.nodes["Principled Volume"].inputs["Density"]
    for frame, value in ((1, 2.0), (3, 8.0)):
        density.default_value = value
        density.keyframe_insert("default_value", frame=frame)
    _check_kept_between_frames(scene, tmp_path / "density", transform_updates=0, full_exports=3,
                               integrator="VOLPATH")


def test_persistent_data_keeps_the_scene_with_motion_blur(scene_factory, tmp_path):
    """motion_blur with motion blur on (a shutter of 1 frame) and its boxes and camera moving
    every frame: each frame samples its shutter, then edits the kept scene's transforms and motion
    steps in place (lt_scene_set_instance_motion; the camera's motion is set with the camera),
    one export for three frames, each frame the same image as the frame rendered alone. With the
    grid's shape key animated too (deformation blur), its mesh changes every frame: three exports."""
    from test_motion_blur import _motion_line
    scene = scene_factory("motion_blur")
    keys = scene.objects["Deforming"].data.shape_keys
    grid_action = keys.animation_data.action
    keys.animation_data_clear()
    _moving_every_frame(scene, ["Translating", "Rotating", scene.camera.name])
    syncs, frames = _kept_animation(scene, tmp_path / "kept", 4, 7)
    _check_syncs(syncs, transform_updates=2)
    assert syncs[-1]["motion_updates"] == 2, syncs[-1]
    for frame, animated in zip((1, 2, 3), frames):
        alone = _alone(scene, frame, 4, 7)
        assert _motion_line()[0] == (2, 0, 0, "moving, 3 steps"), _motion_line()[1]
        assert np.abs(animated - alone).max() < 1e-4, frame
    keys.animation_data_create().action = grid_action
    _check_kept_between_frames(scene, tmp_path / "deforming", transform_updates=0, full_exports=3)


def test_persistent_data_clears_the_motion_when_motion_blur_is_switched_off(scene_factory, tmp_path):
    """use_motion_blur cannot be keyframed, but a frame handler may switch it: motion_blur moving
    every frame with blur on at frame 1 and 3 and off at frame 2. The kept scene's instances and
    camera lose their motion steps at frame 2 (an edit, not a new export) and get them back at
    frame 3; each frame is the frame rendered alone."""
    from test_motion_blur import _motion_line
    scene = scene_factory("motion_blur")
    scene.objects["Deforming"].data.shape_keys.animation_data_clear()
    _moving_every_frame(scene, ["Translating", "Rotating", scene.camera.name])

    def blur_but_at_frame_2(s, *_):
        if s == scene:
            s.render.use_motion_blur = s.frame_current != 2
    bpy.app.handlers.frame_change_pre.append(blur_but_at_frame_2)
    try:
        syncs, frames = _kept_animation(scene, tmp_path, 4, 7)
        assert [(s["full_exports"], s["transform_updates"], s["motion_updates"], s["top_bvh_builds"])
                for s in syncs] == [(1, 0, 0, 1), (1, 1, 1, 2), (1, 2, 2, 3)], syncs
        # Beside the turning box's motion the still meshes are traced as world-space copies
        # (geometry.cpp, flattens_beside_motion): dropped at frame 2, built again at frame 3.
        assert [s["mesh_bvh_builds"] - syncs[0]["mesh_bvh_builds"] for s in syncs] == [0, 0, 3], syncs
        for frame, animated in zip((1, 2, 3), frames):
            alone = _alone(scene, frame, 4, 7)
            assert _motion_line()[0] == ((2, 0, 0, "moving, 3 steps") if frame != 2 else None), _motion_line()[1]
            assert np.abs(animated - alone).max() < 1e-4, frame
    finally:
        bpy.app.handlers.frame_change_pre.remove(blur_but_at_frame_2)
        scene.render.use_motion_blur = True


def test_persistent_data_keeps_the_scene_with_the_vector_pass(scene_factory, tmp_path):
    """The Vector pass with motion blur off samples the neighbouring frames (export/motion.py): the
    kept scene takes each frame's motion steps as edits too, one export for three frames, and
    each frame's Vector pass is the one of the frame rendered alone (cornell_area's sliding box)."""
    scene = _animated_scene(scene_factory)
    build_scenes.extrapolate_motion(next(o for o in scene.objects if o.animation_data))
    scene.view_layers[0].use_pass_vector = True
    syncs, frames = _kept_animation(scene, tmp_path, 4, 7, pass_name="Vector")
    # The box moves without turning: the core traces it as its triangles baked in world space at
    # each step (geometry.cpp, bakes_motion), a copy built anew when its motion changes.
    assert [(s["full_exports"], s["transform_updates"], s["motion_updates"]) for s in syncs] == \
        [(1, 0, 0), (1, 1, 1), (1, 2, 2)], syncs
    assert [s["mesh_bvh_builds"] - syncs[0]["mesh_bvh_builds"] for s in syncs] == [0, 1, 2], syncs
    assert all(np.abs(f).max() > 0.5 for f in frames)  # the box moves in every frame
    for frame, kept in zip((1, 2, 3), frames):
        scene.frame_set(frame)
        alone = ru.render(scene, ru.LANTERN, 4, seed=7)["Vector"]
        assert np.abs(kept - alone).max() < 1e-4, frame
