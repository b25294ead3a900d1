"""Procedural texture nodes, Lantern against Cycles pixel by pixel (issue 13's check): the node's
output drives an Emission shader on a camera-facing plane, seen by camera rays only, so the image is
the node's value. Every mode of every node is rendered, negative outputs included (see compare()).

Both engines sample each pixel near its centre (Gaussian filter 0.01 px wide), so a pixel's value is
the texture at nearly the same point in both; the few pixels whose centre lies within the jitter of
a discontinuity (Voronoi cell borders, checker and brick edges, saw waves) may differ, and at most
OUTLIERS of them are allowed.
"""
import os

import numpy as np
import pytest
from mathutils import Matrix

import build_scenes as bs
import render_utils as ru

pytestmark = pytest.mark.skipif(not ru.engine_registered(), reason="Lantern add-on not registered")

RES = int(os.environ.get("TEX_RES", 128))
SAMPLES = int(os.environ.get("TEX_SAMPLES", 1))
REL = 1e-3  # |Lantern - Cycles| <= REL |Cycles| + ABS per channel
ABS = 1e-4
OUTLIERS = 0.005  # fraction of pixels allowed beyond the bound (discontinuities under the jitter)
# The view's width in scene units. The engines' sample positions differ by a few thousandths of a
# pixel, so a texture must vary slowly per pixel for 1e-3 to hold: about four features per image.
VIEW = float(os.environ.get("TEX_VIEW", 0.6))


def texture_scene(build, negate=False):
    """A 4 x 4 plane filling an orthographic view; `build(nt, coords)` returns the socket shown.
    The mesh is tilted inside its object (and the object tilted back), so Object coordinates vary
    along all three axes over the image."""
    bs.reset_file()
    scene = bs.new_scene("textures", resolution=(RES, RES), samples=1)
    c = scene.cycles
    c.pixel_filter_type = "GAUSSIAN"
    c.filter_width = 0.01
    c.max_bounces = 0
    c.film_exposure = 1.0
    cam = bs.add_camera(scene, (0, 0, 5), (0, 0, 0))
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = VIEW
    tilt = 0.6
    me = bs.mesh_plane("plane", 4.0, matrix=Matrix.Rotation(tilt, 4, "X"))
    obj = bs.add_object(scene, "plane", me, rotation=(-tilt, 0, 0))
    mat = bpy_material("texture")
    nt = mat.node_tree
    nt.nodes.clear()
    coords = nt.nodes.new("ShaderNodeTexCoord").outputs["Object"]
    shown = build(nt, coords)
    if negate:  # an exact negation after the node
        if shown.type == "VALUE":
            neg = node(nt, "ShaderNodeMath", {"operation": "MULTIPLY"})
            neg.inputs[1].default_value = -1.0
        else:
            neg = node(nt, "ShaderNodeVectorMath", {"operation": "SCALE"})
            neg.inputs["Scale"].default_value = -1.0
        nt.links.new(shown, neg.inputs[0])
        shown = neg.outputs[0]
    em = nt.nodes.new("ShaderNodeEmission")
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(shown, em.inputs["Color"])
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    bs.assign(obj, mat)
    return scene


def bpy_material(name):
    import bpy
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    return mat


def beyond(lantern, cycles):
    """Pixels beyond the bound (a mask), and the worst ratio to the bound."""
    diff = np.abs(lantern - cycles)
    bound = REL * np.abs(cycles) + ABS
    return np.any(diff > bound, axis=-1), float((diff / bound).max())


def render_pair(build, label, outdir, negate=False):
    scene = texture_scene(build, negate)
    tag = label + ("_neg" if negate else "")
    lantern = ru.render(scene, ru.LANTERN, samples=SAMPLES, outdir=outdir, tag=tag + "_lantern").combined[..., :3]
    cycles = ru.render(scene, ru.CYCLES, samples=SAMPLES, outdir=outdir, tag=tag + "_cycles").combined[..., :3]
    return lantern, cycles


def compare(build, label, outdir, flat=False):
    """Renders the set-up `build` makes in both engines and compares them pixel by pixel. Should
    Lantern's emission keep no negative radiance where Cycles' does, the set-up is rendered again
    negated (an exact negation after the node) and the positive parts of both renders are compared,
    so both signs of the output are still checked."""
    lantern, cycles = render_pair(build, label, outdir)
    # The image must show a pattern, or the comparison proves little.
    assert flat or float(cycles.std()) > 1e-3, "%s: Cycles renders a flat image" % label
    bad, worst = beyond(lantern, cycles)
    if bad.mean() > OUTLIERS and (cycles < 0).any() and (lantern >= 0).all():
        lantern_neg, _ = render_pair(build, label, outdir, negate=True)
        bad, worst = beyond(lantern, np.maximum(cycles, 0.0))
        bad_neg, worst_neg = beyond(lantern_neg, np.maximum(-cycles, 0.0))
        bad, worst = bad | bad_neg, max(worst, worst_neg)
    frac = float(bad.mean())
    if frac > OUTLIERS:
        ru.write_png("%s/%s_lantern.png" % (outdir, label), lantern)
        ru.write_png("%s/%s_cycles.png" % (outdir, label), cycles)
    assert frac <= OUTLIERS, "%s: %.2f%% of pixels beyond %g relative (worst %.3g x the bound)" % (
        label, 100 * frac, REL, worst)


