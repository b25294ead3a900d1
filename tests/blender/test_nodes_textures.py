"""Procedural texture nodes, Lantern against Cycles pixel by pixel (issue 13's check): the node's
output drives an Emission shader on a camera-facing plane, seen by camera rays only, so the image is
the node's value. Every mode of every node is rendered, negative outputs included (see compare()).

Both engines sample each pixel near its centre (Gaussian filter 0.01 px wide), so a pixel's value is
the texture at nearly the same point in both; the few pixels whose centre lies within the jitter of
a discontinuity (Voronoi cell borders, checker and brick edges, saw waves) may differ, and at most
OUTLIERS of them are allowed.
"""
import math

import pytest

import render_utils as ru
from node_cases import compare_view as compare
from node_cases import node

pytestmark = pytest.mark.skipif(not ru.engine_registered(), reason="Lantern add-on not registered")

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


# Sky Texture (Cycles' svm_node_tex_sky). Nishita: the core's precompute (shading/sky.cpp) against
# Cycles' (intern/sky), the sun disc (widened to be seen whole: its edge is the only
# discontinuity), setting, off, and the densities and altitude varied; Preetham is analytic.
# On the sphere its Vector is the world normal, so that the image sweeps the sky from below the
# horizon to the zenith (sun rotation pi puts the sun toward the camera), except where Blender
# disables the input (Nishita with its sun disc: Generated coordinates, in both engines).
SKY_CASES = {
    "nishita_sun": dict(sun_disc=True, sun_size=0.35, sun_elevation=0.35, sun_rotation=math.pi),
    "nishita_setting_sun": dict(sun_disc=True, sun_size=0.3, sun_elevation=-0.05, sun_rotation=math.pi + 0.2,
                                sun_intensity=0.4),
    "nishita_no_disc": dict(sun_disc=False, sun_elevation=0.6, sun_rotation=2.5, altitude=5000.0),
    "nishita_densities": dict(sun_disc=True, sun_size=0.2, sun_elevation=0.08, sun_rotation=-2.8, air_density=3.5,
                              dust_density=6.0, ozone_density=8.0, altitude=300.0),
    "nishita_space": dict(sun_disc=True, sun_size=0.25, sun_elevation=1.1, sun_rotation=3.3, altitude=45000.0,
                          air_density=0.6, dust_density=0.2, ozone_density=0.0),
    "preetham": dict(sky_type="PREETHAM", sun_direction=(0.2, -0.8, 0.45), turbidity=3.1),
    "preetham_low_sun": dict(sky_type="PREETHAM", sun_direction=(-0.5, -0.7, 0.08), turbidity=6.0),
}


@pytest.mark.parametrize("case", list(SKY_CASES))
def test_sky(case, outdir):
    def build(nt, coords):
        n = node(nt, "ShaderNodeTexSky", dict(SKY_CASES[case]))
        geo = nt.nodes.new("ShaderNodeNewGeometry")
        nt.links.new(geo.outputs["Normal"], n.inputs["Vector"])
        return n.outputs["Color"]
    compare(build, "sky_" + case, outdir, shape="sphere")


# The World's sky seen whole through an equirectangular camera (the node's unlinked Vector: the
# direction): the sun disc with its limb darkening, rising and high, the sky, the horizon, the
# ground's fade to black. The sun is widened to a few pixels (to 20 in "nishita_wide_sun", where its
# limb darkening must be Cycles' within the bound) so that its inside is compared too.
WORLD_SKY_CASES = {
    "nishita_default": dict(sun_size=0.2),
    "nishita_wide_sun": dict(sun_size=0.5, sun_elevation=0.4, sun_rotation=0.7),
    "nishita_rising_sun": dict(sun_size=0.25, sun_elevation=0.05, sun_rotation=2.0, sun_intensity=0.5),
    "nishita_high_sun": dict(sun_size=0.15, sun_elevation=1.2, sun_rotation=-1.0, altitude=2500.0, air_density=2.0,
                             dust_density=0.5, ozone_density=3.0),
    "nishita_no_disc": dict(sun_disc=False, sun_elevation=0.3, sun_rotation=4.0, dust_density=9.0),
}


@pytest.mark.parametrize("case", list(WORLD_SKY_CASES))
def test_world_sky(case, outdir):
    def build(nt, coords):
        return node(nt, "ShaderNodeTexSky", dict(WORLD_SKY_CASES[case])).outputs["Color"]
    compare(build, "world_sky_" + case, outdir, shape="world")
