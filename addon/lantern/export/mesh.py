"""Mesh export: each distinct evaluated geometry once, then one instance per object instance."""

import bpy
import numpy as np

from .attribute_values import attribute_array
from .light import visibility_bits
from .hair import (curves_arrays, generic_attributes, hair_systems, particle_hair_arrays,
                   particle_hair_attributes, pointcloud_arrays)
from .names import core_call, transform_problem
from .nodes.attributes import object_random_id

# Cycles' defaults of Object.cycles.shadow_terminator_geometry_offset and shadow_terminator_offset.
TERMINATOR_DEFAULT = (0.1, 0.0)


def terminator_of(obj):
    """Cycles' shadow terminator settings of an object (Object Properties > Shading):
    (Geometry Offset, Shading Offset), Cycles' defaults where its settings are absent."""
    c = getattr(obj, "cycles", None)
    if c is None:
        return TERMINATOR_DEFAULT
    return (float(getattr(c, "shadow_terminator_geometry_offset", TERMINATOR_DEFAULT[0])),
            float(getattr(c, "shadow_terminator_offset", TERMINATOR_DEFAULT[1])))


# Object types Blender can turn into a mesh with to_mesh().
CONVERTIBLE_TYPES = {'CURVE', 'SURFACE', 'FONT', 'META'}


def _loop_values(mesh, attr):
    """(components, per-loop values (n_loops, components)) of a Mesh.attributes entry, or None."""
    got = attribute_array(attr) if attr.domain in ('POINT', 'CORNER', 'FACE') else None
    if got is None:
        return None
    n, values = got
    if attr.domain == 'CORNER':
        return n, values
    if attr.domain == 'POINT':
        loop_vertex = np.empty(len(mesh.loops), dtype=np.int32)
        mesh.loops.foreach_get("vertex_index", loop_vertex)
        return n, values[loop_vertex]
    starts = np.empty(len(mesh.polygons), dtype=np.int32)
    totals = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    mesh.polygons.foreach_get("loop_total", totals)
    loop_poly = np.zeros(len(mesh.loops), dtype=np.int64)
    loop_poly[starts[totals > 0]] = 1
    loop_poly = np.cumsum(loop_poly) - 1
    return n, values[loop_poly]


def _render_uv(mesh, name):
    if name:
        return mesh.uv_layers.get(name)
    return next((l for l in mesh.uv_layers if l.active_render), None) or mesh.uv_layers.active


def _map_to_sphere(co):
    """Cycles' map_to_sphere (util/math.h): (u, v) of directions from the origin, in
    float32 as Cycles computes them; (0, 0) at the origin, u = 0 on the Z axis."""
    co = np.asarray(co, np.float32).reshape(-1, 3)
    x, y, z = co[:, 0], co[:, 1], co[:, 2]
    length = np.sqrt(x * x + y * y + z * z)
    safe = np.where(length > 0, length, np.float32(1))
    u = (np.float32(1) - np.arctan2(x, y) / np.float32(np.pi)) / np.float32(2)
    u = np.where((x == 0) & (y == 0), np.float32(0), u)
    v = np.float32(1) - np.arccos(np.clip(z / safe, -1, 1)) / np.float32(np.pi)
    uv = np.stack([u, v], axis=1).astype(np.float32)
    uv[~(length > 0)] = 0
    return uv


def _smooth_triangles(tris):
    """Each loop triangle's smooth flag (all smooth in Blender versions without the property: their
    corner normals are flat on flat faces anyway)."""
    smooth = np.ones(len(tris), dtype=bool)
    try:
        tris.foreach_get("use_smooth", smooth)
    except (AttributeError, TypeError, RuntimeError):
        smooth[:] = True
    return smooth


