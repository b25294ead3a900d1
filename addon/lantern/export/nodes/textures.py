"""Procedural textures (textures.h in the core): Cycles 3.4's Noise, Voronoi, Musgrave, Wave, Magic,
Checker, Brick, Gradient, White Noise and Sky, one instruction each, modes as params."""

import struct

from . import ops, register

DIMENSIONS = {'1D': 1, '2D': 2, '3D': 3, '4D': 4}
VORONOI_FEATURE = {'F1': 0, 'F2': 1, 'SMOOTH_F1': 2, 'DISTANCE_TO_EDGE': 3, 'N_SPHERE_RADIUS': 4}
VORONOI_METRIC = {'EUCLIDEAN': 0, 'MANHATTAN': 1, 'CHEBYCHEV': 2, 'MINKOWSKI': 3}
MUSGRAVE_TYPE = {'MULTIFRACTAL': 0, 'FBM': 1, 'HYBRID_MULTIFRACTAL': 2, 'RIDGED_MULTIFRACTAL': 3,
                 'HETERO_TERRAIN': 4}
WAVE_TYPE = {'BANDS': 0, 'RINGS': 1}
WAVE_BANDS = {'X': 0, 'Y': 1, 'Z': 2, 'DIAGONAL': 3}
WAVE_RINGS = {'X': 0, 'Y': 1, 'Z': 2, 'SPHERICAL': 3}
WAVE_PROFILE = {'SIN': 0, 'SAW': 1, 'TRI': 2}
GRADIENT_TYPE = {'LINEAR': 0, 'QUADRATIC': 1, 'EASING': 2, 'DIAGONAL': 3, 'RADIAL': 4, 'QUADRATIC_SPHERE': 5,
                 'SPHERICAL': 6}


def float_bits(x):
    """A float param word (Brick's offset and squash amounts, Box projection's blend)."""
    return struct.unpack('<I', struct.pack('<f', float(x)))[0]


def _mode(c, node, table, prop):
    value = getattr(node, prop)
    if value not in table:
        c.warn("%s '%s': %s '%s' is not supported; '%s' is used" % (
            node.bl_label, node.name, prop, value, next(iter(table))))
        return 0
    return table[value]


def _coords(c, node):
    """The Vector input; Generated coordinates when unlinked, as Cycles does for texture nodes."""
    sock = node.inputs["Vector"]
    _check_mapping(c, node)
    if not sock.enabled:  # 1D: the instruction ignores it
        return c.const((0.0, 0.0, 0.0))
    if c.linked(sock):
        return c.vector(sock)
    return c.texcoord("Generated")


def _check_mapping(c, node):
    # Cycles applies a texture node's hidden texture_mapping (Python-only); Lantern does not.
    m = getattr(node, "texture_mapping", None)
    if m is None:
        return
    identity = (tuple(m.translation) == (0, 0, 0) and tuple(m.rotation) == (0, 0, 0)
                and tuple(m.scale) == (1, 1, 1) and not m.use_min and not m.use_max
                and m.mapping_x == 'X' and m.mapping_y == 'Y' and m.mapping_z == 'Z')
    if not identity:
        c.warn("%s '%s': its texture_mapping is ignored" % (node.bl_label, node.name))


def _floats(c, node, names):
    return [c.float(node.inputs[n]) for n in names]


@register('TEX_NOISE')
def noise(c, node, want):
    ins = [_coords(c, node)] + _floats(c, node, ("W", "Scale", "Detail", "Roughness", "Distortion"))
    return c.emit(ops.TEX_NOISE, ins, [("Fac", 1), ("Color", 3)],
                  params=[_mode(c, node, DIMENSIONS, "noise_dimensions")])


@register('TEX_VORONOI')
def voronoi(c, node, want):
    ins = [_coords(c, node)] + _floats(c, node, ("W", "Scale", "Smoothness", "Exponent", "Randomness"))
    params = [_mode(c, node, DIMENSIONS, "voronoi_dimensions"), _mode(c, node, VORONOI_FEATURE, "feature"),
              _mode(c, node, VORONOI_METRIC, "distance")]
    return c.emit(ops.TEX_VORONOI, ins,
                  [("Distance", 1), ("Color", 3), ("Position", 3), ("W", 1), ("Radius", 1)], params=params)


@register('TEX_MUSGRAVE')
def musgrave(c, node, want):
    ins = [_coords(c, node)] + _floats(
        c, node, ("W", "Scale", "Detail", "Dimension", "Lacunarity", "Offset", "Gain"))
    params = [_mode(c, node, DIMENSIONS, "musgrave_dimensions"), _mode(c, node, MUSGRAVE_TYPE, "musgrave_type")]
    return c.emit(ops.TEX_MUSGRAVE, ins, [("Fac", 1)], params=params)


