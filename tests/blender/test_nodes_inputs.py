"""Nodes that read the shading point, against Cycles pixel by pixel (issue 13's check, node_cases):
Texture Coordinate, Geometry, Fresnel, Layer Weight, Light Path and the implicit socket
conversions, on a sphere under a perspective camera (normals, incoming directions and angles vary)
and on a tilted plane under an orthographic one; Wireframe; Ambient Occlusion (its rays make it
noisy: the statistical agreement rule instead)."""
import pytest

import build_scenes as bs
import render_utils as ru
from node_cases import bpy_material, compare_view, node

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


@pytest.mark.parametrize("output", ["Position", "Radius", "Random"])
def test_point_info(output, outdir):
    """Point Info on a point cloud scaled unevenly (Cycles' world-space centre, its radius through
    the object's transform, the per-point random number)."""
    compare_view(_output("ShaderNodePointInfo", output), "point_info_" + output, outdir, shape="points",
                 flat=output == "Radius")  # one radius for all points


@pytest.mark.parametrize("pixel_size", [False, True])
def test_wireframe(pixel_size, outdir):
    """Wireframe on the sphere's triangles: a world-space width, and a width in pixels (the ray
    footprint seen across the view)."""
    props = {"use_pixel_size": pixel_size}
    compare_view(_output("ShaderNodeWireframe", "Fac", props, Size=2.0 if pixel_size else 0.04),
                 "wireframe_%s" % ("pixels" if pixel_size else "world"), outdir, shape="sphere")


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


def _smooth_image(name, size=16, colorspace="sRGB"):
    """A byte image of slow periodic colours (seamless when repeated): every pixel's value varies
    slowly enough under the views for the engines' sample jitter."""
    import numpy as np

    import build_scenes as bs
    y, x = (np.mgrid[0:size, 0:size] + 0.5) / size
    rgba = np.stack([0.5 + 0.45 * np.sin(2 * np.pi * x), 0.5 + 0.45 * np.sin(2 * np.pi * y + 1.0),
                     0.5 + 0.45 * np.sin(2 * np.pi * (x + y)), np.ones_like(x)], axis=-1)
    return bs.packed_image(name, rgba, colorspace)


def _image_node(nt, image, **props):
    tex = node(nt, "ShaderNodeTexImage", props)
    tex.image = image
    return tex


@pytest.mark.parametrize("blend", [0.0, 0.25, 0.6])
@pytest.mark.parametrize("shape", ["sphere", "plane"])
def test_image_box_projection(blend, shape, outdir):
    """Box projection (Cycles' svm_node_tex_image_box): three planar lookups along the object
    axes weighted by the object-space normal, blended over `blend`, on a rotated sphere (every
    normal direction) and on a tilted plane. Blend 0 has hard seams: they are the few outliers."""
    def build(nt, coords):
        tex = _image_node(nt, _smooth_image("box"), projection="BOX", projection_blend=blend)
        nt.links.new(coords, tex.inputs["Vector"])
        return tex.outputs["Color"]
    compare_view(build, "image_box_%g_%s" % (blend, shape), outdir, shape=shape)


@pytest.mark.parametrize("projection", ["SPHERE", "TUBE"])
@pytest.mark.parametrize("shape", ["sphere", "plane"])
def test_image_sphere_and_tube_projection(projection, shape, outdir):
    """Sphere and Tube projections (Cycles' map_to_sphere and map_to_tube of the vector remapped
    from [0, 1] to [-1, 1]) of Generated coordinates; the seam where the angle wraps is among the
    outliers."""
    def build(nt, coords):
        tex = _image_node(nt, _smooth_image("wrapped"), projection=projection)
        tc = node(nt, "ShaderNodeTexCoord")
        nt.links.new(tc.outputs["Generated"], tex.inputs["Vector"])
        return tex.outputs["Color"]
    compare_view(build, "image_%s_%s" % (projection.lower(), shape), outdir, shape=shape)


@pytest.mark.parametrize("interpolation", ["Cubic", "Smart", "Linear", "Closest"])
@pytest.mark.parametrize("extension", ["REPEAT", "EXTEND", "CLIP"])
def test_image_interpolation_and_extension(interpolation, extension, outdir):
    """A 6 x 6 image of random texels magnified (7 pixels a texel) through a Mapping of scale 3, so
    the view crosses its edges three times: Cycles' CPU cubic B-spline (Smart is Cubic on the CPU)
    and each extension (Blender 3.4 has no Mirror extension: it came with 3.5)."""
    import numpy as np

    import build_scenes as bs

    def build(nt, coords):
        rng = np.random.default_rng(7)
        rgba = np.concatenate([rng.random((6, 6, 3)), np.ones((6, 6, 1))], axis=-1)
        tex = _image_node(nt, bs.packed_image("texels", rgba, "sRGB"), interpolation=interpolation,
                          extension=extension)
        shift = node(nt, "ShaderNodeVectorMath", {"operation": "MULTIPLY_ADD"})
        nt.links.new(coords, shift.inputs[0])
        shift.inputs[1].default_value = (1.6, 1.6, 1.6)
        shift.inputs[2].default_value = (0.5, 0.5, 0.5)
        mapping = node(nt, "ShaderNodeMapping", {"vector_type": "POINT"})
        mapping.inputs["Scale"].default_value = (3.0, 3.0, 3.0)
        nt.links.new(shift.outputs[0], mapping.inputs["Vector"])
        nt.links.new(mapping.outputs[0], tex.inputs["Vector"])
        return tex.outputs["Color"]
    compare_view(build, "image_%s_%s" % (interpolation, extension), outdir)


