"""Light export: Blender's colour x energy and shape parameters (conversions live in the core)."""

import numpy as np

from .. import core

_TYPES = {
    'POINT': core.LIGHT_POINT,
    'SPOT': core.LIGHT_SPOT,
    'AREA': core.LIGHT_AREA,
    'SUN': core.LIGHT_SUN,
}
_SHAPES = {
    'SQUARE': core.AREA_SQUARE,
    'RECTANGLE': core.AREA_RECTANGLE,
    'DISK': core.AREA_DISK,
    'ELLIPSE': core.AREA_ELLIPSE,
}


def visibility_bits(obj):
    bits = 0
    for flag, bit in (("visible_camera", core.VISIBLE_CAMERA),
                      ("visible_diffuse", core.VISIBLE_DIFFUSE),
                      ("visible_glossy", core.VISIBLE_GLOSSY),
                      ("visible_transmission", core.VISIBLE_TRANSMISSION),
                      ("visible_shadow", core.VISIBLE_SHADOW)):
        if getattr(obj, flag, True):
            bits |= bit
    return bits


def _has_default_nodes(light):
    """True when the light's node tree is Blender's default: Emission (white, 1) -> Light Output."""
    tree = light.node_tree
    if tree is None:
        return True
    for node in tree.nodes:
        if node.type in {'OUTPUT_LIGHT', 'REROUTE', 'FRAME'}:
            continue
        if node.type != 'EMISSION' or node.mute:
            return False
        color = node.inputs["Color"]
        strength = node.inputs["Strength"]
        if color.is_linked or strength.is_linked:
            return False
        if any(abs(c - 1.0) > 1e-6 for c in color.default_value[:3]) or \
                abs(strength.default_value - 1.0) > 1e-6:
            return False
    return True


def export_light(obj, matrix_world, core_scene, report):
    """Adds the light of an (evaluated) light object instance at matrix_world."""
    light = obj.data
    kind = _TYPES.get(light.type)
    if kind is None:
        report({'WARNING'}, "Light '%s': type %s is not supported, skipped" % (obj.name, light.type))
        return False
    if light.use_nodes and not _has_default_nodes(light):
        report({'WARNING'}, "Light '%s': light nodes are not supported, using its colour and "
                            "power only" % obj.name)
    color = np.array(light.color[:3], dtype=np.float32) * np.float32(light.energy)
    kw = dict(type=kind, color=color, transform=matrix_world, visibility=visibility_bits(obj))
    if light.type in {'POINT', 'SPOT'}:
        kw["radius"] = light.shadow_soft_size
    if light.type == 'SPOT':
        kw["spot_size"] = light.spot_size
        kw["spot_blend"] = light.spot_blend
    elif light.type == 'AREA':
        kw["shape"] = _SHAPES.get(light.shape, core.AREA_SQUARE)
        kw["size_x"] = light.size
        # Square and disk lights have one size: Blender keeps a stale size_y for them.
        kw["size_y"] = light.size_y if light.shape in {'RECTANGLE', 'ELLIPSE'} else light.size
    elif light.type == 'SUN':
        kw["angle"] = light.angle
    core_scene.add_light(**kw)
    return True