@register('TEX_WAVE')
def wave(c, node, want):
    ins = [_coords(c, node)] + _floats(
        c, node, ("Scale", "Distortion", "Detail", "Detail Scale", "Detail Roughness", "Phase Offset"))
    params = [_mode(c, node, WAVE_TYPE, "wave_type"), _mode(c, node, WAVE_BANDS, "bands_direction"),
              _mode(c, node, WAVE_RINGS, "rings_direction"), _mode(c, node, WAVE_PROFILE, "wave_profile")]
    return c.emit(ops.TEX_WAVE, ins, [("Color", 3), ("Fac", 1)], params=params)


@register('TEX_MAGIC')
def magic(c, node, want):
    ins = [_coords(c, node)] + _floats(c, node, ("Scale", "Distortion"))
    depth = max(0, min(10, int(node.turbulence_depth)))
    return c.emit(ops.TEX_MAGIC, ins, [("Color", 3), ("Fac", 1)], params=[depth])


@register('TEX_CHECKER')
def checker(c, node, want):
    ins = [_coords(c, node), c.color(node.inputs["Color1"]), c.color(node.inputs["Color2"]),
           c.float(node.inputs["Scale"])]
    return c.emit(ops.TEX_CHECKER, ins, [("Color", 3), ("Fac", 1)])


@register('TEX_BRICK')
def brick(c, node, want):
    ins = [_coords(c, node)] + [c.color(node.inputs[n]) for n in ("Color1", "Color2", "Mortar")]
    ins += _floats(c, node, ("Scale", "Mortar Size", "Mortar Smooth", "Bias", "Brick Width", "Row Height"))
    params = [int(node.offset_frequency), int(node.squash_frequency), float_bits(node.offset),
              float_bits(node.squash)]
    return c.emit(ops.TEX_BRICK, ins, [("Color", 3), ("Fac", 1)], params=params)


@register('TEX_GRADIENT')
def gradient(c, node, want):
    return c.emit(ops.TEX_GRADIENT, [_coords(c, node)], [("Color", 3), ("Fac", 1)],
                  params=[_mode(c, node, GRADIENT_TYPE, "gradient_type")])


@register('TEX_WHITE_NOISE')
def white_noise(c, node, want):
    # Cycles gives White Noise no implicit coordinates: an unlinked Vector is the socket's value.
    ins = [c.vector(node.inputs["Vector"]), c.float(node.inputs["W"])]
    return c.emit(ops.TEX_WHITE_NOISE, ins, [("Value", 1), ("Color", 3)],
                  params=[_mode(c, node, DIMENSIONS, "noise_dimensions")])


SKY_TYPE = {'PREETHAM': 0, 'HOSEK_WILKIE': 1, 'NISHITA': 2}  # Cycles' NodeSkyType


@register('TEX_SKY')
def sky(c, node, want):
    """The core precomputes the sky from the settings when it loads the program (shading/sky.h)."""
    kind = SKY_TYPE.get(node.sky_type, SKY_TYPE['NISHITA'])
    if node.sky_type == 'HOSEK_WILKIE':
        # Hosek and Wilkie's model needs their fitted dataset, which the core does not carry.
        c.warn("%s '%s': the Hosek / Wilkie sky is not supported; Preetham's sky with the same sun "
               "direction and turbidity is rendered instead" % (node.bl_label, node.name))
        kind = SKY_TYPE['PREETHAM']
    if kind == SKY_TYPE['NISHITA']:
        settings = (1.0 if node.sun_disc else 0.0, node.sun_size, node.sun_intensity, node.sun_elevation,
                    node.sun_rotation, node.altitude, node.air_density, node.dust_density, node.ozone_density)
    else:
        settings = tuple(node.sun_direction) + (node.turbidity, 0.0, 0.0, 0.0, 0.0, 0.0)
    params = [kind] + [float_bits(x) for x in settings] + [0]  # the last: the table, the core's
    # Blender disables the Vector input of a Nishita sky with its sun disc: Cycles then reads the
    # Generated coordinates (a world's direction), whatever was linked.
    sock = node.inputs["Vector"]
    _check_mapping(c, node)
    vector = c.vector(sock) if sock.enabled and c.linked(sock) else c.texcoord("Generated")
    return c.emit(ops.TEX_SKY, [vector], [("Color", 3)], params=params)
