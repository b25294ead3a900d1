"""Builds Lantern's test scenes (with bpy only, no external files) and examples.blend.

    blender -b --factory-startup --python scenes/build_scenes.py -- OUTDIR [--only a,b]
    blender -b --factory-startup --python scenes/build_scenes.py -- --examples [PATH]

The first form writes OUTDIR/<name>.blend for every test scene, each holding one Scene named after
itself. The second writes examples.blend (default: the repository root) with one scene per example;
its scenes get Lantern as render engine, with their integrator and samples, only when the add-on is
registered, so write it with the checkout's add-on:

    LANTERN_LIBRARY=$PWD/build/liblantern.so blender -b --factory-startup --python-expr \
      "import sys; sys.path.insert(0, 'addon'); import lantern; lantern.register()" \
      --python scenes/build_scenes.py -- --examples

Both can be given together. Besides the test scenes' builders, the examples use the models in
models/ (MODEL_SCENES: the Sibenik cathedral and Sponza), imported with Blender's OBJ importer.

Every scene is made by one builder function, `build_<name>(scene)`, which fills a Scene made by
`new_scene()`; tests (tests/blender/conftest.py) call `build(name)` in-process, the examples reuse
the same builders at a nicer resolution. Scenes are set up for Cycles on the CPU with a fixed seed,
no adaptive sampling, no denoising, no clamping and no glossy filter, so that Cycles renders the
unbiased image the agreement tests compare Lantern with. Every object's and light's ray visibility
is set explicitly: objects visible to every ray, lights not visible to the camera.
"""
import math
import os
import sys
import tempfile

import bmesh
import bpy
import numpy as np
from mathutils import Matrix, Vector

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLES_PATH = os.path.join(REPO, "examples.blend")

# Cornell box colours (reflectances of the classic measured box, rounded).
RED = (0.63, 0.065, 0.05)
GREEN = (0.14, 0.45, 0.091)
WHITE = (0.725, 0.71, 0.68)


# ----------------------------------------------------------------------------------------------
# Scene, world, camera
# ----------------------------------------------------------------------------------------------
def new_scene(name, resolution=(96, 96), samples=128):
    """An empty Scene called `name` (replacing one of that name) set up for a Cycles CPU render."""
    old = bpy.data.scenes.get(name)
    if old is not None:
        bpy.data.scenes.remove(old)
    scene = bpy.data.scenes.new(name)
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y = resolution
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    r.use_motion_blur = False
    r.film_transparent = False
    r.threads_mode = "AUTO"
    c = scene.cycles
    c.device = "CPU"
    c.feature_set = "SUPPORTED"
    c.samples = samples
    c.seed = 0
    c.use_animated_seed = False
    c.sample_offset = 0
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.use_guiding = False
    c.blur_glossy = 0.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.max_bounces = 12
    c.diffuse_bounces = 4
    c.glossy_bounces = 4
    c.transmission_bounces = 12
    c.transparent_max_bounces = 8
    c.volume_bounces = 0
    c.pixel_filter_type = "BLACKMAN_HARRIS"
    c.filter_width = 1.5
    c.film_exposure = 1.0
    v = scene.view_settings
    scene.display_settings.display_device = "sRGB"
    v.view_transform = "Standard"
    v.look = "None"
    v.exposure = 0.0
    v.gamma = 1.0
    set_world(scene, (0.0, 0.0, 0.0), 0.0)
    return scene


def set_world(scene, color, strength):
    """A World called after the scene with a constant Background colour x strength."""
    world = bpy.data.worlds.new(scene.name)
    world.use_nodes = True
    nt = world.node_tree
    nt.nodes.clear()
    bg = nt.nodes.new("ShaderNodeBackground")
    bg.inputs["Color"].default_value = (*color, 1.0)
    bg.inputs["Strength"].default_value = strength
    out = nt.nodes.new("ShaderNodeOutputWorld")
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    world.cycles_visibility.camera = True
    scene.world = world
    return world


def look_at(obj, target, up_axis="Y"):
    d = Vector(target) - obj.location
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = d.to_track_quat("-Z", up_axis)


def add_camera(scene, location, target, lens=50.0, name="Camera"):
    cam = bpy.data.cameras.new(name)
    cam.type = "PERSP"
    cam.lens_unit = "MILLIMETERS"
    cam.lens = lens
    cam.sensor_fit = "AUTO"
    cam.sensor_width = 36.0
    cam.sensor_height = 24.0
    cam.shift_x = cam.shift_y = 0.0
    cam.clip_start = 0.05
    cam.clip_end = 1000.0
    cam.dof.use_dof = False
    obj = bpy.data.objects.new(name, cam)
    obj.location = location
    scene.collection.objects.link(obj)
    look_at(obj, target)
    scene.camera = obj
    return obj


# ----------------------------------------------------------------------------------------------
# Objects and lights
# ----------------------------------------------------------------------------------------------
def set_visibility(obj, camera=True, diffuse=True, glossy=True, transmission=True, shadow=True,
                   volume_scatter=True):
    obj.hide_render = False
    obj.hide_viewport = False
    obj.visible_camera = camera
    obj.visible_diffuse = diffuse
    obj.visible_glossy = glossy
    obj.visible_transmission = transmission
    obj.visible_shadow = shadow
    obj.visible_volume_scatter = volume_scatter


def add_object(scene, name, data, location=(0, 0, 0), rotation=(0, 0, 0), scale=(1, 1, 1),
               collection=None, **visibility):
    """Links a new object to `collection` (default: the scene's master collection)."""
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    obj.rotation_mode = "XYZ"
    obj.rotation_euler = [math.radians(a) for a in rotation]
    obj.scale = scale
    (collection or scene.collection).objects.link(obj)
    set_visibility(obj, **visibility)
    return obj


def add_light(scene, name, kind, energy, location, rotation=(0, 0, 0), color=(1, 1, 1),
              camera=False, **props):
    """A light (rotation in degrees; lights point down their local -Z). Visible to every ray but
    the camera unless camera=True. props: radius (shadow_soft_size), spot_size (rad), spot_blend,
    shape, size, size_y, angle (rad)."""
    light = bpy.data.lights.new(name, kind)
    light.energy = energy
    light.color = color
    light.use_shadow = True
    light.shadow_soft_size = props.pop("radius", 0.0)
    light.cycles.cast_shadow = True
    light.cycles.use_multiple_importance_sampling = True
    light.cycles.max_bounces = 1024
    if kind == "AREA":
        light.cycles.is_portal = False
    for key, value in props.items():
        setattr(light, key, value)
    return add_object(scene, name, light, location, rotation, camera=camera)


def _mesh(name, bm):
    # Some bmesh primitives (create_uvsphere, welding its seam) order their faces as they lie in
    # memory, which differs from session to session: the same sphere then shades and renders
    # with other bits (Blender's normals are sums in face order; its triangles, the BVH). Faces
    # sorted by their vertices make every build of a scene the same mesh.
    bm.verts.index_update()
    bm.faces.index_update()
    order = sorted(bm.faces, key=lambda f: sorted(v.index for v in f.verts))
    rank = {f.index: k for k, f in enumerate(order)}
    bm.faces.sort(key=lambda f: rank[f.index])
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    return me


def _smooth(me, smooth):
    me.polygons.foreach_set("use_smooth", [smooth] * len(me.polygons))
    return me


def _bmesh_with_uvs():
    """A bmesh with a UV layer: bmesh's calc_uvs fills an existing layer and silently skips
    otherwise."""
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")
    return bm


def mesh_plane(name, size_x, size_y=None, matrix=None):
    """A quad in the XY plane centred at the origin, normal +Z, UVs 0..1."""
    bm = _bmesh_with_uvs()
    bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=0.5, calc_uvs=True,
                          matrix=Matrix.Diagonal((size_x, size_y or size_x, 1.0, 1.0)))
    if matrix is not None:
        bm.transform(matrix)
    return _smooth(_mesh(name, bm), False)


def mesh_box(name, size, origin_at_bottom=True):
    """An axis-aligned box of size (x, y, z) with UVs; origin at the bottom centre by default."""
    sx, sy, sz = size
    m = Matrix.Diagonal((sx, sy, sz, 1.0))
    if origin_at_bottom:
        m = Matrix.Translation((0, 0, sz / 2)) @ m
    bm = _bmesh_with_uvs()
    bmesh.ops.create_cube(bm, size=1.0, matrix=m, calc_uvs=True)
    return _smooth(_mesh(name, bm), False)


def mesh_sphere(name, radius, segments=48, rings=24, smooth=True):
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=radius,
                              calc_uvs=True)
    return _smooth(_mesh(name, bm), smooth)


def mesh_cone(name, radius, depth, segments=32):
    bm = bmesh.new()
    bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=segments,
                          radius1=radius, radius2=0.0, depth=depth, calc_uvs=True,
                          matrix=Matrix.Translation((0, 0, depth / 2)))
    return _smooth(_mesh(name, bm), False)


def assign(obj, *materials):
    """Puts the materials in the mesh's slots (shared by every object using the mesh)."""
    obj.data.materials.clear()
    for mat in materials:
        obj.data.materials.append(mat)
    return obj


# ----------------------------------------------------------------------------------------------
# Materials and images
# ----------------------------------------------------------------------------------------------
def _material(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "ALL"
    out.location = (300, 0)
    return mat, nt, out


def _bsdf_material(name, node_type, color, **inputs):
    mat, nt, out = _material(name)
    bsdf = nt.nodes.new(node_type)
    if color is not None:
        if isinstance(color, bpy.types.NodeSocket):
            nt.links.new(color, bsdf.inputs["Color"])
        else:
            bsdf.inputs["Color"].default_value = (*color, 1.0)
    for key, value in inputs.items():
        if key == "distribution":
            bsdf.distribution = value
        elif isinstance(value, bpy.types.Node):
            nt.links.new(value.outputs[0], bsdf.inputs[key])
        else:
            bsdf.inputs[key].default_value = value
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    mat.diffuse_color = (*color, 1.0) if isinstance(color, tuple) else (0.8, 0.8, 0.8, 1.0)
    return mat


def diffuse(name, color, roughness=0.0):
    return _bsdf_material(name, "ShaderNodeBsdfDiffuse", color, Roughness=roughness)


def glossy(name, color, roughness):
    return _bsdf_material(name, "ShaderNodeBsdfGlossy", color, distribution="GGX",
                          Roughness=roughness)


def glass(name, color, roughness, ior=1.5):
    return _bsdf_material(name, "ShaderNodeBsdfGlass", color, distribution="GGX",
                          Roughness=roughness, IOR=ior)


def image_material(name, image, shader="ShaderNodeBsdfDiffuse", target="Color", **inputs):
    """`shader` with the image (UV-mapped, linear interpolation, repeat) feeding `target`."""
    mat, nt, out = _material(name)
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = "Linear"
    tex.extension = "REPEAT"
    tex.projection = "FLAT"
    tex.location = (-300, 0)
    bsdf = nt.nodes.new(shader)
    if shader == "ShaderNodeBsdfGlossy":
        bsdf.distribution = "GGX"
    for key, value in inputs.items():
        bsdf.inputs[key].default_value = (*value, 1.0) if key == "Color" else value
    nt.links.new(tex.outputs["Color"], bsdf.inputs[target])
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return mat


def packed_image(name, pixels, colorspace):
    """An 8-bit image from float pixels (h, w, 4), rows bottom first, packed into the .blend."""
    h, w, _ = pixels.shape
    img = bpy.data.images.new(name, width=w, height=h, alpha=True, float_buffer=False)
    img.colorspace_settings.name = colorspace
    img.alpha_mode = "STRAIGHT"
    img.pixels.foreach_set(np.ascontiguousarray(pixels, np.float32).ravel())
    img.update()
    img.pack()
    return img


def leaf_pixels(size=64):
    """A leaf card's RGBA (straight alpha): an ellipse of alpha 1 fading to 0 over its rim, greens
    varying across it, and the colour outside it kept (as painted textures keep it)."""
    y, x = (np.mgrid[0:size, 0:size] + 0.5) / size * 2 - 1
    r = np.hypot(x / 0.55, y / 0.9)
    alpha = np.clip((1.0 - r) / 0.2, 0.0, 1.0)
    rgba = np.empty((size, size, 4))
    rgba[..., 0] = 0.15 + 0.25 * (x + 1) / 2
    rgba[..., 1] = 0.45 + 0.4 * (y + 1) / 2
    rgba[..., 2] = 0.1
    rgba[..., 3] = alpha
    return rgba


def leaf_card(name, image):
    """Principled BSDF with Base Color and Alpha from an image texture, as a leaf card is built."""
    mat, nt, out = _material(name)
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    nt.links.new(tex.outputs["Alpha"], bsdf.inputs["Alpha"])
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    mat.blend_method = "HASHED"
    return mat


def build_leaf_cards(scene):
    """Issue 13's alpha-mapped leaf card: three cards of an RGBA image (Principled Alpha from the
    image's alpha) standing on a ground under a low sun and a sky; their shadows fall through the
    transparent parts."""
    set_world(scene, (0.3, 0.45, 0.7), 0.6)
    ground = add_object(scene, "Ground", mesh_plane("Ground", 20.0))
    assign(ground, principled("Ground", (0.6, 0.55, 0.45), 0.9))
    mat = leaf_card("Leaf", packed_image("LeafImage", leaf_pixels(), "sRGB"))
    for i, (x, rot) in enumerate(((-0.7, 20), (0.0, -10), (0.7, 35))):
        card = add_object(scene, "Leaf%d" % i, mesh_plane("Leaf%d" % i, 0.9), (x, 0.2 * i, 0.55),
                          (90, 0, rot))
        assign(card, mat)
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(60, 0, -30), angle=math.radians(1.0))
    add_camera(scene, (0.4, -3.5, 1.3), (0, 0.2, 0.4), lens=40.0)


def _mix_with(name, node_type, fac, color):
    """Mix Shader of a Diffuse BSDF (fac 0) and a `node_type` shader (fac 1)."""
    mat, nt, out = _material(name)
    mix = nt.nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = fac
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*color, 1.0)
    nt.links.new(d.outputs[0], mix.inputs[1])
    nt.links.new(nt.nodes.new(node_type).outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs["Surface"])
    return mat


def build_holdout(scene):
    """Issue 16's holdout: on a ground under an area light and a sky, a sphere of Mix Shader
    (Diffuse, Holdout 0.4), a cube that is a holdout object (Object.is_holdout), a sphere of Mix
    (Diffuse, Transparent 0.5) in a holdout collection (LayerCollection.holdout), a card of
    Holdout alone, which casts its shadow (a Holdout closure is opaque to shadow rays), and a card
    of Mix (Diffuse, Transparent 0.5) against the sky."""
    set_world(scene, (0.3, 0.45, 0.7), 0.8)
    ground = add_object(scene, "Ground", mesh_plane("Ground", 8.0))
    assign(ground, diffuse("Ground", WHITE))
    assign(add_object(scene, "HoldoutMix", mesh_sphere("HoldoutMix", 0.5), (-1.1, 0, 0.5)),
           _mix_with("HoldoutMix", "ShaderNodeHoldout", 0.4, RED))
    cube = add_object(scene, "HoldoutCube", mesh_box("HoldoutCube", (0.8, 0.8, 0.8)), (0.1, 0.3, 0), (0, 0, 20))
    assign(cube, diffuse("Cube", GREEN))
    cube.is_holdout = True
    held = bpy.data.collections.new("Held")
    scene.collection.children.link(held)
    glass_ball = add_object(scene, "HeldBall", mesh_sphere("HeldBall", 0.45), (1.2, -0.2, 0.45), collection=held)
    assign(glass_ball, _mix_with("HeldBall", "ShaderNodeBsdfTransparent", 0.5, WHITE))
    scene.view_layers[0].layer_collection.children["Held"].holdout = True
    card = add_object(scene, "HoldoutCard", mesh_plane("HoldoutCard", 0.6), (-0.3, -1.0, 0.8), (70, 0, 10))
    mat, nt, out = _material("HoldoutCard")
    nt.links.new(nt.nodes.new("ShaderNodeHoldout").outputs[0], out.inputs["Surface"])
    assign(card, mat)
    # Against the sky: with Film > Transparent the sky behind a transparent surface is transparent.
    see_through = add_object(scene, "SeeThrough", mesh_plane("SeeThrough", 0.8), (0.3, 2.5, 1.75), (90, 0, 0))
    assign(see_through, _mix_with("SeeThrough", "ShaderNodeBsdfTransparent", 0.5, WHITE))
    add_light(scene, "Area", "AREA", 400.0, (0.5, -1.0, 3.0), size=1.5)
    add_camera(scene, (0.0, -4.5, 2.2), (0.0, 0.0, 0.5), lens=35.0)


def build_shadow_catcher(scene):
    """Issue 16's shadow catcher: a red cube standing on a ground that is a shadow catcher
    (Object.is_shadow_catcher), lit by an area light and a sky."""
    set_world(scene, (0.3, 0.45, 0.7), 0.8)
    ground = add_object(scene, "Catcher", mesh_plane("Catcher", 8.0))
    assign(ground, diffuse("Catcher", WHITE))
    ground.is_shadow_catcher = True
    cube = add_object(scene, "Cube", mesh_box("Cube", (0.8, 0.8, 0.8)), (0.0, 0.3, 0), (0, 0, 20))
    assign(cube, diffuse("Cube", RED))
    add_light(scene, "Area", "AREA", 400.0, (0.8, -1.0, 3.0), size=1.0)
    add_camera(scene, (0.0, -4.5, 2.2), (0.0, 0.0, 0.5), lens=35.0)


def build_light_groups(scene):
    """Issue 16's light groups: a floor, a diffuse sphere and a glossy box lit by an area light
    (group "key"), a point light and an emissive ball (group "fill") and a world in no group
    (view layer light groups "key" and "fill"; Cycles writes Combined_key and Combined_fill)."""
    set_world(scene, (0.2, 0.25, 0.3), 0.5)
    assign(add_object(scene, "Floor", mesh_plane("Floor", 8.0)), diffuse("Floor", WHITE))
    assign(add_object(scene, "Ball", mesh_sphere("Ball", 0.5), (-0.6, 0.2, 0.5)), diffuse("Ball", RED))
    assign(add_object(scene, "Box", mesh_box("Box", (0.7, 0.7, 0.7)), (0.7, 0.3, 0), (0, 0, 25)),
           glossy("Box", (0.8, 0.8, 0.8), 0.3))
    glow = add_object(scene, "Glow", mesh_sphere("Glow", 0.15), (0.1, -0.8, 0.15))
    assign(glow, emission("Glow", (1.0, 0.6, 0.3), 6.0))
    key = add_light(scene, "Key", "AREA", 300.0, (-1.0, -1.5, 3.0), rotation=(30, 0, -20), size=1.0)
    fill = add_light(scene, "Fill", "POINT", 150.0, (2.0, -1.0, 1.5), radius=0.1)
    for name in ("key", "fill"):
        scene.view_layers[0].lightgroups.add(name=name)
    key.lightgroup = "key"
    fill.lightgroup = glow.lightgroup = "fill"
    add_camera(scene, (0.0, -4.5, 2.0), (0.0, 0.0, 0.4), lens=35.0)


def _aov_material(name, color, transparent=0.0):
    """A Diffuse BSDF of `color` (mixed with a Transparent BSDF of weight `transparent`) with three
    AOV Outputs: "paint" the constant colour, "coords" Texture Coordinate's Generated, "mask" the
    constant value 0.25."""
    mat = _mix_with(name, "ShaderNodeBsdfTransparent", transparent, color)
    nt = mat.node_tree
    coords = nt.nodes.new("ShaderNodeTexCoord")
    for aov_name, source in (("paint", None), ("coords", coords.outputs["Generated"]), ("mask", 0.25)):
        aov = nt.nodes.new("ShaderNodeOutputAOV")
        aov.name = aov_name  # Blender 3.4 keeps the AOV's name in the node's
        if source is None:
            aov.inputs["Color"].default_value = (*color, 1.0)
        elif isinstance(source, float):
            aov.inputs["Value"].default_value = source
        else:
            nt.links.new(source, aov.inputs["Color"])
    return mat


