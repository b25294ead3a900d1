"""Maths, colour and converter nodes against Cycles, pixel by pixel (issue 13's check).

Each case is one material: a node set-up whose output drives an Emission shader (strength 1) on a
camera-facing plane seen by an orthographic camera, so the image is the node's value. The plane's
UV square is cut into 4 x 4 cells, each feeding the set-up a different pair of inputs (a, b)
built from the cell index; only pixels at least 2 pixels inside a cell are compared, so the
pixel filter never mixes two cells. Many cases share one render: one plane per case, in a grid.
Each case is rendered twice, as V and as -V (an exact negation after the node), and the positive
parts are compared: Lantern's emission keeps no negative radiance while Cycles' does, so this sees
both signs of every node's output either way.
Bound: |Lantern - Cycles| <= 1e-3 |Cycles| + 1e-5 (float rounding near zero).
"""
import pytest

import render_utils
from node_cases import compare_grid

pytestmark = pytest.mark.skipif(not render_utils.engine_registered(), reason="Lantern add-on not registered")

# -- cases ---------------------------------------------------------------------------------------

MATH_OPS = ['ADD', 'SUBTRACT', 'MULTIPLY', 'DIVIDE', 'MULTIPLY_ADD', 'POWER', 'LOGARITHM', 'SQRT',
            'INVERSE_SQRT', 'ABSOLUTE', 'EXPONENT', 'MINIMUM', 'MAXIMUM', 'LESS_THAN', 'GREATER_THAN',
            'SIGN', 'COMPARE', 'SMOOTH_MIN', 'SMOOTH_MAX', 'ROUND', 'FLOOR', 'CEIL', 'TRUNC', 'FRACT',
            'MODULO', 'WRAP', 'SNAP', 'PINGPONG', 'SINE', 'COSINE', 'TANGENT', 'ARCSINE', 'ARCCOSINE',
            'ARCTANGENT', 'ARCTAN2', 'SINH', 'COSH', 'TANH', 'RADIANS', 'DEGREES']


def _math_case(op, clamp):
    def fn(s):
        n = s.node("ShaderNodeMath", operation=op, use_clamp=clamp)
        s.feed(n.inputs[0], s.cell_input(0, -1.7, 2.3))
        s.feed(n.inputs[1], s.cell_input(1, -0.6, 1.9))
        n.inputs[2].default_value = 0.35
        # Emission of a negative value is kept by both, but keep magnitudes moderate (exp, sinh).
        return n.outputs[0]
    return fn


VECTOR_OPS = ['ADD', 'SUBTRACT', 'MULTIPLY', 'DIVIDE', 'MULTIPLY_ADD', 'CROSS_PRODUCT', 'PROJECT', 'REFLECT',
              'REFRACT', 'FACEFORWARD', 'DOT_PRODUCT', 'DISTANCE', 'LENGTH', 'SCALE', 'NORMALIZE', 'ABSOLUTE',
              'MINIMUM', 'MAXIMUM', 'FLOOR', 'CEIL', 'FRACTION', 'MODULO', 'WRAP', 'SNAP', 'SINE', 'COSINE',
              'TANGENT']
SCALAR_VECTOR_OPS = {'DOT_PRODUCT', 'DISTANCE', 'LENGTH'}


def _vector_case(op):
    def fn(s):
        n = s.node("ShaderNodeVectorMath", operation=op)
        a, b = s.cell_input(0, -1.3, 1.6), s.cell_input(1, -0.9, 2.2)
        s.feed(n.inputs[0], s.vec(a, b, 0.4))
        s.feed(n.inputs[1], s.vec(b, 0.7, a))
        s.feed(n.inputs[2], s.vec(0.3, a, -1.1))
        n.inputs[3].default_value = 0.67
        return n.outputs["Value" if op in SCALAR_VECTOR_OPS else "Vector"]
    return fn


