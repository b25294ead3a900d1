"""One core scene kept up to date with a depsgraph: a full export first, then each depsgraph's
updates applied as incremental edits. The viewport keeps one per view; final renders keep one
between frames when the scene's Persistent Data is on (Render Properties > Performance, as Cycles),
so that an animation whose frames only move objects, edit materials or change lights re-exports
nothing (lantern.h, incremental edits). With motion blur, the objects' motion over each frame's
shutter is edited in place too (lt_scene_set_instance_motion).
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


def depsgraph_updates(depsgraph):
    """The depsgraph's updates as (original ID, whether its geometry was updated): read before
    anything evaluates the depsgraph again (motion blur's sub-frames), then given to sync_scene."""
    return [(u.id.original, u.is_updated_geometry) for u in depsgraph.updates]


def _same_motion(a, b):
    """Whether two instances' motion steps (None: still) are the same."""
    return (a is None) == (b is None) and (a is None or np.array_equal(a, b))


class SceneSync:
    def __init__(self, report):
        self.report = report
        self.scene = None
        self.state = {}
        self.camera_object = None  # final renders: the camera the scene was exported with
        self.summary = {}          # export_scene's summary of the last full export
        # What each kind of update did (tests and benchmarks read these).
        self.counters = dict(full_exports=0, transform_updates=0, material_updates=0,
                             light_updates=0, value_updates=0, motion_updates=0)

    def sync_scene(self, depsgraph, camera_object=None, updates=None, motion=None):
        """Brings the core scene up to date with the depsgraph, committed. camera_object: the
        render camera (final renders), exported with the scene; None: the caller sets the
        camera (the viewport). updates: depsgraph_updates(depsgraph) read before motion was
        sampled (default: read now); motion: export/motion.py's Motion of this frame's shutter,
        the depsgraph at its centre, or None. Raises core.LanternError (the scene is then closed)."""
        if updates is None:
            updates = depsgraph_updates(depsgraph)
        try:
            if self.scene is None or _key(camera_object) != _key(self.camera_object) \
                    or not self._incremental(depsgraph, camera_object, updates, motion):
                self._full_export(depsgraph, camera_object, motion)
        except core.LanternError:
            self._close_scene()
            raise

    def _before_edit(self):
        """Called before the first edit of a committed scene (the viewport stops its render)."""

    def _changed(self):
        """Called after the scene changed."""

    def _full_export(self, depsgraph, camera_object, motion):
        self._close_scene()
        self.scene = core.Scene()
        self.state = {}
        self.camera_object = camera_object
        self.summary = export_scene(depsgraph, self.scene, self.report, camera_object=camera_object,
                                    state=self.state, motion=motion)
        self.scene.commit()
        self.counters["full_exports"] += 1
        self._changed()

    def _incremental(self, depsgraph, camera_object, updates, motion):
        """Applies the depsgraph's updates in place; False when they need a new scene."""
        if motion is not None:
            motion.report = self.report
        # With motion blur, or a scene that has motion (blur since turned off; counted by the
        # core), every frame's motion is compared with the scene's.
        stats = self.scene.stats()
        transforms = motion is not None or stats["motion_instances"] > 0 or stats["moving_volumes"] > 0
        lights = False
        materials = []
        for idb, geometry in updates:
            if isinstance(idb, bpy.types.Object):
                # A moved emitter whose hair may deform over the shutter: its strands' steps change.
                if geometry and idb.type in _TRACED_TYPES | {'VOLUME'} \
                        and (not self._emitter_unchanged(depsgraph, idb)
                             or (motion is not None and idb.as_pointer() in motion.strands)):
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
        # A Volume object's material is its medium (export/volume.py), which only an export sets.
        volume_materials = {entry[1] for entry in self.state["volumes"].values()}
        if any(m.original.as_pointer() in volume_materials for m in materials):
            return False
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
        moves, values, motions = self._instance_edits(depsgraph, motion) if transforms else ([], [], [])
        if moves is None:
            return False
        if not (moves or values or motions or lights or materials or camera_object is not None):
            return True  # e.g. a selection change: nothing to render again
        self._before_edit()
        if camera_object is not None:
            export_camera(depsgraph, self.scene, self.report, camera_object, motion=motion)
        instances = self.state["instances"]
        for key, core_id, matrix in moves:
            self.scene.set_instance_transform(core_id, matrix)
            instances[key] = (core_id, matrix)
        if moves:
            self.counters["transform_updates"] += 1
        recorded = self.state["meshes"].instance_motion
        for core_id, steps in motions:  # after the moves: a motion is checked against the instance's transform
            self.scene.set_instance_motion(core_id, steps)
            recorded[core_id] = steps
        if motions:
            self.counters["motion_updates"] += 1
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

    def _instance_edits(self, depsgraph, motion):
        """([(key, core id, new matrix)] of the exported instances that moved, [(key, core id,
        instance_values)] of those whose ray visibility, Object Info values or object attributes
        changed, [(core id, motion steps or None)] of those whose motion over the shutter changed),
        or (None, None, None) when the set of instances changed or a Volume object moved (a new
        scene is needed)."""
        instances = self.state["instances"]
        flags = self.state.get("flags", {})
        meshes = self.state["meshes"]
        object_keys = self.state["materials"].attributes.object_keys()
        view_layer = depsgraph.view_layer_eval
        groups = lightgroup_indices(view_layer)
        volumes = self.state["volumes"]
        recorded_motion = meshes.instance_motion
        seen = seen_volumes = 0
        moves, values, motions = [], [], []
        for inst in depsgraph.object_instances:
            t = inst.object.type
            base = instance_key(inst)
            if t == 'VOLUME' and inst.show_self:
                # A medium's grid transform and motion are set by its export: a moved Volume object
                # needs a new scene.
                entry = volumes.get(base)
                matrix = np.array(inst.matrix_world, dtype=np.float32)
                if entry is None or not np.array_equal(entry[0], matrix) or not _same_motion(
                        entry[2], motion.transforms(base, matrix, inst.object.name) if motion is not None else None):
                    return None, None, None
                seen_volumes += 1
                continue
            hair = hair_key(inst)
            keys = [] if hair is None else [hair]
            if inst.show_self and t in _TRACED_TYPES:
                keys.append(base)
            if keys and instance_flags(inst, view_layer, groups) != flags.get(base, NO_FLAGS):
                # Holdout, light group, catcher or terminator changed: the instance is added anew.
                return None, None, None
            if keys:  # the emitter's hair records its values under the emitter's key
                values += [(base, core_id, now) for core_id, now in
                           meshes.value_edits(inst, base, instancer_of(inst), object_keys)]
            matrix = steps = None
            for key in keys:
                entry = instances.get(key)
                if entry is None:
                    if t in _RECORDED_TYPES:
                        return None, None, None  # an instance that was not exported
                    continue
                seen += 1
                core_id, old = entry
                if matrix is None:
                    matrix = np.array(inst.matrix_world, dtype=np.float32)
                    # Its transforms over the shutter, as the export asks them (the hair's too).
                    steps = motion.transforms(base, matrix, inst.object.name) if motion is not None else None
                    if motion is not None and steps is motion.HIDDEN:
                        return None, None, None  # a particle instance born or dying within the shutter
                if core_id is None:
                    continue
                if not np.array_equal(matrix, old):
                    moves.append((key, core_id, matrix))
                if not _same_motion(steps, recorded_motion.get(core_id)):
                    motions.append((core_id, steps))
        if seen != len(instances) or seen_volumes != len(volumes):
            return None, None, None  # an exported instance or Volume object is gone
        return moves, values, motions

    def _close_scene(self):
        if self.scene is not None:
            self.scene.close()
            self.scene = None

    def close(self):
        self._close_scene()
