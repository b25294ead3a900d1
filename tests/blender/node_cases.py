"""Node set-ups against Cycles, pixel by pixel (issue 13's check): a node's output drives an Emission
shader seen by camera rays only, so the image is the node's value, rendered by both engines.

Two ways to look:
- compare_grid(name, cases, outdir): many set-ups in one render, one camera-facing plane each; each
  plane's UV square is cut into CELLS x CELLS cells feeding the set-up different inputs (Setup's
  cell_input); only pixels at least 2 pixels inside a cell are compared, so the pixel filter never
  mixes two cells. Each case is also rendered negated (an exact negation after the node).
- compare_view(build, label, outdir, shape=...): one set-up on a tilted plane under an orthographic
  camera (object coordinates vary along every axis), or on a sphere under a perspective camera
  (normals, incoming directions and angles vary), sampled near each pixel's centre (Gaussian filter
  0.01 px wide); the few pixels whose centre lies within the engines' sample jitter of a
  discontinuity or a silhouette may differ, at most OUTLIERS of them.
Bound: |Lantern - Cycles| <= 1e-3 |Cycles| + a small absolute term (float rounding near zero).
"""
import math
import os

import bmesh
import bpy
import numpy as np
from mathutils import Matrix

import build_scenes
import build_scenes as bs
import render_utils
import render_utils as ru

TILE = 32  # pixels per case (one plane)
CELLS = 4  # input cells per axis within a tile
COLUMNS = 8
RTOL, ATOL = 1e-3, 1e-5


class Setup:
    """Node-building helpers for one case's material."""

    def __init__(self, nt):
        self.nt = nt

    def node(self, idname, **props):
        n = self.nt.nodes.new(idname)
        for k, v in props.items():
            setattr(n, k, v)
        return n

    def link(self, out, inp):
        self.nt.links.new(out, inp)

    def value(self, x):
        n = self.node("ShaderNodeValue")
        n.outputs[0].default_value = x
        return n.outputs[0]

    def math(self, op, a, b=0.0):
        n = self.node("ShaderNodeMath", operation=op)
        for sock, v in ((n.inputs[0], a), (n.inputs[1], b)):
            if isinstance(v, (int, float)):
                sock.default_value = v
            else:
                self.link(v, sock)
        return n.outputs[0]

    def cell_input(self, axis, lo, hi):
        """lo..hi in CELLS steps along the plane's U (axis 0) or V (axis 1)."""
        tc = self.node("ShaderNodeTexCoord")
        sep = self.node("ShaderNodeSeparateXYZ")
        self.link(tc.outputs["UV"], sep.inputs[0])
        k = self.math("FLOOR", self.math("MULTIPLY", sep.outputs[axis], float(CELLS)))
        return self.math("ADD", self.math("MULTIPLY", k, (hi - lo) / (CELLS - 1)), lo)

    def vec(self, x, y, z):
        n = self.node("ShaderNodeCombineXYZ")
        for i, v in enumerate((x, y, z)):
            if isinstance(v, (int, float)):
                n.inputs[i].default_value = v
            else:
                self.link(v, n.inputs[i])
        return n.outputs[0]

    def feed(self, socket, v):
        if isinstance(v, (int, float)):
            socket.default_value = v
        elif isinstance(v, tuple):
            socket.default_value = v if len(socket.default_value) == len(v) else v + (1.0,)
        else:
            self.link(v, socket)


def _scene(name, n_cases):
    build_scenes.reset_file()
    rows = (n_cases + COLUMNS - 1) // COLUMNS
    cols = min(n_cases, COLUMNS)
    scene = build_scenes.new_scene(name, resolution=(cols * TILE, rows * TILE), samples=4)
    cam = bpy.data.cameras.new(name)
    cam.type = "ORTHO"
    cam.ortho_scale = float(max(cols, rows))
    cam.sensor_fit = "AUTO"
    obj = bpy.data.objects.new(name, cam)
    obj.location = (0.0, 0.0, 10.0)
    scene.collection.objects.link(obj)
    scene.camera = obj
    return scene, rows, cols


