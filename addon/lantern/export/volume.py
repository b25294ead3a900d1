"""Volume objects (OpenVDB files) -> core heterogeneous media."""

import bpy
from mathutils import Matrix, Vector

from .. import core
from .material import emissive_nodes, follow
from .nodes.attributes import hash_string, hash_uint

# Cycles' default volume shader for a Volume object without material: Principled Volume defaults.
_DEFAULT = dict(node=core.VOLUME_PRINCIPLED, color=(0.5, 0.5, 0.5), density=1.0,
                absorption_color=(0.0, 0.0, 0.0), anisotropy=0.0)


def _vdb_path(obj):
    """The .vdb file of the current frame: the evaluated grids' frame path (sequences), else
    the data's file path resolved against the .blend."""
    volume = obj.data
    path = ""
    try:
        path = volume.grids.frame_filepath or ""
    except AttributeError:
        pass
    if not path:
        path = volume.filepath
    return bpy.path.abspath(path, library=volume.library)


def _density_grid(material, warn):
    """The grid a Volume object's material reads its density from, as Cycles does: the Principled
    Volume's Density Attribute, or the Attribute node feeding a volume node's Density; 'density'
    for Blender's default shader (no material). None for a shader with a constant density."""
    if material is None or not material.use_nodes or material.node_tree is None:
        return "density"
    output = material.node_tree.get_output_node('CYCLES')
    names, stack = [], [output.inputs.get("Volume")] if output is not None else []
    while stack:
        out = follow(stack.pop())
        if out is None:
            continue
        node = out.node
        if node.type in ('ADD_SHADER', 'MIX_SHADER'):
            stack.extend(s for s in node.inputs if s.type == 'SHADER')
        elif node.type == 'PRINCIPLED_VOLUME' and node.inputs["Density Attribute"].default_value:
            names.append(node.inputs["Density Attribute"].default_value)
        elif "Density" in node.inputs:
            src = follow(node.inputs["Density"])
            if src is not None and src.node.type == 'ATTRIBUTE':
                names.append(src.node.attribute_name)
    if len(set(names)) > 1:
        warn("its volume shaders read density from grids %s: only '%s' is used"
             % (", ".join("'%s'" % n for n in sorted(set(names))), names[0]))
    return names[0] if names else None


# Grid names a component may carry (export/material.py: volume_keywords with attributes) and the
# parameter each multiplies; a missing grid reads 0 (Cycles' Attribute node without the attribute).
_PARAM_GRIDS = {"emission_strength_grid": "emission_strength", "blackbody_intensity_grid": "blackbody_intensity",
                "temperature_grid": "temperature"}


def _resolve_grids(desc, names, warn):
    """The components with the grids they name checked against the file's `names`: a parameter's
    missing grid makes it 0 (reported), a missing Temperature Attribute is dropped (Cycles then
    uses the Temperature alone; reported where blackbody emits), and a Color Attribute grid,
    which is not supported, is reported and ignored. Returns (components, grids read)."""
    out, used = [], set()
    for c in desc:
        c = dict(c)
        for key, param in _PARAM_GRIDS.items():
            grid = c.get(key)
            if grid and grid not in names:
                warn("'%s' reads grid '%s', which the file does not have: it is 0 (as in Cycles)"
                     % (c.get("name", "?"), grid))
                c.pop(key)
                c[param] = 0.0
            elif grid:
                used.add(grid)
        grid = c.get("temperature_attribute")
        if grid and grid not in names:
            c.pop("temperature_attribute")
            if c.get("blackbody_intensity", 0.0) > 0.0:
                warn("'%s' emits blackbody light but the file has no '%s' grid (Temperature Attribute): "
                     "the Temperature %g K is used everywhere in the grid's domain, as Cycles does"
                     % (c.get("name", "?"), grid, c.get("temperature", 1000.0)))
        elif grid:
            if c.get("blackbody_intensity", 0.0) > 0.0:
                used.add(grid)
            else:
                c.pop("temperature_attribute")  # nothing reads it
        color = c.pop("color_attribute", None)
        if color and color in names:
            warn("'%s' reads its colour from grid '%s' (Color Attribute), which is not supported; the "
                 "Color is used" % (c.get("name", "?"), color))
        out.append(c)
    return out, used


