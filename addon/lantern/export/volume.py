"""Volume objects (OpenVDB files) -> core heterogeneous media."""

import bpy
from mathutils import Matrix, Vector

from .. import core
from .material import emissive_nodes, without_emission

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


def export_volume(obj, matrix, core_scene, report, materials):
    """Adds the object's density grid; returns 1 if added, 0 if left out (with a report)."""
    volume = obj.data
    path = _vdb_path(obj)
    names = []
    half_voxel = None
    try:
        volume.grids.load()
        names = [g.name for g in volume.grids]
        density = volume.grids.get("density") if "density" in names else None
        if density is not None:
            half_voxel = Matrix(density.matrix_object).to_3x3() @ Vector((0.5, 0.5, 0.5))
    except Exception:  # a file Blender cannot read: the core reports why
        pass
    # Cycles 3.4 samples a Blender volume grid with voxel i's value at index i + 0.5 (measured on
    # vdb_cloud: Lantern agrees with Cycles only when shifted by half a voxel along each index axis),
    # while the core puts it at index i (OpenVDB's convention): shift by half a voxel in object space.
    if half_voxel is not None:
        matrix = Matrix(matrix) @ Matrix.Translation(half_voxel)
    others = [n for n in names if n != "density"]
    if others:
        report({'WARNING'}, "Volume '%s': grids %s are not supported (only 'density'), ignored"
               % (obj.name, ", ".join("'%s'" % n for n in others)))
    material = obj.active_material
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
    try:
        core_scene.add_volume_grid(path, "density", matrix, desc)
    except core.LanternError as e:
        report({'WARNING'}, "Volume '%s' left out: %s" % (obj.name, e))
        return 0
    return 1