def build_aovs(scene):
    """Issue 16's shader AOVs: view layer AOVs "paint" and "coords" (colours) and "mask" (a value),
    written by a ground, a sphere and a card of alpha 0.3 (Mix Shader of Diffuse and Transparent
    0.7) in front of the sphere (the camera path writes at the card and, when it passes it,
    behind; Alpha Threshold 0.5)."""
    set_world(scene, (0.3, 0.35, 0.4), 1.0)
    for name, kind in (("paint", 'COLOR'), ("coords", 'COLOR'), ("mask", 'VALUE')):
        aov = scene.view_layers[0].aovs.add()
        aov.name, aov.type = name, kind
    assign(add_object(scene, "Ground", mesh_plane("Ground", 6.0)), _aov_material("Ground", WHITE))
    assign(add_object(scene, "Ball", mesh_sphere("Ball", 0.6), (0.0, 0.3, 0.6)), _aov_material("Ball", RED))
    card = add_object(scene, "Card", mesh_plane("Card", 0.9), (0.3, -0.8, 0.7), (80, 0, 0))
    assign(card, _aov_material("Card", GREEN, transparent=0.7))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(40, 0, 30))
    add_camera(scene, (0.0, -3.5, 1.6), (0.0, 0.0, 0.5), lens=40.0)


def _aov_group(name, aov_name, value=None):
    """A node group holding an AOV Output `aov_name`: fed by the group's colour input (which it also
    passes to its output), or a constant `value` (a group with no sockets)."""
    g = bpy.data.node_groups.new(name, "ShaderNodeTree")
    aov = g.nodes.new("ShaderNodeOutputAOV")
    aov.name = aov_name
    if value is not None:
        aov.inputs["Value"].default_value = value
        return g
    gi, go = g.nodes.new("NodeGroupInput"), g.nodes.new("NodeGroupOutput")
    g.inputs.new("NodeSocketColor", "Color")
    g.outputs.new("NodeSocketColor", "Color")
    g.links.new(gi.outputs[0], aov.inputs["Color"])
    g.links.new(gi.outputs[0], go.inputs[0])
    return g


def build_aovs_world(scene):
    """Issue 16's World AOVs and AOV Outputs in node groups, with the view layer AOVs of `aovs`: a
    World whose AOV Outputs write "paint" (0.9, 0.5, 0.1), "coords" (Texture Coordinate's
    Generated: the escaping direction) and "mask" 0.5 where a camera ray escapes; a ground whose
    Diffuse colour goes through a group holding the "paint" AOV Output (Cycles flattens groups),
    and a group linked to nothing holding the "mask" one (0.8); the card of `aovs` (alpha 0.3,
    its AOV Outputs at the top level) in front of the sky."""
    world = set_world(scene, (0.3, 0.35, 0.4), 1.0)
    nt = world.node_tree
    coords = nt.nodes.new("ShaderNodeTexCoord")
    for aov_name, source in (("paint", (0.9, 0.5, 0.1, 1.0)), ("coords", coords.outputs["Generated"]),
                             ("mask", 0.5)):
        aov = nt.nodes.new("ShaderNodeOutputAOV")
        aov.name = aov_name
        if isinstance(source, float):
            aov.inputs["Value"].default_value = source
        elif isinstance(source, tuple):
            aov.inputs["Color"].default_value = source
        else:
            nt.links.new(source, aov.inputs["Color"])
    for name, kind in (("paint", 'COLOR'), ("coords", 'COLOR'), ("mask", 'VALUE')):
        aov = scene.view_layers[0].aovs.add()
        aov.name, aov.type = name, kind
    ground = diffuse("AovGround", WHITE)
    gnt = ground.node_tree
    bsdf = next(n for n in gnt.nodes if n.type == 'BSDF_DIFFUSE')
    paint = gnt.nodes.new("ShaderNodeGroup")
    paint.node_tree = _aov_group("PaintAov", "paint")
    paint.inputs[0].default_value = (0.2, 0.6, 0.3, 1.0)
    gnt.links.new(paint.outputs[0], bsdf.inputs["Color"])
    gnt.nodes.new("ShaderNodeGroup").node_tree = _aov_group("MaskAov", "mask", value=0.8)
    assign(add_object(scene, "Ground", mesh_plane("Ground", 4.0)), ground)
    card = add_object(scene, "Card", mesh_plane("Card", 0.9), (0.5, 1.2, 0.95), (80, 0, 0))  # in one 16 px tile
    assign(card, _aov_material("Card", GREEN, transparent=0.7))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(40, 0, 30))
    add_camera(scene, (0.0, -3.5, 1.0), (0.0, 0.0, 0.9), lens=40.0)


