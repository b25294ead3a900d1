"""Particle hair (issue 15): the path cache read in bulk (export/particle_cache.py) gives the
strands ParticleSystem.co_hair gives, key by key, in a render's depsgraph (object space, as Cycles
brings them back), and Cycles' simple Hair BSDF on it against Cycles."""
import bpy
import numpy as np
import pytest

import build_scenes
import render_utils as ru
from lantern import engine
from lantern.export import hair, particle_cache
from test_agreement import ROUNDING, TILE


class _KeysEngine(bpy.types.RenderEngine):
    """Reads the hair ball's keys both ways inside a render (render steps, rendered children)."""
    bl_idname = "LANTERN_TEST_HAIR_KEYS"
    bl_label = "Hair keys (test)"
    found = []

    def render(self, depsgraph):
        obj = bpy.data.objects["Ball"].evaluated_get(depsgraph)
        _KeysEngine.found = [keys_both_ways(obj, psys) for psys in hair.hair_systems(obj)]


def keys_both_ways(obj, psys):
    s = psys.settings
    children = len(psys.child_particles) if s.child_type != 'NONE' else 0
    first = len(psys.particles) if children else 0
    count = children or len(psys.particles)
    steps = (1 << s.render_step) + 1 + (s.kink_extra_steps if s.kink == 'SPIRAL' else 0)
    inverse = np.linalg.inv(np.array(obj.matrix_world, dtype=np.float64))
    world = hair.co_hair_keys(obj, psys, first, count, steps)
    return (particle_cache.object_keys(obj, psys, first, count, steps),
            world @ inverse[:3, :3].T + inverse[:3, 3], world)


@pytest.fixture
def keys_engine():
    bpy.utils.register_class(_KeysEngine)
    yield _KeysEngine
    bpy.utils.unregister_class(_KeysEngine)


