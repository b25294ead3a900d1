"""Nodes that read the shading point, against Cycles pixel by pixel (issue 13's check, node_cases):
Texture Coordinate, Geometry, Fresnel, Layer Weight, Light Path and the implicit socket
conversions, on a sphere under a perspective camera (normals, incoming directions and angles vary)
and on a tilted plane under an orthographic one."""
import pytest

import render_utils as ru
from node_cases import compare_view, node

pytestmark = pytest.mark.skipif(not ru.engine_registered(), reason="Lantern add-on not registered")


def _output(idname, output, props=None, **inputs):
    def build(nt, coords):
        return node(nt, idname, props, **inputs).outputs[output]
    return build


@pytest.mark.parametrize("output", ["Generated", "Normal", "UV", "Object", "Camera", "Window", "Reflection"])
@pytest.mark.parametrize("shape", ["sphere", "plane"])
def test_texture_coordinate(output, shape, outdir):
    # Constant over a plane under an orthographic camera; the sphere has no UV map.
    flat = (shape == "plane" and output in ("Normal", "Reflection")) or (shape == "sphere" and output == "UV")
    compare_view(_output("ShaderNodeTexCoord", output), "texcoord_%s_%s" % (output, shape), outdir, flat=flat,
                 shape=shape)


@pytest.mark.parametrize("output", ["Position", "Normal", "Tangent", "True Normal", "Incoming", "Backfacing"])
def test_geometry(output, outdir):
    compare_view(_output("ShaderNodeNewGeometry", output), "geometry_" + output.replace(" ", "_"), outdir,
                 flat=output == "Backfacing", shape="sphere")


@pytest.mark.parametrize("ior", [1.45, 0.6, 3.0])
def test_fresnel(ior, outdir):
    compare_view(_output("ShaderNodeFresnel", "Fac", IOR=ior), "fresnel_%g" % ior, outdir, shape="sphere")


@pytest.mark.parametrize("output", ["Fresnel", "Facing"])
@pytest.mark.parametrize("blend", [0.1, 0.5, 0.8])
def test_layer_weight(output, blend, outdir):
    compare_view(_output("ShaderNodeLayerWeight", output, Blend=blend), "layer_weight_%s_%g" % (output, blend),
                 outdir, shape="sphere")


@pytest.mark.parametrize("output", ["Is Camera Ray", "Ray Length", "Ray Depth"])
def test_light_path_on_camera_rays(output, outdir):
    compare_view(_output("ShaderNodeLightPath", output), "light_path_" + output.replace(" ", "_"), outdir,
                 flat=output != "Ray Length", shape="sphere")


def test_linked_normal_drives_fresnel(outdir):
    """A Normal input linked from another node (Geometry's Incoming): no default stand-in."""
    def build(nt, coords):
        geo = node(nt, "ShaderNodeNewGeometry")
        mix = node(nt, "ShaderNodeVectorMath", {"operation": "ADD"})
        nt.links.new(geo.outputs["Normal"], mix.inputs[0])
        nt.links.new(geo.outputs["Incoming"], mix.inputs[1])
        norm = node(nt, "ShaderNodeVectorMath", {"operation": "NORMALIZE"})
        nt.links.new(mix.outputs[0], norm.inputs[0])
        f = node(nt, "ShaderNodeFresnel", IOR=1.8)
        nt.links.new(norm.outputs[0], f.inputs["Normal"])
        return f.outputs["Fac"]
    compare_view(build, "fresnel_linked_normal", outdir, shape="sphere")


