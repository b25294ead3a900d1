"""Light export: Blender's colour x energy and shape parameters (conversions live in the core)."""

import numpy as np

from .. import core
from .names import core_call, is_finite

_TYPES = {
    'POINT': core.LIGHT_POINT,
    'SPOT': core.LIGHT_SPOT,
    'AREA': core.LIGHT_AREA,
    'SUN': core.LIGHT_SUN,
}
# The shape values each light type exports.
_SHAPE_VALUES = {
    'POINT': ("shadow_soft_size",),
    'SPOT': ("shadow_soft_size", "spot_size", "spot_blend"),
    'AREA': ("size", "size_y", "spread"),
    'SUN': ("angle",),
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


def export_light(obj, matrix_world, core_scene, report, lightgroup=0):
    """Adds the light of an (evaluated) light object instance at matrix_world; lightgroup: the core's
    (export.lightgroup_of)."""
    light = obj.data
    kind = _TYPES.get(light.type)
    if kind is None:
        report({'WARNING'}, "Light '%s': type %s is not supported, skipped" % (obj.name, light.type))
        return False
    if light.use_nodes and not _has_default_nodes(light):
        report({'WARNING'}, "Light '%s': light nodes are not supported, using its colour and "
                            "power only" % obj.name)
    # Negative energy is negative light (Cycles renders it so); non-finite values leave the light out.
    subject = "Light '%s'" % obj.name
    values = dict(energy=light.energy, color=tuple(light.color[:3]), transform=np.asarray(matrix_world).ravel())
    values.update((name, getattr(light, name)) for name in _SHAPE_VALUES[light.type])
    bad = [name for name, v in values.items() if not is_finite(v)]
    with np.errstate(over='ignore'):  # an overflow is reported below
        color = np.array(light.color[:3], dtype=np.float32) * np.float32(light.energy)
    if not bad and not is_finite(color):
        bad = ["colour x energy (%g)" % light.energy]
    if bad:
        report({'WARNING'}, "%s left out: %s not finite" % (subject, ", ".join(bad)))
        return False
    kw = dict(type=kind, color=color, transform=matrix_world, visibility=visibility_bits(obj), lightgroup=lightgroup)
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
        # A spread of 0 means Cycles' minimum of 1 degree (the core's 0 is "none").
        kw["spread"] = max(light.spread, 1e-6)
    elif light.type == 'SUN':
        kw["angle"] = light.angle
    # The core leaves out black and zero-area lights with a warning (reported naming the light).
    return core_call(core_scene, report, subject, "add_light", **kw) is not None