@pytest.mark.parametrize("vector_type", ["POINT", "VECTOR", "NORMAL"])
@pytest.mark.parametrize("convert_from", ["WORLD", "OBJECT", "CAMERA"])
@pytest.mark.parametrize("convert_to", ["WORLD", "OBJECT", "CAMERA"])
def test_vector_transform(vector_type, convert_from, convert_to, outdir):
    """Cycles' svm_node_vector_transform: points, directions and normals (transformed as
    directions, then normalised) between world, object and camera space, on a rotated, unevenly
    scaled sphere."""
    def build(nt, coords):
        vt = node(nt, "ShaderNodeVectorTransform", {"vector_type": vector_type, "convert_from": convert_from,
                                                    "convert_to": convert_to})
        nt.links.new(coords, vt.inputs["Vector"])
        return vt.outputs["Vector"]
    compare_view(build, "vector_transform_%s_%s_%s" % (vector_type, convert_from, convert_to), outdir,
                 shape="ellipsoid")


def _height_image(nt, coords):
    """A smooth height image (Non-Color, cubic: its slope is continuous) at Object coordinates."""
    tex = _image_node(nt, _smooth_image("height", 16, "Non-Color"), interpolation="Cubic")
    nt.links.new(coords, tex.inputs["Vector"])
    return tex


@pytest.mark.parametrize("source", ["height_object", "height_world", "vector_object", "vector_world",
                                    "vector_tangent", "vector_tangent_sphere"])
@pytest.mark.parametrize("shown", ["Normal", "Fresnel"])
def test_displacement_as_bump(source, shown, outdir):
    """The Material Output's Displacement (method Bump, Cycles 3.4's default): Cycles turns the
    displacement into a height along the normal (its dot with Geometry's Normal), bumps the normal
    from it with finite differences over the ray footprint (Distance 1) and sets that normal as the
    shading point's (SetNormal): Geometry's Normal and every default Normal input see it. Heights
    from an image through Displacement (object or world space) or Vector Displacement (tangent,
    object, world)."""
    def displacement(nt, coords):
        tex = _height_image(nt, coords)
        if source.startswith("height"):
            d = node(nt, "ShaderNodeDisplacement", {"space": source.split("_")[1].upper()}, Midlevel=0.5,
                     Scale=0.15)
            nt.links.new(tex.outputs["Color"], d.inputs["Height"])
        else:
            d = node(nt, "ShaderNodeVectorDisplacement", {"space": source.split("_")[1].upper()}, Midlevel=0.5,
                     Scale=0.15)
            nt.links.new(tex.outputs["Color"], d.inputs["Vector"])
        return d.outputs["Displacement"]

    def build(nt, coords):
        if shown == "Normal":
            return node(nt, "ShaderNodeNewGeometry").outputs["Normal"]
        return node(nt, "ShaderNodeFresnel", IOR=1.5).outputs["Fac"]
    # Tangent space on the plane from its UV map, on the sphere (no UV map) from Cycles' sphere-mapped
    # undeformed coordinates (test_tangent_space_without_uv_map). Object space differs from
    # world space on a scaled object (scaled evenly: on an unevenly scaled smooth mesh Lantern's
    # interpolated normal itself differs from Cycles', README).
    shape = "plane" if source == "vector_tangent" else "scaled" if "object" in source else "sphere"
    compare_view(build, "displacement_%s_%s" % (source, shown), outdir, shape=shape, displacement=displacement)


@pytest.mark.parametrize("case", ["normal_map", "tangent"])
def test_tangent_space_without_uv_map(case, outdir):
    """Tangent space on a mesh without any UV map (the sphere): Cycles 3.4 takes MikkTSpace's
    tangents over the vertices' undeformed coordinates mapped to a sphere (blender/mesh.cpp,
    mikk_get_texture_coordinate with map_to_sphere). Seen failing with the tangents left out
    (the Normal Map flat, the Tangent node zero)."""
    def build(nt, coords):
        if case == "tangent":
            return node(nt, "ShaderNodeTangent", {"direction_type": "UV_MAP"}).outputs["Tangent"]
        n = node(nt, "ShaderNodeNormalMap", {"space": "TANGENT"}, Strength=1.0, Color=(0.75, 0.3, 0.85))
        return n.outputs["Normal"]
    compare_view(build, "no_uv_%s" % case, outdir, shape="sphere")