def export_volume(obj, matrix, core_scene, report, materials, lightgroup=0, motion=None):
    """Adds the object's density grid and the grids its emission reads; returns (1, whether it
    emits) if added, (0, False) if left out (with a report). lightgroup: its emission's (core
    numbering); motion: its transforms over the shutter (Motion.transforms), or None."""
    volume = obj.data
    material = obj.active_material
    path = _vdb_path(obj)
    grid_name = _density_grid(material, lambda m: report({'WARNING'}, "Volume '%s': %s" % (obj.name, m)))
    if grid_name is None:
        report({'WARNING'}, "Volume '%s': its material's density is not read from a grid (no Density "
                            "Attribute); the 'density' grid is used as Cycles' would be with a "
                            "Principled Volume" % obj.name)
        grid_name = "density"
    names = []
    half_voxel = None
    try:
        volume.grids.load()
        names = [g.name for g in volume.grids]
        grid = volume.grids.get(grid_name) if grid_name in names else None
        if grid is not None:
            half_voxel = Matrix(grid.matrix_object).to_3x3() @ Vector((0.5, 0.5, 0.5))
    except Exception:  # a file Blender cannot read: the core reports why
        pass
    # Cycles 3.4 samples a Blender volume grid with voxel i's value at index i + 0.5 (measured on
    # vdb_cloud, at scale 1 and scaled by 1/2 in Object space: Lantern agrees with Cycles only when
    # shifted by half a voxel along each index axis), while the core puts it at index i (OpenVDB's
    # convention): shift by half a voxel in object space.
    if half_voxel is not None:
        matrix = Matrix(matrix) @ Matrix.Translation(half_voxel)
        if motion is not None:
            motion = [Matrix(m) @ Matrix.Translation(half_voxel) for m in motion]
    desc = materials.volume(material, attributes=True) if material is not None else None
    if desc is None:
        desc = [_DEFAULT]
    desc, used = _resolve_grids(desc, names, lambda m: report({'WARNING'}, "Volume '%s': %s" % (obj.name, m)))
    if not desc:
        report({'WARNING'}, "Volume '%s' left out: its material has no usable volume shader" % obj.name)
        return 0, False
    # Render space Object (Blender's default): density and step size are per object-space unit, so
    # a Volume scaled by 1/50 is as dense as unscaled; Cycles scales them by the length of the
    # object's transform applied to a unit diagonal (BKE_volume_density_scale). World: per metre.
    linear = Matrix(matrix).to_3x3()
    render = volume.render
    step = render.step_size
    if render.space == 'OBJECT':
        stretch = (linear @ Vector((1.0, 1.0, 1.0)).normalized()).length
        if stretch > 0:
            desc = [dict(c, density=c.get("density", 1.0) / stretch) for c in desc]
        step = min(abs(c) for c in linear @ Vector((step, step, step)))
        # Cycles scales emission by the same factor (shade_volume.h: volume_shader_sample): the
        # colours are linear in it (an Emission node's Strength too).
        if stretch > 0:
            desc = [dict(c, emission_color=tuple(v / stretch for v in c.get("emission_color", (1.0, 1.0, 1.0))),
                         blackbody_tint=tuple(v / stretch for v in c.get("blackbody_tint", (1.0, 1.0, 1.0))))
                    for c in desc]
    try:
        # Cycles moves each volume mesh by 0.1 x a hash of the datablock's name over the voxels across
        # it (scene/volume.cpp, face_overlap_avoidance; the geometry's name is its data's).
        face_offset = 0.1 * hash_uint(hash_string(volume.name)) / 0xFFFFFFFF
        core_scene.add_volume_grid(path, grid_name, matrix, desc, step=step, clipping=render.clipping,
                                   face_offset=face_offset, lightgroup=lightgroup, motion=motion)
    except core.LanternError as e:
        report({'WARNING'}, "Volume '%s' left out: %s" % (obj.name, e.detail))
        return 0, False
    finally:
        for w in core_scene.take_warnings():
            report({'WARNING'}, "Volume '%s': %s" % (obj.name, w))
    return 1, bool(emissive_nodes(desc))
