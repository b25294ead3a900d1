"""Depsgraph -> core scene. Everything is read from the depsgraph handed in, never bpy.context."""

import numpy as np

from .. import core
from .camera import camera_table, export_camera
from .hair import hair_systems, warn_curve_shape
from .light import export_light
from .material import ImageExporter, MaterialExporter
from .mesh import CONVERTIBLE_TYPES, TERMINATOR_DEFAULT, MeshExporter, terminator_of
from .motion import instance_key, own_geometry
from .volume import export_volume
from .world import ao_distance, export_world, export_world_volume

# Object types that are not rendered (or not yet): skipped silently.
_IGNORED_TYPES = {'CAMERA', 'EMPTY', 'ARMATURE', 'LATTICE', 'SPEAKER', 'LIGHT_PROBE', 'GPENCIL'}


def _deduplicating(report):
    seen = set()

    def wrapped(level, message):
        if message not in seen:
            seen.add(message)
            report(level, message)
    return wrapped


def hair_key(inst):
    """The key of an emitter's particle hair, an instance of its own beside the emitter's (shown
    even where the emitter is not); None for an instance without hair."""
    if inst.object.type == 'MESH' and inst.show_particles and hair_systems(inst.object):
        return instance_key(inst) + ('hair',)
    return None


def instancer_of(inst):
    """(parent object, particle system or None) of an instance, for the Attribute node's
    Instancer type; None for an object that is no instance."""
    if not inst.is_instance or inst.parent is None:
        return None
    return inst.parent, inst.particle_system


def holdout_of(inst, view_layer):
    """Cycles' holdout object (blender/object.cpp): an instance takes its instancer's, an object
    its own flag or its holdout collection's (Object.holdout_get)."""
    owner = inst.parent if inst.is_instance and inst.parent is not None else inst.object
    return bool(owner.holdout_get(view_layer=view_layer))


# What an instance carries besides its geometry, materials and transform (scene_sync adds an
# instance anew when it changes): holdout, light group, shadow catcher, shadow terminator.
NO_FLAGS = (False, 0, False, TERMINATOR_DEFAULT)


def instance_flags(inst, view_layer, groups):
    return (holdout_of(inst, view_layer), lightgroup_of(inst, groups), shadow_catcher_of(inst),
            terminator_of(inst.object))


def shadow_catcher_of(inst):
    """Cycles' shadow catcher object: its own Object.is_shadow_catcher or its instancer's."""
    return bool(inst.object.is_shadow_catcher or (inst.is_instance and inst.parent is not None
                                                   and inst.parent.is_shadow_catcher))


def lightgroup_indices(view_layer):
    """{name: k} of the view layer's light groups, k = 1 + the group's index (the core's 0 is none):
    an emitter naming a group the view layer does not list is in none, as in Cycles."""
    return {g.name: i + 1 for i, g in enumerate(view_layer.lightgroups)}


def aov_indices(view_layer):
    """{name: (index, colour)} of the view layer's valid AOVs, in the order of the render's AOV
    passes (engine.aov_passes)."""
    aovs = [a for a in view_layer.aovs if a.is_valid]
    return {a.name: (i, a.type == 'COLOR') for i, a in enumerate(aovs)}


def lightgroup_of(inst, groups):
    """The core's light group of an object instance's emission (an instance takes its instancer's,
    as holdout_of)."""
    owner = inst.parent if inst.is_instance and inst.parent is not None else inst.object
    return groups.get(owner.lightgroup, 0)


def export_lights(depsgraph, core_scene, report):
    """Adds every light object instance; returns how many were added."""
    lights = 0
    groups = lightgroup_indices(depsgraph.view_layer_eval)
    for inst in depsgraph.object_instances:
        if inst.show_self and inst.object.type == 'LIGHT':
            lights += export_light(inst.object, np.array(inst.matrix_world, dtype=np.float32),
                                   core_scene, report, lightgroup_of(inst, groups))
    return lights


