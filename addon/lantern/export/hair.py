"""Curves and point clouds: particle hair (as Cycles 3.4's blender/curves.cpp builds it), Curves
objects and point clouds, into the core's round Catmull-Rom curves and spheres
(lt_scene_add_curves)."""

import numpy as np

from . import particle_cache
from .attribute_values import attribute_array

# Cycles' radii when a Curves object or point cloud has no radius attribute.
CURVES_DEFAULT_RADIUS = 0.005
POINTS_DEFAULT_RADIUS = 0.01


def hair_systems(obj):
    """The particle systems Cycles renders as hair: Hair type, rendered as Path."""
    return [p for p in getattr(obj, "particle_systems", ())
            if p.settings.type == 'HAIR' and p.settings.render_type == 'PATH']


def _shape_radius(shape, root, tip, time):
    """Cycles' shaperadius: root to tip along time in [0, 1], bent by shape in [-1, 1]."""
    r = 1.0 - time
    if shape < 0.0:
        r = np.power(r, 1.0 + shape)
    elif shape > 0.0:
        r = np.power(r, 1.0 / (1.0 - shape))
    return r * (root - tip) + tip


def co_hair_keys(obj, psys, first, count, steps):
    """World-space keys (count, steps, 3) of strands first..first+count-1 from co_hair, one key a
    call, as Cycles' blender/curves.cpp reads them from C++: a step beyond the strand's cached
    path (a child shortened by Length, for one) is left unwritten, and Cycles repeats the key
    before; from Python an unwritten key reads as the origin."""
    co_hair = psys.co_hair
    flat = []
    extend = flat.extend
    for k in range(first, first + count):
        for j in range(steps):
            extend(co_hair(obj, particle_no=k, step=j))
    co = np.array(flat, dtype=np.float64).reshape(count, steps, 3)
    for j in range(1, steps):
        unwritten = ~co[:, j].any(axis=1)
        co[unwritten, j] = co[unwritten, j - 1]
    return co


# Strands checked against co_hair before the path cache read in bulk is used.
CHECKED_STRANDS = 8


def strand_keys(obj, psys, first, count, steps, report):
    """Object-space keys of the strands: the path cache read in bulk when it reads as co_hair
    gives it on sampled strands, co_hair otherwise (with a warning: slower, same strands)."""
    inverse = np.linalg.inv(np.array(obj.matrix_world, dtype=np.float64))

    def from_co_hair(first, count):
        co = co_hair_keys(obj, psys, first, count, steps)
        return (co.reshape(-1, 3) @ inverse[:3, :3].T).reshape(co.shape) + inverse[:3, 3]
    co = particle_cache.object_keys(obj, psys, first, count, steps)
    if not isinstance(co, str):
        sample = np.unique(np.linspace(0, count - 1, CHECKED_STRANDS).astype(np.int64))
        expect = np.stack([from_co_hair(first + int(k), 1)[0] for k in sample])
        # co_hair works in float32; a wrong layout reads other numbers entirely.
        if np.abs(co[sample] - expect).max() <= 1e-5 * (1.0 + np.abs(expect).max()):
            return co
        co = "the cache read disagrees with co_hair"
    if count >= 2:
        report({'WARNING'}, "Particle hair of '%s' (%s) exported key by key through co_hair, slower: %s"
               % (obj.name, psys.name, co))
    return from_co_hair(first, count)


def particle_hair_arrays(obj, report):
    """(points (n, 4), offsets, slots) of the object's hair systems, object space, or None.

    As Cycles: children replace their parents when the system has any; each strand has
    2^render_step + 1 keys (plus kink_extra_steps for spiral kinks) as ParticleSystem.co_hair gives
    them in world space, brought into object space (strand_keys); radius from the settings' root
    and tip radius times radius_scale / 2 along the distance travelled, 0 at the tip with Close Tip.
    """
    points, offsets, slots = [], [0], []
    n_slots = max(len(obj.material_slots), 1)
    for psys in hair_systems(obj):
        s = psys.settings
        total = len(psys.particles)
        children = len(psys.child_particles) if s.child_type != 'NONE' else 0
        first = total if children else 0
        steps = (1 << s.render_step) + 1
        if s.kink == 'SPIRAL':
            steps += s.kink_extra_steps
        count = total + children - first
        if count <= 0:
            continue
        co = strand_keys(obj, psys, first, count, steps, report)
        d = np.diff(co, axis=1)
        seg = np.sqrt(np.einsum("ijk,ijk->ij", d, d))
        time = np.concatenate([np.zeros((count, 1)), np.cumsum(seg, axis=1)], axis=1)
        length = time[:, -1:]
        with np.errstate(invalid='ignore', divide='ignore'):
            t = np.where(length > 0, time / np.where(length > 0, length, 1.0), 0.0)
        scale = s.radius_scale * 0.5
        radius = _shape_radius(s.shape, scale * s.root_radius, scale * s.tip_radius, np.clip(t, 0.0, 1.0))
        if s.use_close_tip:
            radius[:, -1] = 0.0
        pts = np.empty((count, steps, 4), dtype=np.float32)
        pts[:, :, :3] = co
        pts[:, :, 3] = radius
        points.append(pts.reshape(-1, 4))
        base = offsets[-1]
        offsets.extend(base + steps * np.arange(1, count + 1))
        slots.append(np.full(count, min(max(s.material - 1, 0), n_slots - 1), dtype=np.int32))
    if not points:
        return None
    return np.concatenate(points), np.asarray(offsets, dtype=np.uint32), np.concatenate(slots)


def _attribute(data, name, n, components):
    a = data.attributes.get(name)
    if a is None or len(a.data) != n:
        return None
    prop = "vector" if components == 3 else "value"
    values = np.empty(n * components, dtype=np.float32)
    a.data.foreach_get(prop, values)
    return values.reshape(n, components) if components > 1 else values


