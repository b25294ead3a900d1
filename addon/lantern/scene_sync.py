"""One core scene kept up to date with a depsgraph: a full export first, then each depsgraph's
updates applied as incremental edits. The viewport keeps one per view; final renders keep one
between frames when the scene's Persistent Data is on (Render Properties > Performance, as Cycles),
so that an animation whose frames only move objects, edit materials or change lights re-exports
nothing (lantern.h, incremental edits).
"""

import bpy
import numpy as np

from . import core
from .export import (NO_FLAGS, export_lights, export_scene, hair_key, instance_flags, instance_key,
                     instancer_of, lightgroup_indices)
from .export.camera import camera_table, export_camera
from .export.hair import hair_systems
from .export.mesh import view_layer_value

_GEOMETRY_TYPES = (bpy.types.Mesh, bpy.types.Curve, bpy.types.MetaBall, bpy.types.Volume, bpy.types.Curves,
                   bpy.types.PointCloud, bpy.types.ParticleSettings)
_TRACED_TYPES = {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META', 'CURVES', 'POINTCLOUD'}
# Types whose every instance export_scene records (the others come as a MESH instance of their
# evaluated geometry): one of them not recorded is new.
_RECORDED_TYPES = {'MESH', 'CURVES', 'POINTCLOUD'}


def _key(obj):
    return None if obj is None else obj.original.as_pointer()


class SceneSync:
    def __init__(self, report):
        self.report = report
        self.scene = None
        self.state = {}
        self.camera_object = None  # final renders: the camera the scene was exported with
        self.summary = {}          # export_scene's summary of the last full export
        # What each kind of update did (tests and benchmarks read these).
        self.counters = dict(full_exports=0, transform_updates=0, material_updates=0,
                             light_updates=0, value_updates=0)

    def sync_scene(self, depsgraph, camera_object=None):
        """Brings the core scene up to date with the depsgraph, committed. camera_object: the
        render camera (final renders), exported with the scene; None: the caller sets the
        camera (the viewport). Raises core.LanternError (the scene is then closed)."""
        try:
            if self.scene is None or _key(camera_object) != _key(self.camera_object) \
                    or not self._incremental(depsgraph, camera_object):
                self._full_export(depsgraph, camera_object)
        except core.LanternError:
            self._close_scene()
            raise

    def _before_edit(self):
        """Called before the first edit of a committed scene (the viewport stops its render)."""

    def _changed(self):
        """Called after the scene changed."""

    def _full_export(self, depsgraph, camera_object):
        self._close_scene()
        self.scene = core.Scene()
        self.state = {}
        self.camera_object = camera_object
        self.summary = export_scene(depsgraph, self.scene, self.report, camera_object=camera_object,
                                    state=self.state)
        self.scene.commit()
        self.counters["full_exports"] += 1
        self._changed()

    def _incremental(self, depsgraph, camera_object):
        """Applies the depsgraph's updates in place; False when they need a new scene."""
        transforms = lights = False
        materials = []
        for u in depsgraph.updates:
            idb = u.id
            if isinstance(idb, bpy.types.Object):
                if u.is_updated_geometry and idb.type in _TRACED_TYPES | {'VOLUME'} \
                        and not self._emitter_unchanged(depsgraph, idb):
                    return False
                # Any object update: compare every instance's matrix, and the set of instances
                # (an object hidden, shown or added needs a new scene).
                transforms = True
                lights = lights or idb.type == 'LIGHT'
            elif isinstance(idb, bpy.types.Material):
                materials.append(idb)
            elif isinstance(idb, bpy.types.Light):
                lights = True
            elif isinstance(idb, bpy.types.ShaderNodeTree):
                # A material's own tree changed (an animated node value), or a node group: its
                # material, or every material.
                tree = idb.original
                owners = [m for m in bpy.data.materials if m.node_tree is not None and m.node_tree.original == tree]
                materials.extend(owners or [m for m in bpy.data.materials if m.node_tree is not None])
            elif isinstance(idb, (bpy.types.World, bpy.types.Image, bpy.types.Collection)
                            + _GEOMETRY_TYPES):
                return False
        exporter = self.state["materials"]
        exporter.depsgraph = depsgraph
        # View Layer attributes are constants of the programs: a changed one needs a new scene.
        if any(view_layer_value(depsgraph, name) != value for name, value in exporter.view_layer_seen.items()):
            return False
        if camera_object is not None:
            # Texture Coordinate's Camera and Window read the camera: a moved camera
            # re-translates the materials.
            table = camera_table(depsgraph, camera_object)
            if table != exporter.camera:
                exporter.camera = table
                materials = [m for m in bpy.data.materials if m.original.as_pointer() in exporter.ids]
        # Translated as the depsgraph evaluates them (animated values); bpy.data's are the originals.
        materials = list({m.original.as_pointer(): m.original.evaluated_get(depsgraph) for m in materials}.values())
        # Scene updates (render settings) need nothing here: renders take their settings anew.
        if not (transforms or lights or materials or camera_object is not None):
            return True
        moves, values = self._instance_edits(depsgraph) if transforms else ([], [])
        if moves is None:
            return False
        if not (moves or values or lights or materials or camera_object is not None):
            return True  # e.g. a selection change: nothing to render again
        self._before_edit()
        if camera_object is not None:
            export_camera(depsgraph, self.scene, self.report, camera_object)
        instances = self.state["instances"]
        for key, core_id, matrix in moves:
            self.scene.set_instance_transform(core_id, matrix)
            instances[key] = (core_id, matrix)
        if moves:
            self.counters["transform_updates"] += 1
        for key, core_id, now in values:
            self.scene.set_instance_values(core_id, *now)
            self.state["meshes"].record_values(key, core_id, now)
        if values:
            self.counters["value_updates"] += 1
        for m in materials:
            if m.original.as_pointer() in exporter.ids and not exporter.update(m):
                return False
        if materials:
            self.counters["material_updates"] += 1
        if lights:
            self.scene.clear_lights()
            export_lights(depsgraph, self.scene, self.report)
            self.counters["light_updates"] += 1
        self.scene.commit()
        self._changed()
        return True

    def _emitter_unchanged(self, depsgraph, obj):
        """A particle-hair emitter flagged for geometry whose mesh and hair read as exported: a
        move (Blender evaluates the particles of a moved emitter again)."""
        if obj.type != 'MESH' or not hair_systems(obj):
            return False
        obj = obj.evaluated_get(depsgraph)
        return self.state["meshes"].emitter_unchanged(obj, obj.matrix_world)

    def _instance_edits(self, depsgraph):
        """([(key, core id, new matrix)] of the exported instances that moved, [(key, core id,
        instance_values)] of those whose ray visibility, Object Info values or object attributes
        changed), or (None, None) when the set of instances changed (a new scene is needed)."""
        instances = self.state["instances"]
        flags = self.state.get("flags", {})
        meshes = self.state["meshes"]
        object_keys = self.state["materials"].attributes.object_keys()
        view_layer = depsgraph.view_layer_eval
        groups = lightgroup_indices(view_layer)
        seen = 0
        moves, values = [], []
        for inst in depsgraph.object_instances:
            t = inst.object.type
            base = instance_key(inst)
            hair = hair_key(inst)
            keys = [] if hair is None else [hair]
            if inst.show_self and t in _TRACED_TYPES:
                keys.append(base)
            if keys and instance_flags(inst, view_layer, groups) != flags.get(base, NO_FLAGS):
                return None, None  # holdout, light group, catcher or terminator changed: the instance is added anew
            if keys:  # the emitter's hair records its values under the emitter's key
                values += [(base, core_id, now) for core_id, now in
                           meshes.value_edits(inst, base, instancer_of(inst), object_keys)]
            matrix = None
            for key in keys:
                entry = instances.get(key)
                if entry is None:
                    if t in _RECORDED_TYPES:
                        return None, None  # an instance that was not exported
                    continue
                seen += 1
                core_id, old = entry
                if matrix is None:
                    matrix = np.array(inst.matrix_world, dtype=np.float32)
                if core_id is not None and not np.array_equal(matrix, old):
                    moves.append((key, core_id, matrix))
        if seen != len(instances):
            return None, None  # an exported instance is gone
        return moves, values

    def _close_scene(self):
        if self.scene is not None:
            self.scene.close()
            self.scene = None

    def close(self):
        self._close_scene()
