"""Attribute nodes against Cycles, pixel by pixel (the compare_grid harness of node_cases: each case an Emission
of the node's output on a camera-facing plane): named UV maps, colour attributes of both domains in
byte and float colours, the Attribute node (geometry, object and instancer types), Object Info on objects of
different colours and indices, Tangent and Normal Map. Each case may prepare its plane (its mesh
and object) before the render (compare_grid's prepare).
"""
import bpy
import numpy as np
import pytest

import build_scenes
import render_utils

import node_cases as harness
from node_cases import compare_grid

pytestmark = pytest.mark.skipif(not render_utils.engine_registered(), reason="Lantern add-on not registered")


# -- mesh preparation ----------------------------------------------------------------------------
# The harness compares pixels well inside cells of 4 x 4 per plane, so values must be constant over
# a cell (a gradient would differ by the pixel filter's samples): cells() rebuilds the plane as 16
# separate quads (no shared vertices) and the attributes are constant on each (interpolation within
# a triangle is checked by the native tests).

CELLS = 4


def cells(ob):
    """Replaces the plane by 4 x 4 separate quads; UVMap (the active render map) is each cell's
    centre and a second map 'Second' a different constant per cell."""
    verts, faces = [], []
    for j in range(CELLS):
        for i in range(CELLS):
            x0, y0 = i / CELLS - 0.5, j / CELLS - 0.5
            k = len(verts)
            verts += [(x0, y0, 0), (x0 + 0.25, y0, 0), (x0 + 0.25, y0 + 0.25, 0), (x0, y0 + 0.25, 0)]
            faces.append((k, k + 1, k + 2, k + 3))
    me = bpy.data.meshes.new(ob.name + "_cells")
    me.from_pydata(verts, [], faces)
    for mat in ob.data.materials:
        me.materials.append(mat)
    ob.data = me
    uv = me.uv_layers.new(name="UVMap")
    second = me.uv_layers.new(name="Second")
    for li in range(len(me.loops)):
        f = li // 4
        i, j = f % CELLS, f // CELLS
        uv.data[li].uv = ((i + 0.5) / CELLS, (j + 0.5) / CELLS)
        second.data[li].uv = (0.15 + 0.2 * j, 0.95 - 0.21 * i)
    uv.active_render = True


def second_uv(ob):
    """A second UV map 'Second' on the plane: the first rotated and scaled (tangents constant)."""
    me = ob.data
    first = me.uv_layers[0]
    layer = me.uv_layers.new(name="Second")
    for i, d in enumerate(layer.data):
        u, v = first.data[i].uv
        d.uv = (0.2 + 0.6 * v, 0.9 - 0.7 * u)
    first.active_render = True


PALETTE = [(0.9, 0.1, 0.3, 0.25), (0.2, 0.8, 0.4, 1.0), (0.1, 0.3, 0.95, 0.5), (0.7, 0.6, 0.05, 0.75),
           (0.45, 0.35, 0.6, 0.1)]