def checker_pixels(size=64, squares=8):
    """sRGB-encoded colour checker: warm/cool squares, brightness ramping along U."""
    y, x = np.mgrid[0:size, 0:size]
    check = ((x * squares // size) + (y * squares // size)) % 2
    ramp = 0.35 + 0.65 * (x + 0.5) / size
    a = np.array([0.95, 0.55, 0.15])
    b = np.array([0.15, 0.45, 0.85])
    rgb = np.where(check[..., None] == 1, a, b) * ramp[..., None]
    return np.concatenate([rgb, np.ones((size, size, 1))], axis=-1)


def roughness_pixels(size=64, bands=4):
    """Non-colour roughness: `bands` horizontal bands from 0.05 to 0.6."""
    y = np.mgrid[0:size, 0:size][0]
    v = 0.05 + 0.55 * (y * bands // size) / (bands - 1)
    return np.stack([v, v, v, np.ones_like(v)], axis=-1)


def height_pixels(size=64, bumps=4):
    """A height map (8-bit, non-colour) of round bumps, h = 0.5 + 0.5 sin(pi x) sin(pi y) per bump
    in bands of alternating sign."""
    y, x = (np.mgrid[0:size, 0:size] + 0.5) / size * bumps
    h = 0.5 + 0.5 * np.sin(np.pi * x) * np.sin(np.pi * y)
    return np.stack([h, h, h, np.ones_like(h)], axis=-1)


def displaced_material(name, image, color, roughness, scale, coords="UV"):
    """Image Texture (Non-Color, Linear) -> Displacement (Height; Midlevel 0.5) -> the Material
    Output's Displacement beside a Principled BSDF, as Node Wrangler's Principled set-up and Poly
    Haven's materials build it; Cycles 3.4's default method Bump."""
    mat, nt, out = _material(name)
    assert mat.cycles.displacement_method == "BUMP"
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = "Linear"
    if coords != "UV":
        tc = nt.nodes.new("ShaderNodeTexCoord")
        nt.links.new(tc.outputs[coords], tex.inputs["Vector"])
    disp = nt.nodes.new("ShaderNodeDisplacement")
    disp.inputs["Midlevel"].default_value = 0.5
    disp.inputs["Scale"].default_value = scale
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    nt.links.new(tex.outputs["Color"], disp.inputs["Height"])
    nt.links.new(disp.outputs["Displacement"], out.inputs["Displacement"])
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return mat


def normal_map_pixels(size=64, bumps=4):
    """A tangent-space normal map (8-bit, non-colour) of round bumps: the normals of the height
    field h = sin(pi x) sin(pi y) per bump, encoded 0.5 + 0.5 n."""
    y, x = (np.mgrid[0:size, 0:size] + 0.5) * (bumps / size)
    k = 0.5 * np.pi
    dx = k * np.cos(np.pi * x) * np.sin(np.pi * y)
    dy = k * np.sin(np.pi * x) * np.cos(np.pi * y)
    n = np.stack([-dx, -dy, np.ones_like(dx)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.concatenate([0.5 + 0.5 * n, np.ones((size, size, 1))], axis=-1)


def normal_mapped_material(name, image, color, roughness, metallic=0.0):
    """Image Texture (Non-Color) -> Normal Map (tangent space, active UV map) -> Principled's Normal,
    as Node Wrangler's Principled set-up and the glTF importer build it."""
    mat, nt, out = _material(name)
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = "Linear"
    nmap = nt.nodes.new("ShaderNodeNormalMap")
    nmap.space = "TANGENT"
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    nt.links.new(tex.outputs["Color"], nmap.inputs["Color"])
    nt.links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return mat


# ----------------------------------------------------------------------------------------------
# Scenes
# ----------------------------------------------------------------------------------------------
def cornell_box(scene):
    """The box (interior x, y in [-1, 1], z in [0, 2], open towards -Y), two boxes, camera."""
    white = diffuse("White", WHITE)
    red = diffuse("Red", RED)
    green = diffuse("Green", GREEN)
    walls = [  # name, matrix taking the +Z unit plane into place (normals face inward), material
        ("Floor", Matrix.Identity(4), white),
        ("Ceiling", Matrix.Translation((0, 0, 2)) @ Matrix.Rotation(math.pi, 4, "X"), white),
        ("BackWall", Matrix.Translation((0, 1, 1)) @ Matrix.Rotation(math.pi / 2, 4, "X"), white),
        ("LeftWall", Matrix.Translation((-1, 0, 1)) @ Matrix.Rotation(math.pi / 2, 4, "Y"), red),
        ("RightWall", Matrix.Translation((1, 0, 1)) @ Matrix.Rotation(-math.pi / 2, 4, "Y"), green),
    ]
    for name, m, mat in walls:
        assign(add_object(scene, name, mesh_plane(name, 2.0, 2.0, matrix=m)), mat)
    assign(add_object(scene, "TallBox", mesh_box("TallBox", (0.6, 0.6, 1.2)), (-0.35, 0.3, 0.0),
                      (0, 0, 17)), white)
    assign(add_object(scene, "ShortBox", mesh_box("ShortBox", (0.6, 0.6, 0.6)), (0.36, -0.3, 0.0),
                      (0, 0, -18)), white)
    add_camera(scene, (0, -3.8, 1.0), (0, 0, 1.0), lens=50.0)


def build_cornell_area(scene):
    cornell_box(scene)
    add_light(scene, "AreaLight", "AREA", 50.0, (0, 0, 1.98), shape="SQUARE", size=0.5)


def build_cornell_point(scene):
    cornell_box(scene)
    add_light(scene, "PointLight", "POINT", 30.0, (0, 0, 1.7), radius=0.1)


def build_area_spread(scene):
    """The Cornell box under two area lamps with a Spread (Cycles 3.4's soft-box slats): a square
    of spread 40 degrees and a disk of 90 degrees, both tilted, so the walls see the cut-off."""
    cornell_box(scene)
    add_light(scene, "SpreadSquare", "AREA", 40.0, (-0.3, 0.2, 1.95), rotation=(15, 10, 0), shape="SQUARE",
              size=0.6, spread=math.radians(40.0))
    add_light(scene, "SpreadDisk", "AREA", 30.0, (0.4, -0.1, 1.9), rotation=(-20, -25, 0), shape="DISK",
              size=0.5, spread=math.radians(90.0))


def build_lamp_near_ceiling(scene):
    """The Cornell box lit by a point lamp of radius 0.1 hung 0.05 below the ceiling: the ceiling
    passes through the lamp's sphere, so ceiling points near it lie within its radius (Cycles
    still draws the disk facing them; Lantern refused those hits and read 7.5 % dark)."""
    cornell_box(scene)
    add_light(scene, "PointLight", "POINT", 30.0, (0.2, 0.1, 1.95), radius=0.1)


def build_cornell_spot(scene):
    cornell_box(scene)
    add_light(scene, "SpotLight", "SPOT", 300.0, (0, 0, 1.9), radius=0.05,
              spot_size=math.radians(60.0), spot_blend=0.2, show_cone=False)


def build_cornell_dof(scene):
    """The Cornell box (area light) through a lens with depth of field (issue 15): in focus on the
    short box (Focus Object: its distance along the view axis), at F/0.05 (Cycles: a 50 cm
    aperture radius for the 50 mm lens, so the walls and the tall box blur over several pixels),
    6 blades turned 10 degrees and an anamorphic ratio of 1.3."""
    build_cornell_area(scene)
    cam = scene.camera.data
    cam.dof.use_dof = True
    cam.dof.focus_object = scene.objects["ShortBox"]
    cam.dof.aperture_fstop = 0.05
    cam.dof.aperture_blades = 6
    cam.dof.aperture_rotation = math.radians(10.0)
    cam.dof.aperture_ratio = 1.3


# Issue 15's panoramas, from inside the Cornell box (area light) towards its back wall: Cycles'
# settings on the camera (cam.cycles, the Cycles add-on's), asymmetric ranges and a shift so that
# a mirrored or offset mapping shows.
PANORAMAS = {
    "EQUIRECTANGULAR": dict(latitude_min=math.radians(-60.0), latitude_max=math.radians(75.0),
                            longitude_min=math.radians(-150.0), longitude_max=math.radians(120.0)),
    "FISHEYE_EQUIDISTANT": dict(fisheye_fov=math.radians(200.0)),
    "FISHEYE_EQUISOLID": dict(fisheye_lens=9.0, fisheye_fov=math.radians(170.0)),
    "MIRRORBALL": {},
    # theta(r) = 0.06 r - 3e-4 r^2 + 1e-5 r^3 (r in mm on the 36 mm sensor), cut at 63 degrees:
    # the corners see nothing.
    "FISHEYE_LENS_POLYNOMIAL": dict(fisheye_fov=math.radians(126.0), fisheye_polynomial_k0=0.0,
                                    fisheye_polynomial_k1=-0.06, fisheye_polynomial_k2=3e-4,
                                    fisheye_polynomial_k3=-1e-5, fisheye_polynomial_k4=0.0),
    "EQUIANGULAR_CUBEMAP_FACE": {},
}


def build_panorama(scene, panorama_type):
    build_cornell_area(scene)
    obj = scene.camera
    obj.location = (0.1, -0.6, 1.0)
    look_at(obj, (0.2, 1.0, 0.9))
    cam = obj.data
    cam.type = "PANO"
    cam.cycles.panorama_type = panorama_type
    for key, value in PANORAMAS[panorama_type].items():
        setattr(cam.cycles, key, value)
    cam.shift_x = 0.04
    cam.shift_y = -0.03


def emission(name, color, strength):
    return _bsdf_material(name, "ShaderNodeEmission", color, Strength=strength)


def build_cornell_mesh_light(scene):
    """The Cornell box lit only by an Emission-shader quad (strength 50, no light objects) hanging
    10 cm below the ceiling, its front facing down: Cycles' mesh lights emit from both sides, so
    the ceiling above the quad is lit by its back."""
    cornell_box(scene)
    quad = mesh_plane("LampQuad", 0.5, 0.5, matrix=Matrix.Rotation(math.pi, 4, "X"))
    assign(add_object(scene, "LampQuad", quad, (0, 0, 1.9)), emission("LampQuadEmission", (1, 1, 1), 50.0))


def build_glossy_glass(scene):
    set_world(scene, (0.05, 0.07, 0.1), 1.0)
    floor = add_object(scene, "Floor", mesh_plane("Floor", 12.0))
    assign(floor, diffuse("FloorGrey", (0.5, 0.5, 0.5)))
    spheres = [
        ("GlossyRough", glossy("GlossyR02", (0.8, 0.8, 0.8), 0.2)),
        ("GlossyMirror", glossy("GlossyR00", (0.9, 0.6, 0.3), 0.0)),
        ("GlassClear", glass("GlassR00", (1.0, 1.0, 1.0), 0.0)),
        ("GlassRough", glass("GlassR03", (0.8, 1.0, 0.9), 0.3)),
    ]
    for i, (name, mat) in enumerate(spheres):
        obj = add_object(scene, name, mesh_sphere(name, 0.4), (-1.5 + i, 0, 0.4))
        assign(obj, mat)
    add_object(scene, "BackBlock", mesh_box("BackBlock", (4.0, 0.3, 1.2)), (0, 1.6, 0))
    assign(scene.objects["BackBlock"], diffuse("BlockRed", (0.7, 0.2, 0.15)))
    add_light(scene, "AreaLight", "AREA", 200.0, (0.5, -1.0, 3.0), rotation=(15, 10, 0),
              shape="RECTANGLE", size=1.5, size_y=1.0)
    add_camera(scene, (0, -5.0, 1.6), (0, 0, 0.45), lens=40.0)


def build_world_spheres(scene):
    """Issue 14's "diffuse and glossy spheres under a constant white world": no lamps, every path
    lit by the uniform sky, an integrand smooth in the pixel footprint and the first bounce."""
    set_world(scene, (1.0, 1.0, 1.0), 1.0)
    assign(add_object(scene, "Floor", mesh_plane("Floor", 12.0)), diffuse("FloorGrey", (0.5, 0.5, 0.5)))
    spheres = [
        ("Diffuse", diffuse("SphereDiffuse", (0.8, 0.3, 0.2))),
        ("GlossyRough", glossy("SphereGlossyR03", (0.8, 0.8, 0.8), 0.3)),
        ("DiffuseWhite", diffuse("SphereWhite", (0.8, 0.8, 0.8))),
    ]
    for i, (name, mat) in enumerate(spheres):
        assign(add_object(scene, name, mesh_sphere(name, 0.5), (-1.2 + 1.2 * i, 0, 0.5)), mat)
    add_camera(scene, (0, -4.5, 1.5), (0, 0, 0.4), lens=40.0)


def principled(name, color, roughness, specular=0.5, metallic=0.0):
    """A Principled BSDF at Blender's defaults (GGX) but for Base Color, Roughness, Specular and
    Metallic."""
    mat, nt, out = _material(name)
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Specular"].default_value = specular
    bsdf.inputs["Metallic"].default_value = metallic
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    mat.diffuse_color = (*color, 1.0)
    return mat


def build_principled_ground(scene):
    """Issue 13: a rough Principled ground (Roughness 1, Specular 0) under a low sun behind the
    camera and a sky, seen at a grazing angle, where Cycles' diffuse retro-reflects (Lantern's
    Lambert diffuse was 29 % darker there), and a sphere of Blender's default Principled BSDF."""
    set_world(scene, (0.3, 0.45, 0.7), 1.0)
    ground = add_object(scene, "Ground", mesh_plane("Ground", 40.0))
    assign(ground, principled("RoughGround", (0.6, 0.6, 0.55), 1.0, specular=0.0))
    sphere = add_object(scene, "Sphere", mesh_sphere("Sphere", 0.5), (0.3, 0.0, 0.5))
    assign(sphere, principled("DefaultPrincipled", (0.8, 0.8, 0.8), 0.5))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(75, 0, 10), angle=math.radians(1.0))
    add_camera(scene, (0, -7.0, 0.7), (0, 0, 0.3), lens=35.0)


def build_subsurface(scene, method="RANDOM_WALK"):
    """Subsurface scattering (Cycles 3.4's BSSRDFs) with the given method on both closures: a
    skin-like Principled sphere (Subsurface 0.6, radius about a third of the sphere's in red) and a
    cube of the Subsurface Scattering node (wax-like, anisotropy 0.4 but for Burley), lit by an
    area light and a grey world over a diffuse floor."""
    set_world(scene, (0.25, 0.25, 0.3), 1.0)
    floor = add_object(scene, "Floor", mesh_plane("Floor", 8.0))
    assign(floor, diffuse("SSSFloor", (0.5, 0.5, 0.5)))
    skin = principled("Skin", (0.8, 0.55, 0.45), 0.45)
    bsdf = skin.node_tree.nodes["Principled BSDF"]
    bsdf.subsurface_method = method
    bsdf.inputs["Subsurface"].default_value = 0.6
    bsdf.inputs["Subsurface Radius"].default_value = (0.3, 0.12, 0.06)
    bsdf.inputs["Subsurface Color"].default_value = (0.9, 0.35, 0.25, 1.0)
    sphere = add_object(scene, "SkinSphere", mesh_sphere("SkinSphere", 0.5), (-0.55, 0, 0.5))
    assign(sphere, skin)
    wax, nt, out = _material("Wax")
    sss = nt.nodes.new("ShaderNodeSubsurfaceScattering")
    sss.falloff = method
    sss.inputs["Color"].default_value = (0.85, 0.75, 0.4, 1.0)
    sss.inputs["Scale"].default_value = 0.2
    sss.inputs["Radius"].default_value = (1.0, 0.6, 0.3)
    sss.inputs["Anisotropy"].default_value = 0.0 if method == "BURLEY" else 0.4
    nt.links.new(sss.outputs[0], out.inputs["Surface"])
    cube = add_object(scene, "WaxCube", mesh_box("WaxCube", (0.7, 0.7, 0.7)), (0.6, 0.1, 0.0),
                      rotation=(0, 0, 30))
    assign(cube, wax)
    add_light(scene, "Key", "AREA", 150.0, (1.2, -1.0, 2.2), rotation=(40, 0, 50), size=0.8)
    add_camera(scene, (0, -3.6, 1.4), (0, 0, 0.4), lens=40.0)


def build_resting(scene):
    """Glass resting on a floor as users place it: a Glass BSDF box and a rough Principled glass
    box (Transmission 1) whose bottom faces lie in the floor's plane (origin at the bottom,
    location z = 0), under an area light and a grey world that also lights the floor's underside.
    Seen through the glass, the bottom face meets the floor it touches; a ray origin offset
    forwards stepped over it and saw the world under the floor (4 % bright image mean)."""
    set_world(scene, (0.25, 0.25, 0.3), 1.0)
    floor = add_object(scene, "Floor", mesh_plane("Floor", 8.0))
    assign(floor, diffuse("RestingFloor", (0.5, 0.5, 0.5)))
    block = add_object(scene, "GlassBlock", mesh_box("GlassBlock", (0.7, 0.7, 0.7)), (0.55, 0.1, 0.0),
                       rotation=(0, 0, 30))
    assign(block, glass("RestingGlass", (1.0, 1.0, 1.0), 0.0, ior=1.45))
    slab = add_object(scene, "PrincipledSlab", mesh_box("PrincipledSlab", (0.6, 0.5, 0.3)), (-0.55, -0.1, 0.0),
                      rotation=(0, 0, -20))
    mat = principled("RestingPrincipledGlass", (0.9, 0.95, 1.0), 0.2)
    mat.node_tree.nodes["Principled BSDF"].inputs["Transmission"].default_value = 1.0
    assign(slab, mat)
    add_light(scene, "Key", "AREA", 150.0, (1.2, -1.0, 2.2), rotation=(40, 0, 50), size=0.8)
    add_camera(scene, (0, -3.6, 1.4), (0, 0, 0.3), lens=40.0)


def _node_group(name, inputs, outputs, build):
    """A shader node group with (type, name) inputs and outputs; build(tree, group input node)
    returns {output name: socket} to link to the Group Output."""
    g = bpy.data.node_groups.new(name, "ShaderNodeTree")
    for kind, n in inputs:
        g.inputs.new(kind, n)
    for kind, n in outputs:
        g.outputs.new(kind, n)
    gin, gout = g.nodes.new("NodeGroupInput"), g.nodes.new("NodeGroupOutput")
    for n, socket in build(g, gin).items():
        g.links.new(socket, gout.inputs[n])
    return g


def _node(tree, idname, inputs=(), **props):
    """A node with properties set and inputs fed: values set, sockets linked (by index or name)."""
    n = tree.nodes.new(idname)
    for k, v in props.items():
        setattr(n, k, v)
    for key, v in (inputs.items() if isinstance(inputs, dict) else enumerate(inputs)):
        if v is None:
            continue
        if isinstance(v, bpy.types.NodeSocket):
            tree.links.new(v, n.inputs[key])
        elif isinstance(v, tuple) and len(v) in (3, 4) and len(n.inputs[key].default_value) == 4:
            n.inputs[key].default_value = (*v[:3], 1.0)
        else:
            n.inputs[key].default_value = v
    return n


def layered_material(name):
    """Issue 13's "material of 50+ nodes with nested groups", as users build them: stripes from a
    group (Separate XYZ, Math), used twice inside a tint group (Vector Math, Mix RGB, Hue/Saturation,
    Bright/Contrast, ColorRamp), object coordinates through Mapping, Layer Weight and Fresnel
    driving the mix and the roughness, a Map Range, Clamp, Gamma, Invert and RGB Curves chain,
    into a Principled BSDF."""
    def stripes(g, gin):
        sep = _node(g, "ShaderNodeSeparateXYZ", [gin.outputs["Vector"]])
        scaled = _node(g, "ShaderNodeMath", [sep.outputs["X"], 6.0], operation='MULTIPLY')
        wave = _node(g, "ShaderNodeMath", [scaled.outputs[0]], operation='SINE')
        tilt = _node(g, "ShaderNodeMath", [sep.outputs["Z"], 2.0, wave.outputs[0]], operation='MULTIPLY_ADD')
        ranged = _node(g, "ShaderNodeMapRange", {"Value": tilt.outputs[0], "From Min": -1.0, "From Max": 3.0})
        return {"Fac": _node(g, "ShaderNodeMath", [ranged.outputs[0], 1.4], operation='POWER').outputs[0]}

    stripe_group = _node_group(name + "Stripes", [("NodeSocketVector", "Vector")], [("NodeSocketFloat", "Fac")],
                               stripes)

    def tint(g, gin):
        a = _node(g, "ShaderNodeGroup", node_tree=stripe_group)
        g.links.new(gin.outputs["Vector"], a.inputs["Vector"])
        rotated = _node(g, "ShaderNodeVectorRotate", {"Vector": gin.outputs["Vector"], "Angle": 0.7},
                        rotation_type='Z_AXIS')
        twice = _node(g, "ShaderNodeVectorMath", [rotated.outputs[0], (2.0, 2.0, 2.0)], operation='MULTIPLY')
        b = _node(g, "ShaderNodeGroup", node_tree=stripe_group)
        g.links.new(twice.outputs[0], b.inputs["Vector"])
        both = _node(g, "ShaderNodeMath", [a.outputs["Fac"], b.outputs["Fac"]], operation='MAXIMUM')
        ramp = _node(g, "ShaderNodeValToRGB", [both.outputs[0]])
        ramp.color_ramp.elements[0].color = (0.05, 0.1, 0.3, 1.0)
        ramp.color_ramp.elements[1].color = (0.9, 0.7, 0.3, 1.0)
        mixed = _node(g, "ShaderNodeMixRGB", [a.outputs["Fac"], ramp.outputs["Color"], gin.outputs["Color"]],
                      blend_type='OVERLAY')
        hsv = _node(g, "ShaderNodeHueSaturation", {"Hue": 0.55, "Saturation": 1.2, "Color": mixed.outputs[0]})
        bc = _node(g, "ShaderNodeBrightContrast", {"Color": hsv.outputs[0], "Bright": 0.05, "Contrast": 0.2})
        return {"Color": bc.outputs[0], "Fac": both.outputs[0]}

    tint_group = _node_group(name + "Tint", [("NodeSocketVector", "Vector"), ("NodeSocketColor", "Color")],
                             [("NodeSocketColor", "Color"), ("NodeSocketFloat", "Fac")], tint)
    mat, nt, out = _material(name)
    coords = _node(nt, "ShaderNodeTexCoord")
    mapping = _node(nt, "ShaderNodeMapping", {"Vector": coords.outputs["Object"], "Location": (0.1, 0.2, 0.0),
                                              "Rotation": (0.2, 0.0, 0.4), "Scale": (1.5, 1.5, 1.0)})
    t1 = _node(nt, "ShaderNodeGroup", node_tree=tint_group)
    nt.links.new(mapping.outputs[0], t1.inputs["Vector"])
    t1.inputs["Color"].default_value = (0.6, 0.2, 0.15, 1.0)
    generated = _node(nt, "ShaderNodeVectorMath", [coords.outputs["Generated"], (0.5, 0.5, 0.5)],
                      operation='SUBTRACT')
    t2 = _node(nt, "ShaderNodeGroup", node_tree=tint_group)
    nt.links.new(generated.outputs[0], t2.inputs["Vector"])
    t2.inputs["Color"].default_value = (0.2, 0.5, 0.3, 1.0)
    facing = _node(nt, "ShaderNodeLayerWeight", {"Blend": 0.35})
    mix = _node(nt, "ShaderNodeMixRGB", [facing.outputs["Facing"], t1.outputs["Color"], t2.outputs["Color"]])
    gamma = _node(nt, "ShaderNodeGamma", {"Color": mix.outputs[0], "Gamma": 1.3})
    curves = _node(nt, "ShaderNodeRGBCurve", {"Color": gamma.outputs[0]})
    curves.mapping.curves[3].points.new(0.4, 0.55)
    curves.mapping.update()
    inverted = _node(nt, "ShaderNodeInvert", {"Fac": 0.15, "Color": curves.outputs[0]})
    clamp = _node(nt, "ShaderNodeClamp", {"Value": t2.outputs["Fac"], "Min": 0.1, "Max": 0.9})
    fresnel = _node(nt, "ShaderNodeFresnel", {"IOR": 1.6})
    rough = _node(nt, "ShaderNodeMath", [clamp.outputs[0], fresnel.outputs[0], 0.2], operation='MULTIPLY_ADD')
    rough_range = _node(nt, "ShaderNodeMapRange", {"Value": rough.outputs[0], "To Min": 0.15, "To Max": 0.8},
                        interpolation_type='SMOOTHSTEP')
    metal = _node(nt, "ShaderNodeMath", [t1.outputs["Fac"], 0.8], operation='GREATER_THAN')
    metal_scaled = _node(nt, "ShaderNodeMath", [metal.outputs[0], 0.7], operation='MULTIPLY')
    bsdf = _node(nt, "ShaderNodeBsdfPrincipled", {"Base Color": inverted.outputs[0],
                                                  "Roughness": rough_range.outputs["Result"],
                                                  "Metallic": metal_scaled.outputs[0]})
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return mat


def count_nodes(tree):
    """Nodes in a tree, counting each group's inside once per group node that uses it."""
    return sum(1 + (count_nodes(n.node_tree) if n.type == 'GROUP' and n.node_tree else 0) for n in tree.nodes)


def build_layered_material(scene):
    """Issue 13's 50+ node material with nested groups (layered_material) on two spheres and a
    ground, under a sun and a sky."""
    set_world(scene, (0.3, 0.45, 0.7), 1.0)
    ground = add_object(scene, "Ground", mesh_plane("Ground", 40.0))
    assign(ground, principled("Ground", (0.5, 0.5, 0.5), 0.8))
    mat = layered_material("Layered")
    for i, (x, r) in enumerate(((-0.6, 0.55), (0.7, 0.45))):
        assign(add_object(scene, "Sphere%d" % i, mesh_sphere("Sphere%d" % i, r), (x, 0.0, r)), mat)
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(50, 0, 30), angle=math.radians(2.0))
    add_camera(scene, (0, -4.0, 1.2), (0, 0, 0.45), lens=40.0)


def bsdf_zoo_materials():
    """One material per shader node and distribution issue 13 adds, as users set them up."""
    def principled(name, base, **inputs):
        mat, nt, out = _material(name)
        p = nt.nodes.new("ShaderNodeBsdfPrincipled")
        p.inputs["Base Color"].default_value = (*base, 1.0)
        p.distribution = inputs.pop("distribution", "GGX")
        for key, value in inputs.items():
            p.inputs[key.replace("_", " ")].default_value = value
        nt.links.new(p.outputs[0], out.inputs["Surface"])
        return mat

    def toon(name, component, color):
        mat = _bsdf_material(name, "ShaderNodeBsdfToon", color, Size=0.6, Smooth=0.2)
        mat.node_tree.nodes["Toon BSDF"].component = component
        return mat

    return [
        _bsdf_material("Velvet", "ShaderNodeBsdfVelvet", (0.8, 0.3, 0.5), Sigma=0.6),
        _bsdf_material("Translucent", "ShaderNodeBsdfTranslucent", (0.5, 0.8, 0.4)),
        toon("ToonDiffuse", "DIFFUSE", (0.3, 0.5, 0.9)),
        toon("ToonGlossy", "GLOSSY", (0.9, 0.8, 0.5)),
        _bsdf_material("AnisoGGX", "ShaderNodeBsdfAnisotropic", (0.9, 0.7, 0.5), distribution="GGX",
                       Roughness=0.4, Anisotropy=0.7, Rotation=0.1),
        _bsdf_material("Beckmann", "ShaderNodeBsdfGlossy", (0.6, 0.8, 0.9), distribution="BECKMANN",
                       Roughness=0.35),
        _bsdf_material("Ashikhmin", "ShaderNodeBsdfAnisotropic", (0.8, 0.8, 0.8), distribution="ASHIKHMIN_SHIRLEY",
                       Roughness=0.3, Anisotropy=-0.5),
        _bsdf_material("MultiGGX", "ShaderNodeBsdfGlossy", (0.95, 0.75, 0.4), distribution="MULTI_GGX",
                       Roughness=0.5),
        _bsdf_material("GlassBeckmann", "ShaderNodeBsdfGlass", (1.0, 1.0, 1.0), distribution="BECKMANN",
                       Roughness=0.2, IOR=1.45),
        principled("PrincipledLayers", (0.7, 0.25, 0.1), Sheen=1.0, Sheen_Tint=0.7, Specular_Tint=0.6, Anisotropic=0.6,
                   Anisotropic_Rotation=0.2, Roughness=0.45),
        principled("PrincipledClearcoat", (0.2, 0.35, 0.6), Clearcoat=0.8, Clearcoat_Roughness=0.15, Roughness=0.45),
        principled("PrincipledGlass", (0.9, 0.35, 0.2), Transmission=1.0, Roughness=0.25, Specular_Tint=0.3),
        _bsdf_material("GlassMultiGGX", "ShaderNodeBsdfGlass", (0.85, 0.95, 1.0), distribution="MULTI_GGX",
                       Roughness=0.35, IOR=1.45),
        principled("PrincipledMultiGGX", (0.8, 0.45, 0.2), distribution="MULTI_GGX", Metallic=0.6, Roughness=0.4,
                   Specular_Tint=0.4),
        principled("PrincipledGlassMultiGGX", (0.9, 0.55, 0.35), distribution="MULTI_GGX", Transmission=1.0,
                   Roughness=0.3, Specular_Tint=0.5),
    ]


# The shader nodes whose lit renders depart from Cycles' (README: departures): Cycles 3.4's own
# sample() of these closures disagrees with its eval() (Toon reads its ramp at the random number,
# not the sampled angle; the clearcoat is drawn from GGX but weighed with GTR1's pdf; Multiscatter
# GGX's walk carries the bounce colour once where its eval takes it twice), so Cycles' image
# depends on which strategy reached the light. Lantern follows eval() with both strategies: one
# sphere each lit by the sun alone agrees (Lantern / Cycles 0.9996-1.0000), by the sky alone
# (Cycles' BSDF samples) it is diffuse Toon 0.906, glossy Toon 0.965, clearcoat 1.025,
# Multiscatter GGX 0.981 (sphere means, 256 samples, 0.01-0.06 % standard error). The Multiscatter
# GGX glasses: Cycles' eval() departs from its walk, Lantern follows the walk (README).
ZOO_DEPARTURES = ("ToonDiffuse", "ToonGlossy", "MultiGGX", "PrincipledClearcoat", "GlassMultiGGX",
                  "PrincipledGlassMultiGGX")


def build_bsdf_zoo(scene, departures=False, sun_only=False, hidden=False, glass=True):
    """Issue 13's lit agreement of the new shader nodes: spheres of Velvet, Translucent, Beckmann
    glass, Anisotropic GGX, Beckmann and Ashikhmin-Shirley glossy, the Principled BSDF's sheen,
    specular tint and anisotropy, its glass and its Multiscatter GGX specular (departures: the
    ZOO_DEPARTURES nodes instead) on a ground under a sun and a sky. sun_only: no sky and no
    ground; hidden: spheres that indirect rays do not see, so that all light comes from the sun
    through Cycles' light samples; glass=False leaves the glass spheres out."""
    set_world(scene, (0.35, 0.45, 0.6), 0.0 if sun_only else 0.8)
    if not sun_only:
        ground = add_object(scene, "Ground", mesh_plane("Ground", 30.0))
        assign(ground, principled("Ground", (0.5, 0.5, 0.5), 0.7))
    mats = [m for m in bsdf_zoo_materials()
            if (m.name in ZOO_DEPARTURES) == departures and (glass or "Glass" not in m.name)]
    for i, mat in enumerate(mats):
        row, col = divmod(i, 4)
        visibility = dict(diffuse=False, glossy=False, transmission=False) if hidden else {}
        sphere = add_object(scene, "Sphere_" + mat.name, mesh_sphere("Sphere_" + mat.name, 0.4),
                            ((col - 1.5) * 0.95, row * 1.1, 0.4), **visibility)
        assign(sphere, mat)
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(40, 0, 25), angle=math.radians(3.0))
    add_camera(scene, (0, -5.2, 2.6), (0, 0.55, 0.35), lens=38.0)


def refraction_materials(transmission_roughness=0.5):
    """The Refraction BSDF (Sharp, GGX, Beckmann) at IORs 1.45 and 0.8 and a Principled glass with a
    Transmission Roughness of its own (issue 13)."""
    mats = []
    for ior in (1.45, 0.8):
        for dist, rough, color in (("SHARP", 0.0, (0.95, 0.9, 0.8)), ("GGX", 0.3, (0.8, 0.9, 0.95)),
                                   ("BECKMANN", 0.25, (0.9, 0.95, 0.85))):
            mats.append(_bsdf_material("Refraction%s_%g" % (dist.capitalize(), ior), "ShaderNodeBsdfRefraction", color,
                                       distribution=dist, Roughness=rough, IOR=ior))
    mat, nt, out = _material("PrincipledRoughRefraction")
    p = nt.nodes.new("ShaderNodeBsdfPrincipled")
    p.distribution = "GGX"
    p.inputs["Base Color"].default_value = (0.9, 0.8, 0.7, 1.0)
    p.inputs["Transmission"].default_value = 1.0
    p.inputs["Roughness"].default_value = 0.1
    p.inputs["Transmission Roughness"].default_value = transmission_roughness
    p.inputs["IOR"].default_value = 1.45
    nt.links.new(p.outputs[0], out.inputs["Surface"])
    mats.append(mat)
    return mats


def build_refraction(scene, transmission_roughness=0.5):
    """Issue 13: refraction_materials' seven spheres over a checker ground under a sun and a sky
    (the sun 6 degrees wide, so that the caustics paths find it are not single fireflies)."""
    set_world(scene, (0.35, 0.45, 0.6), 0.8)
    mat, nt, out = _material("Checker")
    checker = nt.nodes.new("ShaderNodeTexChecker")
    checker.inputs["Scale"].default_value = 32.0
    checker.inputs["Color1"].default_value = (0.8, 0.8, 0.75, 1.0)
    checker.inputs["Color2"].default_value = (0.1, 0.15, 0.3, 1.0)
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    nt.links.new(checker.outputs["Color"], bsdf.inputs["Color"])
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    assign(add_object(scene, "Ground", mesh_plane("Ground", 8.0)), mat)
    for i, m in enumerate(refraction_materials(transmission_roughness)):
        row, col = (0, i) if i < 4 else (1, i - 4)
        x = (col - 1.5) * 0.85 if row == 0 else (col - 1.0) * 0.85
        sphere = add_object(scene, "Sphere_" + m.name, mesh_sphere("Sphere_" + m.name, 0.36),
                            (x, 0.0 if row == 0 else 0.9, 0.36))
        assign(sphere, m)
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(35, 0, 20), angle=math.radians(6.0))
    add_camera(scene, (0, -4.6, 2.6), (0, 0.45, 0.3), lens=40.0)


def gltf_pbr_file(directory, scene):
    """A glTF 2.0 file as other tools write them: a UV sphere whose PBR material has a base colour
    texture times a factor, a metallic-roughness texture (G roughness, B metallic) with factors and
    a tangent-space normal map; written by Blender's exporter from the empty `scene` (left empty
    again), factors added to the JSON."""
    import json
    n = 32
    y, x = (np.mgrid[0:n, 0:n] + 0.5) / n
    one = np.ones_like(x)
    textures = {
        "Base": (np.dstack([0.3 + 0.6 * x, 0.4 + 0.3 * y, 0.5 + 0.4 * (1 - x), one]), "sRGB"),
        "MetalRough": (np.dstack([0 * x, 0.2 + 0.6 * y, (x > 0.5) * 1.0, one]), "Non-Color"),
        "NormalMap": (np.dstack([0.5 + 0.3 * np.sin(6 * x), 0.5 + 0.3 * np.cos(6 * y), 0.85 * one, one]), "Non-Color"),
    }
    images = {k: packed_image(k, px, space) for k, (px, space) in textures.items()}
    mat, nt, out = _material("PBR")
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")

    def tex(name):
        t = nt.nodes.new("ShaderNodeTexImage")
        t.image = images[name]
        return t
    nt.links.new(tex("Base").outputs["Color"], bsdf.inputs["Base Color"])
    sep = nt.nodes.new("ShaderNodeSeparateRGB")
    nt.links.new(tex("MetalRough").outputs["Color"], sep.inputs[0])
    nt.links.new(sep.outputs["G"], bsdf.inputs["Roughness"])
    nt.links.new(sep.outputs["B"], bsdf.inputs["Metallic"])
    nmap = nt.nodes.new("ShaderNodeNormalMap")
    nt.links.new(tex("NormalMap").outputs["Color"], nmap.inputs["Color"])
    nt.links.new(nmap.outputs[0], bsdf.inputs["Normal"])
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    ball = add_object(scene, "Ball", mesh_sphere("Ball", 0.6), (0, 0, 0.6))
    assign(ball, mat)
    path = os.path.join(directory, "ball.gltf")
    with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
        bpy.ops.export_scene.gltf(filepath=path, export_format='GLTF_SEPARATE', export_cameras=False,
                                  export_lights=False)
    bpy.data.objects.remove(ball)
    mat.name = "PBR source"  # the imported material takes the glTF's name, "PBR"
    with open(path) as f:
        doc = json.load(f)
    pbr = doc["materials"][0]["pbrMetallicRoughness"]
    pbr.update(baseColorFactor=[0.9, 0.75, 0.6, 1.0], roughnessFactor=0.8, metallicFactor=0.9)
    doc["materials"][0]["normalTexture"]["scale"] = 0.7
    with open(path, "w") as f:
        json.dump(doc, f)
    return path


def build_gltf_pbr(scene):
    """Issue 13's "glTF-imported PBR material": gltf_pbr_file imported by Blender's glTF importer
    (Separate Color for metallic and roughness, Normal Map, base colour times its factor, as the
    importer builds them) on a ground under a sun and a sky."""
    import tempfile
    import numpy
    path = gltf_pbr_file(tempfile.mkdtemp(prefix="lantern_gltf_"), scene)
    if not hasattr(numpy, "bool"):
        numpy.bool = bool  # Blender 3.4's glTF importer uses the alias NumPy 1.24 removed
    with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
        bpy.ops.import_scene.gltf(filepath=path)
    set_world(scene, (0.35, 0.45, 0.6), 0.8)
    ground = add_object(scene, "Ground", mesh_plane("Ground", 20.0))
    assign(ground, principled("Ground", (0.5, 0.5, 0.5), 0.7))
    # A wide sun: the metal half of the ball mirrors it, and a small one would take many samples.
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(45, 0, 30), angle=math.radians(10.0))
    add_camera(scene, (0, -2.6, 1.2), (0, 0, 0.55), lens=45.0)


