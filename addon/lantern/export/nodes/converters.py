"""Maths, colour and converter nodes (native/src/shading/nodes_math.h in the core): each node
becomes one instruction; mode enums are passed as params in the core's enum order, tables (ramps,
curves) are baked as Cycles 3.4 bakes them (intern/cycles/blender/shader.cpp, util.h)."""

from . import ops, register

# Blender's enum identifiers, in the order of the core's enums (nodes_math.h).
MATH_OPS = ('ADD', 'SUBTRACT', 'MULTIPLY', 'DIVIDE', 'MULTIPLY_ADD', 'POWER', 'LOGARITHM', 'SQRT',
            'INVERSE_SQRT', 'ABSOLUTE', 'EXPONENT', 'MINIMUM', 'MAXIMUM', 'LESS_THAN', 'GREATER_THAN',
            'SIGN', 'COMPARE', 'SMOOTH_MIN', 'SMOOTH_MAX', 'ROUND', 'FLOOR', 'CEIL', 'TRUNC', 'FRACT',
            'MODULO', 'WRAP', 'SNAP', 'PINGPONG', 'SINE', 'COSINE', 'TANGENT', 'ARCSINE', 'ARCCOSINE',
            'ARCTANGENT', 'ARCTAN2', 'SINH', 'COSH', 'TANH', 'RADIANS', 'DEGREES')
VECTOR_MATH_OPS = ('ADD', 'SUBTRACT', 'MULTIPLY', 'DIVIDE', 'MULTIPLY_ADD', 'CROSS_PRODUCT', 'PROJECT',
                   'REFLECT', 'REFRACT', 'FACEFORWARD', 'DOT_PRODUCT', 'DISTANCE', 'LENGTH', 'SCALE',
                   'NORMALIZE', 'ABSOLUTE', 'MINIMUM', 'MAXIMUM', 'FLOOR', 'CEIL', 'FRACTION', 'MODULO',
                   'WRAP', 'SNAP', 'SINE', 'COSINE', 'TANGENT')
BLEND_TYPES = ('MIX', 'DARKEN', 'MULTIPLY', 'BURN', 'LIGHTEN', 'SCREEN', 'DODGE', 'ADD', 'OVERLAY',
               'SOFT_LIGHT', 'LINEAR_LIGHT', 'DIFFERENCE', 'SUBTRACT', 'DIVIDE', 'HUE', 'SATURATION',
               'COLOR', 'VALUE')
MAP_RANGE_TYPES = ('LINEAR', 'STEPPED', 'SMOOTHSTEP', 'SMOOTHERSTEP')
CLAMP_TYPES = ('MINMAX', 'RANGE')
COLOR_MODES = ('RGB', 'HSV', 'HSL')
MAPPING_TYPES = ('POINT', 'TEXTURE', 'VECTOR', 'NORMAL')
ROTATE_TYPES = ('AXIS_ANGLE', 'X_AXIS', 'Y_AXIS', 'Z_AXIS', 'EULER_XYZ')

RAMP_TABLE_SIZE = 256  # Cycles' RAMP_TABLE_SIZE


def _mode(c, node, names, value, what):
    if value in names:
        return names.index(value)
    c.warn("%s '%s': %s '%s' is not supported; the first mode is used" % (node.bl_label, node.name, what, value))
    return 0


def _input(node, identifier):
    return next(s for s in node.inputs if s.identifier == identifier)


@register('MATH')
def math(c, node, want):
    a, b, cc = (c.float(s) for s in node.inputs[:3])
    return c.emit(ops.MATH, [a, b, cc], [("Value", 1)],
                  params=[_mode(c, node, MATH_OPS, node.operation, "operation"), int(node.use_clamp)])


@register('VECT_MATH')
def vector_math(c, node, want):
    a, b, cc = (c.vector(s) for s in node.inputs[:3])
    return c.emit(ops.VECTOR_MATH, [a, b, cc, c.float(node.inputs[3])], [("Vector", 3), ("Value", 1)],
                  params=[_mode(c, node, VECTOR_MATH_OPS, node.operation, "operation")])


@register('MIX_RGB')
def mix_rgb(c, node, want):
    # svm_node_mix: the factor is always clamped; Clamp clamps the result.
    inputs = [c.float(node.inputs[0]), c.color(node.inputs[1]), c.color(node.inputs[2])]
    return c.emit(ops.MIX_COLOR, inputs, [("Color", 3)],
                  params=[_mode(c, node, BLEND_TYPES, node.blend_type, "blend type"), 1, int(node.use_clamp)])