def test_tangent_space_of_a_missing_uv_map_warns():
    """A Normal Map naming a UV map the mesh lacks: no tangents (as Cycles, which finds no
    attribute); the export names the object, the map and what Lantern does instead."""
    import build_scenes as bs
    from node_cases import view_scene

    def normal(nt, coords):
        return node(nt, "ShaderNodeNormalMap", {"space": "TANGENT", "uv_map": "Missing"}).outputs["Normal"]
    scene = view_scene(normal, shape="sphere")
    reports = ru.export(scene)[1]
    assert any("'sphere'" in r and "no UV map 'Missing'" in r and "Vector Displacement" in r for r in reports), \
        reports
    bs.reset_file()


def _write_png(path, pixels, bits):
    """A PNG of `pixels` (h, w, channels in 0..1, rows bottom first as Blender's) at 8 or 16 bits."""
    import numpy as np
    q = np.round(np.clip(pixels[::-1], 0, 1) * (2 ** bits - 1)).astype(np.uint16 if bits == 16 else np.uint8)
    ru.write_png_values(path, q)


def _write_exr(path, pixels, half):
    """An OpenEXR file of float RGB(A) `pixels`, written by Blender."""
    import bpy
    import numpy as np
    h, w, c = pixels.shape
    img = bpy.data.images.new("exr_writer", w, h, alpha=c == 4, float_buffer=True)
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :c] = pixels
    img.pixels.foreach_set(rgba.ravel())
    # The scene's output settings choose the depth (EXR is written linear, as the pixels are).
    settings = bpy.context.scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "16" if half else "32"
    settings.color_mode = "RGBA" if c == 4 else "RGB"
    img.save_render(path, scene=bpy.context.scene)
    bpy.data.images.remove(img)


# Blender's file formats and colour modes by file kind and channel count.
_BLENDER_FORMATS = {"jpg": "JPEG", "tif": "TIFF", "tga": "TARGA", "tga_raw": "TARGA_RAW", "tga_top": "TARGA_RAW",
                    "hdr": "HDR"}
_COLOR_MODES = {1: "BW", 3: "RGB", 4: "RGBA"}


def _write_blender(path, pixels, kind, bits):
    """A file of `pixels` (h, w, channels 1, 3 or 4 in 0..1, rows bottom first) written by Blender
    in the format of `kind` at `bits` per channel (8-bit files from a byte image)."""
    import bpy
    import numpy as np
    h, w, c = pixels.shape
    img = bpy.data.images.new("file_writer", w, h, alpha=c == 4, float_buffer=bits > 8)
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :3] = pixels[..., :3] if c >= 3 else pixels[..., :1]
    if c == 4:
        rgba[..., 3] = pixels[..., 3]
    img.pixels.foreach_set(rgba.ravel())
    settings = bpy.context.scene.render.image_settings
    settings.file_format = _BLENDER_FORMATS[kind]
    settings.color_mode = _COLOR_MODES[c]
    if kind == "tif":
        settings.color_depth = str(bits)
    if kind == "jpg":
        settings.quality = 90
    img.save_render(path, scene=bpy.context.scene)
    bpy.data.images.remove(img)
    if kind == "tga_top":
        # The same pixels stored top row first (descriptor bit 5), as most other programs write TGA.
        with open(path, "rb") as f:
            tga = bytearray(f.read())
        start, row = 18 + tga[0], w * tga[16] // 8
        rows = [tga[start + y * row:start + (y + 1) * row] for y in range(h)]
        tga[start:start + h * row] = b"".join(reversed(rows))
        tga[17] |= 0x20
        with open(path, "wb") as f:
            f.write(tga)


def _write_pil(path, pixels, kind):
    """Files Blender does not write, by Pillow (Blender's Python has it): a CMYK JPEG ("jpg_cmyk",
    the colours' complements as C, M, Y, their mean as K) and 16-colour palette TIFF and TGA files
    (rows bottom first)."""
    import numpy as np
    from PIL import Image
    rgb = np.round(pixels[::-1, :, :3] * 255).astype(np.uint8)
    if kind == "jpg_cmyk":
        cmyk = np.concatenate([255 - rgb, rgb.mean(axis=-1, keepdims=True).astype(np.uint8)], axis=-1)
        Image.fromarray(cmyk, "CMYK").save(path, quality=95)
    else:
        Image.fromarray(rgb, "RGB").quantize(16).save(path)