def build_wide_sun(scene):
    """A 20-degree sun alone over a rough ground and a diffuse sphere: Cycles' sun radiance grows
    as 1 / cos^3 across its disk (a constant one, as Lantern had, is 2.3 % darker here)."""
    ground = add_object(scene, "Ground", mesh_plane("Ground", 20.0))
    assign(ground, principled("Ground", (0.6, 0.6, 0.6), 0.8))
    assign(add_object(scene, "Sphere", mesh_sphere("Sphere", 0.5), (0, 0, 0.5)), diffuse("Grey", (0.7, 0.7, 0.7)))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(35, 0, 20), angle=math.radians(20.0))
    add_camera(scene, (0, -3.5, 1.6), (0, 0, 0.4), lens=40.0)


def build_ray_visibility(scene):
    """Objects and lamps with Cycles' ray visibility flags as users set them: a sphere seen only by
    camera and shadow rays, a white card lighting the scene that the camera does not see, a box
    that casts no shadow, and an area lamp hidden from glossy rays (Cycles also leaves it out of
    the glossy closures' light samples), over a rough Principled ground under a 3-degree sun."""
    ground = add_object(scene, "Ground", mesh_plane("Ground", 12.0))
    assign(ground, principled("Ground", (0.6, 0.6, 0.6), 0.35))
    hidden = add_object(scene, "Hidden", mesh_sphere("Hidden", 0.45), (-0.8, 0.3, 0.45),
                        diffuse=False, glossy=False, transmission=False)
    assign(hidden, principled("HiddenMat", (0.8, 0.3, 0.2), 0.3))
    card = add_object(scene, "Card", mesh_plane("Card", 1.6), (0.2, 1.4, 0.8), rotation=(80, 0, 0),
                      camera=False)
    assign(card, diffuse("CardMat", (0.9, 0.9, 0.9)))
    box = add_object(scene, "NoShadow", mesh_box("NoShadow", (0.5, 0.5, 0.5)), (0.9, 0.1, 0.0), rotation=(0, 0, 30),
                     shadow=False)
    assign(box, principled("BoxMat", (0.2, 0.5, 0.8), 0.25))
    lamp = add_light(scene, "Lamp", "AREA", 60.0, (0.5, -0.8, 2.2), rotation=(20, 0, 0), size=0.6)
    lamp.visible_glossy = False
    add_light(scene, "Sun", "SUN", 2.0, (0, 0, 5), rotation=(50, 0, -30), angle=math.radians(3.0))
    add_camera(scene, (0, -3.6, 1.7), (0, 0.4, 0.35), lens=38.0)


def build_metal_box(scene):
    """A closed 4 x 4 x 3 m box of rough (0.2) copper-coloured Principled metal with the camera and
    a small point light inside, 8 bounces of every kind (issue 18: rough metal after several
    bounces). Cycles' Filter Glossy stays off (new_scene): at its default 1.0 it blurs the later
    bounces and Cycles renders this box 12-22 % darker."""
    c = scene.cycles
    c.max_bounces = c.glossy_bounces = c.diffuse_bounces = c.transmission_bounces = 8
    box = add_object(scene, "MetalBox", mesh_box("MetalBox", (4.0, 4.0, 3.0)))
    assign(box, principled("Copper", (0.95, 0.64, 0.54), 0.2, metallic=1.0))
    add_light(scene, "PointLight", "POINT", 100.0, (0.5, 0.3, 2.0), radius=0.1)
    add_camera(scene, (-1.5, -1.5, 1.0), (1.5, 1.0, 1.5), lens=20.0)


def build_sun_world(scene):
    set_world(scene, (0.3, 0.45, 0.7), 1.0)
    ground = add_object(scene, "Ground", mesh_plane("Ground", 40.0))
    assign(ground, diffuse("Ground", (0.6, 0.6, 0.55)))
    cube = add_object(scene, "Cube", mesh_box("Cube", (1.0, 1.0, 1.0)), (-0.9, 0.4, 0), (0, 0, 30))
    assign(cube, diffuse("Orange", (0.8, 0.35, 0.1)))
    sphere = add_object(scene, "Sphere", mesh_sphere("Sphere", 0.5), (0.8, -0.3, 0.5))
    assign(sphere, diffuse("Blue", (0.15, 0.3, 0.8)))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(40, 0, 30), angle=math.radians(1.0))
    add_camera(scene, (0, -6.0, 2.0), (0, 0, 0.5), lens=35.0)


def hdri_pixels(width=64, height=32):
    """An HDR equirectangular sky (RGBA, rows bottom first): a horizon-to-zenith gradient, a dark
    ground and a bright sun-like disk (about 5 degrees across, radiance ~60) above the horizon."""
    y, x = (np.mgrid[0:height, 0:width] + 0.5) / np.array([height, width])[:, None, None]
    elevation = (y - 0.5) * math.pi  # v = 1 at the zenith
    azimuth = math.pi - 2 * math.pi * x
    sky = np.clip(np.sin(elevation), 0.0, 1.0)[..., None]
    rgba = np.empty((height, width, 4))
    rgba[..., :3] = np.where(elevation[..., None] > 0, 0.9 * (1 - sky) * (0.7, 0.8, 1.0) + sky * (0.2, 0.35, 0.8),
                             (0.12, 0.1, 0.08))
    d = np.stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth), np.sin(elevation)], -1)
    sun = np.array([math.cos(0.6) * math.cos(2.0), math.cos(0.6) * math.sin(2.0), math.sin(0.6)])
    blob = np.clip((d @ sun - math.cos(math.radians(5.0))) / (1 - math.cos(math.radians(5.0))), 0.0, 1.0)
    rgba[..., :3] += 60.0 * blob[..., None] * (1.0, 0.9, 0.75)
    rgba[..., 3] = 1.0
    return rgba


def hdri_image(name, pixels):
    """A float image written as an OpenEXR file and loaded back (as an HDRI is), packed into the .blend."""
    h, w, _ = pixels.shape
    src = bpy.data.images.new(name + "_src", width=w, height=h, alpha=True, float_buffer=True)
    src.pixels.foreach_set(np.ascontiguousarray(pixels, np.float32).ravel())
    path = os.path.join(tempfile.mkdtemp(prefix="lantern_hdri_"), name + ".exr")
    src.filepath_raw = path
    src.file_format = "OPEN_EXR"
    src.save()
    bpy.data.images.remove(src)
    img = bpy.data.images.load(path)
    img.name = name
    img.colorspace_settings.name = "Linear"
    img.pack()
    return img


def _world_nodes(scene, name):
    world = bpy.data.worlds.new(name)
    world.use_nodes = True
    nt = world.node_tree
    nt.nodes.clear()
    world.cycles_visibility.camera = True
    scene.world = world
    return world, nt, nt.nodes.new("ShaderNodeOutputWorld")


def _world_objects(scene):
    """A diffuse sphere, a glossy sphere and a grey ground: lit by the world only."""
    ground = add_object(scene, "Ground", mesh_plane("Ground", 30.0))
    assign(ground, diffuse("Ground", (0.5, 0.5, 0.5)))
    assign(add_object(scene, "DiffuseBall", mesh_sphere("DiffuseBall", 0.5), (-0.6, 0.0, 0.5)),
           diffuse("Matte", (0.8, 0.6, 0.4)))
    assign(add_object(scene, "GlossyBall", mesh_sphere("GlossyBall", 0.5), (0.6, 0.2, 0.5)),
           glossy("Shiny", (0.9, 0.9, 0.9), 0.25))
    add_camera(scene, (0, -4.5, 1.6), (0, 0, 0.5), lens=35.0)


def build_hdri_world(scene):
    """Issue 13's HDRI world: an equirectangular EXR (a sky with a sun-like disk) through a Mapping
    node rotating about X, Y and Z, into a Background of strength 1.5."""
    world, nt, out = _world_nodes(scene, "HDRI")
    tc = nt.nodes.new("ShaderNodeTexCoord")
    mapping = _node(nt, "ShaderNodeMapping", {"Vector": tc.outputs["Generated"], "Rotation": (0.3, -0.25, 1.1)})
    env = _node(nt, "ShaderNodeTexEnvironment", {"Vector": mapping.outputs[0]}, projection="EQUIRECTANGULAR")
    env.image = hdri_image("Sky", hdri_pixels())
    bg = _node(nt, "ShaderNodeBackground", {"Color": env.outputs["Color"], "Strength": 1.5})
    nt.links.new(bg.outputs[0], out.inputs["Surface"])
    _world_objects(scene)


def build_light_path_world(scene):
    """The Light Path trick: camera rays see a grey backdrop, every other ray a warm light (a Mix
    Shader of two Backgrounds by Is Camera Ray)."""
    world, nt, out = _world_nodes(scene, "Backdrop")
    lp = nt.nodes.new("ShaderNodeLightPath")
    light = _node(nt, "ShaderNodeBackground", {"Color": (1.0, 0.75, 0.45), "Strength": 2.0})
    backdrop = _node(nt, "ShaderNodeBackground", {"Color": (0.5, 0.5, 0.5), "Strength": 1.0})
    mix = _node(nt, "ShaderNodeMixShader", {0: lp.outputs["Is Camera Ray"], 1: light.outputs[0],
                                            2: backdrop.outputs[0]})
    nt.links.new(mix.outputs[0], out.inputs["Surface"])
    _world_objects(scene)


def build_procedural_world(scene):
    """A procedural sky: a Gradient texture of the direction mixing a dark blue and a Noise
    texture's colour, into a Background of strength 1.2."""
    world, nt, out = _world_nodes(scene, "Procedural")
    tc = nt.nodes.new("ShaderNodeTexCoord")
    grad = _node(nt, "ShaderNodeTexGradient", {"Vector": tc.outputs["Generated"]}, gradient_type="LINEAR")
    noise = _node(nt, "ShaderNodeTexNoise", {"Vector": tc.outputs["Generated"], "Scale": 2.5, "Detail": 3.0})
    mix = _node(nt, "ShaderNodeMixRGB", {"Fac": grad.outputs["Fac"], "Color1": (0.05, 0.1, 0.3),
                                         "Color2": noise.outputs["Color"]})
    bg = _node(nt, "ShaderNodeBackground", {"Color": mix.outputs[0], "Strength": 1.2})
    nt.links.new(bg.outputs[0], out.inputs["Surface"])
    _world_objects(scene)


def build_nishita_world(scene):
    """Issue 13's Sky Texture lighting a scene: Blender's default Nishita sky with its sun disc
    (0.545 degrees across) at 35 degrees, behind the camera on its left, into a Background of
    strength 0.05 (the sun gives an irradiance of about 10 there), over _world_objects."""
    world, nt, out = _world_nodes(scene, "Nishita")
    sky = _node(nt, "ShaderNodeTexSky", {}, sky_type="NISHITA", sun_disc=True, sun_elevation=math.radians(35.0),
                sun_rotation=math.radians(212.0))
    bg = _node(nt, "ShaderNodeBackground", {"Color": sky.outputs["Color"], "Strength": 0.05})
    nt.links.new(bg.outputs[0], out.inputs["Surface"])
    _world_objects(scene)


def build_textured(scene):
    set_world(scene, (0.1, 0.1, 0.1), 1.0)
    checker = packed_image("Checker", checker_pixels(), "sRGB")
    rough = packed_image("RoughnessBands", roughness_pixels(), "Non-Color")
    floor = add_object(scene, "Floor", mesh_plane("Floor", 4.0))
    assign(floor, image_material("CheckerDiffuse", checker))
    cube = add_object(scene, "Cube", mesh_box("Cube", (0.8, 0.8, 0.8)), (-0.7, 0.2, 0), (0, 0, 25))
    assign(cube, floor.data.materials[0])
    panel = add_object(scene, "GlossyPanel",
                       mesh_plane("GlossyPanel", 1.6, 1.6,
                                  matrix=Matrix.Rotation(math.pi / 2, 4, "X")),
                       (0.8, 0.6, 0.8), (0, 0, -20))
    assign(panel, image_material("BandedGlossy", rough, shader="ShaderNodeBsdfGlossy",
                                 target="Roughness", Color=(0.9, 0.9, 0.9)))
    add_light(scene, "AreaLight", "AREA", 100.0, (-0.5, -1.5, 3.0), rotation=(25, 0, 0),
              shape="SQUARE", size=1.0)
    add_camera(scene, (0.3, -4.2, 2.2), (0, 0.2, 0.4), lens=40.0)


def build_normal_mapped(scene):
    """Tangent-space normal maps (an 8-bit Non-Color image through a Normal Map node into the
    Principled Normal, as Node Wrangler and glTF build it) on a diffuse ground, a rotated panel, a
    smooth sphere and a rotated metal box, under a low sun and a sky: steep bumps seen and lit at
    grazing angles, where Cycles tilts normals (ensure_valid_reflection) and darkens bumped diffuse
    closures (bump_shadowing_term)."""
    set_world(scene, (0.2, 0.25, 0.35), 1.0)
    img = packed_image("BumpNormals", normal_map_pixels(), "Non-Color")
    ground = add_object(scene, "Ground", mesh_plane("Ground", 6.0))
    assign(ground, normal_mapped_material("BumpyGround", img, (0.6, 0.55, 0.5), 0.6))
    panel = add_object(scene, "Panel", mesh_plane("Panel", 1.0), (1.0, 0.6, 0.9), (60, 0, 20))
    assign(panel, normal_mapped_material("BumpyPanel", img, (0.8, 0.3, 0.15), 0.4))
    sphere = add_object(scene, "Sphere", mesh_sphere("Sphere", 0.45), (0.1, -0.2, 0.45))
    assign(sphere, normal_mapped_material("BumpySphere", img, (0.3, 0.7, 0.35), 0.5))
    box = add_object(scene, "Box", mesh_box("Box", (0.8, 0.8, 0.8)), (-1.0, 0.4, 0), (0, 0, 30))
    assign(box, normal_mapped_material("BumpyBox", img, (0.5, 0.6, 0.9), 0.45, metallic=1.0))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(55, 0, 40), angle=math.radians(1.0))
    add_camera(scene, (0, -4.0, 1.8), (0, 0.2, 0.4), lens=40.0)


def build_tilted_metal(scene):
    """Rough metal whose normal is bent by a constant Normal Map colour (tilts of 0, 30 and 60
    degrees, roughness 0.6) on three flat tiles under a white World: Cycles' GGX sampling keeps
    reflections below the bent normal that its evaluation has not (1.2 % at 30 degrees), and it
    does not light-sample a constant World (Bsdf::sample_below_shading)."""
    set_world(scene, (1.0, 1.0, 1.0), 1.0)
    for k, tilt in enumerate((0.0, 30.0, 60.0)):
        mat = principled("Tilted%d" % k, (0.8, 0.8, 0.8), 0.6, metallic=1.0)
        nt = mat.node_tree
        nm = nt.nodes.new("ShaderNodeNormalMap")
        rgb = nt.nodes.new("ShaderNodeRGB")
        t = math.radians(tilt)
        rgb.outputs[0].default_value = (0.5 + 0.5 * math.sin(t), 0.5, 0.5 + 0.5 * math.cos(t), 1.0)
        nt.links.new(rgb.outputs[0], nm.inputs["Color"])
        nt.links.new(nm.outputs[0], nt.nodes["Principled BSDF"].inputs["Normal"])
        tile = add_object(scene, "Tile%d" % k, mesh_plane("Tile%d" % k, 1.2), ((k - 1) * 1.3, 0.0, 0.0))
        assign(tile, mat)
    add_camera(scene, (0.0, -3.4, 2.0), (0.0, 0.0, 0.0), lens=35.0)


def build_displaced(scene):
    """The Material Output's Displacement as bump (Cycles 3.4's default method): a height image
    through a Displacement node on a rough ground (UV) and a smooth sphere (Object coordinates),
    under a low sun and a sky: the bumps' lit and shadowed sides."""
    set_world(scene, (0.2, 0.25, 0.35), 1.0)
    img = packed_image("Heights", height_pixels(), "Non-Color")
    ground = add_object(scene, "Ground", mesh_plane("Ground", 6.0))
    assign(ground, displaced_material("DisplacedGround", img, (0.6, 0.55, 0.5), 0.7, 0.08))
    sphere = add_object(scene, "Sphere", mesh_sphere("Sphere", 0.6), (0.2, 0.0, 0.6), (20, 10, 30))
    assign(sphere, displaced_material("DisplacedSphere", img, (0.3, 0.6, 0.8), 0.4, 0.02, coords="Object"))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(60, 0, 40), angle=math.radians(1.0))
    add_camera(scene, (0, -4.0, 1.8), (0, 0.2, 0.4), lens=40.0)