@register('MIX')
def mix(c, node, want):
    # Blender 3.4's Mix node: one instruction per data type (svm/mix.h). All outputs are named
    # "Result"; only the data type's own is visible.
    clamp_factor = int(node.clamp_factor)
    if node.data_type == 'FLOAT':
        inputs = [c.float(_input(node, 'Factor_Float')), c.float(_input(node, 'A_Float')),
                  c.float(_input(node, 'B_Float'))]
        return c.emit(ops.MIX_FLOAT, inputs, [("Result", 1)], params=[clamp_factor])
    if node.data_type == 'VECTOR':
        a, b = c.vector(_input(node, 'A_Vector')), c.vector(_input(node, 'B_Vector'))
        if node.factor_mode == 'NON_UNIFORM':
            return c.emit(ops.MIX_VECTOR_NON_UNIFORM, [c.vector(_input(node, 'Factor_Vector')), a, b],
                          [("Result", 3)], params=[clamp_factor])
        return c.emit(ops.MIX_VECTOR, [c.float(_input(node, 'Factor_Float')), a, b], [("Result", 3)],
                      params=[clamp_factor])
    if node.data_type != 'RGBA':
        c.warn("Mix '%s': data type '%s' is not supported; mixed as colour" % (node.name, node.data_type))
    inputs = [c.float(_input(node, 'Factor_Float')), c.color(_input(node, 'A_Color')),
              c.color(_input(node, 'B_Color'))]
    return c.emit(ops.MIX_COLOR, inputs, [("Result", 3)],
                  params=[_mode(c, node, BLEND_TYPES, node.blend_type, "blend type"), clamp_factor,
                          int(node.clamp_result)])


@register('INVERT')
def invert(c, node, want):
    return c.emit(ops.INVERT, [c.float(node.inputs["Fac"]), c.color(node.inputs["Color"])], [("Color", 3)])


@register('HUE_SAT')
def hue_sat(c, node, want):
    inputs = [c.float(node.inputs[k]) for k in ("Hue", "Saturation", "Value", "Fac")]
    return c.emit(ops.HUE_SAT_VAL, inputs + [c.color(node.inputs["Color"])], [("Color", 3)])


@register('BRIGHTCONTRAST')
def bright_contrast(c, node, want):
    inputs = [c.color(node.inputs["Color"]), c.float(node.inputs["Bright"]), c.float(node.inputs["Contrast"])]
    return c.emit(ops.BRIGHT_CONTRAST, inputs, [("Color", 3)])


@register('GAMMA')
def gamma(c, node, want):
    return c.emit(ops.GAMMA, [c.color(node.inputs["Color"]), c.float(node.inputs["Gamma"])], [("Color", 3)])


def _curve_range(mapping, count):
    # util.h curvemapping_minmax: first and last point over the curves used.
    lo = min(mapping.curves[i].points[0].location[0] for i in range(count))
    hi = max(mapping.curves[i].points[-1].location[0] for i in range(count))
    return lo, hi


def _prepare(mapping):
    mapping.initialize()
    mapping.update()


def _curves_table(mapping, rgb_curve):
    # util.h curvemapping_color_to_array: RAMP_TABLE_SIZE samples over [min_x, max_x]; RGB Curves
    # apply the combined curve (curves[3]) first.
    _prepare(mapping)
    lo, hi = _curve_range(mapping, 4 if rgb_curve else 3)
    table = [lo, hi]
    for i in range(RAMP_TABLE_SIZE):
        t = lo + i / (RAMP_TABLE_SIZE - 1) * (hi - lo)
        for k in range(3):
            x = mapping.evaluate(mapping.curves[3], t) if rgb_curve else t
            table.append(mapping.evaluate(mapping.curves[k], x))
    return table


@register('CURVE_RGB', 'CURVE_VEC')
def curves(c, node, want):
    rgb = node.type == 'CURVE_RGB'
    mapping = node.mapping
    params = [c.table(_curves_table(mapping, rgb)), int(mapping.extend == 'EXTRAPOLATED')]
    value = c.color(node.inputs["Color"]) if rgb else c.vector(node.inputs["Vector"])
    name = "Color" if rgb else "Vector"
    return c.emit(ops.CURVES, [c.float(node.inputs["Fac"]), value], [(name, 3)], params=params)


@register('CURVE_FLOAT')
def float_curve(c, node, want):
    mapping = node.mapping
    _prepare(mapping)
    lo, hi = _curve_range(mapping, 1)
    table = [lo, hi] + [mapping.evaluate(mapping.curves[0], lo + i / (RAMP_TABLE_SIZE - 1) * (hi - lo))
                        for i in range(RAMP_TABLE_SIZE)]
    params = [c.table(table), int(mapping.extend == 'EXTRAPOLATED')]
    return c.emit(ops.FLOAT_CURVE, [c.float(node.inputs["Factor"]), c.float(node.inputs["Value"])],
                  [("Value", 1)], params=params)


@register('VALTORGB')
def color_ramp(c, node, want):
    # util.h colorramp_to_array: Blender's own evaluation (every interpolation and colour mode,
    # HSV and HSL included) at RAMP_TABLE_SIZE points; Cycles interpolates linearly between them
    # unless the ramp is Constant.
    ramp = node.color_ramp
    table = []
    for i in range(RAMP_TABLE_SIZE):
        table.extend(ramp.evaluate(i / (RAMP_TABLE_SIZE - 1)))
    params = [c.table(table), int(ramp.interpolation != 'CONSTANT')]
    return c.emit(ops.COLOR_RAMP, [c.float(node.inputs["Fac"])], [("Color", 3), ("Alpha", 1)], params=params)


