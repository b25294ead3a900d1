"""Volume objects (OpenVDB files) -> core heterogeneous media."""

import bpy
from mathutils import Matrix, Vector

from .. import core
from .material import follow, emissive_nodes, without_emission

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


def export_volume(obj, matrix, core_scene, report, materials):
    """Adds the object's density grid; returns 1 if added, 0 if left out (with a report)."""
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
    others = [n for n in names if n != grid_name]
    if others:
        report({'WARNING'}, "Volume '%s': grids %s are not supported (only the density grid '%s'), "
                            "ignored" % (obj.name, ", ".join("'%s'" % n for n in others), grid_name))
    desc = materials.volume(material) if material is not None else None
    if desc is None:
        desc = [_DEFAULT]
    emitting = emissive_nodes(desc)
    if emitting:
        report({'WARNING'}, "Volume '%s': volume emission (%s) is supported in material volumes of "
                            "meshes only; left out" % (obj.name, ", ".join("'%s'" % n for n in emitting)))
        desc = without_emission(desc)
    if not desc:
        report({'WARNING'}, "Volume '%s' left out: its material has no usable volume shader" % obj.name)
        return 0
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
    try:
        core_scene.add_volume_grid(path, grid_name, matrix, desc, step=step)
    except core.LanternError as e:
        report({'WARNING'}, "Volume '%s' left out: %s" % (obj.name, e.detail))
        return 0
    finally:
        for w in core_scene.take_warnings():
            report({'WARNING'}, "Volume '%s': %s" % (obj.name, w))
    return 1