# 300 parents x 5 children, or 1500 parents: each cache spans two of Blender's 1024-path buffers.
CASES = {
    "parents": dict(child_type="NONE", count=1500),
    "simple": dict(child_type="SIMPLE", render_step=2),
    "interpolated": dict(child_type="INTERPOLATED"),
    "interpolated_steps5": dict(child_type="INTERPOLATED", render_step=5),
    "interpolated_spiral": dict(child_type="INTERPOLATED", kink="SPIRAL", kink_extra_steps=3),
    "interpolated_parting": dict(child_type="INTERPOLATED", child_parting_factor=1.0, child_parting_min=0.0,
                                 child_parting_max=0.0),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_path_cache_keys_equal_co_hair(case, keys_engine):
    """Parents, Simple and Interpolated children, several render steps, spiral kinks' extra keys and
    parting (children the cache cuts short): the bulk read equals co_hair's keys within co_hair's
    float32 rounding (its two matrix products), all strands, all keys, in a render."""
    build_scenes.reset_file()
    scene = build_scenes.new_scene("hair_keys", (8, 8), 1)
    build_scenes.build_hair_ball(scene, strands=300, children=5, principled=False)
    ball = bpy.data.objects["Ball"]
    ball.rotation_euler = (0.3, -0.2, 0.5)  # imat and the object's matrix, not the identity
    ball.scale = (1.5, 1.2, 1.5)
    settings = ball.particle_systems[0].settings
    for key, value in CASES[case].items():
        setattr(settings, key, value)
    scene.render.engine = keys_engine.bl_idname
    bpy.ops.render.render(scene=scene.name)
    (bulk, expect, world), = keys_engine.found
    assert not isinstance(bulk, str), bulk
    assert bulk.shape == expect.shape and expect.shape[0] >= 1500
    ulp = np.spacing(np.float32(np.abs(world).max()))  # co_hair's float32, in world space
    error = np.abs(bulk - expect).max()
    assert error <= 4 * ulp, "bulk keys differ from co_hair by %g (float32 ulp %g)" % (error, ulp)
    if case == "interpolated_steps5":  # Length 0.9 cuts the children's 33-key paths short
        assert (bulk[:, -1] == bulk[:, -2]).all(axis=1).sum() >= 1000


def test_unreadable_cache_exports_through_co_hair(monkeypatch):
    """A cache whose layout cannot be checked: the same keys from co_hair, with a warning."""
    build_scenes.reset_file()
    scene = build_scenes.new_scene("hair_keys", (8, 8), 1)
    build_scenes.build_hair_ball(scene, strands=50, children=2, principled=False)
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    obj = bpy.data.objects["Ball"].evaluated_get(depsgraph)
    psys = obj.particle_systems[0]
    reports = []
    fast = hair.particle_hair_arrays(obj, lambda kind, text: reports.append(text))
    assert reports == []
    monkeypatch.setattr(particle_cache, "_layout", "layout withheld by the test")
    slow = hair.particle_hair_arrays(obj, lambda kind, text: reports.append(text))
    assert len(reports) == 1 and "layout withheld by the test" in reports[0] and psys.name in reports[0]
    for a, b in zip(fast, slow):
        assert a.shape == b.shape
    assert np.abs(fast[0] - slow[0]).max() <= 4 * np.spacing(np.float32(np.abs(slow[0]).max()))


def lantern_and_cycles(scene_factory, name):
    """Two renders (seeds 0 and 1) of one build by each engine, PATH."""
    return lantern_and_cycles_of(scene_factory(name), name)


def lantern_and_cycles_of(scene, name):
    """lantern_and_cycles of a scene already built (and changed) from the scene `name`."""
    spp = build_scenes.SCENES[name][2]
    return {engine: [ru.render(scene, engine, spp, seed=seed).combined for seed in (0, 1)]
            for engine in (ru.LANTERN, ru.CYCLES)}


@pytest.mark.parametrize("name", ["hair_ball_hair_bsdf_sun", "hair_ball_hair_bsdf_tangent_sun"])
def test_hair_bsdf_agrees_with_cycles_under_the_sun_alone(name, scene_factory, outdir):
    """Cycles' simple Hair BSDF on particle hair: its Reflection and Transmission added, each with
    an Offset and RoughnessU != RoughnessV, and (_tangent) the Reflection's Tangent linked to a
    constant direction. Lit by a sun alone with the hair hidden from indirect rays, Cycles' image
    comes from its light samples, weighed by its eval(), which Lantern's lobes are: per tile and
    the image mean (test_agreement's rule)."""
    both = lantern_and_cycles(scene_factory, name)
    report, _ = ru.agreement_report(name, both[ru.LANTERN], both[ru.CYCLES], outdir, TILE, ROUNDING)
    assert report == "", report


@pytest.mark.xfail(strict=True, reason="Cycles 3.4's sample() of the Hair BSDF departs from its eval(), which "
                   "Lantern follows (README: Hair and points)")
def test_hair_bsdf_departs_from_cycles_when_lit_indirectly(scene_factory, outdir):
    """The same hair under an area light, a world and over a floor: Cycles draws the reflection's
    azimuth with density cos(phi / 2v) / 4v (v the RoughnessV) but states cos(phi / 2) / 4v, and
    the transmission's on half the range its eval() covers, weighing every BSDF sample by 1; so
    its indirect light is not the rendering of its eval() and Lantern, unbiased for eval(),
    differs (measured: image mean 0.950 of Cycles' at 128 samples, standard error 0.3 %).
    Strict, so a change shows."""
    both = lantern_and_cycles(scene_factory, "hair_ball_hair_bsdf")
    report, _ = ru.agreement_report("hair_ball_hair_bsdf", both[ru.LANTERN], both[ru.CYCLES], outdir, TILE,
                                    ROUNDING)
    assert report == "", report


def test_moving_hair_agrees_with_cycles(scene_factory, outdir):
    """Hair moves with its object's transform under motion blur, as in Cycles: particle hair on a
    translating, turning sphere and a translating Curves object; per tile and the image mean, PATH."""
    both = lantern_and_cycles(scene_factory, "hair_motion")
    report, _ = ru.agreement_report("hair_motion", both[ru.LANTERN], both[ru.CYCLES], outdir, TILE, ROUNDING)
    assert report == "", report


def test_deforming_hair_agrees_with_cycles(scene_factory, outdir):
    """Deformation motion blur of particle hair, as Cycles renders it: hair_motion with the hair
    ball held still and its emitter swelling from 1.25 to 1.75 times its size over the shutter (a
    shape key: the roots move, so the strands' keys differ at every motion step and move linearly
    between them). The export sends the strands' keys per step (no warning); per tile and the
    image mean against Cycles, PATH. Lantern used to move strands with their object's transform
    only (and said so): with the deformation left out this test fails."""
    scene = scene_factory("hair_motion")
    ball = bpy.data.objects["Ball"]
    ball.animation_data_clear()
    ball.location = (0.0, 0.0, 0.6)
    ball.shape_key_add(name="Basis")
    swell = ball.shape_key_add(name="Swell")
    for v, k in zip(ball.data.vertices, swell.data):
        k.co = v.co * 2.0
    build_scenes._keyframes(swell, "value", [0.0, 1.0], owner=ball.data.shape_keys)
    ru.render(scene, ru.LANTERN, 1)
    assert "hair, curves or points" not in engine.LAST_RENDER["report"], engine.LAST_RENDER["report"]
    both = lantern_and_cycles_of(scene, "hair_motion")
    report, _ = ru.agreement_report("hair_deforming", both[ru.LANTERN], both[ru.CYCLES], outdir, TILE, ROUNDING)
    assert report == "", report


def test_strand_and_point_attributes_agree_with_cycles(scene_factory, outdir):
    """What strands and points carry for shading, as Cycles 3.4 exports it (blender/curves.cpp,
    pointcloud.cpp), each shown as an Emission colour (scenes/build_scenes.py, hair_attributes):
    particle hair's UV at the root from its emitter's active render UV map (Texture Coordinate) and
    from a second map (UV Map node), and a byte colour attribute of the emitter (Attribute node,
    sRGB to linear); a Curves object's surface_uv_coordinate as its default UV (per curve) and a
    per-point float interpolated along each segment; a point cloud's per-point vector. Per tile
    and the image mean (test_agreement's rule); no warning in the export."""
    scene = scene_factory("hair_attributes")
    reports = ru.export(scene)[1]
    assert reports == [], reports
    both = lantern_and_cycles_of(scene, "hair_attributes")
    report, _ = ru.agreement_report("hair_attributes", both[ru.LANTERN], both[ru.CYCLES], outdir, TILE, ROUNDING)
    assert report == "", report