def colours(ob):
    cells(ob)
    me = ob.data
    for n, (name, dtype, domain) in enumerate((("pf", 'FLOAT_COLOR', 'POINT'), ("pb", 'BYTE_COLOR', 'POINT'),
                                               ("cf", 'FLOAT_COLOR', 'CORNER'), ("cb", 'BYTE_COLOR', 'CORNER'))):
        a = me.color_attributes.new(name, dtype, domain)
        for i, d in enumerate(a.data):
            d.color = PALETTE[(i // 4 + n) % len(PALETTE)]  # 4 vertices or corners per cell
    me.color_attributes.render_color_index = me.color_attributes.find("cb")
    me.color_attributes.active_color_index = me.color_attributes.find("pf")


def generic(ob):
    cells(ob)
    me = ob.data
    h = me.attributes.new("height", 'FLOAT', 'POINT')
    for i, d in enumerate(h.data):
        d.value = 0.2 + 0.05 * (i // 4)
    v = me.attributes.new("cvec", 'FLOAT_VECTOR', 'CORNER')
    for i, d in enumerate(v.data):
        d.vector = (0.05 * (i // 4), 1.0 - 0.04 * (i // 4), 0.5)
    f = me.attributes.new("face", 'FLOAT', 'FACE')
    for i, d in enumerate(f.data):
        d.value = 0.625 - 0.03 * i


def object_values(index):
    def prep(ob):
        ob.color = (0.1 + 0.1 * index, 0.9 - 0.15 * index, 0.3 + 0.05 * index, 0.2 + 0.1 * index)
        ob.pass_index = index + 1
        ob["myprop"] = 0.25 * index + 0.5
        if ob.active_material is not None:
            ob.active_material.pass_index = 2 * index + 1
    return prep


# -- cases ---------------------------------------------------------------------------------------

def node_out(idname, output, **props):
    def fn(s):
        return s.node(idname, **props).outputs[output]
    return fn


def scaled(fn, k):
    def g(s):
        return s.math("MULTIPLY", fn(s), k)
    return g


def test_uv_maps_and_attribute_node(outdir):
    cases = [
        ("UV Map Second", node_out("ShaderNodeUVMap", "UV", uv_map="Second"), cells),
        ("UV Map active", node_out("ShaderNodeUVMap", "UV", uv_map=""), cells),
        ("UV Map missing", node_out("ShaderNodeUVMap", "UV", uv_map="Nope"), cells),
        ("Attribute Second Vector", node_out("ShaderNodeAttribute", "Vector", attribute_name="Second"), cells),
        ("Attribute Second Fac", node_out("ShaderNodeAttribute", "Fac", attribute_name="Second"), cells),
        ("Attribute height Color", node_out("ShaderNodeAttribute", "Color", attribute_name="height"), generic),
        ("Attribute height Fac", node_out("ShaderNodeAttribute", "Fac", attribute_name="height"), generic),
        ("Attribute cvec Vector", node_out("ShaderNodeAttribute", "Vector", attribute_name="cvec"), generic),
        ("Attribute cvec Fac", node_out("ShaderNodeAttribute", "Fac", attribute_name="cvec"), generic),
        ("Attribute face Fac", node_out("ShaderNodeAttribute", "Fac", attribute_name="face"), generic),
        ("Attribute missing Alpha", node_out("ShaderNodeAttribute", "Alpha", attribute_name="nope"), generic),
        ("Attribute missing Color", node_out("ShaderNodeAttribute", "Color", attribute_name="nope"), generic),
    ]
    bad = compare_grid("attr_uv", cases, outdir)
    assert not bad, bad


def test_colour_attributes(outdir):
    cases = []
    for name in ("pf", "pb", "cf", "cb", ""):
        for out in ("Color", "Alpha"):
            cases.append(("Color Attribute '%s' %s" % (name, out),
                          node_out("ShaderNodeVertexColor", out, layer_name=name), colours))
    cases.append(("Color Attribute missing Alpha", node_out("ShaderNodeVertexColor", "Alpha", layer_name="nope"),
                  colours))
    for name in ("pb", "cf"):
        for out in ("Color", "Fac", "Alpha"):
            cases.append(("Attribute '%s' %s" % (name, out),
                          node_out("ShaderNodeAttribute", out, attribute_name=name), colours))
    bad = compare_grid("attr_colour", cases, outdir)
    assert not bad, bad


def test_object_info_and_object_attributes(outdir):
    cases = []
    for i in range(3):
        prep = object_values(i)
        cases += [
            ("Object Info Color %d" % i, node_out("ShaderNodeObjectInfo", "Color"), prep),
            ("Object Info Alpha %d" % i, node_out("ShaderNodeObjectInfo", "Alpha"), prep),
            ("Object Info Index %d" % i, scaled(node_out("ShaderNodeObjectInfo", "Object Index"), 0.1), prep),
            ("Object Info Material Index %d" % i,
             scaled(node_out("ShaderNodeObjectInfo", "Material Index"), 0.1), prep),
            ("Object Info Random %d" % i, node_out("ShaderNodeObjectInfo", "Random"), prep),
            ("Object Info Location %d" % i, scaled(node_out("ShaderNodeObjectInfo", "Location"), 0.2), prep),
            ("Attribute object color %d" % i,
             node_out("ShaderNodeAttribute", "Color", attribute_type='OBJECT', attribute_name="color"), prep),
            ("Attribute object myprop %d" % i,
             node_out("ShaderNodeAttribute", "Fac", attribute_type='OBJECT', attribute_name="myprop"), prep),
        ]
    bad = compare_grid("attr_object", cases, outdir)
    assert not bad, bad


def _normal_map(space, color, strength=1.0, uv_map=""):
    def fn(s):
        n = s.node("ShaderNodeNormalMap", space=space, uv_map=uv_map)
        n.inputs["Strength"].default_value = strength
        n.inputs["Color"].default_value = color + (1.0,)
        return n.outputs["Normal"]
    return fn


def test_tangent_and_normal_map(outdir):
    prep = second_uv
    cases = [
        ("Tangent UV active", node_out("ShaderNodeTangent", "Tangent", direction_type='UV_MAP'), prep),
        ("Tangent UV Second", node_out("ShaderNodeTangent", "Tangent", direction_type='UV_MAP', uv_map="Second"),
         prep),
        ("Normal Map tangent", _normal_map('TANGENT', (0.7, 0.35, 0.9)), prep),
        ("Normal Map tangent Second", _normal_map('TANGENT', (0.7, 0.35, 0.9), uv_map="Second"), prep),
        ("Normal Map tangent strength", _normal_map('TANGENT', (0.2, 0.8, 0.7), strength=0.4), prep),
        ("Normal Map object", _normal_map('OBJECT', (0.6, 0.3, 0.8)), prep),
        ("Normal Map world", _normal_map('WORLD', (0.4, 0.55, 0.9)), prep),
        ("Normal Map Blender object", _normal_map('BLENDER_OBJECT', (0.6, 0.3, 0.1)), prep),
        ("Normal Map Blender world", _normal_map('BLENDER_WORLD', (0.4, 0.55, 0.2), strength=2.0), prep),
    ]
    bad = compare_grid("attr_tangent", cases, outdir)
    assert not bad, bad


def _emission_material(name, colour):
    """A material that emits colour(s), s a harness.Setup of its tree (returns the socket)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    s = harness.Setup(nt)
    out = s.node("ShaderNodeOutputMaterial")
    em = s.node("ShaderNodeEmission")
    s.link(colour(s), em.inputs["Color"])
    s.link(em.outputs[0], out.inputs["Surface"])
    return mat


def _tile_centres(scene, n, half, outdir):
    """Renders scene with Lantern and Cycles and checks that the centres (2 half pixels square) of
    its first n tiles agree within the harness's bounds; returns Cycles' mean of each."""
    lt = render_utils.render(scene, render_utils.LANTERN, samples=4, outdir=outdir, tag=scene.name + "_lantern")
    cy = render_utils.render(scene, render_utils.CYCLES, samples=4, outdir=outdir, tag=scene.name + "_cycles")
    lt, cy = lt.combined[..., :3], cy.combined[..., :3]
    tile = harness.TILE
    c = slice(tile // 2 - half, tile // 2 + half)
    means = []
    for i in range(n):
        a = lt[c, i * tile:(i + 1) * tile][:, c]
        b = cy[c, i * tile:(i + 1) * tile][:, c]
        assert np.all(np.abs(a - b) <= harness.RTOL * np.abs(b) + harness.ATOL), (i, a.mean((0, 1)), b.mean((0, 1)))
        means.append(b.mean((0, 1)))
    return means


def test_object_info_random_of_collection_instances(outdir):
    """Object Info's Random and Location on instances of a collection (DepsgraphObjectInstance
    .random_id, hashed as Cycles does) and on a plain object (Cycles' hash of its name)."""
    scene, _rows, _cols = harness._scene("attr_instances", 4)

    def colour(s):
        info = s.node("ShaderNodeObjectInfo")
        comb = s.node("ShaderNodeCombineXYZ")
        s.link(info.outputs["Random"], comb.inputs[0])
        sep = s.node("ShaderNodeSeparateXYZ")
        s.link(info.outputs["Location"], sep.inputs[0])
        s.link(s.math("MULTIPLY", s.math("ADD", sep.outputs[0], 2.0), 0.2), comb.inputs[2])
        return comb.outputs[0]
    mat = _emission_material("attr_instances_random", colour)
    group = bpy.data.collections.new("attr_instances_group")
    me = build_scenes.mesh_plane("attr_instances_plane", 0.8)
    me.materials.append(mat)
    member = bpy.data.objects.new("attr_instances_member", me)
    group.objects.link(member)
    for i in range(3):
        empty = bpy.data.objects.new("attr_instancer_%d" % i, None)
        empty.instance_type = 'COLLECTION'
        empty.instance_collection = group
        empty.location = (i - 1.5, 0.0, 0.0)
        scene.collection.objects.link(empty)
    plain = build_scenes.add_object(scene, "attr_instances_plain", me.copy(), location=(1.5, 0.0, 0.0))
    plain.data.materials[0] = mat
    values = [float(m[0]) for m in _tile_centres(scene, 4, 6, outdir)]
    assert len(set(round(v, 4) for v in values)) == 4, values  # four different random numbers


def test_instancer_attributes_of_collection_and_particle_instances(outdir):
    """The Attribute node's Instancer type (issue 13) as Cycles 3.4 reads it (lookup_instance_property):
    on an instance, its particle system's settings, then its instancer's custom property, else the
    object's own; on an object that is no instance, its own. A sphere (in a collection the scene does
    not show) reads "tint" into an Emission: instanced by an Empty with a 3-float "tint", by one with
    a float "tint", by one without (the sphere's own 0.7), a plain copy with its own "tint", and one
    particle of an emitter whose settings and object both have one (the settings win)."""
    scene, _rows, _cols = harness._scene("attr_instancer", 5)
    mat = _emission_material("attr_instancer_tint", lambda s: s.node(
        "ShaderNodeAttribute", attribute_type='INSTANCER', attribute_name="tint").outputs["Color"])
    me = build_scenes.mesh_sphere("attr_instancer_sphere", 0.4)
    me.materials.append(mat)
    member = bpy.data.objects.new("attr_instancer_member", me)
    member["tint"] = 0.7
    group = bpy.data.collections.new("attr_instancer_group")
    group.objects.link(member)
    for i, tint in enumerate(((0.9, 0.2, 0.4), 0.35, None)):
        empty = bpy.data.objects.new("attr_instancer_%d" % i, None)
        empty.instance_type = 'COLLECTION'
        empty.instance_collection = group
        empty.location = (i - 2.0, 0.0, 0.0)
        if tint is not None:
            empty["tint"] = tint
        scene.collection.objects.link(empty)
    plain = build_scenes.add_object(scene, "attr_instancer_plain", me, location=(1.0, 0.0, 0.0))
    plain["tint"] = (0.1, 0.6, 0.9)
    point = bpy.data.meshes.new("attr_instancer_point")
    point.from_pydata([(0.0, 0.0, 0.0)], [], [])
    emitter = build_scenes.add_object(scene, "attr_instancer_emitter", point, location=(2.0, 0.0, 0.0))
    emitter["tint"] = 0.15
    emitter.show_instancer_for_render = False
    psys = emitter.modifiers.new("particles", 'PARTICLE_SYSTEM').particle_system
    ps = psys.settings
    ps.count, ps.emit_from, ps.physics_type = 1, 'VERT', 'NO'
    ps.frame_start = ps.frame_end = 1
    ps.lifetime = 100
    ps.render_type, ps.instance_object, ps.particle_size = 'OBJECT', member, 1.0
    ps["tint"] = 0.55
    expected = [(0.9, 0.2, 0.4), (0.35,) * 3, (0.7,) * 3, (0.1, 0.6, 0.9), (0.55,) * 3]
    for i, (got, want) in enumerate(zip(_tile_centres(scene, 5, 4, outdir), expected)):
        assert np.allclose(got, want, atol=1e-3), (i, got, want)


def test_view_layer_attributes_read_the_view_layer_then_the_scene_then_the_world(outdir):
    """The Attribute node's View Layer type (issue 13) as Cycles 3.4 resolves it
    (BKE_view_layer_find_rgba_attribute): one sphere per name, emitting its Color, found on the
    view layer (before the scene's value of the same name), on the scene only, on the world only,
    nowhere (black), and its Fac (the mean of the colour) for a view layer value."""
    scene, _rows, _cols = harness._scene("attr_view_layer", 5)
    layer = scene.view_layers[0]
    layer["vl_a"] = (0.2, 0.5, 0.8)
    scene["vl_a"] = 0.9
    scene["vl_b"] = 0.35
    if scene.world is None:
        scene.world = bpy.data.worlds.new("attr_view_layer_world")
    scene.world.color = (0.0, 0.0, 0.0)
    scene.world["vl_c"] = (0.6, 0.1, 0.3)
    cases = [("vl_a", "Color"), ("vl_b", "Color"), ("vl_c", "Color"), ("vl_none", "Color"), ("vl_a", "Fac")]
    for i, (name, socket) in enumerate(cases):
        mat = _emission_material("attr_view_layer_%d" % i, lambda s, name=name, socket=socket: s.node(
            "ShaderNodeAttribute", attribute_type='VIEW_LAYER', attribute_name=name).outputs[socket])
        me = build_scenes.mesh_sphere("attr_view_layer_sphere_%d" % i, 0.4)
        me.materials.append(mat)
        build_scenes.add_object(scene, "attr_view_layer_%d" % i, me, location=(i - 2.0, 0.0, 0.0))
    expected = [(0.2, 0.5, 0.8), (0.35,) * 3, (0.6, 0.1, 0.3), (0.0,) * 3, (0.5,) * 3]
    for i, (got, want) in enumerate(zip(_tile_centres(scene, 5, 4, outdir), expected)):
        assert np.allclose(got, want, atol=1e-3), (i, got, want)


def test_view_layer_attribute_animated_re_exports_each_frame(tmp_path):
    """A View Layer attribute is a constant of the programs: rendering an animation with
    Persistent Data, a scene property keyed 0.2 at frame 1 and 0.6 at frame 3 makes each frame
    a new export (the kept scene would show the first frame's value) with that frame's value."""
    from lantern import engine
    scene, _rows, _cols = harness._scene("attr_view_layer_anim", 1)
    if scene.world is None:
        scene.world = bpy.data.worlds.new("attr_view_layer_anim_world")
    scene.world.color = (0.0, 0.0, 0.0)
    mat = _emission_material("attr_view_layer_anim", lambda s: s.node(
        "ShaderNodeAttribute", attribute_type='VIEW_LAYER', attribute_name="vl_anim").outputs["Color"])
    me = build_scenes.mesh_sphere("attr_view_layer_anim_sphere", 0.4)
    me.materials.append(mat)
    build_scenes.add_object(scene, "attr_view_layer_anim", me)
    for frame, value in ((1, 0.2), (3, 0.6)):
        scene["vl_anim"] = value
        scene.keyframe_insert('["vl_anim"]', frame=frame)
    for fc in scene.animation_data.action.fcurves:
        for k in fc.keyframe_points:
            k.interpolation = 'LINEAR'
    scene.frame_start, scene.frame_end = 1, 3
    render_utils.configure(scene, render_utils.LANTERN, 4, 0)
    render_utils._exr_settings(scene)
    scene.render.use_persistent_data = True
    scene.render.filepath = str(tmp_path / "vl_")
    bpy.ops.render.render(animation=True, scene=scene.name)
    scene.render.use_persistent_data = False
    assert engine.LAST_RENDER["scene_sync"]["full_exports"] == 3, engine.LAST_RENDER["scene_sync"]
    for frame, want in ((1, 0.2), (2, 0.4), (3, 0.6)):
        img = render_utils.read_multilayer_exr(str(tmp_path / ("vl_%04d.exr" % frame)))["Combined"]
        h, w = img.shape[:2]
        centre = img[h // 2 - 2:h // 2 + 2, w // 2 - 2:w // 2 + 2, :3]
        assert np.allclose(centre, want, atol=2e-3), (frame, centre.mean((0, 1)))