def compare_grid(name, cases, outdir):
    """cases: [(label, fn(setup) -> output socket[, prepare(plane object)])]: prepare, when given,
    adds what the case's set-up reads to its plane (attributes, object values). Renders all with
    both engines and returns [(label, worst relative excess)] of failing cases."""
    tiles = [(case[0], case[1], case[2] if len(case) > 2 else None, sign) for case in cases for sign in (1.0, -1.0)]
    scene, rows, cols = _scene(name, len(tiles))
    for i, (label, fn, prepare, sign) in enumerate(tiles):
        row, col = divmod(i, COLUMNS)
        mat = bpy.data.materials.new("%s_%d" % (name, i))
        mat.use_nodes = True
        nt = mat.node_tree
        nt.nodes.clear()
        s = Setup(nt)
        out = s.node("ShaderNodeOutputMaterial")
        em = s.node("ShaderNodeEmission")
        em.inputs["Strength"].default_value = 1.0
        value = fn(s)
        if sign < 0:
            neg = s.node("ShaderNodeMath", operation="MULTIPLY") if value.type == "VALUE" else s.node(
                "ShaderNodeVectorMath", operation="MULTIPLY")
            s.link(value, neg.inputs[0])
            neg.inputs[1].default_value = -1.0 if value.type == "VALUE" else (-1.0, -1.0, -1.0)
            value = neg.outputs[0]
        s.link(value, em.inputs["Color"])
        s.link(em.outputs[0], out.inputs["Surface"])
        me = build_scenes.mesh_plane("plane_%d" % i, 1.0)
        ob = build_scenes.add_object(scene, "plane_%d" % i, me,
                                     location=(col + 0.5 - cols / 2.0, rows / 2.0 - row - 0.5, 0.0))
        build_scenes.assign(ob, mat)
        if prepare is not None:
            prepare(ob)
    lt = render_utils.render(scene, render_utils.LANTERN, samples=4, outdir=outdir, tag=name + "_lantern").combined
    cy = render_utils.render(scene, render_utils.CYCLES, samples=4, outdir=outdir, tag=name + "_cycles").combined
    inner = (np.arange(TILE) % (TILE // CELLS) >= 2) & (np.arange(TILE) % (TILE // CELLS) < TILE // CELLS - 2)
    mask = inner[:, None] & inner[None, :]
    bad = []
    overall = 0.0
    for i, (label, _fn, _prepare, sign) in enumerate(tiles):
        row, col = divmod(i, COLUMNS)
        tl = np.maximum(lt[row * TILE:(row + 1) * TILE, col * TILE:(col + 1) * TILE, :3][mask], 0.0)
        tc = np.maximum(cy[row * TILE:(row + 1) * TILE, col * TILE:(col + 1) * TILE, :3][mask], 0.0)
        label = label if sign > 0 else "-(%s)" % label
        excess = np.abs(tl - tc) / (RTOL * np.abs(tc) + ATOL)
        worst = float(np.nanmax(excess)) if np.all(np.isfinite(tl)) else math.inf
        overall = max(overall, worst)
        if not worst <= 1.0:
            k = int(np.nanargmax(excess)) if np.isfinite(worst) else 0
            bad.append((label, round(worst, 2), tl.flat[k], tc.flat[k]))
    print("%s: %d cases, worst |L-C| / bound %.3g" % (name, len(cases), overall))
    if bad:
        render_utils.write_png(os.path.join(outdir, name + "_lantern.png"), lt)
        render_utils.write_png(os.path.join(outdir, name + "_cycles.png"), cy)
    return bad


# -- one set-up per view ----------------------------------------------------------------------

RES = int(os.environ.get("TEX_RES", 128))
SAMPLES = int(os.environ.get("TEX_SAMPLES", 1))
REL = 1e-3  # |Lantern - Cycles| <= REL |Cycles| + ABS per channel
ABS = 1e-4
OUTLIERS = 0.005  # fraction of pixels allowed beyond the bound (discontinuities under the jitter)
# Lantern's and Cycles' sample positions in a pixel differ by about 0.005 pixel (measured with this
# filter, 16 samples); where the image changes quickly, twice that times the change per pixel is
# allowed on top.
JITTER = 0.01
# The view's width in scene units. The engines' sample positions differ by a few thousandths of a
# pixel, so a texture must vary slowly per pixel for 1e-3 to hold: about four features per image.
VIEW = float(os.environ.get("TEX_VIEW", 0.6))


def view_scene(build, negate=False, shape="plane", displacement=None):
    """shape "plane": a 4 x 4 plane filling an orthographic view; the mesh is tilted inside its
    object (and the object tilted back), so Object coordinates vary along all three axes over the
    image. "sphere": a smooth UV sphere of radius 1 filling most of a perspective view;
    "ellipsoid": that sphere scaled unevenly, "scaled": scaled by 0.8 (object and world lengths
    differ); "points": a geometry-nodes point cloud (Mesh to Points on a 5 x 5 grid, radius 0.3)
    scaled unevenly and turned, under that camera. `build(nt,
    coords)` returns the socket shown (coords: Texture Coordinate's Object output); `displacement`,
    when given, the same way the socket linked into the Material Output's Displacement."""
    bs.reset_file()
    scene = bs.new_scene("view", resolution=(RES, RES), samples=1)
    c = scene.cycles
    c.pixel_filter_type = "GAUSSIAN"
    c.filter_width = 0.01
    c.max_bounces = 0
    c.film_exposure = 1.0
    scene.render.film_transparent = True  # alpha marks what the object covers
    if shape == "world":
        return world_view_scene(scene, build)
    if shape == "points":
        bs.add_camera(scene, (0.3, -3.2, 1.1), (0, 0, 0), lens=50.0)
        grid = bs.mesh_plane("points", 2.4, matrix=Matrix.Rotation(1.2, 4, "X"))
        bm = bmesh.new()
        bm.from_mesh(grid)
        bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=3, use_grid_fill=True)
        bm.to_mesh(grid)
        bm.free()
        obj = bs.add_object(scene, "points", grid, rotation=(0.3, 0.2, 0.5), scale=(1.0, 0.7, 1.25))
    elif shape in ("sphere", "ellipsoid", "scaled"):
        bs.add_camera(scene, (0.3, -3.2, 1.1), (0, 0, 0), lens=50.0)
        obj = bs.add_object(scene, "sphere", bs.mesh_sphere("sphere", 1.0), rotation=(0.3, 0.2, 0.5),
                            scale={"ellipsoid": (1.0, 0.7, 1.25), "scaled": (0.8, 0.8, 0.8)}.get(shape, (1, 1, 1)))
    else:
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
    if displacement is not None:
        nt.links.new(displacement(nt, coords), out.inputs["Displacement"])
    bs.assign(obj, mat)
    if shape == "points":
        tree = bpy.data.node_groups.new("ToPoints", "GeometryNodeTree")
        tree.inputs.new("NodeSocketGeometry", "Geometry")
        tree.outputs.new("NodeSocketGeometry", "Geometry")
        to_points = tree.nodes.new("GeometryNodeMeshToPoints")
        to_points.inputs["Radius"].default_value = 0.3
        set_mat = tree.nodes.new("GeometryNodeSetMaterial")
        set_mat.inputs["Material"].default_value = mat
        tree.links.new(tree.nodes.new("NodeGroupInput").outputs[0], to_points.inputs["Mesh"])
        tree.links.new(to_points.outputs[0], set_mat.inputs["Geometry"])
        tree.links.new(set_mat.outputs[0], tree.nodes.new("NodeGroupOutput").inputs[0])
        obj.modifiers.new("Points", "NODES").node_group = tree
    return scene


def world_view_scene(scene, build):
    """shape "world": the World's node tree shown by `build(nt, coords)` (coords: Texture
    Coordinate's Generated, the direction) seen whole through an equirectangular panorama (every
    direction, 2 RES x RES pixels), nothing else."""
    scene.render.resolution_x, scene.render.resolution_y = 2 * RES, RES
    scene.render.film_transparent = False
    cam = bs.add_camera(scene, (0, 0, 0), (0, 1, 0))
    cam.data.type = "PANO"
    cam.data.cycles.panorama_type = "EQUIRECTANGULAR"
    world, nt, out = bs._world_nodes(scene, "view")
    shown = build(nt, nt.nodes.new("ShaderNodeTexCoord").outputs["Generated"])
    bg = node(nt, "ShaderNodeBackground", Strength=1.0)
    nt.links.new(shown, bg.inputs["Color"])
    nt.links.new(bg.outputs[0], out.inputs["Surface"])
    return scene


def bpy_material(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    return mat


def beyond(lantern, cycles, slope):
    """Pixels beyond the bound (a mask), and the worst ratio to the bound. slope: how much the image
    changes per pixel there; the engines' sample positions differ by up to JITTER pixels."""
    diff = np.abs(lantern - cycles)
    bound = REL * np.abs(cycles) + ABS + JITTER * slope
    return np.any(diff > bound, axis=-1), float((diff / bound).max())


def slope_of(img):
    """Per pixel and channel, the largest change to a neighbouring pixel."""
    s = np.zeros_like(img)
    for axis in (0, 1):
        d = np.abs(np.diff(img, axis=axis))
        pad = [(0, 0)] * img.ndim
        pad[axis] = (1, 0)
        s = np.maximum(s, np.pad(d, pad))
        pad[axis] = (0, 1)
        s = np.maximum(s, np.pad(d, pad))
    return s


def render_pair(build, label, outdir, negate=False, shape="plane", displacement=None):
    scene = view_scene(build, negate, shape, displacement)
    tag = label + ("_neg" if negate else "")
    lantern = ru.render(scene, ru.LANTERN, samples=SAMPLES, outdir=outdir, tag=tag + "_lantern").combined
    cycles = ru.render(scene, ru.CYCLES, samples=SAMPLES, outdir=outdir, tag=tag + "_cycles").combined
    # Pixels next to a silhouette see the object or the background depending on the engines' jitter:
    # only pixels whose 3 x 3 neighbourhood is covered in both renders are compared.
    covered = np.minimum(lantern[..., 3], cycles[..., 3]) >= 1
    inner = covered.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= np.roll(np.roll(covered, dy, axis=0), dx, axis=1)
    inner[[0, -1], :] = False
    inner[:, [0, -1]] = False
    slope = slope_of(cycles[..., :3])[inner]
    return lantern[..., :3][inner], cycles[..., :3][inner], (lantern, cycles, slope)


def compare_view(build, label, outdir, flat=False, shape="plane", displacement=None):
    """Renders the set-up `build` makes in both engines and compares them pixel by pixel. Should
    Lantern's emission keep no negative radiance where Cycles' does, the set-up is rendered again
    negated (an exact negation after the node) and the positive parts of both renders are compared,
    so both signs of the output are still checked."""
    lantern, cycles, images = render_pair(build, label, outdir, shape=shape, displacement=displacement)
    # The image must show a pattern, or the comparison proves little.
    assert flat or float(cycles.std()) > 1e-3, "%s: Cycles renders a flat image" % label
    slope = images[2]
    bad, worst = beyond(lantern, cycles, slope)
    if bad.mean() > OUTLIERS and (cycles < 0).any() and (lantern >= 0).all():
        lantern_neg, _, _ = render_pair(build, label, outdir, negate=True, shape=shape, displacement=displacement)
        bad, worst = beyond(lantern, np.maximum(cycles, 0.0), slope)
        bad_neg, worst_neg = beyond(lantern_neg, np.maximum(-cycles, 0.0), slope)
        bad, worst = bad | bad_neg, max(worst, worst_neg)
    frac = float(bad.mean())
    if frac > OUTLIERS:
        ru.write_png("%s/%s_lantern.png" % (outdir, label), images[0])
        ru.write_png("%s/%s_cycles.png" % (outdir, label), images[1])
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
