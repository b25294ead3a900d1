"""The running Blender's Cycles still follows the light conventions Lantern's core copies.

DESIGN.md ("Cycles conventions to match") was measured with Blender 3.4.1; these tests re-measure
it with Cycles alone, so a different Blender (4.x changed area lights to P/(pi A)) shows up here
first, with a plain message, rather than as a scatter of agreement-test failures.

Set-up: an albedo-1 Diffuse plane, 200 m wide, at z = 0; an orthographic camera looking straight
down at a 2 cm patch of it (the light's fall-off across the patch is below 2e-4 relative). With
albedo 1 the plane's radiance is E / pi, E the irradiance at the centre. Each light is 1 m above
the plane, 1000 W (sun: strength 1). A value passes when it is within 6 standard errors of the
closed form (pixel spread / sqrt(pixels)) plus 3e-4 relative for the patch's fall-off.
"""
import math

import numpy as np
import pytest

import bpy
import build_scenes as bs
import render_utils as ru

P = 1000.0
RES = 16


def _square_view_factor(a, b, h):
    """Point-to-rectangle view factor, rectangle a x b parallel to the receiver, one corner above
    the point, at height h (standard closed form)."""
    x, y = a / h, b / h
    return (x / math.sqrt(1 + x * x) * math.atan(y / math.sqrt(1 + x * x))
            + y / math.sqrt(1 + y * y) * math.atan(x / math.sqrt(1 + y * y))) / (2 * math.pi)


def _ortho_camera(scene, z, looking_up=False, scale=0.02):
    target = (0, 0, z + 1) if looking_up else (0, 0, z - 1)
    cam = bs.add_camera(scene, (0, 0, z), target)
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = scale
    cam.data.clip_start = 1e-3
    return cam


def _plane_scene(samples):
    bs.reset_file()
    scene = bs.new_scene("conventions", (RES, RES), samples)
    plane = bs.add_object(scene, "Plane", bs.mesh_plane("Plane", 200.0))
    bs.assign(plane, bs.diffuse("Albedo1", (1.0, 1.0, 1.0)))
    _ortho_camera(scene, 0.5)
    return scene


def _measure(scene, samples):
    img = ru.render(scene, ru.CYCLES, samples, seed=0).combined[..., :3].astype(np.float64)
    return img.mean(), img.std() / math.sqrt(img.size)


def _check(label, scene, samples, expected):
    mean, se = _measure(scene, samples)
    bound = 6.0 * se + 3e-4 * abs(expected) + 1e-6
    assert abs(mean - expected) <= bound, (
        "Cycles %s: measured %.5f, expected %.5f (+- %.5f): Blender %s no longer follows the "
        "convention Lantern's core copies" % (label, mean, expected, bound, bpy.app.version_string))


# name, light kind, properties, samples, expected plane radiance
_SQUARE = 4 * _square_view_factor(0.5, 0.5, 1.0)
_SUN_HALF = math.radians(5.0)
ILLUMINATION = [
    ("point r=0: I = P/(4 pi)", "POINT", dict(radius=0.0), 256, P / (4 * math.pi ** 2)),
    # Cycles 3.4 samples a point light with radius r as a disk of radiance P/(4 pi^2 r^2) facing
    # the receiver: E = P / (4 pi (d^2 + r^2)).
    ("point r=0.1: disk facing the receiver", "POINT", dict(radius=0.1), 1024,
     P / (4 * math.pi ** 2 * (1 + 0.01))),
    ("spot 90 deg blend 0: point intensity on the axis", "SPOT",
     dict(radius=0.0, spot_size=math.radians(90.0), spot_blend=0.0), 256, P / (4 * math.pi ** 2)),
    ("square area 1 m: radiance P/(4A)", "AREA", dict(shape="SQUARE", size=1.0), 1024,
     P / 4.0 * _SQUARE),
    ("disk area d=1 m: radiance P/(4A)", "AREA", dict(shape="DISK", size=1.0), 1024,
     P / (4 * math.pi * 0.25) * 0.2),
    ("sun 1, angle 0: E = strength", "SUN", dict(angle=0.0), 16, 1.0 / math.pi),
    # A sun of angular diameter 2a is a disk of uniform radiance in the tangent plane at unit
    # distance; straight down E = strength * 2 cos a / (1 + cos a).
    ("sun 1, angle 10 deg", "SUN", dict(angle=2 * _SUN_HALF), 256,
     2 * math.cos(_SUN_HALF) / (1 + math.cos(_SUN_HALF)) / math.pi),
]


@pytest.mark.parametrize("label,kind,props,samples,expected", ILLUMINATION,
                         ids=[i[0].split(":")[0] for i in ILLUMINATION])
def test_light_units(label, kind, props, samples, expected):
    scene = _plane_scene(samples)
    energy = 1.0 if kind == "SUN" else P
    bs.add_light(scene, "Light", kind, energy, (0, 0, 1.0), **props)
    _check(label, scene, samples, expected)


def test_emission_and_background_radiance():
    scene = _plane_scene(16)
    emit = bs._bsdf_material("Emit", "ShaderNodeEmission", (1.0, 1.0, 1.0), Strength=1.0)
    bs.assign(scene.objects["Plane"], emit)
    _check("emission plane, front", scene, 16, 1.0)
    scene.objects["Plane"].rotation_euler.x = math.pi  # now the camera sees the plane's back
    _check("emission plane, back", scene, 16, 1.0)
    scene.objects["Plane"].hide_render = True
    bs.set_world(scene, (1.0, 1.0, 1.0), 1.0)
    _check("world background colour 1 strength 1", scene, 16, 1.0)


def test_lights_seen_by_the_camera():
    bs.reset_file()
    scene = bs.new_scene("conventions", (RES, RES), 64)
    _ortho_camera(scene, -1.0, looking_up=True, scale=0.05)
    light = bpy.data.lights.new("Point", "POINT")
    obj = bpy.data.objects.new("Point", light)
    scene.collection.objects.link(obj)
    # Lights made through the data API are not camera-visible by default ...
    assert obj.visible_camera is False
    light.energy, light.shadow_soft_size = P, 0.1
    _check("point light, camera-invisible", scene, 16, 0.0)
    # ... and when they are, a point light of radius r is a disk of radiance P/(4 pi^2 r^2),
    obj.visible_camera = True
    _check("point light r=0.1 seen directly", scene, 64, P / (4 * math.pi ** 2 * 0.01))
    bpy.data.objects.remove(obj)
    # an area light shows radiance P/(4A) on its front (-Z) side and nothing on its back.
    area = bs.add_light(scene, "Area", "AREA", P, (0, 0, 0), shape="SQUARE", size=1.0,
                        camera=True)
    _check("square area light seen from the front", scene, 64, P / 4.0)
    area.rotation_euler.x = math.pi
    _check("square area light seen from the back", scene, 16, 0.0)