BLENDS = ['MIX', 'DARKEN', 'MULTIPLY', 'BURN', 'LIGHTEN', 'SCREEN', 'DODGE', 'ADD', 'OVERLAY', 'SOFT_LIGHT',
          'LINEAR_LIGHT', 'DIFFERENCE', 'SUBTRACT', 'DIVIDE', 'HUE', 'SATURATION', 'COLOR', 'VALUE']


def _two_colours(s):
    a, b = s.cell_input(0, 0.0, 1.0), s.cell_input(1, 0.1, 0.9)
    return s.vec(a, 0.3, b), s.vec(0.8, b, s.math("SUBTRACT", 1.0, a))


def _mix_rgb_case(blend, clamp, fac):
    def fn(s):
        n = s.node("ShaderNodeMixRGB", blend_type=blend, use_clamp=clamp)
        c1, c2 = _two_colours(s)
        s.feed(n.inputs["Fac"], fac)
        s.feed(n.inputs["Color1"], c1)
        s.feed(n.inputs["Color2"], c2)
        return n.outputs[0]
    return fn


def _mix_case(data_type, blend="MIX", factor_mode="UNIFORM", clamp_factor=True, clamp_result=False, fac=0.6):
    def fn(s):
        n = s.node("ShaderNodeMix", data_type=data_type)
        n.blend_type = blend
        n.factor_mode = factor_mode
        n.clamp_factor = clamp_factor
        n.clamp_result = clamp_result
        ins = {sck.identifier: sck for sck in n.inputs}
        outs = {sck.identifier: sck for sck in n.outputs}
        a, b = s.cell_input(0, -0.5, 1.5), s.cell_input(1, 0.1, 0.9)
        s.feed(ins["Factor_Float"], fac)
        s.feed(ins["Factor_Vector"], s.vec(b, 1.4, -0.2))
        s.feed(ins["A_Float"], a)
        s.feed(ins["B_Float"], b)
        s.feed(ins["A_Vector"], s.vec(a, b, 0.2))
        s.feed(ins["B_Vector"], s.vec(0.5, a, b))
        c1, c2 = _two_colours(s)
        s.feed(ins["A_Color"], c1)
        s.feed(ins["B_Color"], c2)
        return outs[{"FLOAT": "Result_Float", "VECTOR": "Result_Vector", "RGBA": "Result_Color"}[data_type]]
    return fn


def _colour_node_case(idname, **inputs):
    def fn(s):
        n = s.node(idname)
        a, b = s.cell_input(0, 0.0, 1.0), s.cell_input(1, 0.05, 0.95)
        for k, v in inputs.items():
            s.feed(n.inputs[k], v(s, a, b) if callable(v) else v)
        return n.outputs[0]
    return fn


def _colour_in(s, a, b):
    return s.vec(a, b, 0.35)


def _ramp_case(interpolation, color_mode="RGB", hue="NEAR"):
    def fn(s):
        n = s.node("ShaderNodeValToRGB")
        r = n.color_ramp
        r.interpolation = interpolation
        r.color_mode = color_mode
        r.hue_interpolation = hue
        r.elements[0].position, r.elements[0].color = 0.1, (0.9, 0.1, 0.2, 1.0)
        r.elements[1].position, r.elements[1].color = 0.8, (0.1, 0.3, 0.9, 0.4)
        e = r.elements.new(0.45)
        e.color = (0.2, 0.9, 0.3, 0.7)
        s.feed(n.inputs["Fac"], s.math("ADD", s.cell_input(0, -0.1, 1.1), s.math("MULTIPLY", s.cell_input(1, 0, 1),
                                                                                   0.07)))
        return n.outputs["Color"]
    return fn


def _folded_ramp(s):
    # Every input constant: the core folds the instruction at load (its table read from the pool).
    ramp = _ramp_case("B_SPLINE")
    n = s.node("ShaderNodeRGBCurve")
    n.inputs["Fac"].default_value = 0.7
    n.inputs["Color"].default_value = (0.2, 0.5, 0.9, 1.0)
    mix = s.node("ShaderNodeMixRGB", blend_type="MULTIPLY")
    mix.inputs["Fac"].default_value = 0.8
    s.link(n.outputs[0], mix.inputs["Color1"])
    s.link(ramp(s), mix.inputs["Color2"])
    return mix.outputs[0]