def true_displacement_material(name, color, method, vector=False, scale=0.3, noise_scale=4.0, coords=None):
    """Noise Texture -> Displacement (its Fac as Height, Midlevel 0.5) or, with `vector`, its Color
    -> Vector Displacement (object space, Midlevel 0.5) -> the Material Output's Displacement
    beside a Principled BSDF; Material > Settings > Displacement `method` ('DISPLACEMENT' or
    'BOTH'). coords: a Texture Coordinate output for the noise (None: its default, Generated)."""
    mat, nt, out = _material(name)
    mat.cycles.displacement_method = method
    noise = nt.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = noise_scale
    noise.inputs["Detail"].default_value = 2.0
    if coords is not None:
        tc = nt.nodes.new("ShaderNodeTexCoord")
        nt.links.new(tc.outputs[coords], noise.inputs["Vector"])
    if vector:
        disp = nt.nodes.new("ShaderNodeVectorDisplacement")
        disp.space = "OBJECT"
        nt.links.new(noise.outputs["Color"], disp.inputs["Vector"])
    else:
        disp = nt.nodes.new("ShaderNodeDisplacement")
        nt.links.new(noise.outputs["Fac"], disp.inputs["Height"])
    disp.inputs["Midlevel"].default_value = 0.5
    disp.inputs["Scale"].default_value = scale
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.5
    nt.links.new(disp.outputs["Displacement"], out.inputs["Displacement"])
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return mat


def build_true_displaced(scene):
    """Cycles 3.4's true displacement (mesh_displace.cpp): a flat-shaded plane made a grid by a
    Simple Subdivision Surface modifier, Displacement Only from a Noise Texture's Fac; a smooth
    sphere (a Catmull-Clark level on top) with Displacement and Bump from its Color through
    Vector Displacement (object space); a smooth pebble with Displacement Only (its smooth normals
    recomputed); under a low sun and a sky: silhouettes, cast shadows, recomputed and bumped
    normals."""
    set_world(scene, (0.2, 0.25, 0.35), 1.0)
    ground = add_object(scene, "Ground", mesh_plane("Ground", 4.0))
    sub = ground.modifiers.new("Grid", "SUBSURF")
    sub.subdivision_type = "SIMPLE"
    sub.levels = sub.render_levels = 5
    assign(ground, true_displacement_material("TrueDisplacedGround", (0.6, 0.55, 0.5), "DISPLACEMENT", scale=0.4))
    sphere = add_object(scene, "Sphere", mesh_sphere("Sphere", 0.5, 32, 16), (0.2, 0.0, 0.7), (20, 10, 30))
    sub = sphere.modifiers.new("Smooth", "SUBSURF")
    sub.levels = sub.render_levels = 1
    assign(sphere, true_displacement_material("TrueDisplacedSphere", (0.3, 0.6, 0.8), "BOTH", vector=True,
                                              scale=0.25, noise_scale=3.0, coords="Object"))
    pebble = add_object(scene, "Pebble", mesh_sphere("Pebble", 0.3, 24, 12), (-0.9, 0.3, 0.35))
    sub = pebble.modifiers.new("Smooth", "SUBSURF")
    sub.levels = sub.render_levels = 1
    assign(pebble, true_displacement_material("TrueDisplacedPebble", (0.8, 0.5, 0.3), "DISPLACEMENT", scale=0.3,
                                              noise_scale=2.5))
    # Cycles' shadow terminator geometry offset (default 0.1) moves shadow rays off smooth
    # triangles whose normals lean away from their faces, as Displacement and Bump's undisplaced
    # normals do on displaced faces; off here, so that the test checks the displacement alone.
    for obj in (ground, sphere, pebble):
        obj.cycles.shadow_terminator_geometry_offset = 0.0
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(60, 0, 40), angle=math.radians(1.0))
    add_camera(scene, (0, -3.6, 2.2), (0, 0.2, 0.4), lens=40.0)


def build_terminator(scene, shading_offset=None):
    """Cycles' shadow terminator Geometry Offset at its default (0.1): a low-poly smooth UV sphere
    (16 segments, 8 rings) and a smooth-shaded cube on a floor, lit from low at the side by a small
    point lamp, so that the camera sees their terminators, where shadow rays from the flat
    triangles graze their neighbours. shading_offset: the objects' Shading Offset (default 0)."""
    floor = add_object(scene, "TermFloor", mesh_plane("TermFloor", 8.0))
    assign(floor, diffuse("TermFloorGrey", (0.5, 0.5, 0.5)))
    sphere = add_object(scene, "TermSphere", mesh_sphere("TermSphere", 0.5, segments=16, rings=8), (-0.6, 0.0, 0.5))
    assign(sphere, diffuse("TermSphereWhite", (0.8, 0.8, 0.8)))
    cube = add_object(scene, "TermCube", _smooth(mesh_box("TermCube", (0.7, 0.7, 0.7)), True), (0.65, 0.3, 0.0),
                      (0, 0, 30))
    assign(cube, diffuse("TermCubeOrange", (0.8, 0.5, 0.3)))
    if shading_offset is not None:
        sphere.cycles.shadow_terminator_offset = cube.cycles.shadow_terminator_offset = shading_offset
    add_light(scene, "TermLamp", "POINT", 600.0, (3.0, -1.5, 0.9), radius=0.1)
    add_camera(scene, (0.0, -4.0, 1.4), (0.0, 0.0, 0.4), lens=45.0)


def build_instanced(scene):
    set_world(scene, (0.05, 0.05, 0.05), 1.0)
    floor = add_object(scene, "Floor", mesh_plane("Floor", 10.0))
    assign(floor, diffuse("FloorGrey", (0.6, 0.6, 0.6)))
    shared = mesh_box("SharedBox", (0.5, 0.5, 0.5))
    shared.materials.append(diffuse("SharedGreen", (0.2, 0.6, 0.25)))
    # Alt+D duplicates: three objects, one mesh datablock (one non-uniformly scaled).
    add_object(scene, "Box.A", shared, (-1.2, 0.0, 0), (0, 0, 10))
    add_object(scene, "Box.B", shared, (-0.4, 0.8, 0), (0, 0, 40), (1.0, 1.0, 2.0))
    add_object(scene, "Box.C", shared, (-1.4, 1.2, 0.5), (30, 20, 0), (0.8, 0.8, 0.8))
    # A collection instanced twice by empties; the collection itself is not in the scene.
    group = bpy.data.collections.new("InstancedGroup")
    group.instance_offset = (0, 0, 0)
    sph = add_object(scene, "GroupSphere", mesh_sphere("GroupSphere", 0.3), (0, 0, 0.3),
                     collection=group)
    assign(sph, diffuse("GroupOrange", (0.85, 0.4, 0.1)))
    cone = add_object(scene, "GroupCone", mesh_cone("GroupCone", 0.25, 0.7), (0.5, 0, 0),
                      collection=group)
    assign(cone, diffuse("GroupBlue", (0.15, 0.25, 0.8)))
    for name, loc, rot, scale in (("GroupInstance.A", (0.6, -0.3, 0), (0, 0, 0), 1.0),
                                  ("GroupInstance.B", (0.9, 0.9, 0), (0, 0, 70), 1.3)):
        empty = add_object(scene, name, None, loc, rot, (scale,) * 3)
        empty.instance_type = "COLLECTION"
        empty.instance_collection = group
    add_light(scene, "AreaLight", "AREA", 150.0, (0.5, -1.0, 3.0), rotation=(15, 0, 0),
              shape="DISK", size=1.2)
    add_camera(scene, (0, -4.5, 2.5), (0, 0.3, 0.3), lens=40.0)


def build_door(scene, lamp_up=False):
    """A door ajar (the scene of Veach & Guibas 1997, "Metropolis light transport"): two rooms side
    by side, the lamp in the lit one (x > 0), the camera in the other. The partition's doorway is
    closed by a door opened by 6 degrees: light reaches the camera's room only through the 8 cm gap
    at the door's free edge, so next-event estimation from there is almost always occluded. The
    lamp hangs under the ceiling facing down, so some of its light shines straight through the gap
    onto the camera's room; with lamp_up it faces the ceiling from 0.5 m below, so every path
    through the gap has bounced in the lit room first."""
    white = diffuse("DoorWhite", (0.75, 0.75, 0.75))
    w, d, h = 4.0, 3.0, 2.5  # both rooms together: x in [-2, 2], y in [-1.5, 1.5], z in [0, 2.5]
    walls = [  # the +Z unit plane moved into place, normals inward
        ("Floor", (w, d), Matrix.Identity(4)),
        ("Ceiling", (w, d), Matrix.Translation((0, 0, h)) @ Matrix.Rotation(math.pi, 4, "X")),
        ("South", (w, h), Matrix.Translation((0, -d / 2, h / 2)) @ Matrix.Rotation(-math.pi / 2, 4, "X")),
        ("North", (w, h), Matrix.Translation((0, d / 2, h / 2)) @ Matrix.Rotation(math.pi / 2, 4, "X")),
        ("West", (h, d), Matrix.Translation((-w / 2, 0, h / 2)) @ Matrix.Rotation(math.pi / 2, 4, "Y")),
        ("East", (h, d), Matrix.Translation((w / 2, 0, h / 2)) @ Matrix.Rotation(-math.pi / 2, 4, "Y")),
    ]
    for name, (sx, sy), m in walls:
        assign(add_object(scene, "Door" + name, mesh_plane("Door" + name, sx, sy, matrix=m)), white)
    # The partition: x in [-0.05, 0.05], a doorway at y in [0.2, 1.0], z in [0, 2].
    t, y0, y1, dh = 0.1, 0.2, 1.0, 2.0
    south, north = y0 + d / 2, d / 2 - y1
    for name, size, loc in (("PartitionSouth", (t, south, h), (0, -d / 2 + south / 2, 0)),
                            ("PartitionNorth", (t, north, h), (0, d / 2 - north / 2, 0)),
                            ("Lintel", (t, y1 - y0, h - dh), (0, (y0 + y1) / 2, dh))):
        assign(add_object(scene, name, mesh_box(name, size), loc), white)
    # The door (4 cm thick) hinged at the doorway's north edge on the lit side, (0.05, 1.0), and
    # turned into the lit room: its free edge stands 0.8 sin(6 deg) = 8.4 cm off the wall.
    angle, thick, width = math.radians(6.0), 0.04, y1 - y0
    cx, cy = thick / 2, -width / 2  # the door's centre relative to the hinge, closed
    loc = (t / 2 + cx * math.cos(angle) - cy * math.sin(angle), y1 + cx * math.sin(angle) + cy * math.cos(angle), 0)
    assign(add_object(scene, "Door", mesh_box("Door", (thick, width, dh)), loc, (0, 0, 6.0)),
           diffuse("DoorWood", (0.6, 0.45, 0.3)))
    assign(add_object(scene, "Crate", mesh_box("Crate", (0.6, 0.6, 0.6)), (-1.2, 0.8, 0), (0, 0, 20)),
           diffuse("DoorCrate", (0.7, 0.5, 0.3)))
    if lamp_up:
        add_light(scene, "LitRoomLight", "AREA", 1000.0, (1.0, 0.0, 2.0), (180, 0, 0), shape="SQUARE", size=0.5)
    else:
        add_light(scene, "LitRoomLight", "AREA", 1000.0, (1.0, 0.0, 2.45), shape="SQUARE", size=0.5)
    add_camera(scene, (-1.9, -1.3, 1.5), (0.0, 0.5, 0.9), lens=22.0)


def build_door_bounce(scene):
    """The door ajar with the lamp facing the ceiling: the camera's room is lit only by light that
    bounced in the lit room before passing the gap."""
    build_door(scene, lamp_up=True)


def diffuse_glossy_mix(name, color, fac, roughness):
    """Mix Shader of a Diffuse BSDF (fac 0) and a GGX Glossy BSDF (fac 1) of the same colour: a
    BSDF with lobes of two kinds, as the Principled BSDF's diffuse and specular."""
    mat, nt, out = _material(name)
    mix = nt.nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = fac
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*color, 1.0)
    d.inputs["Roughness"].default_value = 0.0
    g = nt.nodes.new("ShaderNodeBsdfGlossy")
    g.distribution = "GGX"
    g.inputs["Color"].default_value = (*color, 1.0)
    g.inputs["Roughness"].default_value = roughness
    nt.links.new(d.outputs[0], mix.inputs[1])
    nt.links.new(g.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs["Surface"])
    mat.diffuse_color = (*color, 1.0)
    return mat


def build_door_slabs(scene):
    """Issue 12, item 4: the two rooms built of thick slabs whose ends overlap (the floor and
    ceiling span the walls' footprint, the walls reach into them and into each other at the
    corners, the partition into the outer walls, floor and ceiling), the camera in one room, a
    1 x 0.8 m rectangular lamp under the ceiling of the other facing down, the door between them
    opened 8 degrees and a GGX (roughness 0.2) ball near the gap. The walls are mostly diffuse: a
    Mix of Diffuse and Glossy (fac 0.3). With Cycles' default bounce limits a bounce on them counts
    as diffuse or glossy by the lobe a sample picked (pure Diffuse walls make that question moot:
    there BDPT agreed with the path tracer already). tests/native/test_bdpt.cpp builds the same
    scene (DoorSlabsBounceKindsAgreeWithPathTracing)."""
    white = diffuse_glossy_mix("SlabWall", (0.75, 0.75, 0.75), 0.3, 0.5)
    w, d, h, t = 2.0, 1.5, 2.5, 0.2  # half width, half depth, height of the rooms; slab thickness

    def slab(name, lo, hi, material=white):
        size = tuple(b - a for a, b in zip(lo, hi))
        centre = tuple((a + b) / 2 for a, b in zip(lo, hi))
        assign(add_object(scene, name, mesh_box(name, size, origin_at_bottom=False), centre), material)

    slab("SlabFloor", (-w - t, -d - t, -t), (w + t, d + t, 0))
    slab("SlabCeiling", (-w - t, -d - t, h), (w + t, d + t, h + t))
    slab("SlabSouth", (-w - t, -d - t, -t), (w + t, -d, h + t))
    slab("SlabNorth", (-w - t, d, -t), (w + t, d + t, h + t))
    slab("SlabWest", (-w - t, -d - t, -t), (-w, d + t, h + t))
    slab("SlabEast", (w, -d - t, -t), (w + t, d + t, h + t))
    # The partition x in [-0.05, 0.05] with a doorway at y in [0.2, 1.0], z < 2.
    pt, y0, y1, dh, e = 0.1, 0.2, 1.0, 2.0, 0.1
    slab("SlabPartitionSouth", (-pt / 2, -d - e, -e), (pt / 2, y0, h + e))
    slab("SlabPartitionNorth", (-pt / 2, y1, -e), (pt / 2, d + e, h + e))
    slab("SlabLintel", (-pt / 2, y0 - e, dh), (pt / 2, y1 + e, h + e))
    # The door (4 cm thick) hinged at (0.05, 1.0), turned 8 degrees into the lit room (x > 0).
    angle, thick, width = math.radians(8.0), 0.04, y1 - y0
    cx, cy = thick / 2, -width / 2  # the door's centre relative to the hinge, closed
    loc = (pt / 2 + cx * math.cos(angle) - cy * math.sin(angle), y1 + cx * math.sin(angle) + cy * math.cos(angle),
           0)
    assign(add_object(scene, "SlabDoor", mesh_box("SlabDoor", (thick, width, dh - 0.005)), loc, (0, 0, 8.0)),
           diffuse("SlabDoorWood", (0.6, 0.45, 0.3)))
    slab("SlabCrate", (-1.5, 0.5, 0), (-0.9, 1.1, 0.6), diffuse("SlabCrateWood", (0.7, 0.5, 0.3)))
    assign(add_object(scene, "SlabBall", mesh_sphere("SlabBall", 0.3), (-0.6, 0.2, 0.3)),
           glossy("SlabBallGGX", (0.8, 0.8, 0.8), 0.2))
    add_light(scene, "SlabLamp", "AREA", 1000.0, (1.0, 0.0, h - 0.05), shape="RECTANGLE", size=1.0, size_y=0.8)
    add_camera(scene, (-1.9, -1.3, 1.5), (0.0, 0.5, 0.9), lens=22.0)


def build_caustic(scene):
    """A smooth glass sphere on a diffuse floor under a small light: its caustic is reached by
    path tracing only through the glass, by chance."""
    set_world(scene, (0.02, 0.02, 0.03), 1.0)
    floor = add_object(scene, "Floor", mesh_plane("Floor", 6.0))
    assign(floor, diffuse("CausticFloor", (0.7, 0.7, 0.7)))
    ball = add_object(scene, "GlassBall", mesh_sphere("GlassBall", 0.5, segments=64, rings=32), (0, 0, 0.5))
    assign(ball, glass("CausticGlass", (1.0, 1.0, 1.0), 0.0, ior=1.5))
    # A small disk area light rather than a point light with a radius: Cycles 3.4 draws the latter
    # as a disk facing each receiver, which no light subpath can start from (see README).
    add_light(scene, "SmallLight", "AREA", 60.0, (0.6, 0.3, 2.6), shape="DISK", size=0.12)
    add_camera(scene, (0, -3.5, 2.2), (0, 0.1, 0.25), lens=40.0)


def build_unsupported_node(scene):
    """Nodes Lantern does not render: Point Density → Diffuse colour (material
    "PointDensityMaterial") and EEVEE's Specular BSDF ("SpecularMaterial"; Cycles has no node for it)."""
    set_world(scene, (0.1, 0.1, 0.1), 1.0)
    floor = add_object(scene, "Floor", mesh_plane("Floor", 10.0))
    assign(floor, diffuse("FloorGrey", (0.6, 0.6, 0.6)))
    mat, nt, out = _material("PointDensityMaterial")
    density = nt.nodes.new("ShaderNodeTexPointDensity")
    density.name = density.label = "Point Density"
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    nt.links.new(density.outputs["Color"], bsdf.inputs["Color"])
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    assign(add_object(scene, "DensitySphere", mesh_sphere("DensitySphere", 0.5), (-0.6, 0, 0.5)), mat)
    spec = _bsdf_material("SpecularMaterial", "ShaderNodeEeveeSpecular", None, **{"Base Color": (0.8, 0.3, 0.3, 1.0)})
    assign(add_object(scene, "SpecularSphere", mesh_sphere("SpecularSphere", 0.5), (0.6, 0, 0.5)), spec)
    add_light(scene, "AreaLight", "AREA", 100.0, (0, -1.0, 3.0), shape="SQUARE", size=1.0)
    add_camera(scene, (0, -4.0, 1.8), (0, 0, 0.4), lens=40.0)


# name: (builder, resolution, Cycles samples)
def volume_material(name, density, color=(1.0, 1.0, 1.0), anisotropy=0.0,
                    absorption_color=(0.0, 0.0, 0.0)):
    """A material with only a Principled Volume on the Volume output: an invisible boundary."""
    mat, nt, out = _material(name)
    vol = nt.nodes.new("ShaderNodeVolumePrincipled")
    vol.inputs["Density"].default_value = density
    vol.inputs["Color"].default_value = (*color, 1.0)
    vol.inputs["Anisotropy"].default_value = anisotropy
    vol.inputs["Absorption Color"].default_value = (*absorption_color, 1.0)
    nt.links.new(vol.outputs[0], out.inputs["Volume"])
    return mat


def build_smoke_box(scene):
    """The area-lit Cornell box with a homogeneous smoke cube (density 2, no surface shader)."""
    build_cornell_area(scene)
    smoke = volume_material("Smoke", 2.0, color=(0.8, 0.8, 0.8), anisotropy=0.3)
    assign(add_object(scene, "SmokeCube", mesh_box("SmokeCube", (0.6, 0.6, 0.6)), (0.2, -0.45, 0.7)),
           smoke)


def _volume_node(nt, kind, color, density, anisotropy=0.0):
    node = nt.nodes.new(kind)
    node.inputs["Color"].default_value = (*color, 1.0)
    node.inputs["Density"].default_value = density
    if "Anisotropy" in node.inputs:
        node.inputs["Anisotropy"].default_value = anisotropy
    return node