def node(nt, idname, props=None, **inputs):
    n = nt.nodes.new(idname)
    for k, v in (props or {}).items():
        setattr(n, k, v)
    for k, v in inputs.items():
        sock = n.inputs[k.replace("_", " ")]
        sock.default_value = (*v, 1.0) if isinstance(v, tuple) and len(v) == 3 and sock.type == "RGBA" else v
    return n


DIMS = ("1D", "2D", "3D", "4D")


def link_coords(nt, coords, n):
    """Coordinates into Vector, and into W for 1D (a vector into a float socket is the average of
    its components, in both engines), so that a 1D texture varies over the image."""
    nt.links.new(coords, n.inputs["Vector"])
    if n.inputs["W"].enabled and not n.inputs["Vector"].enabled:
        nt.links.new(coords, n.inputs["W"])


@pytest.mark.parametrize("dims", DIMS)
@pytest.mark.parametrize("output", ("Fac", "Color"))
@pytest.mark.parametrize("distortion", (0.0, 1.3))
def test_noise(dims, output, distortion, outdir):
    def build(nt, coords):
        n = node(nt, "ShaderNodeTexNoise", {"noise_dimensions": dims}, W=0.4, Scale=1.3, Detail=3.3,
                 Roughness=0.55, Distortion=distortion)
        link_coords(nt, coords, n)
        return n.outputs[output]
    compare(build, "noise_%s_%s_%g" % (dims, output, distortion), outdir)


VORONOI_OUTPUTS = {"F1": ("Distance", "Color", "Position", "W"), "F2": ("Distance", "Color", "Position", "W"),
                   "SMOOTH_F1": ("Distance", "Color", "Position", "W"), "DISTANCE_TO_EDGE": ("Distance",),
                   "N_SPHERE_RADIUS": ("Radius",)}


def voronoi_cases():
    for dims in DIMS:
        for feature, outputs in VORONOI_OUTPUTS.items():
            metrics = ("EUCLIDEAN",) if feature in ("DISTANCE_TO_EDGE", "N_SPHERE_RADIUS") else (
                "EUCLIDEAN", "MANHATTAN", "CHEBYCHEV", "MINKOWSKI")
            for metric in metrics:
                for output in outputs:
                    if output == "W" and dims in ("2D", "3D") or output == "Position" and dims == "1D":
                        continue  # hidden in Blender for that dimension
                    yield dims, feature, metric, output


@pytest.mark.parametrize("dims,feature,metric,output", list(voronoi_cases()))
def test_voronoi(dims, feature, metric, output, outdir):
    def build(nt, coords):
        n = node(nt, "ShaderNodeTexVoronoi", {"voronoi_dimensions": dims, "feature": feature, "distance": metric},
                 W=0.7, Scale=2.2, Smoothness=0.8, Exponent=1.7, Randomness=0.9)
        link_coords(nt, coords, n)
        return n.outputs[output]
    compare(build, "voronoi_%s_%s_%s_%s" % (dims, feature, metric, output), outdir)


@pytest.mark.parametrize("dims", DIMS)
@pytest.mark.parametrize("kind", ("MULTIFRACTAL", "RIDGED_MULTIFRACTAL", "HYBRID_MULTIFRACTAL", "FBM",
                                  "HETERO_TERRAIN"))
def test_musgrave(dims, kind, outdir):
    def build(nt, coords):
        n = node(nt, "ShaderNodeTexMusgrave", {"musgrave_dimensions": dims, "musgrave_type": kind}, W=0.3,
                 Scale=1.4, Detail=3.6, Dimension=1.2, Lacunarity=2.2, Offset=0.8, Gain=1.1)
        link_coords(nt, coords, n)
        return n.outputs["Fac"]
    compare(build, "musgrave_%s_%s" % (dims, kind), outdir)


def wave_cases():
    for kind, directions in (("BANDS", ("X", "Y", "Z", "DIAGONAL")), ("RINGS", ("X", "Y", "Z", "SPHERICAL"))):
        for direction in directions:
            for profile in ("SIN", "SAW", "TRI"):
                yield kind, direction, profile


@pytest.mark.parametrize("kind,direction,profile", list(wave_cases()))
def test_wave(kind, direction, profile, outdir):
    def build(nt, coords):
        props = {"wave_type": kind, "wave_profile": profile,
                 ("bands_direction" if kind == "BANDS" else "rings_direction"): direction}
        n = node(nt, "ShaderNodeTexWave", props, Scale=0.35, Distortion=2.0, Detail=2.5, Detail_Scale=1.2,
                 Detail_Roughness=0.6, Phase_Offset=0.3)
        nt.links.new(coords, n.inputs["Vector"])
        return n.outputs["Fac"]
    compare(build, "wave_%s_%s_%s" % (kind, direction, profile), outdir)