def _curve_points(curve, points):
    while len(curve.points) < len(points):
        curve.points.new(0.5, 0.5)
    for p, (x, y) in zip(curve.points, points):
        p.location = (x, y)


def _curves_case(idname, extend):
    def fn(s):
        n = s.node(idname)
        m = n.mapping
        m.extend = extend
        for i, curve in enumerate(m.curves):
            _curve_points(curve, [(0.0, 0.1 * i), (0.3 + 0.1 * i, 0.7), (1.0, 0.9 - 0.1 * i)])
            curve.points[1].handle_type = "AUTO"
        m.update()
        a, b = s.cell_input(0, -0.3, 1.3), s.cell_input(1, 0.0, 1.0)
        if idname == "ShaderNodeFloatCurve":
            s.feed(n.inputs["Factor"], 0.8)
            s.feed(n.inputs["Value"], a)
        else:
            s.feed(n.inputs[0], 0.9)
            s.feed(n.inputs[1], s.vec(a, b, s.math("SUBTRACT", 1.2, a)))
        return n.outputs[0]
    return fn


def _map_range_case(data_type, interp, clamp):
    def fn(s):
        n = s.node("ShaderNodeMapRange", data_type=data_type, interpolation_type=interp, clamp=clamp)
        ins = {sck.identifier: sck for sck in n.inputs}
        a, b = s.cell_input(0, -0.5, 1.5), s.cell_input(1, 0.0, 1.0)
        if data_type == "FLOAT":
            s.feed(ins["Value"], a)
            s.feed(ins["From Min"], 0.1)
            s.feed(ins["From Max"], s.math("ADD", b, 0.5))
            s.feed(ins["To Min"], -0.2)
            s.feed(ins["To Max"], 0.9)
            s.feed(ins["Steps"], 3.0)
            return n.outputs["Result"]
        s.feed(ins["Vector"], s.vec(a, b, 0.4))
        s.feed(ins["From_Min_FLOAT3"], (0.1, 0.0, 0.5))
        s.feed(ins["From_Max_FLOAT3"], s.vec(s.math("ADD", b, 0.5), 0.8, 0.5))
        s.feed(ins["To_Min_FLOAT3"], (-0.2, 1.0, 0.0))
        s.feed(ins["To_Max_FLOAT3"], (0.9, 0.0, 1.0))
        s.feed(ins["Steps_FLOAT3"], (3.0, 2.0, 4.0))
        return n.outputs["Vector"]
    return fn


def _separate(idname, mode=None):
    def fn(s):
        n = s.node(idname)
        if mode:
            n.mode = mode
        s.feed(n.inputs[0], s.vec(s.cell_input(0, 0.0, 1.0), s.cell_input(1, 0.1, 0.9), 0.45))
        return s.vec(n.outputs[0], n.outputs[1], n.outputs[2])
    return fn


def _combine(idname, mode=None):
    def fn(s):
        n = s.node(idname)
        if mode:
            n.mode = mode
        s.feed(n.inputs[0], s.cell_input(0, 0.0, 1.0))
        s.feed(n.inputs[1], s.cell_input(1, 0.1, 0.9))
        s.feed(n.inputs[2], 0.6)
        return n.outputs[0]
    return fn


def _mapping(vector_type):
    def fn(s):
        n = s.node("ShaderNodeMapping", vector_type=vector_type)
        a, b = s.cell_input(0, -1.0, 1.0), s.cell_input(1, -0.5, 1.5)
        s.feed(n.inputs["Vector"], s.vec(a, b, 0.3))
        s.feed(n.inputs["Location"], (0.2, -0.3, 0.5))
        s.feed(n.inputs["Rotation"], (0.3, -0.7, 1.1))
        s.feed(n.inputs["Scale"], (1.5, 0.0 if vector_type == "TEXTURE" else 0.8, 2.0))
        return n.outputs[0]
    return fn


