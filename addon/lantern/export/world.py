"""World export: the World Output's Surface compiled into a shader program (export/nodes/, as
materials are), its importance map resolution and camera visibility; the World Output's Volume
as a medium filling the scene."""

from . import nodes
from .material import emissive_nodes, volume_keywords

_CAMERA_DEFAULT = 1


def _visibility(world, warn):
    """Camera visibility (the core's flag); the other kinds are not honoured yet: said so."""
    vis = getattr(world, "cycles_visibility", None)
    if vis is None:
        return _CAMERA_DEFAULT
    hidden = [k for k in ("diffuse", "glossy", "transmission", "scatter") if not getattr(vis, k, True)]
    if hidden:
        warn("ray visibility (%s off) is not supported yet; those rays see the world" % ", ".join(hidden))
    return int(bool(vis.camera))


def _map_resolution(world):
    """Cycles' world sampling map: its width for 'MANUAL', 0 (the core's automatic rule: the largest
    Environment Texture image, else 1024) otherwise. 'NONE' (no importance sampling) changes only
    the noise, not the image: it is sampled as 'AUTOMATIC'."""
    settings = getattr(world, "cycles", None)
    if settings is None or getattr(settings, "sampling_method", 'AUTOMATIC') != 'MANUAL':
        return 0
    return int(settings.sample_map_resolution)


def export_world(depsgraph, core_scene, report, images, camera=None, aovs=None, view_layer_value=None):
    """Sets the world; returns a short description of what was exported. camera: the camera
    table of Texture Coordinate's Camera and Window outputs (camera.camera_table), or None; aovs:
    the view layer's AOVs (aov_indices) its AOV Output nodes write, where a camera ray escapes;
    view_layer_value: the Attribute node's View Layer values (MaterialExporter.view_layer_value)."""
    world = depsgraph.scene_eval.world
    if world is None:
        core_scene.set_world(color=(0.0, 0.0, 0.0), strength=1.0, visibility=1)
        return "none"

    def warn(msg):
        report({'WARNING'}, "World '%s': %s" % (world.name, msg))

    visibility = _visibility(world, warn)
    if not world.use_nodes or world.node_tree is None:
        core_scene.set_world(color=tuple(world.color[:3]), strength=1.0, visibility=visibility)
        return "color"
    output = world.node_tree.get_output_node('CYCLES')
    c = nodes.Compiler(world.name, images, warn, camera=camera, world=True)
    if view_layer_value is not None:
        c.view_layer_value = view_layer_value
    if output is None:
        warn("no active World Output node, rendered black")
    else:
        try:
            c.compile_surface(output)
        except nodes.Unsupported as e:
            warn("%s; the world is left out (black)" % e)
            core_scene.set_world(color=(0.0, 0.0, 0.0), strength=1.0, visibility=visibility)
            return "none"
    try:
        c.compile_aovs(world.node_tree, aovs or {})
    except nodes.Unsupported as e:
        warn("%s; its AOV Outputs are left out" % e)
    if c.bad:
        warn("left out: %s not finite; rendered black" % ", ".join(c.bad))
        core_scene.set_world(color=(0.0, 0.0, 0.0), strength=1.0, visibility=visibility)
        return "none"
    core_scene.set_world_program(c.program(), map_resolution=_map_resolution(world), visibility=visibility)
    return "nodes"


def export_world_volume(depsgraph, core_scene, report):
    """The World Output's Volume input as a World volume; returns (the number of media, 0 or 1,
    whether it emits).

    As in Cycles, escaped rays and shadow rays to sun and world lights cross it to infinity: the
    background and suns are fully attenuated; the Volumetric Path and Bidirectional integrators
    render it, with its emission (in no light group, as Cycles)."""
    world = depsgraph.scene_eval.world
    if world is None or not world.use_nodes or world.node_tree is None:
        return 0, False

    def warn(msg):
        report({'WARNING'}, "World '%s': %s" % (world.name, msg))

    volume = volume_keywords(world.node_tree.get_output_node('CYCLES'), warn)
    if not volume:
        return 0, False
    core_scene.set_world_volume(volume)
    return 1, bool(emissive_nodes(volume))


def ao_distance(world):
    """World > Light Settings > Distance: the AO pass's ray length and the Ambient Occlusion node's
    for a Distance of 0 (Blender's default 10 without a world)."""
    return 10.0 if world is None else world.light_settings.distance