@pytest.mark.parametrize("depth", (0, 1, 2, 3, 5, 10))
@pytest.mark.parametrize("output", ("Color", "Fac"))
def test_magic(depth, output, outdir):
    def build(nt, coords):
        n = node(nt, "ShaderNodeTexMagic", {"turbulence_depth": depth}, Scale=0.6, Distortion=0.8)
        nt.links.new(coords, n.inputs["Vector"])
        return n.outputs[output]
    compare(build, "magic_%d_%s" % (depth, output), outdir)


@pytest.mark.parametrize("output", ("Color", "Fac"))
def test_checker(output, outdir):
    def build(nt, coords):
        n = node(nt, "ShaderNodeTexChecker", Color1=(0.9, 0.3, 0.1), Color2=(0.1, 0.4, 0.8), Scale=1.7)
        nt.links.new(coords, n.inputs["Vector"])
        return n.outputs[output]
    compare(build, "checker_%s" % output, outdir)


# Several rows with hard mortar (its edges are discontinuities: outliers), or one brick's smooth mortar
# ramp (steep: a lower scale keeps it within the bound under the engines' sample jitter).
@pytest.mark.parametrize("scale,smooth", ((4.0, 0.0), (0.5, 1.0)))
@pytest.mark.parametrize("freqs", ((2, 2, 0.5, 1.0), (3, 2, 0.3, 0.6), (1, 3, 0.7, 1.5), (0, 0, 0.5, 1.0)))
@pytest.mark.parametrize("output", ("Color", "Fac"))
def test_brick(scale, smooth, freqs, output, outdir):
    def build(nt, coords):
        of, sf, offset, squash = freqs
        n = node(nt, "ShaderNodeTexBrick", {"offset_frequency": of, "squash_frequency": sf, "offset": offset,
                                             "squash": squash},
                 Color1=(0.8, 0.3, 0.1), Color2=(0.2, 0.6, 0.3), Mortar=(0.05, 0.05, 0.05), Scale=scale,
                 Mortar_Size=0.1 if smooth else 0.03, Mortar_Smooth=smooth, Bias=0.1, Brick_Width=0.6, Row_Height=0.3)
        nt.links.new(coords, n.inputs["Vector"])
        return n.outputs[output]
    compare(build, "brick_%g_%g_%d_%d_%g_%g_%s" % (scale, smooth, *freqs, output), outdir)


@pytest.mark.parametrize("kind", ("LINEAR", "QUADRATIC", "EASING", "DIAGONAL", "SPHERICAL", "QUADRATIC_SPHERE",
                                  "RADIAL"))
def test_gradient(kind, outdir):
    def build(nt, coords):
        n = node(nt, "ShaderNodeTexGradient", {"gradient_type": kind})
        nt.links.new(coords, n.inputs["Vector"])
        return n.outputs["Fac"]
    compare(build, "gradient_%s" % kind, outdir)


@pytest.mark.parametrize("dims", DIMS)
@pytest.mark.parametrize("output", ("Value", "Color"))
def test_white_noise(dims, output, outdir):
    # White noise hashes its exact input: it is fed a Voronoi cell's position and W, constant over
    # each cell, so that both engines hash the same numbers.
    def build(nt, coords):
        v = node(nt, "ShaderNodeTexVoronoi", {"voronoi_dimensions": "4D"}, W=0.4, Scale=2.0)
        nt.links.new(coords, v.inputs["Vector"])
        n = node(nt, "ShaderNodeTexWhiteNoise", {"noise_dimensions": dims})
        nt.links.new(v.outputs["Position"], n.inputs["Vector"])
        nt.links.new(v.outputs["W"], n.inputs["W"])
        return n.outputs[output]
    compare(build, "white_%s_%s" % (dims, output), outdir)


def test_unlinked_vector_is_generated(outdir):
    """Texture nodes read Generated coordinates when their Vector is unlinked (as Cycles)."""
    def build(nt, coords):
        return node(nt, "ShaderNodeTexNoise", Scale=3.0, Detail=2.0).outputs["Fac"]
    compare(build, "noise_generated", outdir)


@pytest.mark.parametrize("dims", DIMS)
def test_white_noise_unlinked_vector_is_its_value(dims, outdir):
    """White Noise has no implicit coordinates in Cycles: an unlinked Vector is the socket's value
    (and the instruction, all constants, is folded by the core at load)."""
    def build(nt, coords):
        n = node(nt, "ShaderNodeTexWhiteNoise", {"noise_dimensions": dims}, W=0.45)
        n.inputs["Vector"].default_value = (0.3, -1.7, 2.2)
        return n.outputs["Color"]
    compare(build, "white_constant_%s" % dims, outdir, flat=True)