@pytest.mark.parametrize("pair", [("RGB", "Float"), ("Vector", "Float"), ("Float", "Color")])
def test_implicit_conversions(pair, outdir):
    """A colour into a float socket is its Rec. 709 luma, a vector the average of its components,
    a float into a colour grey (Blender's and Cycles' conversions)."""
    src, dst = pair

    def build(nt, coords):
        if src == "RGB":
            value = node(nt, "ShaderNodeCombineRGB")
            sep = node(nt, "ShaderNodeSeparateXYZ")
            nt.links.new(coords, sep.inputs[0])
            for k, axis in enumerate("XYZ"):
                nt.links.new(sep.outputs[axis], value.inputs[k])
            out = value.outputs[0]
        elif src == "Vector":
            out = coords
        else:
            sep = node(nt, "ShaderNodeSeparateXYZ")
            nt.links.new(coords, sep.inputs[0])
            out = sep.outputs["Y"]
        target = node(nt, "ShaderNodeMath", {"operation": "ADD"}) if dst == "Float" else node(nt, "ShaderNodeInvert",
                                                                                               Fac=1.0)
        nt.links.new(out, target.inputs[0] if dst == "Float" else target.inputs["Color"])
        return target.outputs[0]
    compare_view(build, "convert_%s_to_%s" % pair, outdir)


@pytest.mark.parametrize("kind", ["byte_straight", "byte_premultiplied", "float", "non_color", "closest"])
@pytest.mark.parametrize("output", ["Color", "Color with Alpha used", "Alpha"])
def test_image_texture_alpha(kind, output, outdir):
    """An RGBA image (a leaf: alpha fading to 0 over its rim) as Cycles reads it: straight byte
    colours associated with alpha, so the Color output is premultiplied unless the Alpha output is
    used (then divided back); float images premultiplied; Non-Color keeps colours apart from alpha."""
    import bpy
    import numpy as np

    import build_scenes as bs

    def build(nt, coords):
        pixels = bs.leaf_pixels(48)
        if kind == "float":
            # Float colours divided by an alpha near 0 (a bilinear alpha at the rim) change faster
            # than the engines' sample jitter allows for: keep alpha at least 0.05 there.
            pixels[..., 3] = np.maximum(pixels[..., 3], 0.05)
            img = bpy.data.images.new("leaf", 48, 48, alpha=True, float_buffer=True)
            img.pixels.foreach_set(np.ascontiguousarray(pixels, np.float32).ravel())
        else:
            img = bs.packed_image("leaf", pixels, "Non-Color" if kind == "non_color" else "sRGB")
            img.alpha_mode = "PREMUL" if kind == "byte_premultiplied" else "STRAIGHT"
        tex = node(nt, "ShaderNodeTexImage")
        tex.image = img
        tex.interpolation = "Closest" if kind == "closest" else "Linear"
        scale = node(nt, "ShaderNodeVectorMath", {"operation": "MULTIPLY_ADD"})
        nt.links.new(coords, scale.inputs[0])
        scale.inputs[1].default_value = (1.6, 1.6, 1.6)
        scale.inputs[2].default_value = (0.5, 0.5, 0.5)
        nt.links.new(scale.outputs[0], tex.inputs["Vector"])
        if output == "Color with Alpha used":
            # Colour x max(Alpha, 2) / 2: the colour, with Alpha reaching the output (Cycles leaves
            # out nodes that reach nothing, and only then unassociates).
            two = node(nt, "ShaderNodeMath", {"operation": "MAXIMUM"})
            nt.links.new(tex.outputs["Alpha"], two.inputs[0])
            two.inputs[1].default_value = 2.0
            scale = node(nt, "ShaderNodeVectorMath", {"operation": "SCALE"})
            nt.links.new(tex.outputs["Color"], scale.inputs[0])
            half = node(nt, "ShaderNodeMath", {"operation": "MULTIPLY"})
            nt.links.new(two.outputs[0], half.inputs[0])
            half.inputs[1].default_value = 0.5
            nt.links.new(half.outputs[0], scale.inputs["Scale"])
            return scale.outputs[0]
        return tex.outputs["Alpha" if output == "Alpha" else "Color"]
    compare_view(build, "image_%s_%s" % (kind, output.replace(" ", "_")), outdir)