@register('MAP_RANGE')
def map_range(c, node, want):
    mode = _mode(c, node, MAP_RANGE_TYPES, node.interpolation_type, "interpolation")
    if node.data_type == 'FLOAT_VECTOR':
        ids = ('Vector', 'From_Min_FLOAT3', 'From_Max_FLOAT3', 'To_Min_FLOAT3', 'To_Max_FLOAT3', 'Steps_FLOAT3')
        return c.emit(ops.MAP_RANGE_VECTOR, [c.vector(_input(node, k)) for k in ids], [("Vector", 3)],
                      params=[mode, int(node.clamp)])
    ids = ('Value', 'From Min', 'From Max', 'To Min', 'To Max', 'Steps')
    return c.emit(ops.MAP_RANGE, [c.float(_input(node, k)) for k in ids], [("Result", 1)],
                  params=[mode, int(node.clamp)])


@register('CLAMP')
def clamp(c, node, want):
    inputs = [c.float(node.inputs[k]) for k in ("Value", "Min", "Max")]
    return c.emit(ops.CLAMP, inputs, [("Result", 1)],
                  params=[_mode(c, node, CLAMP_TYPES, node.clamp_type, "clamp type")])


# Separate and Combine nodes: (input names or output names, colour mode).
_SEPARATE = {'SEPRGB': ("Image", ("R", "G", "B"), 'RGB'), 'SEPHSV': ("Color", ("H", "S", "V"), 'HSV'),
             'SEPARATE_COLOR': ("Color", ("Red", "Green", "Blue"), None)}
_COMBINE = {'COMBRGB': (("R", "G", "B"), "Image", 'RGB'), 'COMBHSV': (("H", "S", "V"), "Color", 'HSV'),
            'COMBINE_COLOR': (("Red", "Green", "Blue"), "Color", None)}


@register(*_SEPARATE)
def separate_color(c, node, want):
    inp, outs, mode = _SEPARATE[node.type]
    mode = _mode(c, node, COLOR_MODES, mode or node.mode, "mode")
    return c.emit(ops.SEPARATE_COLOR, [c.color(node.inputs[inp])], [(n, 1) for n in outs], params=[mode])


@register(*_COMBINE)
def combine_color(c, node, want):
    ins, out, mode = _COMBINE[node.type]
    mode = _mode(c, node, COLOR_MODES, mode or node.mode, "mode")
    return c.emit(ops.COMBINE_COLOR, [c.float(node.inputs[n]) for n in ins], [(out, 3)], params=[mode])


@register('SEPXYZ')
def separate_xyz(c, node, want):
    return c.emit(ops.SEPARATE_XYZ, [c.vector(node.inputs["Vector"])], [("X", 1), ("Y", 1), ("Z", 1)])


@register('COMBXYZ')
def combine_xyz(c, node, want):
    return c.emit(ops.COMBINE_XYZ, [c.float(node.inputs[n]) for n in ("X", "Y", "Z")], [("Vector", 3)])


@register('RGBTOBW')
def rgb_to_bw(c, node, want):
    return c.emit(ops.RGB_TO_BW, [c.color(node.inputs["Color"])], [("Val", 1)])


@register('WAVELENGTH')
def wavelength(c, node, want):
    return c.emit(ops.WAVELENGTH, [c.float(node.inputs["Wavelength"])], [("Color", 3)])


@register('BLACKBODY')
def blackbody(c, node, want):
    return c.emit(ops.BLACKBODY, [c.float(node.inputs["Temperature"])], [("Color", 3)])


@register('MAPPING')
def mapping(c, node, want):
    inputs = [c.vector(node.inputs[k]) for k in ("Vector", "Location", "Rotation", "Scale")]
    return c.emit(ops.MAPPING, inputs, [("Vector", 3)],
                  params=[_mode(c, node, MAPPING_TYPES, node.vector_type, "type")])


@register('VECTOR_ROTATE')
def vector_rotate(c, node, want):
    inputs = [c.vector(node.inputs["Vector"]), c.vector(node.inputs["Center"]), c.vector(node.inputs["Axis"]),
              c.float(node.inputs["Angle"]), c.vector(node.inputs["Rotation"])]
    return c.emit(ops.VECTOR_ROTATE, inputs, [("Vector", 3)],
                  params=[_mode(c, node, ROTATE_TYPES, node.rotation_type, "type"), int(node.invert)])


@register('NORMAL')
def normal(c, node, want):
    # The node's own direction is its Normal output's value; an unlinked Normal input is the
    # shading normal (Cycles' LINK_NORMAL), read from the Geometry instruction.
    direction = c.const(tuple(node.outputs["Normal"].default_value))
    if c.linked(node.inputs["Normal"]):
        n = c.vector(node.inputs["Normal"])
    else:
        n = c.geometry()["Normal"]
    return c.emit(ops.NORMAL, [direction, n], [("Normal", 3), ("Dot", 1)])
