"""World export: Background colour or equirectangular Environment Texture, times strength; the
World Output's Volume as a medium filling the scene."""

import math

from .material import follow, emissive_nodes, volume_keywords, without_emission

_CAMERA_DEFAULT = 1


def _visibility(world):
    vis = getattr(world, "cycles_visibility", None)
    return int(bool(vis.camera)) if vis is not None else _CAMERA_DEFAULT


def _value(socket):
    """Constant of a socket, from its own value or an RGB/Value node; None if unsupported."""
    out = follow(socket)
    if out is None:
        v = socket.default_value
        return tuple(v)[:3] if hasattr(v, "__len__") else float(v)
    if out.node.type in {'RGB', 'VALUE'}:
        v = out.default_value
        return tuple(v)[:3] if hasattr(v, "__len__") else float(v)
    return None


def _rotation_z(tex, warn):
    """Z rotation of a Mapping node between Texture Coordinate and the environment texture."""
    out = follow(tex.inputs["Vector"])
    if out is None:
        return 0.0
    node = out.node
    if node.type == 'TEX_COORD':
        return 0.0
    if node.type != 'MAPPING':
        warn("environment texture vector from '%s' is not supported, ignored" % node.name)
        return 0.0
    src = follow(node.inputs["Vector"])
    if src is not None and src.node.type != 'TEX_COORD':
        warn("Mapping node '%s' input from '%s' is not supported, ignored"
             % (node.name, src.node.name))
    rot = node.inputs["Rotation"]
    loc = node.inputs.get("Location")
    scale = node.inputs.get("Scale")
    if any(s is not None and follow(s) is not None for s in (rot, loc, scale)):
        warn("Mapping node '%s' with linked inputs is not supported, ignored" % node.name)
        return 0.0
    r = rot.default_value
    if abs(r[0]) > 1e-6 or abs(r[1]) > 1e-6 or \
            (loc is not None and node.vector_type in {'POINT', 'TEXTURE'}
             and any(abs(c) > 1e-6 for c in loc.default_value)) or \
            (scale is not None and any(abs(c - 1.0) > 1e-6 for c in scale.default_value)):
        warn("Mapping node '%s': only a rotation about Z is supported, the rest is ignored"
             % node.name)
    # 'TEXTURE' mapping applies the inverse transform.
    return -r[2] if node.vector_type == 'TEXTURE' else r[2]


def export_world(depsgraph, core_scene, report, images):
    """Sets the world; returns a short description of what was exported."""
    world = depsgraph.scene_eval.world
    if world is None:
        core_scene.set_world(color=(0.0, 0.0, 0.0), strength=1.0, visibility=1)
        return "none"

    def warn(msg):
        report({'WARNING'}, "World '%s': %s" % (world.name, msg))

    visibility = _visibility(world)
    plain = dict(color=tuple(world.color[:3]), strength=1.0, visibility=visibility)

    if not world.use_nodes or world.node_tree is None:
        core_scene.set_world(**plain)
        return "color"

    def fallback(msg):
        warn(msg + ", using the world colour")
        core_scene.set_world(**plain)
        return "color"

    output = world.node_tree.get_output_node('CYCLES')
    if output is None:
        core_scene.set_world(color=(0.0, 0.0, 0.0), strength=1.0, visibility=visibility)
        return "none"
    out = follow(output.inputs["Surface"])
    if out is None:
        core_scene.set_world(color=(0.0, 0.0, 0.0), strength=1.0, visibility=visibility)
        return "none"
    bg = out.node
    if bg.type != 'BACKGROUND':
        return fallback("node '%s' (%s) on the Surface output is not supported"
                        % (bg.name, bg.bl_idname))

    strength = _value(bg.inputs["Strength"])
    if strength is None:
        warn("Background strength from a '%s' node is not supported, using its value"
             % follow(bg.inputs["Strength"]).node.name)
        strength = float(bg.inputs["Strength"].default_value)

    color_in = bg.inputs["Color"]
    color = _value(color_in)
    if color is not None:
        core_scene.set_world(color=color, strength=strength, visibility=visibility)
        return "color"

    src = follow(color_in)
    tex = src.node
    if tex.type != 'TEX_ENVIRONMENT' or src.name != "Color":
        return fallback("node '%s' (%s) feeding the Background colour is not supported"
                        % (tex.name, tex.bl_idname))
    if tex.projection != 'EQUIRECTANGULAR':
        return fallback("environment texture '%s': %s projection is not supported"
                        % (tex.name, tex.projection))
    image_id = images.export(tex.image, tex.interpolation, 'REPEAT',
                             "World '%s', environment texture '%s'" % (world.name, tex.name))
    if image_id is None:
        return fallback("environment texture '%s' has no usable image" % tex.name)
    rotation = _rotation_z(tex, warn)
    core_scene.set_world(color=(1.0, 1.0, 1.0), strength=strength, image=image_id,
                         rotation_z=math.fmod(rotation, 2.0 * math.pi), visibility=visibility)
    return "environment"


def export_world_volume(depsgraph, core_scene, report):
    """The World Output's Volume input as a World volume; returns the number of media (0 or 1).

    As in Cycles, escaped rays and shadow rays to sun and world lights cross it to infinity: the
    background and suns are fully attenuated; the Volumetric Path and Bidirectional integrators
    render it."""
    world = depsgraph.scene_eval.world
    if world is None or not world.use_nodes or world.node_tree is None:
        return 0

    def warn(msg):
        report({'WARNING'}, "World '%s': %s" % (world.name, msg))

    volume = volume_keywords(world.node_tree.get_output_node('CYCLES'), warn)
    emitting = emissive_nodes(volume)
    if emitting:
        warn("volume emission (%s) is supported in material volumes only; the World volume's "
             "emission is left out" % ", ".join("'%s'" % n for n in emitting))
        volume = without_emission(volume)
    if not volume:
        return 0
    core_scene.set_world_volume(volume)
    return 1