def _rotate(rotation_type, invert):
    def fn(s):
        n = s.node("ShaderNodeVectorRotate", rotation_type=rotation_type, invert=invert)
        a, b = s.cell_input(0, -1.0, 1.0), s.cell_input(1, -0.5, 1.5)
        s.feed(n.inputs["Vector"], s.vec(a, b, 0.3))
        s.feed(n.inputs["Center"], (0.1, 0.2, -0.3))
        s.feed(n.inputs["Axis"], (0.3, -0.5, 0.8))
        s.feed(n.inputs["Angle"], s.math("MULTIPLY", a, 2.0))
        s.feed(n.inputs["Rotation"], (0.4, -0.9, 1.3))
        return n.outputs[0]
    return fn


def _normal_case(output):
    def fn(s):
        n = s.node("ShaderNodeNormal")
        n.outputs["Normal"].default_value = (0.3, -0.4, 0.866)
        s.feed(n.inputs["Normal"], s.vec(s.cell_input(0, -1.0, 1.0), s.cell_input(1, -0.5, 1.5), 0.7))
        return n.outputs[output]
    return fn


def _check(name, cases, outdir):
    bad = compare_grid(name, cases, outdir)
    assert not bad, "%s: cases outside the bound (label, worst |L-C|/bound, Lantern, Cycles): %s (images in %s)" % (
        name, bad, outdir)


def test_math_every_operation(outdir):
    cases = [(op, _math_case(op, False)) for op in MATH_OPS]
    cases += [(op + "+clamp", _math_case(op, True)) for op in ('ADD', 'SUBTRACT', 'MULTIPLY', 'POWER')]
    _check("nodes_math", cases, outdir)


def test_vector_math_every_operation(outdir):
    _check("nodes_vector_math", [(op, _vector_case(op)) for op in VECTOR_OPS], outdir)


def test_mix_rgb_every_blend(outdir):
    cases = [(b, _mix_rgb_case(b, False, 0.6)) for b in BLENDS]
    cases += [(b + "+clamp", _mix_rgb_case(b, True, 1.3)) for b in BLENDS]
    _check("nodes_mix_rgb", cases, outdir)


def test_mix_node_every_type(outdir):
    cases = [("float", _mix_case("FLOAT")), ("float fac 1.4", _mix_case("FLOAT", fac=1.4)),
             ("float unclamped", _mix_case("FLOAT", clamp_factor=False, fac=1.4)),
             ("vector", _mix_case("VECTOR")), ("vector unclamped", _mix_case("VECTOR", clamp_factor=False, fac=-0.3)),
             ("vector non-uniform", _mix_case("VECTOR", factor_mode="NON_UNIFORM")),
             ("vector non-uniform unclamped", _mix_case("VECTOR", factor_mode="NON_UNIFORM", clamp_factor=False))]
    cases += [("color " + b, _mix_case("RGBA", blend=b)) for b in BLENDS]
    cases += [("color %s clamped" % b, _mix_case("RGBA", blend=b, clamp_factor=False, clamp_result=True, fac=1.3))
              for b in BLENDS]
    _check("nodes_mix", cases, outdir)


