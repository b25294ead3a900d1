// The maths family of the shader machine (opcodes 64-191): Math, Vector Math, Mix, colour nodes,
// curves and ramps, converters, Mapping, Vector Rotate, Normal. Formulas are Cycles 3.4's
// (intern/cycles/kernel/svm/*.h); every instruction is pure (reads only its inputs).
//
// Each opcode below lists its operands in emission order: in (f = float, v = vec3), out, params
// (math_family_signature() holds the same as data). Unknown mode values give zero outputs unless
// noted; a table ('t' param) with too few entries passes the input through (ramps: black).
#pragma once

#include <cstdint>

#include "shading/program.h"

namespace lt {

enum MathOp : uint32_t {
  // in: a f, b f, c f; out: value f; params: MathType, clamp (result to [0, 1])
  kOpMath = kFamilyMathBegin,
  // in: a v, b v, c v, scale f (Scale and Refract's IOR); out: vector v, value f; params: VectorMathType
  kOpVectorMath,
  // in: fac f, a v, b v; out: color v; params: MixBlend, clamp factor, clamp result
  // (legacy Mix RGB: clamp factor 1, clamp result = Clamp; 3.4 Mix node, Color)
  kOpMixColor,
  // in: fac f, a f, b f; out: value f; params: clamp factor
  kOpMixFloat,
  // in: fac f, a v, b v; out: vector v; params: clamp factor
  kOpMixVector,
  // in: fac v, a v, b v; out: vector v; params: clamp factor (non-uniform factor)
  kOpMixVectorNonUniform,
  // in: fac f, color v; out: color v
  kOpInvert,
  // in: hue f, saturation f, value f, fac f, color v; out: color v
  kOpHueSatVal,
  // in: color v, bright f, contrast f; out: color v
  kOpBrightContrast,
  // in: color v, gamma f; out: color v
  kOpGamma,
  // RGB Curves and Vector Curves. in: fac f, color v; out: color v; params: table, extrapolate.
  // Table: min_x, max_x, then n RGB triples sampled at min_x + i / (n - 1) (max_x - min_x).
  kOpCurves,
  // Float Curve. in: fac f, value f; out: value f; params: table, extrapolate.
  // Table: min_x, max_x, then n floats.
  kOpFloatCurve,
  // ColorRamp. in: fac f; out: color v, alpha f; params: table, interpolate (0: Constant).
  // Table: n RGBA quadruples (Blender's ramp evaluated at i / (n - 1)).
  kOpColorRamp,
  // in: value f, from_min f, from_max f, to_min f, to_max f, steps f; out: result f;
  // params: MapRangeType (unknown: Linear), clamp
  kOpMapRange,
  // in: value v, from_min v, from_max v, to_min v, to_max v, steps v; out: vector v;
  // params: MapRangeType, clamp
  kOpMapRangeVector,
  // in: value f, min f, max f; out: result f; params: ClampType (unknown: Min Max)
  kOpClamp,
  // in: color v; out: a f, b f, c f; params: ColorMode (Separate RGB/HSV/Color; unknown: RGB)
  kOpSeparateColor,
  // in: a f, b f, c f; out: color v; params: ColorMode (Combine RGB/HSV/Color)
  kOpCombineColor,
  // in: vector v; out: x f, y f, z f
  kOpSeparateXyz,
  // in: x f, y f, z f; out: vector v
  kOpCombineXyz,
  // in: color v; out: value f (Rec. 709 luma, Blender's OCIO config)
  kOpRgbToBw,
  // in: wavelength f (nm); out: color v
  kOpWavelength,
  // in: temperature f (K); out: color v
  kOpBlackbody,
  // in: vector v, location v, rotation v (XYZ Euler), scale v; out: vector v; params: MappingType
  kOpMapping,
  // in: vector v, center v, axis v, angle f, rotation v; out: vector v; params: RotateType
  // (unknown: Axis Angle), invert
  kOpVectorRotate,
  // in: direction v (the node's own normal), normal v; out: normal v, dot f
  kOpNormal,
  kMathFamilyEnd,
};

// Blender's operation names map one to one onto these (addon/lantern/export/nodes/converters.py).
enum class MathType : uint32_t {
  Add,
  Subtract,
  Multiply,
  Divide,
  MultiplyAdd,
  Power,
  Logarithm,
  Sqrt,
  InverseSqrt,
  Absolute,
  Exponent,
  Minimum,
  Maximum,
  LessThan,
  GreaterThan,
  Sign,
  Compare,
  SmoothMin,
  SmoothMax,
  Round,
  Floor,
  Ceil,
  Trunc,
  Fract,
  Modulo,
  Wrap,
  Snap,
  PingPong,
  Sine,
  Cosine,
  Tangent,
  Arcsine,
  Arccosine,
  Arctangent,
  Arctan2,
  Sinh,
  Cosh,
  Tanh,
  Radians,
  Degrees,
  Count
};

enum class VectorMathType : uint32_t {
  Add,
  Subtract,
  Multiply,
  Divide,
  MultiplyAdd,
  CrossProduct,
  Project,
  Reflect,
  Refract,
  Faceforward,
  DotProduct,
  Distance,
  Length,
  Scale,
  Normalize,
  Absolute,
  Minimum,
  Maximum,
  Floor,
  Ceil,
  Fraction,
  Modulo,
  Wrap,
  Snap,
  Sine,
  Cosine,
  Tangent,
  Count
};

enum class MixBlend : uint32_t {
  Mix,
  Darken,
  Multiply,
  Burn,
  Lighten,
  Screen,
  Dodge,
  Add,
  Overlay,
  SoftLight,
  LinearLight,
  Difference,
  Subtract,
  Divide,
  Hue,
  Saturation,
  Color,
  Value,
  Count
};

enum class MapRangeType : uint32_t { Linear, Stepped, SmoothStep, SmootherStep, Count };
enum class ClampType : uint32_t { MinMax, Range, Count };
enum class ColorMode : uint32_t { Rgb, Hsv, Hsl, Count };
enum class MappingType : uint32_t { Point, Texture, Vector, Normal, Count };
enum class RotateType : uint32_t { AxisAngle, XAxis, YAxis, ZAxis, EulerXyz, Count };

// Cycles' helpers, exposed for tests and for other families.
float svm_math(MathType type, float a, float b, float c);
Vec3 svm_mix(MixBlend type, float t, const Vec3& a, const Vec3& b);
Vec3 rgb_to_hsv(const Vec3& rgb);
Vec3 hsv_to_rgb(const Vec3& hsv);
Vec3 rgb_to_hsl(const Vec3& rgb);
Vec3 hsl_to_rgb(const Vec3& hsl);
Vec3 blackbody_rgb(float temperature);
Vec3 wavelength_rgb(float nm);
// CIE XYZ to the scene linear RGB (Cycles' xyz_to_rgb with Blender's config).
Vec3 xyz_to_rgb(const Vec3& xyz);
Vec3 euler_rotate(const Vec3& euler, const Vec3& v, bool transposed);

}  // namespace lt