def _write_tiff(path, pixels, bits=32, layout="strip"):
    """An uncompressed TIFF of `pixels` (h, w, channels 1, 3 or 4 in 0..1, rows bottom first, alpha
    unassociated) written by hand, for what Blender 3.4 does not write: 32-bit float (bits 32), and
    8-bit files in 16 x 16 tiles (layout "tiled") or with separate planes (layout "planar")."""
    import struct
    import numpy as np
    h, w, c = pixels.shape
    top = np.ascontiguousarray(pixels[::-1])
    if bits == 32:
        top = top.astype("<f4")
    else:
        top = np.round(top * 255).astype(np.uint8)
    if layout == "tiled":
        t = 16
        th, tw = -(-h // t), -(-w // t)
        padded = np.zeros((th * t, tw * t, c), top.dtype)
        padded[:h, :w] = top
        chunks = [padded[y * t:(y + 1) * t, x * t:(x + 1) * t].tobytes() for y in range(th) for x in range(tw)]
        where = [(322, 3, [t]), (323, 3, [t]), (324, 4, None), (325, 4, [len(b) for b in chunks])]
    elif layout == "planar":
        chunks = [np.ascontiguousarray(top[..., k]).tobytes() for k in range(c)]
        where = [(273, 4, None), (278, 4, [h]), (279, 4, [len(b) for b in chunks])]
    else:
        chunks = [top.tobytes()]
        where = [(273, 4, None), (278, 4, [h]), (279, 4, [len(chunks[0])])]
    offsets = [8 + sum(len(b) for b in chunks[:i]) for i in range(len(chunks))]
    where = [(tag, kind, offsets if values is None else values) for tag, kind, values in where]
    tags = [(256, 4, [w]), (257, 4, [h]), (258, 3, [bits] * c), (259, 3, [1]), (262, 3, [1 if c == 1 else 2]),
            (277, 3, [c]), (284, 3, [2 if layout == "planar" else 1]), (339, 3, [3 if bits == 32 else 1] * c)]
    tags += where
    if c == 4:
        tags.append((338, 3, [2]))
    tags.sort()
    data = b"".join(chunks)
    ifd = 8 + len(data)
    extra = ifd + 2 + 12 * len(tags) + 4  # where values longer than 4 bytes go
    entries, blobs = b"", b""
    for tag, kind, values in tags:
        packed = struct.pack("<%d%s" % (len(values), "I" if kind == 4 else "H"), *values)
        if len(packed) <= 4:
            entries += struct.pack("<HHI", tag, kind, len(values)) + packed.ljust(4, b"\0")
        else:
            entries += struct.pack("<HHII", tag, kind, len(values), extra + len(blobs))
            blobs += packed
    with open(path, "wb") as f:
        f.write(b"II*\0" + struct.pack("<I", ifd) + data + struct.pack("<H", len(tags)) + entries
                + b"\0\0\0\0" + blobs)


# name: (file, channels, bits, colour space, alpha mode, whether the core reads the file itself)
IMAGE_FILES = {
    "png8_srgb_rgb": ("png", 3, 8, "sRGB", "STRAIGHT", True),
    "png8_srgb_rgba": ("png", 4, 8, "sRGB", "STRAIGHT", True),
    "png8_grey": ("png", 1, 8, "sRGB", "STRAIGHT", True),
    "png8_grey_alpha": ("png", 2, 8, "sRGB", "STRAIGHT", True),
    "png8_non_color_rgba": ("png", 4, 8, "Non-Color", "STRAIGHT", True),
    "png8_linear_rgba": ("png", 4, 8, "Linear", "STRAIGHT", True),
    "png8_channel_packed": ("png", 4, 8, "sRGB", "CHANNEL_PACKED", True),
    "png8_alpha_none": ("png", 4, 8, "sRGB", "NONE", True),
    # Blender unpremultiplies 8-bit buffers in Premultiplied mode (imb_handle_alpha): so does the core.
    "png8_premultiplied": ("png", 4, 8, "sRGB", "PREMUL", True),
    "png8_grey_alpha_premultiplied": ("png", 2, 8, "sRGB", "PREMUL", True),
    "png16_linear_rgba": ("png", 4, 16, "Linear", "STRAIGHT", True),
    "png16_non_color_rgba": ("png", 4, 16, "Non-Color", "STRAIGHT", True),
    "png16_linear_grey": ("png", 1, 16, "Linear", "STRAIGHT", True),
    # Blender converts float buffers from sRGB with its OpenColorIO configuration: left to Blender.
    "png16_srgb_rgba": ("png", 4, 16, "sRGB", "STRAIGHT", False),
    "exr32_rgba": ("exr", 4, 32, "Linear", "PREMUL", True),
    "exr32_rgba_straight": ("exr", 4, 32, "Linear", "STRAIGHT", True),
    "exr32_rgb": ("exr", 3, 32, "Linear", "PREMUL", True),
    "exr16_rgba": ("exr", 4, 16, "Linear", "PREMUL", True),
    "exr16_rgba_straight": ("exr", 4, 16, "Linear", "STRAIGHT", True),
    "exr16_rgb": ("exr", 3, 16, "Linear", "PREMUL", True),
    "exr32_non_color": ("exr", 4, 32, "Non-Color", "STRAIGHT", True),
    # JPEG (4:2:0, OpenImageIO decodes as Blender's jpeg.c: same libjpeg-turbo, same settings).
    "jpeg_srgb": ("jpg", 3, 8, "sRGB", "STRAIGHT", True),
    "jpeg_grey_non_color": ("jpg", 1, 8, "Non-Color", "STRAIGHT", True),
    "tiff8_srgb_rgba": ("tif", 4, 8, "sRGB", "STRAIGHT", True),
    "tiff8_grey": ("tif", 1, 8, "sRGB", "STRAIGHT", True),
    "tiff8_channel_packed": ("tif", 4, 8, "sRGB", "CHANNEL_PACKED", True),
    "tiff8_premultiplied": ("tif", 4, 8, "sRGB", "PREMUL", True),
    # 8-bit tiles and separate planes (Blender's TIFFReadRGBAImage reads any layout); Blender 3.4
    # loads no pixels from a tiled grey or RGB TIFF, which the core leaves to it.
    "tiff8_tiled_rgba": ("tif_tiled", 4, 8, "sRGB", "STRAIGHT", True),
    "tiff8_planar_rgb": ("tif_planar", 3, 8, "sRGB", "STRAIGHT", True),
    "tiff8_planar_rgba": ("tif_planar", 4, 8, "sRGB", "PREMUL", True),
    # Left to Blender: OpenImageIO 2.4 rounds where Blender's jpeg.c truncates (c k / 255) and has
    # no raw CMYK read; expands a TIFF palette by / 257 where libtiff takes the high byte; Blender's
    # targa.c gives colour-mapped texels an alpha of its own (0 for some).
    "jpeg_cmyk": ("jpg_cmyk", 3, 8, "sRGB", "STRAIGHT", False),
    "tiff8_palette": ("tif_palette", 3, 8, "sRGB", "STRAIGHT", False),
    "tga_colour_mapped": ("tga_palette", 3, 8, "sRGB", "STRAIGHT", False),
    "tiff16_linear_rgba": ("tif", 4, 16, "Linear", "STRAIGHT", True),
    "tiff16_non_color_grey": ("tif", 1, 16, "Non-Color", "STRAIGHT", True),
    "tiff16_srgb_rgb": ("tif", 3, 16, "sRGB", "STRAIGHT", False),
    "tiff32_linear_rgba": ("tif", 4, 32, "Linear", "STRAIGHT", True),
    "tiff32_linear_rgb": ("tif", 3, 32, "Linear", "PREMUL", True),
    "tiff32_non_color_grey": ("tif", 1, 32, "Non-Color", "STRAIGHT", True),
    "tga_srgb_rgba": ("tga", 4, 8, "sRGB", "STRAIGHT", True),
    "tga_raw_rgb": ("tga_raw", 3, 8, "sRGB", "STRAIGHT", True),
    "tga_grey_non_color": ("tga", 1, 8, "Non-Color", "STRAIGHT", True),
    "tga_alpha_none": ("tga_raw", 4, 8, "sRGB", "NONE", True),
    "tga_top_left": ("tga_top", 4, 8, "sRGB", "STRAIGHT", True),
    # Radiance RGBE: Blender's (m + 0.5) 2^(e - 136), a float image.
    "hdr_linear": ("hdr", 3, 32, "Linear", "STRAIGHT", True),
    "hdr_srgb": ("hdr", 3, 32, "sRGB", "STRAIGHT", False),
}


# What the core keeps of some of them, bytes per texel (the file's precision, no alpha plane).
IMAGE_FILE_BYTES = {"png8_srgb_rgb": 3, "png8_grey": 1, "png16_linear_grey": 4, "exr32_rgb": 12, "exr16_rgb": 6,
                    "jpeg_srgb": 3, "jpeg_grey_non_color": 1, "tiff8_grey": 1, "tiff16_non_color_grey": 4,
                    "tga_raw_rgb": 3, "hdr_linear": 12, "tiff32_linear_rgb": 12,
                    "tiff32_non_color_grey": 4}


@pytest.mark.parametrize("output", ["Color", "Color with Alpha used", "Alpha"])
@pytest.mark.parametrize("case", sorted(IMAGE_FILES))
def test_image_file_read_by_the_core_equals_blenders_pixels(case, output, tmp_path):
    """Images read by the core from their files (so that Blender never loads them) give exactly
    the texels Blender's Image.pixels gives: the same view rendered with the image from its file
    and with a packed copy of the same file (which goes through Image.pixels) is the same image,
    pixel for pixel (each render pixel a bilinear mix of texels, so that every texel counts).
    PNG files are written here, OpenEXR, JPEG, TIFF (8 and 16 bits), TGA and HDR ones by Blender,
    32-bit float TIFFs by hand (Blender 3.4 writes none); the cases the core leaves to Blender
    check that it does."""
    _file_against_packed(case, output, tmp_path)


# Cubic (and Smart, which is Cubic on Cycles' CPU) on the core's 8-bit, half and float storage,
# each with an extension: (case, interpolation, extension, output).
CUBIC_FILE_CASES = [("png8_srgb_rgba", "Cubic", "REPEAT", "Color with Alpha used"),
                    ("exr16_rgba", "Cubic", "EXTEND", "Color with Alpha used"),
                    ("exr32_rgb", "Smart", "CLIP", "Color"),
                    ("png16_linear_grey", "Smart", "EXTEND", "Color"),
                    ("hdr_linear", "Smart", "environment", "Color")]  # an Environment Texture


@pytest.mark.parametrize("case,interpolation,extension,output", CUBIC_FILE_CASES)
def test_image_file_cubic_read_by_the_core_equals_blenders_pixels(case, interpolation, extension, output,
                                                                  tmp_path):
    """Cubic and Smart image textures read from their files by the core (no longer through
    Image.pixels) filter the stored bytes, halves or floats as they filter Blender's pixels: the
    view magnified (about 2.4 pixels a texel, so that the B-spline's 4 x 4 texels show) and
    widened past the image's edges (so that the extension shows), equal to the packed copy's
    render within 1e-6. That cubic filter is Cycles' (test_image_interpolation_and_extension)."""
    _file_against_packed(case, output, tmp_path, interpolation, extension, zoom=1.3)


def _file_against_packed(case, output, tmp_path, interpolation="Linear", extension="REPEAT", zoom=1.0):
    """The view of one IMAGE_FILES case read from its file and from a packed copy: equal within
    1e-6, read by the core or left to Blender as the case says. zoom: UVs scaled about the centre;
    extension "environment": an Environment Texture instead of an Image Texture."""
    import bpy
    import numpy as np

    import build_scenes as bs
    from node_cases import view_scene
    from lantern import engine
    kind, channels, bits, space, alpha_mode, by_core = IMAGE_FILES[case]
    rng = np.random.default_rng(7)
    pixels = rng.random((24, 32, channels))
    if channels in (2, 4):
        pixels[..., -1] = np.where(rng.random((24, 32)) < 0.2, rng.choice([0.0, 1.0], (24, 32)), pixels[..., -1])
    if kind in ("exr", "hdr") or bits == 32:
        pixels[..., :3] *= 4.0  # beyond 1
    path = str(tmp_path / ("%s.%s" % (case, kind.split("_")[0])))
    if kind == "png":
        _write_png(path, pixels, bits)
    elif kind == "exr":
        _write_exr(path, pixels.astype(np.float32), bits == 16)
    elif kind == "tif" and bits == 32:
        _write_tiff(path, pixels)
    elif kind in ("tif_tiled", "tif_planar"):
        _write_tiff(path, pixels, bits, kind.split("_")[1])
    elif kind in ("jpg_cmyk", "tif_palette", "tga_palette"):
        _write_pil(path, pixels, kind)
    else:
        _write_blender(path, pixels, kind, bits)

    loaded = []

    def render(packed):
        def build(nt, coords):
            img = bpy.data.images.load(path)
            loaded.append(img)
            img.colorspace_settings.name = space
            img.alpha_mode = alpha_mode
            if packed:
                img.pack()
            if extension == "environment":  # the Generated coordinates' directions
                tex = node(nt, "ShaderNodeTexEnvironment", {"interpolation": interpolation})
                tex.image = img
                nt.links.new(node(nt, "ShaderNodeTexCoord").outputs["Generated"], tex.inputs["Vector"])
                return tex.outputs["Color"]
            tex = node(nt, "ShaderNodeTexImage", {"interpolation": interpolation, "extension": extension})
            tex.image = img
            uv = node(nt, "ShaderNodeTexCoord").outputs["UV"]
            if zoom != 1.0:
                mapping = node(nt, "ShaderNodeMapping", {"vector_type": "POINT"})
                mapping.inputs["Scale"].default_value = (zoom, zoom, 1.0)
                mapping.inputs["Location"].default_value = (0.5 - 0.5 * zoom, 0.5 - 0.5 * zoom, 0.0)
                nt.links.new(uv, mapping.inputs["Vector"])
                uv = mapping.outputs[0]
            nt.links.new(uv, tex.inputs["Vector"])
            if output == "Color with Alpha used":
                mix = node(nt, "ShaderNodeMixRGB", {"blend_type": "ADD"})
                nt.links.new(tex.outputs["Alpha"], mix.inputs["Fac"])
                nt.links.new(tex.outputs["Color"], mix.inputs["Color1"])
                mix.inputs["Color2"].default_value = (0, 0, 0, 1)
                return mix.outputs[0]
            return tex.outputs["Alpha" if output == "Alpha" else "Color"]
        scene = view_scene(build)
        scene.render.resolution_x = scene.render.resolution_y = 100
        obj = scene.objects["plane"]
        obj.rotation_euler = (0, 0, 0)
        flat = bs.mesh_plane("flat", 0.55)  # the image fills the view
        flat.materials.append(obj.data.materials[0])
        obj.data = flat
        img = ru.render(scene, ru.LANTERN, samples=1, seed=3).combined
        line = [l for l in engine.LAST_RENDER["report"].splitlines() if l.startswith("texture memory:")]
        return img, line

    from_file, line = render(packed=False)
    expect = "1 read from their files" if by_core else "0 read from their files"
    assert line and expect in line[0], (case, line)
    if case in IMAGE_FILE_BYTES:
        assert "(%.2f bytes per texel)" % IMAGE_FILE_BYTES[case] in line[0], (case, line)
    # Blender never loaded the pixels of an image the core read.
    assert loaded[-1].has_data != by_core, (case, loaded[-1].has_data)
    through_blender, line = render(packed=True)
    assert line and "0 read from their files" in line[0], (case, line)
    assert float(np.ptp(from_file[..., :3])) > 1e-3, "%s: the view shows no pattern" % case
    diff = float(np.abs(from_file - through_blender).max())
    assert diff <= 1e-6, "%s %s: the core's texels differ from Blender's by up to %g" % (case, output, diff)


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


def _ao_material(name, color=(1.0, 1.0, 1.0), distance=1.0, samples=4, inside=False, only_local=False,
                 output="AO"):
    mat = bpy_material(name)
    nt = mat.node_tree
    nt.nodes.clear()
    ao = node(nt, "ShaderNodeAmbientOcclusion", {"samples": samples, "inside": inside, "only_local": only_local},
              Color=color, Distance=distance)
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(ao.outputs[output], em.inputs["Color"])
    nt.links.new(em.outputs[0], nt.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    return mat


def test_ambient_occlusion_agrees_with_cycles(outdir):
    """Ambient Occlusion's rays, seen through emission by camera rays (the agreement rule of
    test_agreement.py, two seeds each): a floor under a box and a sphere (Color output, tinted), the
    box with Inside and Distance 0 (the World's AO distance, 0.4 here), the sphere with Only Local
    (the floor does not darken it)."""
    bs.reset_file()
    scene = bs.new_scene("ao_node", resolution=(64, 48), samples=64)
    scene.cycles.max_bounces = 0
    bs.set_world(scene, (0.0, 0.0, 0.0), 1.0)
    scene.world.light_settings.distance = 0.4
    bs.assign(bs.add_object(scene, "Floor", bs.mesh_plane("Floor", 6.0)),
              _ao_material("AOFloor", color=(1.0, 0.5, 0.25), distance=0.8, output="Color"))
    bs.assign(bs.add_object(scene, "Box", bs.mesh_box("Box", (0.8, 0.8, 0.8)), (-0.7, 0.2, 0.0)),
              _ao_material("AOInside", distance=0.0, inside=True))
    bs.assign(bs.add_object(scene, "Ball", bs.mesh_sphere("Ball", 0.45), (0.6, 0.0, 0.45)),
              _ao_material("AOLocal", distance=1.0, only_local=True, samples=8))
    bs.add_camera(scene, (0.0, -3.6, 2.0), (0.0, 0.0, 0.3), lens=35.0)
    report, _ = ru.two_seed_agreement(scene, 64, "PATH", "ao_node", outdir)
    assert report == "", report


def _bevel_material(name, radius, samples=8, emit=False, normal_from=None):
    """Bevel's Normal as a colour (n / 2 + 1/2) on an Emission (emit), else into a Diffuse's Normal;
    normal_from: a Geometry output linked to the Bevel's Normal input."""
    mat = bpy_material(name)
    nt = mat.node_tree
    nt.nodes.clear()
    bevel = node(nt, "ShaderNodeBevel", {"samples": samples}, Radius=radius)
    if normal_from:
        nt.links.new(node(nt, "ShaderNodeNewGeometry").outputs[normal_from], bevel.inputs["Normal"])
    if emit:
        half = node(nt, "ShaderNodeVectorMath", {"operation": "MULTIPLY_ADD"})
        half.inputs[1].default_value = (0.5, 0.5, 0.5)
        half.inputs[2].default_value = (0.5, 0.5, 0.5)
        nt.links.new(bevel.outputs["Normal"], half.inputs[0])
        shader = nt.nodes.new("ShaderNodeEmission")
        nt.links.new(half.outputs[0], shader.inputs["Color"])
    else:
        shader = node(nt, "ShaderNodeBsdfDiffuse", Color=(0.8, 0.8, 0.8, 1.0))
        nt.links.new(bevel.outputs["Normal"], shader.inputs["Normal"])
    nt.links.new(shader.outputs[0], nt.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    return mat


def _bevel_scene(name, emit):
    """A flat-shaded box turned towards the camera and a flat-shaded, coarse sphere (its facets'
    edges rounded too), with Bevel; the sphere's keeps a linked Normal (Geometry's True Normal)."""
    bs.reset_file()
    scene = bs.new_scene(name, resolution=(64, 48), samples=64)
    bs.assign(bs.add_object(scene, "Box", bs.mesh_box("Box", (1.0, 1.0, 1.0)), (-0.55, 0.3, 0.0), (0, 0, 35)),
              _bevel_material("BevelBox", 0.25, emit=emit))
    bs.assign(bs.add_object(scene, "Ball", bs.mesh_sphere("Ball", 0.45, 12, 6, smooth=False), (0.7, -0.1, 0.55)),
              _bevel_material("BevelBall", 0.1, samples=4, emit=emit, normal_from="True Normal"))
    bs.add_camera(scene, (0.0, -3.6, 2.2), (0.0, 0.0, 0.4), lens=40.0)
    return scene


@pytest.mark.parametrize("integrator", ["PATH", "BIDIRECTIONAL"])
def test_bevel_normal_agrees_with_cycles(integrator, outdir):
    """Bevel's Normal output seen through emission: rounded edges on a box and on a faceted sphere
    (a linked Normal keeps the bevel's change) where camera rays see them; on a diffuse floor, the
    light they emit as a diffuse bounce and light samples see it, unbevelled (Cycles' min_ray_pdf,
    and its light evaluations without ray tracing; BIDIRECTIONAL's light subpaths start there).
    Random per sample: the agreement rule of test_agreement.py, two seeds each."""
    scene = _bevel_scene("bevel_normal", emit=True)
    scene.cycles.max_bounces = 1
    bs.set_world(scene, (0.0, 0.0, 0.0), 1.0)
    bs.assign(bs.add_object(scene, "Floor", bs.mesh_plane("Floor", 8.0)), bs.diffuse("Floor", (0.8, 0.8, 0.8)))
    report, _ = ru.two_seed_agreement(scene, 64, integrator, "bevel_normal_" + integrator.lower(), outdir)
    assert report == "", report


def test_bevel_lit_agrees_with_cycles(outdir):
    """A bevelled box and sphere (Diffuse with Bevel's normal) on a mirror floor under an area
    light and a dim world: bevelled where the camera sees them and in the mirror (a sharp bounce
    keeps Cycles' min_ray_pdf), not where diffuse light reaches them (Cycles' blurry paths). PATH
    only: BIDIRECTIONAL departs (README)."""
    scene = _bevel_scene("bevel_lit", emit=False)
    bs.set_world(scene, (0.2, 0.2, 0.25), 1.0)
    scene.cycles.max_bounces = 4
    floor = bs.add_object(scene, "Floor", bs.mesh_plane("Floor", 8.0))
    mirror = bpy_material("Mirror")
    nt = mirror.node_tree
    nt.nodes.clear()
    glossy = node(nt, "ShaderNodeBsdfGlossy", {"distribution": "SHARP"}, Color=(0.7, 0.7, 0.7, 1.0))
    nt.links.new(glossy.outputs[0], nt.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    bs.assign(floor, mirror)
    bs.add_light(scene, "Key", "AREA", 150.0, (-1.5, -1.5, 2.5), (40, 0, -35), size=1.0)
    report, _ = ru.two_seed_agreement(scene, 128, "PATH", "bevel_lit", outdir)
    assert report == "", report


@pytest.mark.parametrize("output", ["Color", "Alpha"])
def test_shader_to_rgb_as_cycles(output, outdir):
    """Shader to RGB (an EEVEE node) fed by a Diffuse BSDF: Cycles 3.4 drops its links, and the
    sockets it feeds keep their own values (a Mix's second colour, a Math node's second value) over a
    pattern from the object's X; so does Lantern, with a warning."""
    def build(nt, coords):
        s2r = node(nt, "ShaderNodeShaderToRGB")
        nt.links.new(node(nt, "ShaderNodeBsdfDiffuse", Color=(0.9, 0.1, 0.1)).outputs[0], s2r.inputs["Shader"])
        uv = node(nt, "ShaderNodeSeparateXYZ")
        nt.links.new(coords, uv.inputs[0])
        if output == "Color":
            mix = node(nt, "ShaderNodeMixRGB", Color1=(0.1, 0.2, 0.9), Color2=(0.2, 0.7, 0.3))
            nt.links.new(uv.outputs["X"], mix.inputs["Fac"])
            nt.links.new(s2r.outputs["Color"], mix.inputs["Color2"])
            return mix.outputs[0]
        add = node(nt, "ShaderNodeMath", {"operation": "ADD"})
        add.inputs[1].default_value = 0.3
        nt.links.new(uv.outputs["X"], add.inputs[0])
        nt.links.new(s2r.outputs["Alpha"], add.inputs[1])
        return add.outputs[0]
    compare_view(build, "shader_to_rgb_" + output.lower(), outdir)


@pytest.mark.parametrize("space", ["Filmic Log", "Filmic sRGB", "Linear ACES", "Linear ACEScg", "XYZ"])
@pytest.mark.parametrize("channels,packed", [(3, False), (1, False), (3, True), (4, True)])
def test_image_colour_space_as_cycles(space, channels, packed, tmp_path, outdir):
    """An 8-bit PNG (RGB, grey or RGBA, every byte value present) in each of Blender 3.4's other
    input colour spaces: converted to scene linear with OpenColorIO as Cycles converts it (half
    floats; RGBA associated, divided by alpha around the conversion), pixel by pixel against Cycles
    (Closest texels, 6 pixels each). The file the core reads itself, or the image packed into the
    .blend, whose byte values come from Blender (Image.pixels) and which the core converts."""
    import bpy
    import numpy as np

    rng = np.random.default_rng(11)
    values = np.concatenate([np.arange(256), rng.integers(0, 256, 16 * 16 * channels - 256)]) / 255.0
    path = str(tmp_path / "texels.png")
    _write_png(path, rng.permutation(values).reshape(16, 16, channels), 8)

    def build(nt, coords):
        img = bpy.data.images.load(path)
        if packed:
            img.pack()
        img.colorspace_settings.name = space
        tex = _image_node(nt, img, interpolation="Closest", extension="EXTEND")
        shift = node(nt, "ShaderNodeVectorMath", {"operation": "MULTIPLY_ADD"})
        nt.links.new(coords, shift.inputs[0])
        shift.inputs[1].default_value = (1.0, 1.0, 1.0)
        shift.inputs[2].default_value = (0.5, 0.5, 0.5)
        nt.links.new(shift.outputs[0], tex.inputs["Vector"])
        return tex.outputs["Color"]
    compare_view(build, "image_space_%s_%d%s" % (space.replace(" ", "_"), channels, "_packed" * packed), outdir)