def _sphere_tangents(mesh, warn):
    """Cycles 3.4's tangents on a mesh without UV maps (blender/mesh.cpp, MikkTSpace fed the loop
    triangles, each corner's UV its vertex's undeformed position mapped to a sphere): Blender's
    MikkTSpace run on a temporary mesh of those triangles (run on the polygons, it would split the
    quads where the wrapped coordinates jump differently). Smooth triangles take that mesh's vertex
    normals, Cycles the polygons' (equal where the polygons are planar). Per triangle corner:
    (tangents, signs), or None."""
    tris = mesh.loop_triangles
    nt, nv = len(tris), len(mesh.vertices)
    triangles = np.empty(nt * 3, dtype=np.int32)
    tris.foreach_get("vertices", triangles)
    smooth = _smooth_triangles(tris)
    co = np.empty(nv * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    undeformed = np.empty(nv * 3, dtype=np.float32)
    mesh.vertices.foreach_get("undeformed_co", undeformed)
    # Cycles' coordinates: the undeformed ones through its Generated attribute and back, in float32
    # (mesh_texture_space; the seam's u of 0 or 1 turns on the sign of what remains of x = 0).
    size = np.array(mesh.texspace_size, np.float32)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(size != 0, np.float32(0.5) / size, size)
        loc = np.array(mesh.texspace_location, np.float32) * scale - np.float32(0.5)
        generated = undeformed.reshape(-1, 3) * scale - loc
        orco = (generated + loc) * (np.float32(1) / scale)
    try:
        tm = bpy.data.meshes.new("lantern_sphere_tangents")
    except RuntimeError as e:  # a context where data cannot be added
        warn("tangents from the undeformed coordinates cannot be computed here (%s); Normal Maps are "
             "left flat" % str(e).strip())
        return None
    try:
        tm.vertices.add(nv)
        tm.vertices.foreach_set("co", co)
        tm.loops.add(nt * 3)
        tm.loops.foreach_set("vertex_index", triangles)
        tm.polygons.add(nt)
        tm.polygons.foreach_set("loop_start", np.arange(0, nt * 3, 3, dtype=np.int32))
        tm.polygons.foreach_set("loop_total", np.full(nt, 3, dtype=np.int32))
        tm.polygons.foreach_set("use_smooth", smooth)
        tm.update(calc_edges=True)
        layer = tm.uv_layers.new(name="sphere", do_init=False)
        layer.data.foreach_set("uv", _map_to_sphere(orco)[triangles].reshape(-1))
        tm.calc_tangents(uvmap=layer.name)
        t = np.empty(nt * 9, dtype=np.float32)
        sign = np.empty(nt * 3, dtype=np.float32)
        tm.loops.foreach_get("tangent", t)
        tm.loops.foreach_get("bitangent_sign", sign)
        return t, sign
    finally:
        bpy.data.meshes.remove(tm)


def _requested(mesh, key, warn):
    """(components, per-loop values) of an attribute request (AttributeRegistry key), or None when
    the mesh lacks it (the core then gives Cycles' values for a missing attribute); a third
    element 'corners' when the values are per loop triangle corner already."""
    kind, name = key
    nl = len(mesh.loops)
    if kind == 'tangent':
        layer = _render_uv(mesh, name)
        if layer is None and not name and not len(mesh.uv_layers):
            # Cycles 3.4 (blender/mesh.cpp, mikk_get_texture_coordinate): without any UV map the
            # default tangent space comes from the undeformed coordinates mapped to a sphere.
            got = _sphere_tangents(mesh, warn)
            corners = True
        elif layer is None:
            warn("no UV map '%s' for tangent space: Normal Maps are left flat and Vector Displacement "
                 "uses each triangle's first edge as tangent" % name if name else
                 "no render UV map for tangent space: Normal Maps are left flat and Vector Displacement "
                 "uses each triangle's first edge as tangent")
            return None
        else:
            try:
                mesh.calc_tangents(uvmap=layer.name)
            except RuntimeError as e:
                warn("tangents of UV map '%s' cannot be computed (%s); normal maps there are left flat"
                     % (layer.name, str(e).strip()))
                return None
            got, corners = (np.empty(nl * 3, dtype=np.float32), np.empty(nl, dtype=np.float32)), False
            mesh.loops.foreach_get("tangent", got[0])
            mesh.loops.foreach_get("bitangent_sign", got[1])
        if got is None:
            return None
        values = np.empty((len(got[1]), 4), dtype=np.float32)
        values[:, :3] = got[0].reshape(-1, 3)
        values[:, 3] = got[1]
        return (4, values, 'corners') if corners else (4, values)
    if kind == 'color':
        attrs = getattr(mesh, "color_attributes", None)
        if attrs is None or not len(attrs):
            return None
        index = getattr(attrs, "render_color_index", -1)
        attr = attrs[index] if 0 <= index < len(attrs) else attrs.active_color
        return _loop_values(mesh, attr) if attr is not None else None
    layer = mesh.uv_layers.get(name)
    if layer is not None:
        uvs = np.empty(nl * 2, dtype=np.float32)
        layer.data.foreach_get("uv", uvs)
        return 2, uvs.reshape(-1, 2)
    attr = mesh.attributes.get(name)
    return _loop_values(mesh, attr) if attr is not None else None


def mesh_attributes(mesh, requests, corner_loops, warn=lambda _t: None):
    """The core's (id, components, per-corner values) for the requested attributes the mesh has."""
    out = []
    for key, attr_id in requests:
        got = _requested(mesh, key, warn)
        if got is None:
            continue
        n, values = got[:2]
        values = np.nan_to_num(values if len(got) > 2 else values[corner_loops], nan=0.0, posinf=0.0, neginf=0.0)
        out.append((attr_id, n, np.ascontiguousarray(values, dtype=np.float32).reshape(-1)))
    return out


def _property(owner, name):
    """Cycles' lookup_property (blender/object.cpp): a custom property or an RNA path of owner
    that is a number or an array of at most 4 floats, as (x, y, z, w) (a number n: (n, n, n, 1),
    a shorter array padded with 0 and a last 1); None where there is none."""
    for path in ('["%s"]' % name.replace('\\', '\\\\').replace('"', '\\"'), name):
        try:
            value = owner.path_resolve(path)
        except (ValueError, TypeError):
            continue
        if isinstance(value, bool):  # a boolean property: Cycles reads none
            continue
        if isinstance(value, (int, float)):
            v = [float(value)] * 3 + [1.0]
        else:
            try:
                items = list(value)
            except TypeError:
                continue
            if not items or len(items) > 4 or not all(isinstance(x, float) for x in items):
                continue
            v = items + [0.0, 0.0, 0.0, 1.0][len(items):]
        if all(x == x and abs(x) != float('inf') for x in v):
            return v
    return None


def object_values(obj, keys, instancer=None):
    """(id, 4 floats) of the object attributes (the Attribute node's Object and Instancer types)
    found as Cycles' lookup_instance_property finds them: for the Instancer type on an instance,
    on its particle system's settings, then on its instancer (instancer = (parent object,
    particle system or None)); then on the object, then on its data."""
    out = []
    for name, attr_id, use_instancer in keys:
        if not name:
            continue
        owners = []
        if use_instancer and instancer is not None:
            parent, psys = instancer
            owners = [psys.settings if psys is not None else None, parent]
        owners += [obj, getattr(obj, "data", None)]
        for owner in owners:
            value = _property(owner, name) if owner is not None else None
            if value is not None:
                out.append((attr_id, value))
                break
    return out


def instance_values(obj, object_keys, instancer=None):
    """What a core instance takes from its object beside its geometry and transform: ray
    visibility bits, Object Info's Color and Object Index, the Attribute node's object values
    (object_values)."""
    return visibility_bits(obj), tuple(obj.color), obj.pass_index, object_values(obj, object_keys, instancer)


def view_layer_value(depsgraph, name):
    """The Attribute node's View Layer type as Cycles 3.4 resolves it (resolve_view_layer_attributes,
    BKE_view_layer_find_rgba_attribute): name on the view layer, then the scene, then its world
    (a custom property before an RNA path, as _property); 4 zeros where none has it."""
    scene = depsgraph.scene_eval
    for owner in (depsgraph.view_layer_eval, scene, scene.world):
        value = _property(owner, name) if owner is not None and name else None
        if value is not None:
            return tuple(value)
    return (0.0, 0.0, 0.0, 0.0)


def smooth_vertex_normals(mesh, positions):
    """Blender 3.x's vertex normals (mesh_normals.cc, mesh_calc_normals_poly_and_vertex: each
    polygon's normal weighted by its corner's angle, summed per vertex, normalised; a zero sum
    takes the normalised position), summed in a fixed order. Blender sums them with atomic adds
    over threads, so its normals differ in the last bits from one evaluation to the next (a
    subdivided Suzanne's in each of 10), and with them a seed's render; these are the same bits
    every time. Its polygon normals are computed one polygon at a time: those are taken."""
    n_loops, n_polys = len(mesh.loops), len(mesh.polygons)
    vert = np.empty(n_loops, np.int32)
    mesh.loops.foreach_get("vertex_index", vert)
    start = np.empty(n_polys, np.int32)
    total = np.empty(n_polys, np.int32)
    face = np.empty(n_polys * 3, np.float32)
    mesh.polygons.foreach_get("loop_start", start)
    mesh.polygons.foreach_get("loop_total", total)
    mesh.polygons.foreach_get("normal", face)
    # Each corner's neighbours in its polygon.
    nxt = np.arange(1, n_loops + 1, dtype=np.int32)
    nxt[start + total - 1] = start
    prv = np.arange(-1, n_loops - 1, dtype=np.int32)
    prv[start] = start + total - 1
    p = positions.reshape(-1, 3)
    a = p[vert]
    to_prev, to_next = p[vert[prv]] - a, p[vert[nxt]] - a
    _normalise(to_prev, 0.0)
    _normalise(to_next, 0.0)
    cosine = np.einsum("ij,ij->i", to_prev, to_next)
    angle = np.arccos(np.clip(cosine, -1.0, 1.0, out=cosine), out=cosine)
    corner_face = face.reshape(-1, 3)[np.repeat(np.arange(n_polys, dtype=np.int32), total)]
    normals = np.empty((len(p), 3), np.float64)
    for k in range(3):
        normals[:, k] = np.bincount(vert, corner_face[:, k] * angle, len(p))
    zero = _normalise(normals, 0.0)
    normals[zero] = p[zero]  # Blender's fallback for a vertex whose sum is zero
    _normalise(normals, 0.0)
    return normals.astype(np.float32)


def _normalise(v, fallback):
    """Normalises the rows of v in place; rows of length 0 become `fallback`. Returns those rows."""
    length = np.sqrt(np.einsum("ij,ij->i", v, v))
    zero = length == 0
    length[zero] = 1
    v /= length[:, None]
    v[zero] = fallback
    return zero


def mesh_arrays(mesh, requests=(), warn=lambda _t: None):
    """Triangle arrays of a Blender mesh, or None when it has no faces.

    Corner normals come from Blender's split normals (smooth, flat, auto smooth and custom
    normals alike); they are omitted when every face is flat, the core then uses the
    geometric normal as Cycles does.
    """
    mesh.calc_loop_triangles()
    tris = mesh.loop_triangles
    nt = len(tris)
    if nt == 0:
        return None
    nv = len(mesh.vertices)
    positions = np.empty(nv * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", positions)
    triangles = np.empty(nt * 3, dtype=np.int32)
    tris.foreach_get("vertices", triangles)
    corner_loops = np.empty(nt * 3, dtype=np.int32)
    tris.foreach_get("loops", corner_loops)
    material_slots = np.empty(nt, dtype=np.int32)
    tris.foreach_get("material_index", material_slots)

    smooth = _smooth_triangles(tris)
    has_custom = getattr(mesh, "has_custom_normals", False)
    corner_normals = flat_triangles = None
    if smooth.any() or has_custom:
        if not has_custom and getattr(mesh, "use_auto_smooth", True) is False:
            # Blender < 4.1 without Auto Smooth: a smooth corner's normal is its vertex's.
            corner_normals = smooth_vertex_normals(mesh, positions)[triangles]
        else:
            if hasattr(mesh, "calc_normals_split"):  # Blender < 4.1; later versions keep them current
                mesh.calc_normals_split()
            nl = len(mesh.loops)
            loop_normals = np.empty(nl * 3, dtype=np.float32)
            if hasattr(mesh, "corner_normals"):
                mesh.corner_normals.foreach_get("vector", loop_normals)
            else:
                mesh.loops.foreach_get("normal", loop_normals)
            corner_normals = loop_normals.reshape(-1, 3)[corner_loops]
        if not has_custom and not smooth.all():
            # Flat triangles of a non-planar polygon: the triangle's own normal, as Cycles.
            flat = ~smooth
            p = positions.reshape(-1, 3)[triangles.reshape(-1, 3)[flat]]
            n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
            corner_normals.reshape(nt, 3, 3)[flat] = n[:, None, :]
            flat_triangles = flat  # true displacement gives them their displaced face normal
        corner_normals = corner_normals.reshape(-1)

    corner_uvs = None
    layer = next((l for l in mesh.uv_layers if l.active_render), None) or mesh.uv_layers.active
    if layer is not None:
        uvs = np.empty(len(mesh.loops) * 2, dtype=np.float32)
        layer.data.foreach_get("uv", uvs)
        corner_uvs = uvs.reshape(-1, 2)[corner_loops].reshape(-1)

    # After the normals: computing tangents recomputes the loop normals.
    attributes = mesh_attributes(mesh, requests, corner_loops, warn) if requests else []

    # Generated coordinates live in the mesh's texture space (automatic: its bounds).
    texspace = dict(texspace_location=tuple(getattr(mesh, "texspace_location", (0.0, 0.0, 0.0))),
                    texspace_size=tuple(getattr(mesh, "texspace_size", (0.0, 0.0, 0.0))))
    return dict(positions=positions, triangles=triangles, corner_normals=corner_normals, flat_triangles=flat_triangles,
                corner_uvs=corner_uvs, material_slots=material_slots, attributes=attributes, **texspace)


_NOT_KEPT = object()  # equal to no arrays (_same)


def _same(a, b):
    """Exact equality of export arrays: dicts, sequences, numpy arrays and plain values."""
    if isinstance(a, dict) or isinstance(b, dict):
        return isinstance(a, dict) and isinstance(b, dict) and a.keys() == b.keys() \
            and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype \
            and np.array_equal(a, b)
    if isinstance(a, (list, tuple)) or isinstance(b, (list, tuple)):
        return isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)) and len(a) == len(b) \
            and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def _same_strands(new, old, matrix_world):
    """particle_hair_arrays' (points, offsets, slots) the same up to the rounding of reading keys
    back into object space: offsets and slots exactly, keys within 1e-5 of their world-space extent
    once placed by matrix_world, radii within 1e-5 of the largest."""
    if new[0].shape != old[0].shape or not _same(new[1:], old[1:]):
        return False
    m = np.asarray(matrix_world, dtype=np.float64)
    p, q = new[0].astype(np.float64), old[0].astype(np.float64)
    extent = 1.0 + np.abs(p[:, :3] @ m[:3, :3].T + m[:3, 3]).max(initial=0.0)
    moved = np.abs((p[:, :3] - q[:, :3]) @ m[:3, :3].T).max(initial=0.0)
    radius = np.abs(p[:, 3] - q[:, 3]).max(initial=0.0)
    return bool(moved <= 1e-5 * extent and radius <= 1e-5 * np.abs(q[:, 3]).max(initial=0.0))