def _volume_box(scene, mat):
    """The area-lit Cornell box with a 0.7 m cube of `mat` (a volume-only material)."""
    build_cornell_area(scene)
    assign(add_object(scene, "VolumeCube", mesh_box("VolumeCube", (0.7, 0.7, 0.7)), (0.2, -0.45, 0.7)), mat)


def build_volume_add(scene):
    """A cube whose Volume output is Add Shader(Volume Scatter, Volume Absorption): the usual Cycles
    way to set scattering and absorption apart (issue 12 item 2)."""
    mat, nt, out = _material("AddVolume")
    scatter = _volume_node(nt, "ShaderNodeVolumeScatter", (0.9, 0.7, 0.5), 2.5, anisotropy=0.4)
    absorb = _volume_node(nt, "ShaderNodeVolumeAbsorption", (0.6, 0.8, 0.9), 1.5)
    add = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(scatter.outputs[0], add.inputs[0])
    nt.links.new(absorb.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], out.inputs["Volume"])
    _volume_box(scene, mat)


VOLUME_MIX = dict(fac=0.35, g_a=0.8, g_b=-0.5, color_a=0.9, color_b=0.6, density=4.0)


def build_volume_mix(scene):
    """A cube whose Volume output is Mix Shader(0.35, Volume Scatter g = 0.8, Volume Scatter
    g = -0.5), both of density 4, grey colours 0.9 and 0.6 (so the lobes' weights are the same in
    every channel), in the area-lit Cornell box (VOLUME_MIX holds the parameters)."""
    p = VOLUME_MIX
    mat, nt, out = _material("MixVolume")
    a = _volume_node(nt, "ShaderNodeVolumeScatter", (p["color_a"],) * 3, p["density"], anisotropy=p["g_a"])
    b = _volume_node(nt, "ShaderNodeVolumeScatter", (p["color_b"],) * 3, p["density"], anisotropy=p["g_b"])
    mix = nt.nodes.new("ShaderNodeMixShader")
    mix.inputs[0].default_value = p["fac"]
    nt.links.new(a.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs["Volume"])
    _volume_box(scene, mat)


def build_volume_emission(scene, blackbody=False):
    """A cube of emissive Principled Volume (density 0.8, emission colour x strength, or blackbody
    at 2500 K) in the Cornell box under a dim area light."""
    mat, nt, out = _material("GlowVolume")
    vol = _volume_node(nt, "ShaderNodeVolumePrincipled", (0.7, 0.7, 0.7), 0.8, anisotropy=0.2)
    if blackbody:
        vol.inputs["Blackbody Intensity"].default_value = 1.0
        vol.inputs["Temperature"].default_value = 2500.0
    else:
        vol.inputs["Emission Strength"].default_value = 1.5
        vol.inputs["Emission Color"].default_value = (1.0, 0.5, 0.2, 1.0)
    nt.links.new(vol.outputs[0], out.inputs["Volume"])
    cornell_box(scene)
    add_light(scene, "AreaLight", "AREA", 10.0, (0, 0, 1.98), shape="SQUARE", size=0.5)
    assign(add_object(scene, "VolumeCube", mesh_box("VolumeCube", (0.7, 0.7, 0.7)), (0.2, -0.45, 0.7)), mat)


def build_volume_blackbody(scene):
    build_volume_emission(scene, blackbody=True)


def _fog_room(scene, density):
    """The area-lit Cornell box filled by a fog cube slightly smaller than the room."""
    build_cornell_area(scene)
    fog = volume_material("Fog%g" % density, density, color=(0.9, 0.9, 0.9))
    assign(add_object(scene, "Fog", mesh_box("Fog", (1.9, 1.9, 1.9)), (0.0, 0.0, 0.02)), fog)


def build_thin_fog(scene):
    _fog_room(scene, 0.1)


def build_dense_fog(scene):
    _fog_room(scene, 1.5)


def build_world_fog(scene):
    """A ground plane, a sphere, a point light and a sun in a World volume (Principled Volume,
    density 0.15, anisotropy 0.3). As in Cycles 3.4 the background and the sun are fully hidden
    (escaped rays and sun shadow rays cross the world volume to infinity): only the point light
    lights the ground and the fog."""
    world = set_world(scene, (0.3, 0.45, 0.7), 1.0)
    nt = world.node_tree
    vol = nt.nodes.new("ShaderNodeVolumePrincipled")
    vol.inputs["Density"].default_value = 0.15
    vol.inputs["Color"].default_value = (0.9, 0.8, 0.7, 1.0)
    vol.inputs["Anisotropy"].default_value = 0.3
    nt.links.new(vol.outputs[0], nt.get_output_node('CYCLES').inputs["Volume"])
    ground = add_object(scene, "Ground", mesh_plane("Ground", 8.0))
    assign(ground, diffuse("Ground", (0.6, 0.6, 0.55)))
    sphere = add_object(scene, "Sphere", mesh_sphere("Sphere", 0.5), (0.5, 0.3, 0.5))
    assign(sphere, diffuse("Blue", (0.15, 0.3, 0.8)))
    add_light(scene, "Lamp", "POINT", 300.0, (-0.6, -0.4, 1.8))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(40, 0, 30))
    add_camera(scene, (0, -5.0, 1.5), (0, 0, 0.8), lens=30.0)

# ---- OpenVDB scenes ---------------------------------------------------------------------------
# The .vdb files are written at build time by tests/scenes/make_test_vdb.cpp into <build>/test_vdb;
# LANTERN_TEST_VDB_DIR names that directory (scripts/run_tests.sh exports it). examples.blend points
# its Volume objects at "//assets/<file>" instead (write_examples; scripts/render_examples.sh copies
# the files there before rendering).


def test_vdb_path(filename):
    """Absolute path of a generated test .vdb (LANTERN_TEST_VDB_DIR, default <repo>/build/test_vdb)."""
    directory = os.environ.get("LANTERN_TEST_VDB_DIR") or os.path.join(REPO, "build", "test_vdb")
    return os.path.join(directory, filename)


def add_vdb_volume(scene, name, filename, material, location=(0, 0, 0), rotation=(0, 0, 0),
                   scale=(1, 1, 1)):
    """A Volume object reading the generated `filename` (grid "density"), with `material`. Render
    step size 0 (auto: one voxel), object space, as Cycles' defaults."""
    vol = bpy.data.volumes.new(name)
    vol.filepath = test_vdb_path(filename)
    vol.render.space = "OBJECT"
    vol.render.step_size = 0.0
    vol.materials.append(material)
    obj = add_object(scene, name, vol, location, rotation, scale)
    return obj


def build_vdb_cloud(scene):
    """cloud.vdb (a few noisy blobs, 48^3 voxels of 4 cm, density 0..1 x 5) with a white Principled
    Volume under a sun and a blue-grey world; Cycles ray-marches it at a quarter voxel
    (volume_step_rate 0.25), two volume bounces."""
    set_world(scene, (0.35, 0.45, 0.6), 0.8)
    cloud = volume_material("CloudVolume", 5.0, color=(1.0, 1.0, 1.0), anisotropy=0.0)
    add_vdb_volume(scene, "Cloud", "cloud.vdb", cloud, (0, 0, 1.0))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(50, 0, 40), angle=math.radians(1.0))
    add_camera(scene, (0, -4.2, 1.4), (0, 0, 1.0), lens=80.0)
    scene.cycles.volume_step_rate = 0.25
    scene.cycles.volume_max_steps = 4096
    scene.cycles.volume_bounces = 2


def build_vdb_cloud_scaled(scene):
    """vdb_cloud's grid in a Volume object scaled unevenly to about half its size (render space
    Object, Blender's default: density 1 per object-space unit, so Cycles renders it as dense as
    unscaled, 1 / |M n| times per metre for n the unit diagonal), read through the Principled
    Volume's Density Attribute 'cloud' of a file whose 'density' grid is a different shape."""
    build_vdb_cloud(scene)
    cloud = scene.objects["Cloud"]
    cloud.scale = (0.8, 0.5, 0.3)
    cloud.data.filepath = test_vdb_path("two_grids.vdb")
    volume = cloud.active_material.node_tree.nodes["Principled Volume"]
    volume.inputs["Density Attribute"].default_value = "cloud"
    volume.inputs["Density"].default_value = 1.0  # thin: the image mean follows the density
    scene.camera.data.lens = 140.0


def build_vdb_smoke(scene):
    """smoke.vdb (a rising noisy plume, 40x40x64 voxels of 3 cm) on a grey floor under a sun."""
    set_world(scene, (0.4, 0.45, 0.55), 0.6)
    floor = add_object(scene, "Floor", mesh_plane("Floor", 10.0))
    assign(floor, diffuse("Floor", (0.5, 0.5, 0.5)))
    smoke = volume_material("SmokeVolume", 12.0, color=(0.7, 0.7, 0.7), anisotropy=0.2)
    add_vdb_volume(scene, "Smoke", "smoke.vdb", smoke, (0, 0, 0.0))
    add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(45, 0, -35), angle=math.radians(1.0))
    add_camera(scene, (0, -3.0, 1.0), (0, 0, 0.9), lens=55.0)
    scene.cycles.volume_step_rate = 0.5
    scene.cycles.volume_bounces = 1


def build_vdb_fire(scene):
    """fire.vdb (density, flame, temperature; 24x24x32 voxels of 5 cm) as a Volume object whose
    Principled Volume emits from its grids: Emission Strength from an Attribute node 'flame'
    (orange, colour above 1), blackbody from the Temperature Attribute 'temperature' x 2000 K (so
    0 to 2400 K, mostly below 1900 K, where Cycles 3.4's Principled Volume emits negative green and
    blue); grey smoke of density 2 around it, a dark blue world, one volume bounce."""
    set_world(scene, (0.01, 0.012, 0.02), 1.0)
    mat, nt, out = _material("FireVolume")
    vol = nt.nodes.new("ShaderNodeVolumePrincipled")
    vol.inputs["Density"].default_value = 2.0
    vol.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    vol.inputs["Emission Color"].default_value = (6.0, 2.7, 0.6, 1.0)
    vol.inputs["Blackbody Intensity"].default_value = 1.0
    vol.inputs["Temperature"].default_value = 2000.0
    vol.inputs["Temperature Attribute"].default_value = "temperature"
    flame = nt.nodes.new("ShaderNodeAttribute")
    flame.attribute_name = "flame"
    nt.links.new(flame.outputs["Fac"], vol.inputs["Emission Strength"])
    nt.links.new(vol.outputs[0], out.inputs["Volume"])
    add_vdb_volume(scene, "Fire", "fire.vdb", mat, (0, 0, 0.0))
    add_camera(scene, (0, -3.2, 0.8), (0, 0, 0.75), lens=60.0)
    scene.cycles.volume_step_rate = 0.25
    scene.cycles.volume_max_steps = 4096
    scene.cycles.volume_bounces = 1


def build_world_glow(scene):
    """A World volume that emits: Principled Volume of density 0.3 (white scattering) with Emission
    Strength 0.4, colour (1, 0.6, 0.3), over a diffuse ground and sphere; no lamps, a black world
    (escaped rays see none of it anyway)."""
    world = set_world(scene, (0.0, 0.0, 0.0), 1.0)
    nt = world.node_tree
    vol = nt.nodes.new("ShaderNodeVolumePrincipled")
    vol.inputs["Density"].default_value = 0.3
    vol.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    vol.inputs["Emission Strength"].default_value = 0.4
    vol.inputs["Emission Color"].default_value = (1.0, 0.6, 0.3, 1.0)
    nt.links.new(vol.outputs[0], nt.get_output_node('CYCLES').inputs["Volume"])
    ground = add_object(scene, "Ground", mesh_plane("Ground", 8.0))
    assign(ground, diffuse("Ground", (0.6, 0.6, 0.55)))
    sphere = add_object(scene, "Sphere", mesh_sphere("Sphere", 0.5), (0.3, 0.3, 0.5))
    assign(sphere, diffuse("Blue", (0.15, 0.3, 0.8)))
    add_camera(scene, (0, -5.0, 1.5), (0, 0, 0.6), lens=35.0)
    scene.cycles.volume_bounces = 0


def build_smoke_interior(scene):
    """A closed room (6 x 6 x 4 m) filled with thin homogeneous smoke; the sun enters through a
    window in the left wall and draws a shaft of light across the smoke (like the sheet's
    a05_sibenik_smoke)."""
    set_world(scene, (0.5, 0.6, 0.8), 1.0)
    wall = diffuse("Wall", (0.7, 0.68, 0.62))
    t = 0.2
    parts = [("Floor", (6.4, 6.4, t), (0, 0, -t)), ("Ceiling", (6.4, 6.4, t), (0, 0, 4.0)),
             ("Back", (6.4, t, 4.0), (0, 3.0 + t / 2, 0)), ("Front", (6.4, t, 4.0), (0, -3.0 - t / 2, 0)),
             ("Right", (t, 6.0, 4.0), (3.0 + t / 2, 0, 0)),
             # the left wall around a window: y in [-0.8, 1.2], z in [1.2, 3.0]
             ("LeftLow", (t, 6.0, 1.2), (-3.0 - t / 2, 0, 0)), ("LeftHigh", (t, 6.0, 1.0), (-3.0 - t / 2, 0, 3.0)),
             ("LeftA", (t, 2.2, 1.8), (-3.0 - t / 2, -1.9, 1.2)), ("LeftB", (t, 1.8, 1.8), (-3.0 - t / 2, 2.1, 1.2))]
    for name, size, loc in parts:
        assign(add_object(scene, name, mesh_box(name, size), loc), wall)
    column = add_object(scene, "Column", mesh_box("Column", (0.5, 0.5, 4.0)), (0.6, 0.8, 0))
    assign(column, diffuse("Column", (0.6, 0.55, 0.5)))
    smoke = volume_material("RoomSmoke", 0.2, color=(0.9, 0.9, 0.9), anisotropy=0.4)
    assign(add_object(scene, "RoomSmoke", mesh_box("RoomSmoke", (5.98, 5.98, 3.98)), (0, 0, 0.01)), smoke)
    add_light(scene, "Sun", "SUN", 8.0, (0, 0, 8), rotation=(55, 0, -70), angle=math.radians(0.5))
    add_camera(scene, (1.8, -2.7, 1.5), (-1.2, 1.0, 1.4), lens=22.0)
    scene.cycles.volume_bounces = 1


# ---- Scenes from the models in models/ (the exercise sheet's a05_sibenik and a05_spz) ----------
# The OBJ files are stored gzip-compressed with their SOURCE.md notes (authors, licences) in
# models/<name>/; they are decompressed to a temporary folder and read by Blender's own OBJ
# importer (3.4: the C++ importer, bpy.ops.wm.obj_import). Both models are +Y up; the importer
# turns them to Blender's +Z up with an object rotation. Only examples.blend uses them (the test
# scenes above need no files).
MODELS = os.path.join(REPO, "models")


def import_obj(name, rewrite=None):
    """Imports models/<name>/<name>.obj.gz (its .mtl and textures from the same folder) and returns
    the imported objects. `rewrite(line)` may change each line of the OBJ text on the way (returns
    the line to write, or None to drop it). Images keep the paths of the model's own texture files
    (write_examples makes them relative to examples.blend: //models/<name>/textures/...)."""
    import gzip
    import tempfile

    folder = os.path.join(MODELS, name)
    before = set(bpy.data.objects)
    with tempfile.TemporaryDirectory(prefix="lantern_obj_") as tmp:
        obj_path = os.path.join(tmp, name + ".obj")
        with gzip.open(os.path.join(folder, name + ".obj.gz"), "rt") as src, \
                open(obj_path, "w") as dst:
            for line in src:
                line = rewrite(line) if rewrite else line
                if line is not None:
                    dst.write(line)
        # The importer looks for the .mtl beside the .obj and for textures relative to the .mtl.
        for entry in os.listdir(folder):
            if entry.endswith(".mtl") or entry == "textures":
                os.symlink(os.path.join(folder, entry), os.path.join(tmp, entry))
        bpy.ops.wm.obj_import(filepath=obj_path, forward_axis="NEGATIVE_Z", up_axis="Y",
                              validate_meshes=True)
        imported = [o for o in bpy.data.objects if o not in before]
        for image in {n.image for o in imported for m in o.data.materials if m and m.node_tree
                      for n in m.node_tree.nodes if n.type == "TEX_IMAGE" and n.image}:
            loaded = bpy.path.abspath(image.filepath)
            if os.path.commonpath([loaded, tmp]) == tmp:  # found through the symlinks above
                image.filepath = os.path.join(folder, os.path.relpath(loaded, tmp))
    for obj in imported:
        set_visibility(obj)
    return imported


def _collection(name, objects):
    coll = bpy.data.collections.new(name)
    for obj in objects:
        for c in obj.users_collection:
            c.objects.unlink(obj)
        coll.objects.link(obj)
    return coll


def import_sibenik():
    """The Sibenik cathedral (models/sibenik) in a collection "Sibenik" (imported once per file and
    shared by the scenes that link it): floor at z = 0, the nave along +X from the rose window
    (west front, x = -19.8) to the apse. What is changed in the importer's materials:
    - Transmission 0 everywhere: Blender 3.4's importer reads the MTL transmission filter `Tf 1 1 1`
      as a Principled Transmission weight of 1, which would turn the stone into glass; alpha 1
      (opaque) for the window glass (`d` < 1), which Lantern does not support, so the coloured
      panes of the rose window are glossy and opaque;
    - the bump maps are dropped: the importer reads `map_bump` height maps as tangent-space normal
      maps (and Lantern ignores normal maps anyway)."""
    coll = bpy.data.collections.get("Sibenik")
    if coll is not None:
        return coll
    objects = import_obj("sibenik")
    for obj in objects:
        obj.location.z += 15.15  # the nave floor is at y = -15.15 in the OBJ
    for mat in {m for o in objects for m in o.data.materials if m}:
        nt = mat.node_tree
        for node in [n for n in nt.nodes if n.type == "NORMAL_MAP"]:
            for link in node.inputs["Color"].links:
                nt.nodes.remove(link.from_node)
            nt.nodes.remove(node)
        for node in nt.nodes:
            if node.type == "BSDF_PRINCIPLED":
                node.inputs["Transmission"].default_value = 0.0
                node.inputs["Alpha"].default_value = 1.0
        mat.blend_method = "OPAQUE"
    return _collection("Sibenik", objects)


# Sponza (models/sponza) has no materials: a diffuse colour per OBJ group; groups not listed here
# (arches, pillars and their bases, the object* parts of the colonnades) are the light stone.
SPONZA_STONE = (0.62, 0.57, 0.48)
SPONZA_COLOURS = {
    "floors": (0.42, 0.36, 0.30),  # the courtyard and the galleries' floors
    "walls": (0.66, 0.58, 0.46), "ceiling": (0.55, 0.50, 0.42), "outside01": (0.55, 0.50, 0.42),
    "doors": (0.30, 0.17, 0.08), "windows": (0.30, 0.17, 0.08),
    "parapet": (0.50, 0.45, 0.38), "relief": (0.50, 0.45, 0.38),
}


def import_sponza():
    """The Dabrovic Sponza atrium (models/sponza) in a collection "Sponza": the courtyard floor
    near z = 0, the atrium along X, open to the sky. Each named OBJ group (`g name`) is turned into `usemtl name`
    on the way (Blender 3.4's importer ignores groups), and each of the resulting material slots
    gets a Diffuse BSDF from SPONZA_COLOURS. The OBJ's UVs and normals are dropped (below)."""
    coll = bpy.data.collections.get("Sponza")
    if coll is not None:
        return coll

    def group_to_material(line):
        if line.startswith("g"):
            words = line.split()
            return "usemtl %s\n" % words[1] if len(words) > 1 and words[0] == "g" else None
        return line

    objects = import_obj("sponza", group_to_material)
    for obj in objects:
        me = obj.data
        while me.uv_layers:  # untextured: its UVs would only take room in examples.blend
            me.uv_layers.remove(me.uv_layers[0])
        # The OBJ's vertex normals face away from the winding of about 7,500 of its triangles
        # (faces flipped in the original export). Cycles still lights those faces, Lantern shades
        # them dark (measured with the OBJ's normals: dark bands under the nearest arches, image
        # mean Lantern/Cycles 0.98; 1.00 with these). Blender's own normals follow the faces:
        # smooth up to 40 degrees.
        with bpy.context.temp_override(object=obj, active_object=obj, selected_objects=[obj]):
            bpy.ops.mesh.customdata_custom_splitnormals_clear()
        me.use_auto_smooth = True
        me.auto_smooth_angle = math.radians(40.0)
        for i, old in enumerate(me.materials):
            me.materials[i] = diffuse("spz_" + old.name, SPONZA_COLOURS.get(old.name, SPONZA_STONE))
            bpy.data.materials.remove(old)
    return _collection("Sponza", objects)