@pytest.mark.parametrize("source", ["noise_object", "wave_uv", "checker_generated"])
@pytest.mark.parametrize("invert", [False, True])
def test_bump(source, invert, outdir):
    """Bump's normal (Cycles' finite differences over the ray footprint: the Height input at the
    point and moved along the footprint's two differentials) from heights that vary slowly per
    pixel: the normal is a difference over the footprint of each sample, so where it turns fast
    across a pixel the engines' sample jitter shows (a Noise of scale 2 differs at 3 % of pixels;
    the footprint scaled by 2 or 0.5 differs everywhere, median 0.013 and 0.007)."""
    def build(nt, coords):
        if source == "noise_object":
            tex = node(nt, "ShaderNodeTexNoise", Scale=0.8, Detail=0.0)
            nt.links.new(coords, tex.inputs["Vector"])
            height = tex.outputs["Fac"]
        elif source == "wave_uv":
            tc = node(nt, "ShaderNodeTexCoord")
            tex = node(nt, "ShaderNodeTexWave", Scale=3.0)
            nt.links.new(tc.outputs["UV"], tex.inputs["Vector"])
            height = tex.outputs["Fac"]
        else:
            tc = node(nt, "ShaderNodeTexCoord")
            sep = node(nt, "ShaderNodeSeparateXYZ")
            nt.links.new(tc.outputs["Generated"], sep.inputs[0])
            height = node(nt, "ShaderNodeMath", {"operation": "SINE"}).outputs[0]
            scaled = node(nt, "ShaderNodeMath", {"operation": "MULTIPLY"})
            scaled.inputs[1].default_value = 4.0
            nt.links.new(sep.outputs["Z"], scaled.inputs[0])
            nt.links.new(scaled.outputs[0], height.node.inputs[0])
        b = node(nt, "ShaderNodeBump", {"invert": invert}, Strength=0.8, Distance=0.3)
        nt.links.new(height, b.inputs["Height"])
        return b.outputs["Normal"]
    compare_view(build, "bump_%s_%s" % (source, invert), outdir, shape="sphere")


@pytest.mark.parametrize("output", ["View Vector", "View Z Depth", "View Distance"])
def test_camera_data(output, outdir):
    compare_view(_output("ShaderNodeCameraData", output), "camera_data_" + output.replace(" ", "_"), outdir,
                 shape="sphere")


@pytest.mark.parametrize("output", ["Quadratic", "Linear", "Constant"])
@pytest.mark.parametrize("smooth", [0.0, 2.0])
def test_light_falloff(output, smooth, outdir):
    """On camera rays: the strength times 1, the ray length or its square (Cycles' ray length from
    the near clip), smoothed."""
    def build(nt, coords):
        f = node(nt, "ShaderNodeLightFalloff", Smooth=smooth)
        sep = node(nt, "ShaderNodeSeparateXYZ")
        nt.links.new(coords, sep.inputs[0])
        nt.links.new(sep.outputs["Z"], f.inputs["Strength"])
        return f.outputs[output]
    compare_view(build, "light_falloff_%s_%g" % (output, smooth), outdir, shape="sphere")


@pytest.mark.parametrize("projection", ["EQUIRECTANGULAR", "MIRROR_BALL"])
@pytest.mark.parametrize("vector", ["Position", "Normal"])
def test_environment_texture(projection, vector, outdir):
    """Environment Texture on a sphere's material (Cycles' svm_node_tex_environment): the image
    along the normalised vector, by default the Position (here the sphere's, centred at the
    origin), or the Normal. A float image periodic in u, so the equirectangular seam is smooth."""
    import bpy
    import numpy as np

    def build(nt, coords):
        w, h = 64, 32
        y, x = (np.mgrid[0:h, 0:w] + 0.5) / np.array([h, w])[:, None, None]
        rgba = np.dstack([0.5 + 0.4 * np.cos(2 * np.pi * x), 0.2 + 0.6 * y,
                          0.5 + 0.3 * np.sin(2 * np.pi * x) * np.sin(np.pi * y), np.ones_like(x)])
        img = bpy.data.images.new("env", w, h, alpha=True, float_buffer=True)
        img.pixels.foreach_set(np.ascontiguousarray(rgba, np.float32).ravel())
        tex = node(nt, "ShaderNodeTexEnvironment", {"projection": projection, "interpolation": "Linear"})
        tex.image = img
        if vector == "Normal":
            nt.links.new(node(nt, "ShaderNodeNewGeometry").outputs["Normal"], tex.inputs["Vector"])
        return tex.outputs["Color"]
    compare_view(build, "environment_%s_%s" % (projection.lower(), vector.lower()), outdir, shape="sphere")