def open_edge_count(triangles):
    """Edges used by exactly one triangle (0 for a closed mesh)."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    e.sort(axis=1)
    keys = e[:, 0] * (int(t.max()) + 1) + e[:, 1]
    _, counts = np.unique(keys, return_counts=True)
    return int((counts == 1).sum())


class MeshExporter:
    """Adds geometry once per distinct evaluated datablock and an instance per object instance."""

    def __init__(self, depsgraph, core_scene, report, materials, motion=None):
        self.depsgraph = depsgraph
        self.motion = motion  # export/motion.py's Motion, or None
        self.core_scene = core_scene
        self.report = report
        self.materials = materials
        self.mesh_ids = {}  # geometry key -> core mesh id, or None for empty geometry
        self.open_edges = {}  # geometry key -> edges with one triangle (meshes with volumes only)
        self.instance_count = 0
        # Original object pointer -> {'mesh': mesh_arrays, 'hair': (points, offsets, slots)} of
        # each particle-hair emitter, kept for emitter_unchanged (a dict when the scene is kept:
        # the viewport's, Persistent Data's), 16 bytes a hair key beside the core's copy.
        self.emitters = None
        # instance_key -> [(how many object keys, instance_values, core id)] of each core instance
        # added for it, kept for value_edits (a dict when the scene is kept).
        self.instance_values = None
        # Core id -> the motion steps it was added with (None: still), kept for the kept scene's
        # motion edits (a dict when the scene is kept with motion blur).
        self.instance_motion = None

    def _geometry_key(self, obj):
        if obj.type == 'MESH' and obj.data is not None:
            return ('MESH', obj.data.as_pointer())
        # Converted geometry depends on the object's own modifiers: one per object.
        return (obj.type, obj.original.as_pointer())

    def _mesh_id(self, obj, warn_empty=True, deform=False):
        key = self._geometry_key(obj)
        emitter = self.emitters is not None and obj.type == 'MESH' and hair_systems(obj)
        if key in self.mesh_ids:
            if emitter:  # arrays read for another object, not kept: emitter_unchanged says no
                self.emitters.setdefault(obj.original.as_pointer(), {})['mesh'] = _NOT_KEPT
            return self.mesh_ids[key]
        mesh_id = None
        mesh, temporary = None, False
        try:
            if obj.type == 'MESH':
                mesh = obj.data
            else:
                mesh, temporary = obj.to_mesh(), True
            warn = lambda t: self.report({'WARNING'}, "Object '%s': %s" % (obj.name, t))  # noqa: E731
            requests = self.materials.attributes.mesh_keys()
            arrays = mesh_arrays(mesh, requests, warn) if mesh is not None else None
            if emitter:
                self.emitters.setdefault(obj.original.as_pointer(), {})['mesh'] = arrays
            if arrays is None:
                # Vertices or edges without faces; an empty mesh (all of a geometry-nodes object's
                # output points or instances, which come as their own instances) says nothing.
                if warn_empty and mesh is not None and len(mesh.vertices):
                    self.report({'WARNING'}, "Object '%s' has no faces, skipped" % obj.name)
            else:
                if deform and self.motion is not None and obj.type == 'MESH':
                    d = self.motion.deformation(obj, arrays)
                    if d is not None:
                        arrays.update(motion_positions=d[0], motion_corner_normals=d[1])
                # Degenerate or non-finite triangles are dropped by the core (reported by name).
                mesh_id = core_call(self.core_scene, self.report, "Object '%s'" % obj.name, "add_mesh", **arrays)
                if arrays["triangles"].size and self.materials.media:
                    self.open_edges[key] = open_edge_count(arrays["triangles"])
        finally:
            if temporary:
                obj.to_mesh_clear()
        self.mesh_ids[key] = mesh_id
        return mesh_id

    def _material_ids(self, obj):
        slots = obj.material_slots
        if len(slots):
            mats = [s.material for s in slots]
        else:
            data = obj.data
            mats = list(getattr(data, "materials", [])) if data is not None else []
        return [self.materials.export(m) for m in mats]

    def export_instance(self, obj, matrix_world, warn_empty=True, random_id=None, key=None, deform=False,
                        holdout=False, lightgroup=0, shadow_catcher=False, instancer=None):
        """obj: an evaluated object of a mesh or convertible type; random_id: the depsgraph
        instance's (None for an object that is no instance); key: its instance_key, for motion
        blur; deform: whether its mesh may deform over the shutter (an object, not an instance);
        holdout: a holdout object (export.holdout_of); lightgroup: its emission's (export.lightgroup_of);
        instancer: an instance's (export.instancer_of), for Instancer attributes.
        Returns the core instance id, or None when the object has no geometry."""
        problem = transform_problem(matrix_world)
        if problem is not None:
            self.report({'WARNING'}, "Object '%s' left out: %s" % (obj.name, problem))
            return None
        # Materials first: the mesh exports the attributes their programs read.
        material_ids = self._material_ids(obj)
        mesh_id = self._mesh_id(obj, warn_empty, deform)
        if mesh_id is None:
            return None
        motion = self.motion.transforms(key, matrix_world, obj.name) if self.motion is not None else None
        if np.linalg.det(np.asarray(matrix_world, dtype=np.float64)[:3, :3]) == 0:
            self.report({'WARNING'}, "Object '%s' has zero scale on an axis: rendered as the flat shape it "
                        "becomes (Cycles 3.4 renders such objects black)" % obj.name)
        self._check_closed(obj, material_ids)
        self._check_adaptive(obj)
        return self._add_instance("Object '%s'" % obj.name, obj, mesh_id, matrix_world, material_ids, random_id,
                                  instancer, motion, key, holdout, shadow_catcher, lightgroup)

    def export_curves_instance(self, obj, matrix_world, kind, random_id=None, holdout=False, lightgroup=0,
                               shadow_catcher=False, key=None, instancer=None):
        """Curves or spheres of obj as an instance: kind 'HAIR' (the object's particle hair),
        'CURVES' (a Curves object) or 'POINTCLOUD'; key: the object instance's instance_key, for
        its transform's motion; the strands' deformation comes from the Motion's samples;
        instancer as export_instance's. Returns the core instance id or None."""
        problem = transform_problem(matrix_world)
        if problem is not None:
            self.report({'WARNING'}, "Object '%s' left out: %s" % (obj.name, problem))
            return None
        material_ids = self._material_ids(obj)
        geometry = (kind, obj.original.as_pointer() if kind == 'HAIR' else self._geometry_key(obj))
        subject = "Object '%s'%s" % (obj.name, " (particle hair)" if kind == 'HAIR' else "")
        if geometry not in self.mesh_ids:
            reads = set().union(*(self.materials.geometry_reads.get(m, ()) for m in material_ids))
            ids = self.materials.attributes.ids
            values = None, ()
            texspace = None
            if kind == 'HAIR':
                arrays = particle_hair_arrays(obj, self.report)
                args = arrays and (arrays[0], arrays[1], arrays[2])
                if args and reads:
                    values = particle_hair_attributes(obj, reads, ids)
                # Cycles' sync_particle_hair: Generated is each strand's root through the emitter's texture space.
                texspace = tuple(obj.data.texspace_location), tuple(obj.data.texspace_size)
            elif kind == 'CURVES':
                arrays = curves_arrays(obj.data)
                args = arrays and (arrays[0], arrays[1], None)
                if args and reads:
                    values = generic_attributes(obj.data, reads, ids, {'POINT': True, 'CURVE': False})
            else:
                points = pointcloud_arrays(obj.data)
                args = None if points is None else (points, None, None)
                if args and reads:
                    values = generic_attributes(obj.data, reads, ids, {'POINT': True})
            if self.emitters is not None and kind == 'HAIR':
                self.emitters.setdefault(obj.original.as_pointer(), {})['hair'] = args
            deform = None
            if args is not None and self.motion is not None:
                deform = self.motion.strand_deformation(obj, args[0])
            self.mesh_ids[geometry] = None if args is None else core_call(self.core_scene, self.report, subject,
                                                                          "add_curves", *args, motion=deform,
                                                                          uvs=values[0], texspace=texspace,
                                                                          attributes=values[1])
        mesh_id = self.mesh_ids[geometry]
        if mesh_id is None:
            return None
        motion = None
        if self.motion is not None and key is not None:
            motion = self.motion.transforms(key, matrix_world, obj.name)
        return self._add_instance(subject, obj, mesh_id, matrix_world, material_ids, random_id, instancer, motion,
                                  key, holdout, shadow_catcher, lightgroup)

    def _add_instance(self, subject, obj, mesh_id, matrix_world, material_ids, random_id, instancer, motion, key,
                      holdout, shadow_catcher, lightgroup):
        if self.motion is not None and motion is self.motion.HIDDEN:
            return None
        if random_id is None:
            random_id = object_random_id(obj.name)
        object_keys = self.materials.attributes.object_keys()
        values = instance_values(obj, object_keys, instancer)
        visibility, color, pass_index, attributes = values
        instance = core_call(self.core_scene, self.report, subject, "add_instance",
                             mesh_id, matrix_world, material_ids, visibility, color=color,
                             pass_index=pass_index, random_id=random_id, attributes=attributes, motion=motion,
                             cryptomatte=self.materials.cryptomatte.instance(obj), holdout=holdout,
                             shadow_catcher=shadow_catcher, terminator=terminator_of(obj),
                             lightgroup=lightgroup)
        if instance is not None:
            self.instance_count += 1
            if self.instance_motion is not None:
                self.instance_motion[instance] = motion
            if self.instance_values is not None and key is not None:
                self.instance_values.setdefault(key, []).append((len(object_keys), values, instance))
        return instance

    def value_edits(self, inst, key, instancer, object_keys):
        """What the object of depsgraph instance inst (instance_key key) now gives its core instances
        (object_keys: the materials' attributes.object_keys()), against what they were added with:
        [(core id, instance_values)] of those whose ray visibility, colour, pass index or object
        attributes changed (the core sets them in place: set_instance_values, then record_values)."""
        edits = []
        for n, values, core_id in self.instance_values.get(key, ()):
            now = instance_values(inst.object, object_keys[:n], instancer)
            if now != values:
                edits.append((core_id, now))
        return edits

    def record_values(self, key, core_id, values):
        """The values value_edits found, once the core instance core_id of key has them."""
        self.instance_values[key] = [(n, values if i == core_id else v, i) for n, v, i in self.instance_values[key]]

    def emitter_unchanged(self, obj, matrix_world):
        """Whether a particle-hair emitter's evaluated geometry is still what the export recorded,
        so that the kept scene only moves it: Blender flags every move of an emitter as a geometry
        update (its particles are evaluated again). The mesh must read the same to the bit; the hair
        keys, read back from Blender's world-space float32 path cache into object space, to
        rounding: within 1e-5 of the strands' world-space extent when placed by matrix_world."""
        kept = (self.emitters or {}).get(obj.original.as_pointer())
        if not kept:
            return False
        silent = lambda *_: None  # noqa: E731 (the export reported them)
        if 'mesh' in kept:
            mesh = mesh_arrays(obj.data, self.materials.attributes.mesh_keys(), silent)
            if not _same(mesh, kept['mesh']):
                return False
        if 'hair' in kept:
            hair, old = particle_hair_arrays(obj, silent), kept['hair']
            if (hair is None) != (old is None) or (hair is not None and not _same_strands(hair, old, matrix_world)):
                return False
        return True

    def _check_adaptive(self, obj):
        """Cycles' experimental adaptive subdivision (dicing by screen size) is not done."""
        scene = self.depsgraph.scene
        if (getattr(getattr(obj, "cycles", None), "use_adaptive_subdivision", False)
                and getattr(getattr(scene, "cycles", None), "feature_set", "") == 'EXPERIMENTAL'):
            self.report({'WARNING'}, "Object '%s': adaptive subdivision (Cycles' experimental feature) is not "
                        "supported; the mesh renders as the depsgraph evaluates it (true displacement moves its "
                        "vertices)" % obj.name)

    def _check_closed(self, obj, material_ids):
        """Warns when a mesh carrying a volume material is open: the volume stack enters a medium
        where a ray crosses one of its faces from the front and leaves it only where a ray crosses
        one from the back, so an open mesh's medium has no defined inside."""
        volumes = [self.materials.volume_name(m) for m in material_ids]
        volumes = [v for v in volumes if v is not None]
        if not volumes:
            return
        key = self._geometry_key(obj)
        if key not in self.open_edges:  # the mesh was exported before any volume material
            mesh, temporary = (obj.data, False) if obj.type == 'MESH' else (obj.to_mesh(), True)
            try:
                arrays = mesh_arrays(mesh) if mesh is not None else None
                self.open_edges[key] = open_edge_count(arrays["triangles"]) if arrays else 0
            finally:
                if temporary:
                    obj.to_mesh_clear()
        n = self.open_edges[key]
        if n:
            self.report({'WARNING'}, "Object '%s': its mesh is not closed (%d open edge(s)) but carries the volume "
                        "of material %s. Lantern enters a medium where a ray crosses one of the mesh's faces from "
                        "the front and leaves it where a ray crosses one from the back: through the opening, rays "
                        "stay inside the medium (or outside it) beyond the mesh; close the mesh for a defined "
                        "volume" % (obj.name, n, ", ".join("'%s'" % v for v in sorted(set(volumes)))))

    @property
    def mesh_count(self):
        return sum(1 for v in self.mesh_ids.values() if v is not None)