def build_sibenik(scene):
    """The Sibenik cathedral lit by a lamp inside (the sheet's a05_sibenik): a small point lamp
    high in the nave, a black world; the camera at the west end looks down the nave to the apse."""
    scene.collection.children.link(import_sibenik())
    add_light(scene, "Lamp", "POINT", 1500.0, (-2.0, 0.0, 7.0), radius=0.25)
    add_camera(scene, (-17.0, 0.0, 3.0), (10.0, 0.0, 5.5), lens=18.0)


def build_sibenik_smoke(scene):
    """a05_sibenik filled with thin homogeneous smoke (the sheet's a05_sibenik_smoke, its Figure 3):
    a box covering the interior with a Principled Volume (no surface), density 0.06 per metre."""
    build_sibenik(scene)
    smoke = volume_material("CathedralSmoke", 0.06, color=(0.9, 0.9, 0.9), anisotropy=0.3)
    box = add_object(scene, "Smoke", mesh_box("Smoke", (39.0, 16.0, 28.0)), (-0.5, 0.0, 0.02))
    assign(box, smoke)
    scene.cycles.volume_bounces = 1


def build_sponza(scene):
    """The Sponza atrium under a sun and a blue sky through its open roof (the sheet's a05_spz)."""
    scene.collection.children.link(import_sponza())
    set_world(scene, (0.45, 0.6, 0.9), 1.0)
    add_light(scene, "Sun", "SUN", 5.0, (0, 0, 20), rotation=(30, 0, 100), angle=math.radians(0.5))
    add_camera(scene, (-13.5, 0.0, 1.6), (10.0, 0.0, 4.0), lens=18.0)


def build_sponza_motion(scene):
    """Sponza (build_sponza) with a default-sized area lamp and every kind of motion issue 15
    names, over a shutter of 1 frame at frame 1 (keys at frames 0 and 2): a box sliding 2.8 m, a
    box turning 90 degrees, a grid bulging (deformation blur) and the camera panning 4 degrees.
    Motion blur's cost on a real model (bench/feature_cost.py)."""
    build_sponza(scene)
    add_light(scene, "Lamp", "AREA", 800.0, (-6.0, 0.0, 4.5), size=1.0)
    slider = add_object(scene, "Sliding", mesh_box("Sliding", (0.8, 0.8, 0.8)), (-7.0, -1.0, 1.1))
    assign(slider, diffuse("SlidingRed", RED))
    _keyframes(slider, "location", [(-7.0, -1.0, 1.1), (-5.0, 1.0, 1.1)])
    turner = add_object(scene, "Turning", mesh_box("Turning", (1.0, 1.0, 1.0)), (-5.0, -2.0, 0.5))
    assign(turner, diffuse("TurningGreen", GREEN))
    _keyframes(turner, "rotation_euler", [(0.0, 0.0, 0.0), (0.0, 0.0, math.radians(90.0))])
    _bulging_grid(scene, (-6.0, 1.8, 1.5), (90, 0, -90), 1.5)
    pan_camera(scene.camera, -4.0)
    scene.frame_current = 1
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0


def build_lamps500(scene):
    """Many lights (issue 14's 500-lamp room): a closed 8 x 6 x 3 m room, two boxes, and a 25 x 20
    grid of small point lamps (2 W, radius 3 cm, alternately warm and cool) 40 cm below the
    ceiling. Each point sees a few lamps close by and hundreds far away: the case a light tree
    is for."""
    white = diffuse("White", WHITE)
    walls = [  # the +Z unit plane into place, normals facing inward
        ("Floor", Matrix.Identity(4), 8.0, 6.0),
        ("Ceiling", Matrix.Translation((0, 0, 3)) @ Matrix.Rotation(math.pi, 4, "X"), 8.0, 6.0),
        ("Back", Matrix.Translation((0, 3, 1.5)) @ Matrix.Rotation(math.pi / 2, 4, "X"), 8.0, 3.0),
        ("Front", Matrix.Translation((0, -3, 1.5)) @ Matrix.Rotation(-math.pi / 2, 4, "X"), 8.0, 3.0),
        ("Left", Matrix.Translation((-4, 0, 1.5)) @ Matrix.Rotation(math.pi / 2, 4, "Y"), 3.0, 6.0),
        ("Right", Matrix.Translation((4, 0, 1.5)) @ Matrix.Rotation(-math.pi / 2, 4, "Y"), 3.0, 6.0),
    ]
    for name, m, sx, sy in walls:
        assign(add_object(scene, name, mesh_plane(name, sx, sy, matrix=m)), white)
    assign(add_object(scene, "TallBox", mesh_box("TallBox", (0.8, 0.8, 1.6)), (-1.2, 0.8, 0.0), (0, 0, 20)),
           white)
    assign(add_object(scene, "LowBox", mesh_box("LowBox", (1.2, 0.8, 0.6)), (1.4, -0.2, 0.0), (0, 0, -15)),
           diffuse("Red", RED))
    for i in range(25):
        for j in range(20):
            warm = (i + j) % 2 == 0
            add_light(scene, "Lamp_%02d_%02d" % (i, j), "POINT", 2.0,
                      (-3.6 + 7.2 * i / 24, -2.7 + 5.4 * j / 19, 2.6), radius=0.03,
                      color=(1.0, 0.85, 0.7) if warm else (0.75, 0.85, 1.0))
    add_camera(scene, (0.0, -2.8, 1.4), (0.0, 1.0, 0.9), lens=20.0)


def _keyframes(idblock, path, values, frames=(0, 2), owner=None):
    """Keys idblock.path at each frame with linear interpolation (constant velocity); owner: the
    ID holding the animation (idblock itself by default)."""
    for frame, value in zip(frames, values):
        setattr(idblock, path, value)
        idblock.keyframe_insert(path, frame=frame)
    for fc in (owner or idblock).animation_data.action.fcurves:
        for k in fc.keyframe_points:
            k.interpolation = "LINEAR"


def extrapolate_motion(obj):
    """Extends obj's F-curves linearly past their keys: every frame of an animation moves it."""
    if obj.animation_data and obj.animation_data.action:
        for fc in obj.animation_data.action.fcurves:
            fc.extrapolation = "LINEAR"


def _bulging_grid(scene, location, rotation, size):
    """A 12 x 12 grid of `size` metres (smooth, blue) whose centre bulges by 0.6 size over keys at
    frames 0 and 2: an animated shape key, deformation blur."""
    bm = _bmesh_with_uvs()
    bmesh.ops.create_grid(bm, x_segments=12, y_segments=12, size=0.5 * size, calc_uvs=True)
    grid = add_object(scene, "Deforming", _smooth(_mesh("Deforming", bm), True), location, rotation)
    assign(grid, diffuse("GridBlue", (0.15, 0.25, 0.8)))
    grid.shape_key_add(name="Basis")
    bulge = grid.shape_key_add(name="Bulge")
    for v, b in zip(grid.data.vertices, bulge.data):
        r2 = (v.co.x * v.co.x + v.co.y * v.co.y) / (size * size)
        b.co = v.co + Vector((0.0, 0.0, 0.6 * size * math.exp(-8.0 * r2)))
    _keyframes(bulge, "value", [0.0, 1.0], owner=grid.data.shape_keys)
    return grid


def pan_camera(cam, degrees):
    """Keys the camera turning about world Z by `degrees` a frame through its present pose at
    frame 1 (keys at frames 0 and 2)."""
    cam.rotation_mode = "XYZ"
    base = cam.rotation_quaternion.to_euler("XYZ")
    _keyframes(cam, "rotation_euler", [(base.x, base.y, base.z - math.radians(degrees)),
                                       (base.x, base.y, base.z + math.radians(degrees))])
    return cam


def move_and_turn(obj, metres, degrees):
    """Keys obj translating along X by `metres` and turning about its Z by `degrees` a frame
    through its present pose at frame 1 (keys at frames 0 and 2)."""
    x, y, z = obj.location
    rx, ry, rz = obj.rotation_euler
    _keyframes(obj, "location", [(x - metres, y, z), (x + metres, y, z)])
    _keyframes(obj, "rotation_euler", [(rx, ry, rz - math.radians(degrees)), (rx, ry, rz + math.radians(degrees))])
    return obj


def build_motion_blur(scene, blur=True):
    """Issue 15's motion blur, rendered at frame 1 with a shutter of 1 frame centred on it (Cycles'
    defaults: 3 motion steps per object): a box translating 0.8 m a frame, a box spinning 120
    degrees a frame about its vertical axis (60 degrees between motion steps: a linear blend of
    the matrices would shrink it by up to 13 %), a grid bulging by an animated shape key
    (deformation blur) and a camera panning 8 degrees a frame (a 6-pixel streak), under an area
    light and a dim world. blur=False: the same scene with motion blur off (bench/)."""
    set_world(scene, (0.05, 0.05, 0.05), 1.0)
    floor = add_object(scene, "Floor", mesh_plane("Floor", 10.0))
    assign(floor, diffuse("FloorGrey", (0.6, 0.6, 0.6)))
    wall = add_object(scene, "Wall", mesh_plane("Wall", 10.0, 4.0), (0, 2.0, 2.0), (90, 0, 0))
    assign(wall, diffuse("WallWhite", WHITE))
    mover = add_object(scene, "Translating", mesh_box("Translating", (0.5, 0.5, 0.5)),
                       (-1.2, 0.0, 0.0))
    assign(mover, diffuse("MoverRed", RED))
    _keyframes(mover, "location", [(-1.6, 0.0, 0.0), (0.0, 0.0, 0.0)])
    spinner = add_object(scene, "Rotating", mesh_box("Rotating", (1.0, 0.25, 0.6)), (1.0, 0.6, 0.0))
    assign(spinner, diffuse("SpinnerGreen", GREEN))
    _keyframes(spinner, "rotation_euler",
               [(0.0, 0.0, math.radians(-120.0)), (0.0, 0.0, math.radians(120.0))])
    _bulging_grid(scene, (0.0, 1.2, 1.6), (70, 0, 0), 1.0)
    add_light(scene, "AreaLight", "AREA", 200.0, (0.5, -1.5, 3.0), rotation=(25, 0, 0), shape="DISK", size=1.5)
    pan_camera(add_camera(scene, (0.0, -4.0, 1.6), (0.0, 0.5, 0.7), lens=30.0), 8.0)
    scene.frame_current = 1  # keys at 0 and 2: the shutter (0.5 to 1.5) sees constant velocities
    scene.render.use_motion_blur = blur
    scene.render.motion_blur_shutter = 1.0
    scene.cycles.motion_blur_position = "CENTER"


def build_motion_blur_only(scene, animated):
    """motion_blur with only the objects named in `animated` animated (the rest keep their pose at
    the frame). motion_blur_one: the turning box alone, a scene's one moving object, which the core
    splits into motion segments (Geometry::attach_moving). motion_blur_sliding: everything but the
    turning box, whose motion the core bakes into world-space triangles (bakes_motion)."""
    build_motion_blur(scene)
    for ob in scene.objects:
        if ob.name not in animated and ob.animation_data:
            ob.animation_data_clear()
        keys = getattr(getattr(ob, "data", None), "shape_keys", None)
        if ob.name not in animated and keys is not None and keys.animation_data:
            keys.animation_data_clear()


# ----------------------------------------------------------------------------------------------
# Curves and points (issue 15)
# ----------------------------------------------------------------------------------------------
def hair_material(name, melanin=0.5, redness=0.3, roughness=0.3, radial=0.3, random_color=0.2,
                  random_roughness=0.1):
    mat, nt, out = _material(name)
    hair = nt.nodes.new("ShaderNodeBsdfHairPrincipled")
    hair.parametrization = "MELANIN"
    for key, value in (("Melanin", melanin), ("Melanin Redness", redness), ("Roughness", roughness),
                       ("Radial Roughness", radial), ("Random Color", random_color),
                       ("Random Roughness", random_roughness)):
        hair.inputs[key].default_value = value
    nt.links.new(hair.outputs[0], out.inputs["Surface"])
    return mat


def hair_bsdf_material(name, tangent=False):
    """Cycles' simple Hair BSDF: its Reflection (Offset 6 degrees, RoughnessU 0.15, RoughnessV 0.5)
    added to its Transmission (Offset -4 degrees, RoughnessU 0.3, RoughnessV 0.7), each tinted;
    tangent: the Reflection's Tangent linked to a constant direction (Cycles then takes it as
    given instead of the strand's direction)."""
    mat, nt, out = _material(name)
    add = nt.nodes.new("ShaderNodeAddShader")
    for k, (component, color, offset, ru, rv) in enumerate(
            (("Reflection", (0.9, 0.7, 0.5, 1.0), 6.0, 0.15, 0.5),
             ("Transmission", (0.4, 0.6, 0.9, 1.0), -4.0, 0.3, 0.7))):
        node = nt.nodes.new("ShaderNodeBsdfHair")
        node.component = component
        node.inputs["Color"].default_value = color
        node.inputs["Offset"].default_value = math.radians(offset)
        node.inputs["RoughnessU"].default_value = ru
        node.inputs["RoughnessV"].default_value = rv
        nt.links.new(node.outputs[0], add.inputs[k])
        if tangent and component == "Reflection":
            direction = nt.nodes.new("ShaderNodeCombineXYZ")
            for axis, value in zip("XYZ", (0.3, -0.2, 0.9)):
                direction.inputs[axis].default_value = value
            nt.links.new(direction.outputs[0], node.inputs["Tangent"])
    nt.links.new(add.outputs[0], out.inputs["Surface"])
    return mat


def build_hair_ball(scene, strands=600, children=4, principled=True, hair_mat=None, sun_only=False):
    """A sphere with particle hair (Principled Hair BSDF, melanin) under an area light, above a
    grey floor: `strands` parents, each replaced by `children` interpolated children as Cycles
    renders them, 2^3 + 1 keys per strand, radius 5 mm at the root tapering to 0 (Close Tip).
    Cycles' curve shape is 3D curves (THICK), as Lantern's. principled=False: a Diffuse BSDF on
    the strands instead (the curves' geometry and export alone); hair_mat: that material instead.
    sun_only: lit by a sun alone, no floor, no world, the ball and its hair hidden from indirect
    rays (all light through Cycles' light samples)."""
    scene.cycles_curves.shape = "THICK"
    if not sun_only:
        floor = add_object(scene, "Floor", mesh_plane("Floor", 6.0))
        assign(floor, diffuse("Floor", (0.5, 0.5, 0.5)))
    visibility = dict(diffuse=False, glossy=False, transmission=False) if sun_only else {}
    ball = add_object(scene, "Ball", mesh_sphere("Ball", 0.5, segments=32, rings=16), location=(0, 0, 0.6),
                      **visibility)
    assign(ball, diffuse("Scalp", (0.3, 0.2, 0.15)),
           hair_mat or (hair_material("Hair") if principled else diffuse("HairDiffuse", (0.6, 0.4, 0.3))))
    ball.modifiers.new("Hair", "PARTICLE_SYSTEM")
    psys = ball.particle_systems[0]
    psys.seed = 1  # a new system draws a random seed: fix it so that every build has the same strands
    psys.child_seed = 2
    s = psys.settings
    s.type = "HAIR"
    s.count = strands
    s.hair_length = 0.35
    s.render_step = 3
    s.display_step = 2
    s.material = 2
    s.root_radius = 1.0
    s.tip_radius = 0.0
    s.radius_scale = 0.01
    s.shape = 0.0
    s.use_close_tip = True
    s.child_type = "INTERPOLATED" if children else "NONE"
    s.rendered_child_count = children
    s.child_nbr = min(children, 4)
    s.child_length = 0.9
    s.roughness_2 = 0.05
    if sun_only:
        add_light(scene, "Sun", "SUN", 3.0, (0, 0, 5), rotation=(50, 0, 30), angle=math.radians(3.0))
        set_world(scene, (0.05, 0.06, 0.08), 0.0)
    else:
        add_light(scene, "AreaLight", "AREA", 300.0, (0.8, -0.6, 2.6), rotation=(20, 15, 0), shape="SQUARE",
                  size=1.0)
        set_world(scene, (0.05, 0.06, 0.08), 1.0)
    add_camera(scene, (0.0, -3.0, 1.2), (0.0, 0.0, 0.6), lens=50.0)


def _random_curves(scene):
    """A Curves object of Blender's random curves (500), named RandomCurves, in the scene."""
    bpy.ops.object.curves_random_add()  # into the context's scene: moved to this one
    curves = bpy.context.active_object
    for c in list(curves.users_collection):
        c.objects.unlink(curves)
    scene.collection.objects.link(curves)
    curves.name = "RandomCurves"
    return curves


def build_hair_motion(scene):
    """Moving hair under motion blur (a shutter of 1 frame centred on frame 1, 3 motion steps): the
    hair ball (a Diffuse BSDF on 300 x 4 strands) translating 0.6 m a frame and turning 40 degrees
    a frame about its vertical axis, and a Curves object (500 random curves, Blender's
    curves_random_add) translating upward 0.5 m a frame."""
    build_hair_ball(scene, strands=300, principled=False)
    move_and_turn(scene.objects["Ball"], 0.6, 40.0)
    curves = _random_curves(scene)
    curves.data.materials.append(diffuse("CurvesOrange", (0.8, 0.4, 0.1)))
    curves.scale = (0.8, 0.8, 0.8)
    _keyframes(curves, "location", [(0.9, -0.6, 0.2), (0.9, -0.6, 1.2)])
    scene.frame_current = 1
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0
    scene.cycles.motion_blur_position = "CENTER"


def build_point_cloud(scene):
    """Points from geometry nodes (Mesh to Points on an icosphere's vertices, radius 6 cm, then
    Set Material): they reach the depsgraph as POINTCLOUD geometry, rendered as spheres. A glossy
    and a diffuse material on two clouds, under an area light above a floor."""
    floor = add_object(scene, "Floor", mesh_plane("Floor", 6.0))
    assign(floor, diffuse("Floor", (0.5, 0.5, 0.5)))
    bm = bmesh.new()
    bmesh.ops.create_icosphere(bm, subdivisions=2, radius=0.6)
    for k, (mat, x) in enumerate(((diffuse("Points", (0.7, 0.3, 0.2)), -0.7),
                                  (glossy("PointsGlossy", (0.8, 0.8, 0.8), 0.3), 0.7))):
        obj = add_object(scene, "Cloud%d" % k, _mesh("Cloud%d" % k, bm.copy()), location=(x, 0, 0.7))
        tree = bpy.data.node_groups.new("ToPoints%d" % k, "GeometryNodeTree")
        tree.inputs.new("NodeSocketGeometry", "Geometry")
        tree.outputs.new("NodeSocketGeometry", "Geometry")
        gin = tree.nodes.new("NodeGroupInput")
        gout = tree.nodes.new("NodeGroupOutput")
        to_points = tree.nodes.new("GeometryNodeMeshToPoints")
        to_points.inputs["Radius"].default_value = 0.06
        set_mat = tree.nodes.new("GeometryNodeSetMaterial")
        set_mat.inputs["Material"].default_value = mat
        tree.links.new(gin.outputs[0], to_points.inputs["Mesh"])
        tree.links.new(to_points.outputs[0], set_mat.inputs["Geometry"])
        tree.links.new(set_mat.outputs[0], gout.inputs[0])
        obj.modifiers.new("Points", "NODES").node_group = tree
    bm.free()
    add_light(scene, "AreaLight", "AREA", 200.0, (0.5, -0.8, 2.5), rotation=(20, 10, 0), shape="SQUARE", size=1.0)
    set_world(scene, (0.05, 0.06, 0.08), 1.0)
    add_camera(scene, (0.0, -3.2, 1.4), (0.0, 0.0, 0.6), lens=45.0)