def export_scene(depsgraph, core_scene, report, camera_object=None, state=None, motion=None):
    """Fills core_scene (not committed) from the depsgraph; returns a summary dict.

    report(level_set, message) receives warnings, like RenderEngine.report. camera_object
    overrides the scene camera (RenderEngine.camera_override); None with state given: no camera
    (the viewport sets its own). state, a dict, receives what viewport updates need: the
    material and mesh exporters and each mesh instance's (core instance id, matrix) by instance_key.
    motion: what moves over the shutter (export/motion.py's collect), None without motion blur.
    """
    report = _deduplicating(report)
    summary = {}
    if motion is not None:
        motion.report = report
    if state is None or camera_object is not None:
        summary["camera"] = export_camera(depsgraph, core_scene, report, camera_object, motion=motion)

    images = ImageExporter(core_scene, report)
    materials = MaterialExporter(core_scene, report, images)
    materials.ao_distance = ao_distance(depsgraph.scene_eval.world)
    materials.depsgraph = depsgraph
    if state is None or camera_object is not None:
        materials.camera = camera_table(depsgraph, camera_object)
    meshes = MeshExporter(depsgraph, core_scene, report, materials, motion)
    if state is not None:
        meshes.emitters = {}
        meshes.instance_values = {}
        meshes.instance_motion = {}
    materials.aovs = aov_indices(depsgraph.view_layer_eval)
    try:
        summary["world"] = export_world(depsgraph, core_scene, report, images, camera=materials.camera,
                                        aovs=materials.aovs, view_layer_value=materials.view_layer_value)
    except core.LanternError as e:  # a value the core refuses (not finite): no world, the render goes on
        if e.status != core.ERROR_INVALID_ARGUMENT:
            raise
        report({'WARNING'}, "World '%s' left out: %s" % (depsgraph.scene_eval.world.name, e.detail))
        core_scene.set_world(color=(0.0, 0.0, 0.0), strength=1.0, visibility=1)
        summary["world"] = "none (left out)"
    groups = lightgroup_indices(depsgraph.view_layer_eval)
    world = depsgraph.scene_eval.world
    if world is not None and groups.get(world.lightgroup, 0):
        core_scene.set_world_lightgroup(groups[world.lightgroup])
    for w in core_scene.take_warnings():
        report({'WARNING'}, w)
    world_media, emissive_media = export_world_volume(depsgraph, core_scene, report)

    lights = volumes = 0
    light_kinds = {}
    skipped_types = set()
    # Curves, surfaces, text and metaballs come as their object and, since Blender 3.0, as a
    # MESH instance of their evaluated geometry: export the latter, convert only if it is absent.
    deferred = []
    instances = {}  # instance_key -> (core instance id or None for no geometry, matrix)
    volume_objects = {}  # instance_key -> (matrix, its material's pointer or None, motion): kept for edits
    has_mesh_instance = set()
    hair = 0
    flags = {}  # instance_key -> instance_flags where not NO_FLAGS
    catchers = 0
    view_layer = depsgraph.view_layer_eval
    for inst in depsgraph.object_instances:
        obj = inst.object
        t = obj.type
        inst_flags = instance_flags(inst, view_layer, groups)
        holdout, lightgroup, catcher, _ = inst_flags
        catchers += catcher and inst.show_self and (t in ('MESH', 'CURVES', 'POINTCLOUD') or t in CONVERTIBLE_TYPES)
        if inst_flags != NO_FLAGS:
            flags[instance_key(inst)] = inst_flags
        key = hair_key(inst)
        if key is not None:
            if not hair:
                warn_curve_shape(depsgraph, report)
            matrix = np.array(inst.matrix_world, dtype=np.float32)
            instances[key] = (meshes.export_curves_instance(obj, matrix, 'HAIR', holdout=holdout,
                                                            shadow_catcher=catcher, lightgroup=lightgroup,
                                                            key=instance_key(inst), instancer=instancer_of(inst)),
                              matrix)
            hair += 1
        if not inst.show_self:  # e.g. a particle emitter set not to render itself
            continue
        if t in _IGNORED_TYPES:
            continue
        # The iterator reuses its matrix: copy it now.
        matrix = np.array(inst.matrix_world, dtype=np.float32)
        if t == 'MESH':
            if inst.is_instance and inst.parent is not None and inst.parent.type in CONVERTIBLE_TYPES:
                has_mesh_instance.add(inst.parent.original.as_pointer())
            random_id = inst.random_id if inst.is_instance else None
            instances[instance_key(inst)] = (meshes.export_instance(obj, matrix, random_id=random_id,
                                                                    key=instance_key(inst),
                                                                    deform=own_geometry(inst),
                                                                    holdout=holdout, shadow_catcher=catcher,
                                                                    lightgroup=lightgroup,
                                                                    instancer=instancer_of(inst)), matrix)
        elif t in CONVERTIBLE_TYPES:
            if inst.is_instance:
                instances[instance_key(inst)] = (meshes.export_instance(obj, matrix, warn_empty=False,
                                                                        random_id=inst.random_id,
                                                                        key=instance_key(inst),
                                                                        holdout=holdout, shadow_catcher=catcher,
                                                                        lightgroup=lightgroup,
                                                                        instancer=instancer_of(inst)),
                                                 matrix)
            else:
                deferred.append((obj, matrix, instance_key(inst), holdout, lightgroup, catcher))
        elif t == 'LIGHT':
            if export_light(obj, matrix, core_scene, report, lightgroup):
                lights += 1
                light_kinds[obj.data.type] = light_kinds.get(obj.data.type, 0) + 1
        elif t == 'VOLUME':
            steps = motion.transforms(instance_key(inst), matrix, obj.name) if motion is not None else None
            if motion is not None and steps is motion.HIDDEN:  # a particle instance born or dying mid-shutter
                continue
            material = obj.active_material
            volume_objects[instance_key(inst)] = (matrix, None if material is None else material.original.as_pointer(),
                                                  steps)
            added, emits = export_volume(obj, matrix, core_scene, report, materials, lightgroup, motion=steps)
            volumes += added
            emissive_media += emits
        elif t in ('CURVES', 'POINTCLOUD'):
            if t == 'CURVES' and not hair:
                warn_curve_shape(depsgraph, report)
            hair += t == 'CURVES'
            random_id = inst.random_id if inst.is_instance else None
            instances[instance_key(inst)] = (meshes.export_curves_instance(obj, matrix, t, random_id=random_id,
                                                                           holdout=holdout, shadow_catcher=catcher,
                                                                           lightgroup=lightgroup,
                                                                           key=instance_key(inst),
                                                                           instancer=instancer_of(inst)),
                                             matrix)
        elif t not in skipped_types:
            skipped_types.add(t)
            report({'WARNING'}, "Objects of type %s are not supported yet, skipped (e.g. '%s')"
                   % (t, obj.name))
    for obj, matrix, key, holdout, lightgroup, catcher in deferred:
        if obj.original.as_pointer() not in has_mesh_instance:
            # e.g. a curve without bevel
            instances[key] = (meshes.export_instance(obj, matrix, warn_empty=False, key=key, holdout=holdout,
                                                     shadow_catcher=catcher, lightgroup=lightgroup), matrix)
    if state is not None:
        state.update(materials=materials, meshes=meshes, instances=instances, flags=flags, volumes=volume_objects)

    summary.update(shadow_catchers=catchers, meshes=meshes.mesh_count, instances=meshes.instance_count,
                   materials=len(materials.ids), images=sum(1 for v in images.ids.values()
                                                            if v is not None),
                   image_files=images.from_files,
                   lights=lights, light_kinds=light_kinds, volumes=volumes, hair=hair,
                   material_media=materials.media, world_media=world_media,
                   emissive_media=materials.emissive_media + emissive_media, subsurface=sorted(materials.subsurface),
                   media=volumes + materials.media + world_media,
                   cryptomatte=materials.cryptomatte.manifests)
    if motion is not None:
        summary.update(moving_objects=motion.moving_instances, deforming_meshes=motion.deforming_meshes,
                       camera_motion=motion.camera_moves)
        if motion.hidden_particles:
            report({'INFO'}, "%d particle instance(s) born or dying within the shutter are not rendered, as "
                             "Cycles hides them" % motion.hidden_particles)
    return summary