def curves_arrays(curves):
    """(points, offsets) of a Curves datablock (Blender 3.4's hair curves), or None."""
    n = len(curves.points)
    if n == 0 or len(curves.curves) == 0:
        return None
    pos = _attribute(curves, "position", n, 3)
    radius = _attribute(curves, "radius", n, 1)
    if radius is None:
        radius = np.full(n, CURVES_DEFAULT_RADIUS, dtype=np.float32)
    offsets = np.empty(len(curves.curves) + 1, dtype=np.int32)
    curves.curve_offset_data.foreach_get("value", offsets)
    return np.column_stack([pos, radius]).astype(np.float32), offsets.astype(np.uint32)


def pointcloud_arrays(cloud):
    n = len(cloud.points)
    if n == 0:
        return None
    pos = _attribute(cloud, "position", n, 3)
    radius = _attribute(cloud, "radius", n, 1)
    if radius is None:
        radius = np.full(n, POINTS_DEFAULT_RADIUS, dtype=np.float32)
    return np.column_stack([pos, radius]).astype(np.float32)


def _srgb_to_linear(c):
    """Cycles' color_srgb_to_linear, per component."""
    c = np.asarray(c, dtype=np.float32)
    with np.errstate(invalid='ignore'):
        return np.where(c < 0.04045, np.maximum(c, 0) / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def _on_emitter(obj, method, **layer):
    """Per strand of particle_hair_arrays (same order), ParticleSystem.uv_on_emitter or
    mcol_on_emitter (method) of the emitter's layer (uv_no or vcol_no), as Cycles' ObtainCacheParticleUV and
    ObtainCacheParticleVcol call it (children pass the first particle)."""
    out = []
    for psys in hair_systems(obj):
        total = len(psys.particles)
        children = len(psys.child_particles) if psys.settings.child_type != 'NONE' else 0
        first = total if children else 0
        if total + children - first <= 0:
            continue
        modifier = next((m for m in obj.modifiers if m.type == 'PARTICLE_SYSTEM' and m.particle_system == psys), None)
        if modifier is None:
            return None
        call = getattr(psys, method)
        particles = psys.particles
        for k in range(first, total + children):
            particle = particles[k] if k < total else particles[0]
            out.append(tuple(call(modifier, particle=particle, particle_no=k, **layer)))
    return np.asarray(out, dtype=np.float32)


def particle_hair_attributes(obj, reads, ids):
    """Cycles' values of particle hair (blender/curves.cpp, sync_particle_hair), one per strand:
    the emitter's UV maps at the strand's root (its active render map the default UV) and its byte
    colour attributes (Mesh.vertex_colors, sRGB to linear, alpha 1). reads: the registry keys the
    materials read; ids: the registry's ids. Returns (uvs or None, [(id, components, per_point,
    values)]); other names read nothing there (as in Cycles)."""
    mesh = obj.data
    uv_layers = list(getattr(mesh, "uv_layers", ()))
    vcols = list(getattr(mesh, "vertex_colors", ()))
    cache = {}

    def uv(i):
        if ('uv', i) not in cache:
            cache['uv', i] = _on_emitter(obj, 'uv_on_emitter', uv_no=i)
        return cache['uv', i]
    uvs = None
    if ('uv', '') in reads:
        render = next((i for i, l in enumerate(uv_layers) if l.active_render), None)
        uvs = uv(render) if render is not None else None
    attrs = []
    for kind, name in sorted(reads):
        if kind != 'attr':
            continue
        got = None
        layer = next((i for i, l in enumerate(uv_layers) if l.name == name), None)
        if layer is not None:
            got = uv(layer)
        else:
            vcol = next((i for i, l in enumerate(vcols) if l.name == name), None)
            rgb = _on_emitter(obj, 'mcol_on_emitter', vcol_no=vcol) if vcol is not None else None
            if rgb is not None and len(rgb):
                got = np.column_stack([_srgb_to_linear(rgb), np.ones(len(rgb), np.float32)])
        if got is not None and len(got):
            attrs.append((ids[kind, name], got.shape[1], False, got))
    return (uvs if uvs is not None and len(uvs) else None), attrs


def generic_attributes(data, reads, ids, domains):
    """Named attributes of a Curves or PointCloud datablock that the materials read (reads, ids as
    particle_hair_attributes'), as Cycles' attr_create_generic takes them: domains maps a Blender
    domain to per_point ({'POINT': True, 'CURVE': False} for curves). Returns (uvs or None,
    [(id, components, per_point, values)]): the default UV is the first 2D vector of the curve
    domain (Cycles' rule; Blender's surface_uv_coordinate)."""
    uvs = None
    if ('uv', '') in reads and 'CURVE' in domains:
        first = next((a for a in data.attributes if a.data_type == 'FLOAT2' and a.domain == 'CURVE'), None)
        uvs = attribute_array(first)[1] if first is not None else None
    attrs = []
    for kind, name in sorted(reads):
        a = data.attributes.get(name) if kind == 'attr' else None
        got = attribute_array(a) if a is not None and a.domain in domains else None
        if got is not None:
            attrs.append((ids[kind, name], got[0], domains[a.domain], got[1]))
    return uvs, attrs


def warn_curve_shape(depsgraph, report):
    """Lantern renders Cycles' 3D curves; a scene set to ribbons renders differently in Cycles."""
    settings = getattr(depsgraph.scene_eval, "cycles_curves", None)
    if settings is not None and getattr(settings, "shape", 'THICK') != 'THICK':
        report({'WARNING'}, "Curves render as 3D curves (Cycles' Curves > Shape is Rounded Ribbons: "
               "Cycles renders them flat)")