def _emission_of(name, color):
    """An Emission shader (strength 1) whose Color is color(nt), a node output of the tree, plus a
    quarter of |Generated|."""
    mat, nt, out = _material(name)
    em = nt.nodes.new("ShaderNodeEmission")
    generated = _vector_math(nt, "ABSOLUTE", nt.nodes.new("ShaderNodeTexCoord").outputs["Generated"])
    nt.links.new(_vector_math(nt, "MULTIPLY_ADD", generated, (0.25, 0.25, 0.25), color(nt)), em.inputs["Color"])
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    return mat


def _vector_math(nt, operation, *inputs):
    node = nt.nodes.new("ShaderNodeVectorMath")
    node.operation = operation
    for k, value in enumerate(inputs):
        if isinstance(value, tuple):
            node.inputs[k].default_value = value
        else:
            nt.links.new(value, node.inputs[k])
    return node.outputs[0]


def _into_blue(nt, value):
    """(0, 0, value) of a float output."""
    combine = nt.nodes.new("ShaderNodeCombineXYZ")
    nt.links.new(value, combine.inputs["Z"])
    return combine.outputs[0]


def build_hair_attributes(scene):
    """What strands and points carry for shading, each shown as an Emission colour (issue 15):
    particle hair (300 x 4 strands on the hair ball) reads its emitter's UV maps at the roots
    (Texture Coordinate's UV: the active render map; a UV Map node: a second map) and a byte colour
    attribute (Attribute node 'Col'); a Curves object (Blender's random curves) reads its
    surface_uv_coordinate (the default UV) and a per-point float 'ramp'; a point cloud reads a
    per-point vector 'pc' stored by geometry nodes; all three add a quarter of |Generated|. No
    lights: a dim world."""
    def hair_color(nt):
        uv = nt.nodes.new("ShaderNodeTexCoord").outputs["UV"]
        second = nt.nodes.new("ShaderNodeUVMap")
        second.uv_map = "Second"
        sep = nt.nodes.new("ShaderNodeSeparateXYZ")
        nt.links.new(second.outputs["UV"], sep.inputs[0])
        col = nt.nodes.new("ShaderNodeAttribute")
        col.attribute_name = "Col"
        base = _vector_math(nt, "ADD", uv, _into_blue(nt, sep.outputs["X"]))
        return _vector_math(nt, "MULTIPLY_ADD", col.outputs["Color"], (0.5, 0.5, 0.5), base)
    build_hair_ball(scene, strands=300, hair_mat=_emission_of("HairValues", hair_color))
    for name in ("AreaLight", "Floor"):
        bpy.data.objects.remove(scene.objects[name])
    ball = scene.objects["Ball"].data
    co = np.empty(3 * len(ball.vertices), np.float32)
    ball.vertices.foreach_get("co", co)
    loop_vertex = np.empty(len(ball.loops), np.int32)
    ball.loops.foreach_get("vertex_index", loop_vertex)
    p = co.reshape(-1, 3)[loop_vertex]
    uv = np.column_stack([np.arctan2(p[:, 1], p[:, 0]) / (2 * np.pi) + 0.5, p[:, 2] + 0.5])
    ball.uv_layers.new(name="UVMap").data.foreach_set("uv", uv.reshape(-1))
    ball.uv_layers.new(name="Second").data.foreach_set("uv", (1.0 - uv).reshape(-1))
    ball.uv_layers["UVMap"].active_render = True
    rgba = np.ones((len(ball.loops), 4), np.float32)
    rgba[:, :3] = np.abs(p) * 1.6
    col = ball.color_attributes.new("Col", "BYTE_COLOR", "CORNER")
    col.data.foreach_set("color", np.clip(rgba, 0, 1).reshape(-1))

    curves = _random_curves(scene)
    curves.location = (1.0, -0.4, 0.5)
    curves.scale = (0.35, 0.35, 0.35)
    data = curves.data
    n, offsets = len(data.curves), np.empty(len(data.curves) + 1, np.int32)
    data.curve_offset_data.foreach_get("value", offsets)
    k = np.arange(n, dtype=np.float32)
    surface_uv = data.attributes.new("surface_uv_coordinate", "FLOAT2", "CURVE")
    surface_uv.data.foreach_set("vector", np.column_stack([k / n, (k * 0.37) % 1.0]).reshape(-1))
    ramp = np.concatenate([np.linspace(0.0, 1.0, e - b, dtype=np.float32) for b, e in zip(offsets, offsets[1:])])
    data.attributes.new("ramp", "FLOAT", "POINT").data.foreach_set("value", ramp)

    def curves_color(nt):
        uv = nt.nodes.new("ShaderNodeTexCoord").outputs["UV"]
        attr = nt.nodes.new("ShaderNodeAttribute")
        attr.attribute_name = "ramp"
        return _vector_math(nt, "ADD", uv, _into_blue(nt, attr.outputs["Fac"]))
    data.materials.append(_emission_of("CurvesValues", curves_color))

    bm = bmesh.new()
    bmesh.ops.create_icosphere(bm, subdivisions=2, radius=0.3)
    cloud = add_object(scene, "Cloud", _mesh("Cloud", bm), location=(-0.9, -0.5, 0.4))

    def cloud_color(nt):
        attr = nt.nodes.new("ShaderNodeAttribute")
        attr.attribute_name = "pc"
        return attr.outputs["Color"]
    tree = bpy.data.node_groups.new("ToPointsWithValues", "GeometryNodeTree")
    tree.inputs.new("NodeSocketGeometry", "Geometry")
    tree.outputs.new("NodeSocketGeometry", "Geometry")
    gin, gout = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    to_points = tree.nodes.new("GeometryNodeMeshToPoints")
    to_points.inputs["Radius"].default_value = 0.05
    store = tree.nodes.new("GeometryNodeStoreNamedAttribute")
    store.data_type = "FLOAT_VECTOR"
    store.domain = "POINT"
    store.inputs["Name"].default_value = "pc"
    position = tree.nodes.new("GeometryNodeInputPosition")
    scaled = tree.nodes.new("ShaderNodeVectorMath")
    scaled.operation = "MULTIPLY_ADD"
    scaled.inputs[1].default_value = (1.5, 1.5, 1.5)
    scaled.inputs[2].default_value = (0.5, 0.5, 0.5)
    tree.links.new(position.outputs[0], scaled.inputs[0])
    tree.links.new(scaled.outputs[0], next(i for i in store.inputs if i.identifier == "Value_Vector"))
    set_mat = tree.nodes.new("GeometryNodeSetMaterial")
    set_mat.inputs["Material"].default_value = _emission_of("CloudValues", cloud_color)
    tree.links.new(gin.outputs[0], to_points.inputs["Mesh"])
    tree.links.new(to_points.outputs[0], store.inputs["Geometry"])
    tree.links.new(store.outputs[0], set_mat.inputs["Geometry"])
    tree.links.new(set_mat.outputs[0], gout.inputs[0])
    cloud.modifiers.new("Points", "NODES").node_group = tree
    scene.camera.location = (0.0, -4.5, 1.5)  # farther back on the line to the ball
    scene.camera.data.lens = 50.0


SCENES = {
    "hair_ball": (build_hair_ball, (96, 96), 128),
    "hair_ball_diffuse": (lambda scene: build_hair_ball(scene, principled=False), (96, 96), 128),
    "hair_ball_hair_bsdf": (lambda scene: build_hair_ball(scene, 300, hair_mat=hair_bsdf_material("HairBsdf")),
                            (48, 48), 128),
    "hair_ball_hair_bsdf_sun": (lambda scene: build_hair_ball(
        scene, 300, hair_mat=hair_bsdf_material("HairBsdf"), sun_only=True), (48, 48), 256),
    "hair_ball_hair_bsdf_tangent_sun": (lambda scene: build_hair_ball(
        scene, 300, hair_mat=hair_bsdf_material("HairBsdfTangent", tangent=True), sun_only=True), (48, 48), 256),
    "hair_motion": (build_hair_motion, (48, 48), 128),
    "point_cloud": (build_point_cloud, (96, 96), 128),
    "hair_attributes": (build_hair_attributes, (96, 48), 64),
    "lamps500": (build_lamps500, (160, 120), 64),
    "cornell_area": (build_cornell_area, (96, 96), 128),
    "cornell_point": (build_cornell_point, (96, 96), 128),
    "lamp_near_ceiling": (build_lamp_near_ceiling, (48, 48), 640),
    "area_spread": (build_area_spread, (48, 48), 1536),
    "cornell_spot": (build_cornell_spot, (96, 96), 128),
    "cornell_mesh_light": (build_cornell_mesh_light, (96, 96), 512),
    "glossy_glass": (build_glossy_glass, (96, 96), 128),
    "cornell_dof": (build_cornell_dof, (96, 96), 128),
    "motion_blur": (build_motion_blur, (96, 64), 128),
    "motion_blur_one": (lambda scene: build_motion_blur_only(scene, {"Rotating"}), (96, 64), 128),
    "motion_blur_sliding": (lambda scene: build_motion_blur_only(scene, {"Translating", "Deforming", "Camera"}),
                            (96, 64), 128),
    "pano_equirectangular": (lambda scene: build_panorama(scene, "EQUIRECTANGULAR"), (64, 32), 128),
    "pano_fisheye_equidistant": (lambda scene: build_panorama(scene, "FISHEYE_EQUIDISTANT"), (48, 48), 128),
    "pano_fisheye_equisolid": (lambda scene: build_panorama(scene, "FISHEYE_EQUISOLID"), (48, 32), 128),
    "pano_mirrorball": (lambda scene: build_panorama(scene, "MIRRORBALL"), (32, 32), 128),
    "pano_fisheye_polynomial": (lambda scene: build_panorama(scene, "FISHEYE_LENS_POLYNOMIAL"), (32, 32), 128),
    "pano_cubemap_face": (lambda scene: build_panorama(scene, "EQUIANGULAR_CUBEMAP_FACE"), (40, 32), 128),
    "sun_world": (build_sun_world, (96, 96), 128),
    "world_spheres": (build_world_spheres, (96, 64), 128),
    "textured": (build_textured, (96, 96), 128),
    "hdri_world": (build_hdri_world, (96, 64), 128),
    "light_path_world": (build_light_path_world, (96, 64), 128),
    "procedural_world": (build_procedural_world, (96, 64), 128),
    "nishita_world": (build_nishita_world, (96, 64), 128),
    "instanced": (build_instanced, (96, 96), 128),
    "normal_mapped": (build_normal_mapped, (96, 96), 128),
    "tilted_metal": (build_tilted_metal, (96, 48), 128),
    "displaced": (build_displaced, (96, 96), 128),
    "true_displaced": (build_true_displaced, (96, 96), 128),
    "terminator": (build_terminator, (96, 64), 128),
    "terminator_shading": (lambda scene: build_terminator(scene, shading_offset=0.6), (96, 64), 128),
    "metal_box": (build_metal_box, (64, 64), 512),
    "principled_ground": (build_principled_ground, (96, 64), 128),
    "subsurface": (build_subsurface, (64, 48), 128),
    "resting": (build_resting, (64, 48), 128),
    "subsurface_burley": (lambda scene: build_subsurface(scene, "BURLEY"), (64, 48), 128),
    "subsurface_fixed": (lambda scene: build_subsurface(scene, "RANDOM_WALK_FIXED_RADIUS"), (64, 48), 128),
    "layered_material": (build_layered_material, (96, 64), 128),
    "leaf_cards": (build_leaf_cards, (96, 64), 128),
    "holdout": (build_holdout, (64, 48), 128),
    "shadow_catcher": (build_shadow_catcher, (48, 36), 128),
    "light_groups": (build_light_groups, (80, 60), 128),
    "aovs": (build_aovs, (64, 48), 64),
    "aovs_world": (build_aovs_world, (64, 48), 64),
    "gltf_pbr": (build_gltf_pbr, (80, 80), 256),
    "wide_sun": (build_wide_sun, (64, 48), 128),
    "ray_visibility": (build_ray_visibility, (96, 64), 256),
    "bsdf_zoo": (build_bsdf_zoo, (128, 80), 128),
    "bsdf_zoo_departures": (lambda scene: build_bsdf_zoo(scene, departures=True), (128, 80), 128),
    "bsdf_zoo_departures_sun": (lambda scene: build_bsdf_zoo(scene, departures=True, sun_only=True, hidden=True),
                                (128, 80), 128),
    # Without the glass: a 3-degree sun's caustics through rough glass, which PATH finds by BSDF
    # samples alone, are too noisy at these samples (Bdpt.LampsInMultiscatterGlobesAgreeWithPathTracing
    # checks that glass's light-side evaluation).
    "bsdf_zoo_departures_sun_visible": (lambda scene: build_bsdf_zoo(scene, departures=True, sun_only=True,
                                                                     glass=False),
                                        (128, 80), 128),
    "refraction": (build_refraction, (96, 64), 256),
    "unsupported_node": (build_unsupported_node, (96, 96), 64),
    "door": (build_door, (96, 96), 512),
    "door_bounce": (build_door_bounce, (96, 96), 1600),
    "door_slabs": (build_door_slabs, (64, 48), 640),
    "caustic": (build_caustic, (96, 96), 256),
    "smoke_box": (build_smoke_box, (64, 64), 128),
    "volume_add": (build_volume_add, (64, 64), 128),
    "volume_mix": (build_volume_mix, (64, 64), 128),
    "volume_emission": (build_volume_emission, (64, 64), 128),
    "volume_blackbody": (build_volume_blackbody, (64, 64), 128),
    "thin_fog": (build_thin_fog, (64, 64), 128),
    "dense_fog": (build_dense_fog, (64, 64), 256),
    "world_fog": (build_world_fog, (64, 64), 1536),
    "vdb_cloud": (build_vdb_cloud, (64, 64), 128),
    "vdb_cloud_scaled": (build_vdb_cloud_scaled, (64, 64), 128),
    "vdb_smoke": (build_vdb_smoke, (64, 64), 64),
    "vdb_fire": (build_vdb_fire, (48, 48), 128),
    "world_glow": (build_world_glow, (48, 48), 128),
    "smoke_interior": (build_smoke_interior, (64, 64), 64),
}

# Scenes made from the models in models/ (examples only; not part of the test suite).
MODEL_SCENES = {
    "sibenik": (build_sibenik, (160, 120), 64),
    "sibenik_smoke": (build_sibenik_smoke, (160, 120), 64),
    "sponza": (build_sponza, (160, 120), 64),
    "sponza_motion": (build_sponza_motion, (200, 150), 64),
}

# example scene name: (builder scene, resolution, samples, Lantern integrator[, other Lantern
# settings])
EXAMPLES = {
    "a05_box": ("cornell_area", (256, 256), 128, "BIDIRECTIONAL"),  # the sheet's BDPT Cornell box
    "glossy_glass": ("glossy_glass", (320, 240), 256, "PATH"),
    "door": ("door", (320, 240), 128, "BIDIRECTIONAL"),
    "caustic": ("caustic", (320, 240), 128, "BIDIRECTIONAL"),
    # the sheet's volume scenes (the .vdb files: "//assets/", see write_examples)
    "a05_smoke_debug": ("vdb_smoke", (320, 240), 16, "VOLUME_DEBUG"),
    "a05_cloud_march": ("vdb_cloud", (256, 256), 128, "VOLPATH",
                        dict(volume_estimator="RAY_MARCHING", volume_step=0.0)),
    "a05_cloud_track": ("vdb_cloud", (256, 256), 128, "VOLPATH", dict(volume_estimator="TRACKING")),
    "a05_smoke_interior": ("smoke_interior", (320, 240), 256, "VOLPATH"),
    # the sheet's model scenes (models/, imported with Blender's OBJ importer)
    "a05_sibenik": ("sibenik", (320, 240), 64, "BIDIRECTIONAL"),
    "a05_sibenik_smoke": ("sibenik_smoke", (320, 240), 64, "VOLPATH", dict(volume_bounces=1)),
    "a05_spz": ("sponza", (320, 240), 128, "PATH"),
}

# Where examples.blend's Volume objects find their .vdb files: next to the .blend.
EXAMPLE_ASSETS = "//assets/"


def build(name, scene_name=None, resolution=None, samples=None):
    """Builds test scene `name` into a new Scene (called scene_name, default name) and returns it."""
    builder, res, spp = SCENES[name] if name in SCENES else MODEL_SCENES[name]
    scene = new_scene(scene_name or name, resolution or res, samples or spp)
    builder(scene)
    return scene


def _lantern_registered():
    return any(getattr(c, "bl_idname", None) == "LANTERN"
               for c in bpy.types.RenderEngine.__subclasses__())


def reset_file():
    """Empties the current file (keeps one placeholder scene, returned)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    placeholder = bpy.data.scenes[0]
    placeholder.name = "__placeholder__"
    return placeholder


def _save(path, placeholder):
    if placeholder.name in bpy.data.scenes and len(bpy.data.scenes) > 1:
        bpy.data.scenes.remove(placeholder)
    bpy.data.orphans_purge(do_recursive=True) if hasattr(bpy.data, "orphans_purge") else None
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(path), compress=True, copy=False)


def write_test_blends(outdir, names=None):
    """OUTDIR/<name>.blend for each test scene; returns the paths."""
    paths = []
    for name in names or SCENES:
        placeholder = reset_file()
        build(name)
        path = os.path.join(outdir, name + ".blend")
        _save(path, placeholder)
        paths.append(path)
        print("wrote", path)
    return paths


def write_examples(path=EXAMPLES_PATH):
    """examples.blend: one scene per example, render engine Lantern when it is registered."""
    placeholder = reset_file()
    lantern = _lantern_registered()
    for example, (name, res, spp, integrator, *extra) in EXAMPLES.items():
        scene = build(name, scene_name=example, resolution=res, samples=spp)
        if lantern:
            scene.render.engine = "LANTERN"
            scene.lantern.samples = spp
            scene.lantern.integrator = integrator
            for key, value in (extra[0] if extra else {}).items():
                setattr(scene.lantern, key, value)
    # Blender-relative .vdb paths: scripts/render_examples.sh copies <build>/test_vdb/*.vdb into
    # assets/ next to examples.blend (a build directory is not part of a user's checkout).
    for volume in bpy.data.volumes:
        volume.filepath = EXAMPLE_ASSETS + os.path.basename(volume.filepath)
    # The models' textures stay in models/ (not packed: examples.blend stays small), found
    # relative to the .blend.
    for image in bpy.data.images:
        if image.source == "FILE" and os.path.isabs(image.filepath):
            image.filepath = bpy.path.relpath(image.filepath, start=os.path.dirname(os.path.abspath(path)))
    for window in bpy.context.window_manager.windows:
        window.scene = bpy.data.scenes["a05_box"]
    _save(path, placeholder)
    print("wrote", path, "(engine %s)" % ("LANTERN" if lantern else "CYCLES"))
    return path


def main(argv):
    import argparse

    p = argparse.ArgumentParser(prog="build_scenes.py", description=__doc__.split("\n")[0])
    p.add_argument("outdir", nargs="?", help="write one .blend per test scene here")
    p.add_argument("--only", default="", help="comma-separated scene names (default: all)")
    p.add_argument("--examples", nargs="?", const=EXAMPLES_PATH, default=None,
                   help="also write examples.blend (default path: %(const)s)")
    args = p.parse_args(argv)
    if not args.outdir and not args.examples:
        p.error("give OUTDIR and/or --examples")
    names = [n for n in args.only.split(",") if n] or None
    for n in names or ():
        if n not in SCENES and n not in MODEL_SCENES:
            p.error("unknown scene %r; known: %s" % (n, ", ".join([*SCENES, *MODEL_SCENES])))
    if args.outdir:
        write_test_blends(args.outdir, names)
    if args.examples:
        write_examples(args.examples)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