def test_colour_nodes(outdir):
    cases = [
        ("invert", _colour_node_case("ShaderNodeInvert", Fac=lambda s, a, b: b, Color=_colour_in)),
        ("hue/sat", _colour_node_case("ShaderNodeHueSaturation", Hue=lambda s, a, b: a, Saturation=1.3,
                                      Value=lambda s, a, b: s.math("ADD", b, 0.4), Fac=0.85, Color=_colour_in)),
        ("bright/contrast", _colour_node_case("ShaderNodeBrightContrast", Color=_colour_in, Bright=0.1,
                                              Contrast=lambda s, a, b: s.math("SUBTRACT", b, 0.3))),
        ("gamma", _colour_node_case("ShaderNodeGamma", Color=_colour_in,
                                    Gamma=lambda s, a, b: s.math("MULTIPLY", b, 2.5))),
        ("rgb to bw", _colour_node_case("ShaderNodeRGBToBW", Color=_colour_in)),
        ("wavelength", _colour_node_case("ShaderNodeWavelength", Wavelength=lambda s, a, b: s.math(
            "ADD", s.math("MULTIPLY", a, 430.0), s.math("MULTIPLY", b, 100.0)))),
        ("blackbody", _colour_node_case("ShaderNodeBlackbody", Temperature=lambda s, a, b: s.math(
            "ADD", s.math("MULTIPLY", a, 9000.0), s.math("MULTIPLY", b, 5000.0)))),
        ("blackbody low", _colour_node_case("ShaderNodeBlackbody", Temperature=lambda s, a, b: s.math(
            "ADD", s.math("MULTIPLY", a, 1500.0), s.math("MULTIPLY", b, 400.0)))),
    ]
    _check("nodes_colour", cases, outdir)


def test_ramps_and_curves(outdir):
    cases = [("ramp " + i, _ramp_case(i)) for i in ("CONSTANT", "LINEAR", "EASE", "CARDINAL", "B_SPLINE")]
    cases += [("ramp HSV far", _ramp_case("LINEAR", "HSV", "FAR")), ("ramp HSL near", _ramp_case("LINEAR", "HSL"))]
    cases.append(("ramp folded (constant input)", _folded_ramp))
    for idname in ("ShaderNodeRGBCurve", "ShaderNodeVectorCurve", "ShaderNodeFloatCurve"):
        for extend in ("EXTRAPOLATED", "HORIZONTAL"):
            cases.append(("%s %s" % (idname, extend), _curves_case(idname, extend)))
    _check("nodes_ramps", cases, outdir)


def test_map_range_and_clamp(outdir):
    cases = []
    for dt in ("FLOAT", "FLOAT_VECTOR"):
        for interp in ("LINEAR", "STEPPED", "SMOOTHSTEP", "SMOOTHERSTEP"):
            for clamp in (False, True):
                cases.append(("%s %s %s" % (dt, interp, clamp), _map_range_case(dt, interp, clamp)))
    for ct in ("MINMAX", "RANGE"):
        def fn(s, ct=ct):
            n = s.node("ShaderNodeClamp", clamp_type=ct)
            s.feed(n.inputs["Value"], s.cell_input(0, -0.5, 1.5))
            s.feed(n.inputs["Min"], s.cell_input(1, 0.0, 1.2))
            s.feed(n.inputs["Max"], 0.7)
            return n.outputs[0]
        cases.append(("clamp " + ct, fn))
    _check("nodes_map_range", cases, outdir)


def test_separate_combine(outdir):
    cases = [("sep rgb", _separate("ShaderNodeSeparateRGB")), ("sep xyz", _separate("ShaderNodeSeparateXYZ")),
             ("sep hsv", _separate("ShaderNodeSeparateHSV")), ("comb rgb", _combine("ShaderNodeCombineRGB")),
             ("comb xyz", _combine("ShaderNodeCombineXYZ")), ("comb hsv", _combine("ShaderNodeCombineHSV"))]
    for mode in ("RGB", "HSV", "HSL"):
        cases.append(("sep color " + mode, _separate("ShaderNodeSeparateColor", mode)))
        cases.append(("comb color " + mode, _combine("ShaderNodeCombineColor", mode)))
    _check("nodes_sepcomb", cases, outdir)


def test_vector_nodes(outdir):
    cases = [("mapping " + t, _mapping(t)) for t in ("POINT", "TEXTURE", "VECTOR", "NORMAL")]
    for t in ("AXIS_ANGLE", "X_AXIS", "Y_AXIS", "Z_AXIS", "EULER_XYZ"):
        for inv in (False, True):
            cases.append(("rotate %s %s" % (t, inv), _rotate(t, inv)))
    cases += [("normal", _normal_case("Normal")), ("normal dot", _normal_case("Dot"))]
    _check("nodes_vector", cases, outdir)
