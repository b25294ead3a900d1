// The maths family: Cycles 3.4's converter, colour and vector nodes (kernel/svm/*.h, util/color.h,
// util/math*.h), rewritten for the register machine. See nodes_math.h for operands.
#include "shading/nodes_math.h"

#include <cfloat>
#include <cmath>
#include <string>

namespace lt {

namespace {

// util/math_base.h helpers, as Cycles defines them (the "safe" variants return 0, not NaN).
float safe_divide(float a, float b) { return b != 0.0f ? a / b : 0.0f; }
Vec3 safe_divide(const Vec3& a, const Vec3& b) {
  return {safe_divide(a.x, b.x), safe_divide(a.y, b.y), safe_divide(a.z, b.z)};
}
float safe_modulo(float a, float b) { return b != 0.0f ? std::fmod(a, b) : 0.0f; }
float fractf(float x) { return x - std::floor(x); }
float saturatef(float x) { return clamp(x, 0.0f, 1.0f); }
Vec3 saturate(const Vec3& v) { return {saturatef(v.x), saturatef(v.y), saturatef(v.z)}; }
float safe_powf(float a, float b) {
  if (a < 0.0f && b != static_cast<float>(static_cast<int>(b))) return 0.0f;
  return std::pow(a, b);
}
float safe_logf(float a, float b) {
  if (a <= 0.0f || b <= 0.0f) return 0.0f;
  return safe_divide(std::log(a), std::log(b));
}
float wrapf(float value, float max, float min) {
  float range = max - min;
  return range != 0.0f ? value - range * std::floor((value - min) / range) : min;
}
float pingpongf(float a, float b) { return b != 0.0f ? std::fabs(fractf((a - b) / (b * 2.0f)) * b * 2.0f - b) : 0.0f; }
float smoothminf(float a, float b, float k) {
  if (k == 0.0f) return std::fmin(a, b);
  float h = std::fmax(k - std::fabs(a - b), 0.0f) / k;
  return std::fmin(a, b) - h * h * h * k * (1.0f / 6.0f);
}
float compatible_signf(float f) { return f == 0.0f ? 0.0f : (f < 0.0f ? -1.0f : 1.0f); }
Vec3 safe_normalize(const Vec3& a) {
  float t = length(a);
  return t != 0.0f ? a * (1.0f / t) : a;
}
Vec3 vfloor(const Vec3& a) { return {std::floor(a.x), std::floor(a.y), std::floor(a.z)}; }
Vec3 vceil(const Vec3& a) { return {std::ceil(a.x), std::ceil(a.y), std::ceil(a.z)}; }
Vec3 interp(const Vec3& a, const Vec3& b, float t) { return a + t * (b - a); }

// Cycles' vector helpers (util/math_float3.h).
Vec3 project(const Vec3& v, const Vec3& onto) {
  float len_sq = dot(onto, onto);
  return len_sq != 0.0f ? (dot(v, onto) / len_sq) * onto : Vec3();
}
Vec3 reflect(const Vec3& incident, const Vec3& normal) {
  Vec3 n = normalize(normal);
  return incident - 2.0f * n * dot(incident, n);
}
Vec3 refract(const Vec3& incident, const Vec3& normal, float eta) {
  float d = dot(normal, incident);
  float k = 1.0f - eta * eta * (1.0f - d * d);
  if (k < 0.0f) return Vec3();
  return eta * incident - (eta * d + std::sqrt(k)) * normal;
}

void svm_vector_math(VectorMathType type, const Vec3& a, const Vec3& b, const Vec3& c, float scale, Vec3* vector,
                     float* value) {
  *vector = Vec3();
  *value = 0.0f;
  switch (type) {
    case VectorMathType::Add:
      *vector = a + b;
      break;
    case VectorMathType::Subtract:
      *vector = a - b;
      break;
    case VectorMathType::Multiply:
      *vector = a * b;
      break;
    case VectorMathType::Divide:
      *vector = safe_divide(a, b);
      break;
    case VectorMathType::MultiplyAdd:
      *vector = a * b + c;
      break;
    case VectorMathType::CrossProduct:
      *vector = cross(a, b);
      break;
    case VectorMathType::Project:
      *vector = project(a, b);
      break;
    case VectorMathType::Reflect:
      *vector = reflect(a, b);
      break;
    case VectorMathType::Refract:
      *vector = refract(a, normalize(b), scale);
      break;
    case VectorMathType::Faceforward:
      *vector = dot(c, b) < 0.0f ? a : -a;
      break;
    case VectorMathType::DotProduct:
      *value = dot(a, b);
      break;
    case VectorMathType::Distance:
      *value = length(a - b);
      break;
    case VectorMathType::Length:
      *value = length(a);
      break;
    case VectorMathType::Scale:
      *vector = a * scale;
      break;
    case VectorMathType::Normalize:
      *vector = safe_normalize(a);
      break;
    case VectorMathType::Absolute:
      *vector = abs(a);
      break;
    case VectorMathType::Minimum:
      *vector = vmin(a, b);
      break;
    case VectorMathType::Maximum:
      *vector = vmax(a, b);
      break;
    case VectorMathType::Floor:
      *vector = vfloor(a);
      break;
    case VectorMathType::Ceil:
      *vector = vceil(a);
      break;
    case VectorMathType::Fraction:
      *vector = a - vfloor(a);
      break;
    case VectorMathType::Modulo:
      *vector = {safe_modulo(a.x, b.x), safe_modulo(a.y, b.y), safe_modulo(a.z, b.z)};
      break;
    case VectorMathType::Wrap:
      *vector = {wrapf(a.x, b.x, c.x), wrapf(a.y, b.y, c.y), wrapf(a.z, b.z, c.z)};
      break;
    case VectorMathType::Snap:
      *vector = vfloor(safe_divide(a, b)) * b;
      break;
    case VectorMathType::Sine:
      *vector = {std::sin(a.x), std::sin(a.y), std::sin(a.z)};
      break;
    case VectorMathType::Cosine:
      *vector = {std::cos(a.x), std::cos(a.y), std::cos(a.z)};
      break;
    case VectorMathType::Tangent:
      *vector = {std::tan(a.x), std::tan(a.y), std::tan(a.z)};
      break;
    default:
      break;
  }
}

// kernel/svm/color_util.h blend modes, per channel where Cycles writes them per channel.
Vec3 mix_overlay(float t, const Vec3& c1, const Vec3& c2) {
  float tm = 1.0f - t;
  Vec3 o = c1;
  for (int i = 0; i < 3; ++i) {
    if (o[i] < 0.5f)
      o[i] *= tm + 2.0f * t * c2[i];
    else
      o[i] = 1.0f - (tm + 2.0f * t * (1.0f - c2[i])) * (1.0f - o[i]);
  }
  return o;
}
Vec3 mix_divide(float t, const Vec3& c1, const Vec3& c2) {
  float tm = 1.0f - t;
  Vec3 o = c1;
  for (int i = 0; i < 3; ++i)
    if (c2[i] != 0.0f) o[i] = tm * o[i] + t * o[i] / c2[i];
  return o;
}
Vec3 mix_dodge(float t, const Vec3& c1, const Vec3& c2) {
  Vec3 o = c1;
  for (int i = 0; i < 3; ++i) {
    if (o[i] == 0.0f) continue;
    float tmp = 1.0f - t * c2[i];
    if (tmp <= 0.0f)
      o[i] = 1.0f;
    else if ((tmp = o[i] / tmp) > 1.0f)
      o[i] = 1.0f;
    else
      o[i] = tmp;
  }
  return o;
}
Vec3 mix_burn(float t, const Vec3& c1, const Vec3& c2) {
  float tm = 1.0f - t;
  Vec3 o = c1;
  for (int i = 0; i < 3; ++i) {
    float tmp = tm + t * c2[i];
    if (tmp <= 0.0f) {
      o[i] = 0.0f;
    } else {
      tmp = 1.0f - (1.0f - o[i]) / tmp;
      o[i] = tmp < 0.0f ? 0.0f : (tmp > 1.0f ? 1.0f : tmp);
    }
  }
  return o;
}
Vec3 mix_hue(float t, const Vec3& c1, const Vec3& c2) {
  Vec3 hsv2 = rgb_to_hsv(c2);
  if (hsv2.y == 0.0f) return c1;
  Vec3 hsv = rgb_to_hsv(c1);
  hsv.x = hsv2.x;
  return interp(c1, hsv_to_rgb(hsv), t);
}
Vec3 mix_saturation(float t, const Vec3& c1, const Vec3& c2) {
  Vec3 hsv = rgb_to_hsv(c1);
  if (hsv.y == 0.0f) return c1;
  Vec3 hsv2 = rgb_to_hsv(c2);
  hsv.y = (1.0f - t) * hsv.y + t * hsv2.y;
  return hsv_to_rgb(hsv);
}
Vec3 mix_value(float t, const Vec3& c1, const Vec3& c2) {
  Vec3 hsv = rgb_to_hsv(c1);
  Vec3 hsv2 = rgb_to_hsv(c2);
  hsv.z = (1.0f - t) * hsv.z + t * hsv2.z;
  return hsv_to_rgb(hsv);
}
Vec3 mix_color(float t, const Vec3& c1, const Vec3& c2) {
  Vec3 hsv2 = rgb_to_hsv(c2);
  if (hsv2.y == 0.0f) return c1;
  Vec3 hsv = rgb_to_hsv(c1);
  hsv.x = hsv2.x;
  hsv.y = hsv2.y;
  return interp(c1, hsv_to_rgb(hsv), t);
}
Vec3 mix_soft(float t, const Vec3& c1, const Vec3& c2) {
  Vec3 one(1.0f);
  Vec3 scr = one - (one - c2) * (one - c1);
  return (1.0f - t) * c1 + t * ((one - c1) * c2 * c1 + c1 * scr);
}

// kernel/svm/ramp.h: table lookup with optional linear interpolation and extrapolation past
// [0, 1] along the end slope. `stride` floats per entry, channel `ch`.
float ramp_lookup(const float* table, int n, int stride, int ch, float f, bool interpolate, bool extrapolate) {
  auto at = [&](int i) { return table[i * stride + ch]; };
  if (n == 1) return at(0);
  if ((f < 0.0f || f > 1.0f) && extrapolate) {
    float t0, dy;
    if (f < 0.0f) {
      t0 = at(0);
      dy = t0 - at(1);
      f = -f;
    } else {
      t0 = at(n - 1);
      dy = t0 - at(n - 2);
      f = f - 1.0f;
    }
    return t0 + dy * f * static_cast<float>(n - 1);
  }
  f = saturatef(f) * static_cast<float>(n - 1);
  int i = std::isnan(f) ? 0 : clamp(static_cast<int>(f), 0, n - 1);
  float t = f - static_cast<float>(i);
  float a = at(i);
  if (interpolate && t > 0.0f) a = (1.0f - t) * a + t * at(i + 1);
  return a;
}

// util/math_base.h smoothstep and kernel/svm/map_range.h smootherstep.
float smoothstep(float e0, float e1, float x) {
  if (x < e0) return 0.0f;
  if (x >= e1) return 1.0f;
  float t = (x - e0) / (e1 - e0);
  return (3.0f - 2.0f * t) * (t * t);
}
float smootherstep(float e0, float e1, float x) {
  x = clamp(safe_divide(x - e0, e1 - e0), 0.0f, 1.0f);
  return x * x * x * (x * (x * 6.0f - 15.0f) + 10.0f);
}

// MapRangeNode::expand clamps the float result with a Clamp node in Range mode.
float clamp_range(float v, float a, float b) { return a > b ? clamp(v, b, a) : clamp(v, a, b); }

float map_range(MapRangeType type, float value, float fmin, float fmax, float tmin, float tmax, float steps) {
  if (fmax == fmin) return 0.0f;
  float factor = value;
  switch (type) {
    case MapRangeType::Stepped:
      factor = (value - fmin) / (fmax - fmin);
      factor = steps > 0.0f ? std::floor(factor * (steps + 1.0f)) / steps : 0.0f;
      break;
    case MapRangeType::SmoothStep:
      factor = fmin > fmax ? 1.0f - smoothstep(fmax, fmin, factor) : smoothstep(fmin, fmax, factor);
      break;
    case MapRangeType::SmootherStep:
      factor = fmin > fmax ? 1.0f - smootherstep(fmax, fmin, factor) : smootherstep(fmin, fmax, factor);
      break;
    default:
      factor = (value - fmin) / (fmax - fmin);
      break;
  }
  return tmin + factor * (tmax - tmin);
}

// The vector variant divides safely and never special-cases reversed ranges (map_range.h).
float map_range_component(MapRangeType type, float value, float fmin, float fmax, float tmin, float tmax, float steps,
                          bool use_clamp) {
  float factor = safe_divide(value - fmin, fmax - fmin);
  switch (type) {
    case MapRangeType::Stepped:
      factor = steps > 0.0f ? std::floor(factor * (steps + 1.0f)) / steps : 0.0f;
      break;
    case MapRangeType::SmoothStep:
      factor = saturatef(factor);
      factor = (3.0f - 2.0f * factor) * (factor * factor);
      break;
    case MapRangeType::SmootherStep:
      factor = saturatef(factor);
      factor = factor * factor * factor * (factor * (factor * 6.0f - 15.0f) + 10.0f);
      break;
    default:
      break;
  }
  float r = tmin + factor * (tmax - tmin);
  bool clamps = use_clamp && (type == MapRangeType::Linear || type == MapRangeType::Stepped);
  return clamps ? clamp_range(r, tmin, tmax) : r;
}

// Rodrigues' rotation of p about a unit axis (util/math_float3.h rotate_around_axis).
Vec3 rotate_around_axis(const Vec3& p, const Vec3& axis, float angle) {
  float c = std::cos(angle), s = std::sin(angle);
  return p * c + cross(axis, p) * s + axis * (dot(axis, p) * (1.0f - c));
}

Vec3 mapping(MappingType type, const Vec3& v, const Vec3& loc, const Vec3& rot, const Vec3& scale) {
  switch (type) {
    case MappingType::Point:
      return euler_rotate(rot, v * scale, false) + loc;
    case MappingType::Texture:
      return safe_divide(euler_rotate(rot, v - loc, true), scale);
    case MappingType::Vector:
      return euler_rotate(rot, v * scale, false);
    case MappingType::Normal:
      return safe_normalize(euler_rotate(rot, safe_divide(v, scale), false));
    default:
      return Vec3();
  }
}

Vec3 vector_rotate(RotateType type, bool invert, const Vec3& v, const Vec3& center, const Vec3& axis_in, float angle,
                   const Vec3& rotation) {
  if (type == RotateType::EulerXyz) return euler_rotate(rotation, v - center, invert) + center;
  Vec3 axis = type == RotateType::XAxis   ? Vec3(1, 0, 0)
              : type == RotateType::YAxis ? Vec3(0, 1, 0)
              : type == RotateType::ZAxis ? Vec3(0, 0, 1)
                                          : axis_in;
  float axis_length = length(axis);
  if (axis_length == 0.0f) return v;
  return rotate_around_axis(v - center, axis / axis_length, invert ? -angle : angle) + center;
}

// CIE 1931 colour matching functions, 380-780 nm every 5 nm (kernel/tables.h cie_color_match).
constexpr float kCie[81][3] = {
    {0.0014f, 0.0000f, 0.0065f}, {0.0022f, 0.0001f, 0.0105f}, {0.0042f, 0.0001f, 0.0201f}, {0.0076f, 0.0002f, 0.0362f},
    {0.0143f, 0.0004f, 0.0679f}, {0.0232f, 0.0006f, 0.1102f}, {0.0435f, 0.0012f, 0.2074f}, {0.0776f, 0.0022f, 0.3713f},
    {0.1344f, 0.0040f, 0.6456f}, {0.2148f, 0.0073f, 1.0391f}, {0.2839f, 0.0116f, 1.3856f}, {0.3285f, 0.0168f, 1.6230f},
    {0.3483f, 0.0230f, 1.7471f}, {0.3481f, 0.0298f, 1.7826f}, {0.3362f, 0.0380f, 1.7721f}, {0.3187f, 0.0480f, 1.7441f},
    {0.2908f, 0.0600f, 1.6692f}, {0.2511f, 0.0739f, 1.5281f}, {0.1954f, 0.0910f, 1.2876f}, {0.1421f, 0.1126f, 1.0419f},
    {0.0956f, 0.1390f, 0.8130f}, {0.0580f, 0.1693f, 0.6162f}, {0.0320f, 0.2080f, 0.4652f}, {0.0147f, 0.2586f, 0.3533f},
    {0.0049f, 0.3230f, 0.2720f}, {0.0024f, 0.4073f, 0.2123f}, {0.0093f, 0.5030f, 0.1582f}, {0.0291f, 0.6082f, 0.1117f},
    {0.0633f, 0.7100f, 0.0782f}, {0.1096f, 0.7932f, 0.0573f}, {0.1655f, 0.8620f, 0.0422f}, {0.2257f, 0.9149f, 0.0298f},
    {0.2904f, 0.9540f, 0.0203f}, {0.3597f, 0.9803f, 0.0134f}, {0.4334f, 0.9950f, 0.0087f}, {0.5121f, 1.0000f, 0.0057f},
    {0.5945f, 0.9950f, 0.0039f}, {0.6784f, 0.9786f, 0.0027f}, {0.7621f, 0.9520f, 0.0021f}, {0.8425f, 0.9154f, 0.0018f},
    {0.9163f, 0.8700f, 0.0017f}, {0.9786f, 0.8163f, 0.0014f}, {1.0263f, 0.7570f, 0.0011f}, {1.0567f, 0.6949f, 0.0010f},
    {1.0622f, 0.6310f, 0.0008f}, {1.0456f, 0.5668f, 0.0006f}, {1.0026f, 0.5030f, 0.0003f}, {0.9384f, 0.4412f, 0.0002f},
    {0.8544f, 0.3810f, 0.0002f}, {0.7514f, 0.3210f, 0.0001f}, {0.6424f, 0.2650f, 0.0000f}, {0.5419f, 0.2170f, 0.0000f},
    {0.4479f, 0.1750f, 0.0000f}, {0.3608f, 0.1382f, 0.0000f}, {0.2835f, 0.1070f, 0.0000f}, {0.2187f, 0.0816f, 0.0000f},
    {0.1649f, 0.0610f, 0.0000f}, {0.1212f, 0.0446f, 0.0000f}, {0.0874f, 0.0320f, 0.0000f}, {0.0636f, 0.0232f, 0.0000f},
    {0.0468f, 0.0170f, 0.0000f}, {0.0329f, 0.0119f, 0.0000f}, {0.0227f, 0.0082f, 0.0000f}, {0.0158f, 0.0057f, 0.0000f},
    {0.0114f, 0.0041f, 0.0000f}, {0.0081f, 0.0029f, 0.0000f}, {0.0058f, 0.0021f, 0.0000f}, {0.0041f, 0.0015f, 0.0000f},
    {0.0029f, 0.0010f, 0.0000f}, {0.0020f, 0.0007f, 0.0000f}, {0.0014f, 0.0005f, 0.0000f}, {0.0010f, 0.0004f, 0.0000f},
    {0.0007f, 0.0002f, 0.0000f}, {0.0005f, 0.0002f, 0.0000f}, {0.0003f, 0.0001f, 0.0000f}, {0.0002f, 0.0001f, 0.0000f},
    {0.0002f, 0.0001f, 0.0000f}, {0.0001f, 0.0000f, 0.0000f}, {0.0001f, 0.0000f, 0.0000f}, {0.0001f, 0.0000f, 0.0000f},
    {0.0000f, 0.0000f, 0.0000f}};

// Blackbody fit in Rec. 709, 800-12000 K (kernel/tables.h, svm/math_util.h).
constexpr float kBlackbodyR[7][3] = {
    {1.61919106e+03f, -2.05010916e-03f, 5.02995757e+00f}, {2.48845471e+03f, -1.11330907e-03f, 3.22621544e+00f},
    {3.34143193e+03f, -4.86551192e-04f, 1.76486769e+00f}, {4.09461742e+03f, -1.27446582e-04f, 7.25731635e-01f},
    {4.67028036e+03f, 2.91258199e-05f, 1.26703442e-01f},  {4.59509185e+03f, 2.87495649e-05f, 1.50345020e-01f},
    {3.78717450e+03f, 9.35907826e-06f, 3.99075871e-01f}};
constexpr float kBlackbodyG[7][3] = {
    {-4.88999748e+02f, 6.04330754e-04f, -7.55807526e-02f}, {-7.55994277e+02f, 3.16730098e-04f, 4.78306139e-01f},
    {-1.02363977e+03f, 1.20223470e-04f, 9.36662319e-01f},  {-1.26571316e+03f, 4.87340896e-06f, 1.27054498e+00f},
    {-1.42529332e+03f, -4.01150431e-05f, 1.43972784e+00f}, {-1.17554822e+03f, -2.16378048e-05f, 1.30408023e+00f},
    {-5.00799571e+02f, -4.59832026e-06f, 1.09098763e+00f}};
constexpr float kBlackbodyB[7][4] = {{5.96945309e-11f, -4.85742887e-08f, -9.70622247e-05f, -4.07936148e-03f},
                                     {2.40430366e-11f, 5.55021075e-08f, -1.98503712e-04f, 2.89312858e-02f},
                                     {-1.40949732e-11f, 1.89878968e-07f, -3.56632824e-04f, 9.10767778e-02f},
                                     {-3.61460868e-11f, 2.84822009e-07f, -4.93211319e-04f, 1.56723440e-01f},
                                     {-1.97075738e-11f, 1.75359352e-07f, -2.50542825e-04f, -2.22783266e-02f},
                                     {-1.61997957e-13f, -1.64216008e-08f, 3.86216271e-04f, -7.38077418e-01f},
                                     {6.72650283e-13f, -2.73078809e-08f, 4.24098264e-04f, -7.52335691e-01f}};

// XYZ to the scene linear space of Blender's OCIO config: the inverse of its srgb_to_xyz.spimtx,
// which is what Cycles derives through the aces_interchange role (scene/colorspace.cpp).
constexpr float kXyzToRgb[3][3] = {{3.240454836f, -1.537138850f, -0.498531547f},
                                   {-0.969266390f, 1.876010929f, 0.041556082f},
                                   {0.055643420f, -0.204025854f, 1.057225162f}};

// Luma of Blender's config (config.ocio "luma"), Cycles' rgb_to_y.
constexpr Vec3 kLuma(0.2126f, 0.7152f, 0.0722f);

// Table entries of a 't' param: pool[offset] is the float count, the floats follow.
const float* table_at(const Machine& m, uint32_t offset, int* count) {
  *count = static_cast<int>(m.k[offset]);
  return m.k + offset + 1;
}

}  // namespace

float svm_math(MathType type, float a, float b, float c) {
  switch (type) {
    case MathType::Add:
      return a + b;
    case MathType::Subtract:
      return a - b;
    case MathType::Multiply:
      return a * b;
    case MathType::Divide:
      return safe_divide(a, b);
    case MathType::MultiplyAdd:
      return a * b + c;
    case MathType::Power:
      return safe_powf(a, b);
    case MathType::Logarithm:
      return safe_logf(a, b);
    case MathType::Sqrt:
      return safe_sqrt(a);
    case MathType::InverseSqrt:
      return 1.0f / std::sqrt(a);
    case MathType::Absolute:
      return std::fabs(a);
    case MathType::Exponent:
      return std::exp(a);
    case MathType::Minimum:
      return std::fmin(a, b);
    case MathType::Maximum:
      return std::fmax(a, b);
    case MathType::LessThan:
      return a < b ? 1.0f : 0.0f;
    case MathType::GreaterThan:
      return a > b ? 1.0f : 0.0f;
    case MathType::Sign:
      return compatible_signf(a);
    case MathType::Compare:
      return (a == b || std::fabs(a - b) <= std::fmax(c, FLT_EPSILON)) ? 1.0f : 0.0f;
    case MathType::SmoothMin:
      return smoothminf(a, b, c);
    case MathType::SmoothMax:
      return -smoothminf(-a, -b, c);
    case MathType::Round:
      return std::floor(a + 0.5f);
    case MathType::Floor:
      return std::floor(a);
    case MathType::Ceil:
      return std::ceil(a);
    case MathType::Trunc:
      return a >= 0.0f ? std::floor(a) : std::ceil(a);
    case MathType::Fract:
      return a - std::floor(a);
    case MathType::Modulo:
      return safe_modulo(a, b);
    case MathType::Wrap:
      return wrapf(a, b, c);
    case MathType::Snap:
      return std::floor(safe_divide(a, b)) * b;
    case MathType::PingPong:
      return pingpongf(a, b);
    case MathType::Sine:
      return std::sin(a);
    case MathType::Cosine:
      return std::cos(a);
    case MathType::Tangent:
      return std::tan(a);
    case MathType::Arcsine:
      return std::asin(clamp(a, -1.0f, 1.0f));
    case MathType::Arccosine:
      return std::acos(clamp(a, -1.0f, 1.0f));
    case MathType::Arctangent:
      return std::atan(a);
    case MathType::Arctan2:
      return std::atan2(a, b);
    case MathType::Sinh:
      return std::sinh(a);
    case MathType::Cosh:
      return std::cosh(a);
    case MathType::Tanh:
      return std::tanh(a);
    case MathType::Radians:
      return a * (kPi / 180.0f);
    case MathType::Degrees:
      return a * (180.0f / kPi);
    default:
      return 0.0f;
  }
}

Vec3 svm_mix(MixBlend type, float t, const Vec3& c1, const Vec3& c2) {
  switch (type) {
    case MixBlend::Mix:
      return interp(c1, c2, t);
    case MixBlend::Add:
      return interp(c1, c1 + c2, t);
    case MixBlend::Multiply:
      return interp(c1, c1 * c2, t);
    case MixBlend::Screen: {
      Vec3 one(1.0f);
      return one - (Vec3(1.0f - t) + t * (one - c2)) * (one - c1);
    }
    case MixBlend::Overlay:
      return mix_overlay(t, c1, c2);
    case MixBlend::Subtract:
      return interp(c1, c1 - c2, t);
    case MixBlend::Divide:
      return mix_divide(t, c1, c2);
    case MixBlend::Difference:
      return interp(c1, abs(c1 - c2), t);
    case MixBlend::Darken:
      return interp(c1, vmin(c1, c2), t);
    case MixBlend::Lighten:
      return interp(c1, vmax(c1, c2), t);
    case MixBlend::Dodge:
      return mix_dodge(t, c1, c2);
    case MixBlend::Burn:
      return mix_burn(t, c1, c2);
    case MixBlend::Hue:
      return mix_hue(t, c1, c2);
    case MixBlend::Saturation:
      return mix_saturation(t, c1, c2);
    case MixBlend::Value:
      return mix_value(t, c1, c2);
    case MixBlend::Color:
      return mix_color(t, c1, c2);
    case MixBlend::SoftLight:
      return mix_soft(t, c1, c2);
    case MixBlend::LinearLight:
      return c1 + t * (2.0f * c2 + Vec3(-1.0f));
    default:
      return Vec3();
  }
}

// util/color.h conversions.
Vec3 rgb_to_hsv(const Vec3& rgb) {
  float cmax = std::fmax(rgb.x, std::fmax(rgb.y, rgb.z));
  float cmin = std::min(rgb.x, std::min(rgb.y, rgb.z));
  float cdelta = cmax - cmin;
  float s = cmax != 0.0f ? cdelta / cmax : 0.0f;
  float h = 0.0f;
  if (s != 0.0f) {
    Vec3 c = (Vec3(cmax) - rgb) / cdelta;
    if (rgb.x == cmax)
      h = c.z - c.y;
    else if (rgb.y == cmax)
      h = 2.0f + c.x - c.z;
    else
      h = 4.0f + c.y - c.x;
    h /= 6.0f;
    if (h < 0.0f) h += 1.0f;
  }
  return {h, s, cmax};
}

Vec3 hsv_to_rgb(const Vec3& hsv) {
  float h = hsv.x, s = hsv.y, v = hsv.z;
  if (s == 0.0f) return Vec3(v);
  if (h == 1.0f) h = 0.0f;
  h *= 6.0f;
  float i = std::floor(h);
  float f = h - i;
  float p = v * (1.0f - s);
  float q = v * (1.0f - s * f);
  float t = v * (1.0f - s * (1.0f - f));
  if (i == 0.0f) return {v, t, p};
  if (i == 1.0f) return {q, v, p};
  if (i == 2.0f) return {p, v, t};
  if (i == 3.0f) return {p, q, v};
  if (i == 4.0f) return {t, p, v};
  return {v, p, q};
}

Vec3 rgb_to_hsl(const Vec3& rgb) {
  float cmax = std::fmax(rgb.x, std::fmax(rgb.y, rgb.z));
  float cmin = std::min(rgb.x, std::min(rgb.y, rgb.z));
  float l = std::min(1.0f, (cmax + cmin) / 2.0f);
  float h = 0.0f, s = 0.0f;
  if (cmax != cmin) {
    float cdelta = cmax - cmin;
    s = l > 0.5f ? cdelta / (2.0f - cmax - cmin) : cdelta / (cmax + cmin);
    if (cmax == rgb.x)
      h = (rgb.y - rgb.z) / cdelta + (rgb.y < rgb.z ? 6.0f : 0.0f);
    else if (cmax == rgb.y)
      h = (rgb.z - rgb.x) / cdelta + 2.0f;
    else
      h = (rgb.x - rgb.y) / cdelta + 4.0f;
  }
  return {h / 6.0f, s, l};
}

Vec3 hsl_to_rgb(const Vec3& hsl) {
  float h = hsl.x, s = hsl.y, l = hsl.z;
  float nr = clamp(std::fabs(h * 6.0f - 3.0f) - 1.0f, 0.0f, 1.0f);
  float ng = clamp(2.0f - std::fabs(h * 6.0f - 2.0f), 0.0f, 1.0f);
  float nb = clamp(2.0f - std::fabs(h * 6.0f - 4.0f), 0.0f, 1.0f);
  float chroma = (1.0f - std::fabs(2.0f * l - 1.0f)) * s;
  return {(nr - 0.5f) * chroma + l, (ng - 0.5f) * chroma + l, (nb - 0.5f) * chroma + l};
}

// svm/blackbody.h: the Rec. 709 fit, taken to the scene space (identity for Blender's config) and
// clamped to non-negative.
Vec3 blackbody_rgb(float t) {
  Vec3 c;
  if (t >= 12000.0f) {
    c = {0.8262954810464208f, 0.9945080501520986f, 1.566307710274283f};
  } else if (t < 800.0f) {
    c = {5.413294490189271f, -0.20319390035873933f, -0.0822535242887164f};
  } else {
    int i = t >= 6365.0f   ? 6
            : t >= 3315.0f ? 5
            : t >= 1902.0f ? 4
            : t >= 1449.0f ? 3
            : t >= 1167.0f ? 2
            : t >= 965.0f  ? 1
                           : 0;
    const float* r = kBlackbodyR[i];
    const float* g = kBlackbodyG[i];
    const float* b = kBlackbodyB[i];
    float t_inv = 1.0f / t;
    c = {r[0] * t_inv + r[1] * t + r[2], g[0] * t_inv + g[1] * t + g[2], ((b[0] * t + b[1]) * t + b[2]) * t + b[3]};
  }
  return vmax(c, Vec3());
}

// svm/wavelength.h: CIE matching functions interpolated, to RGB, scaled by 1/2.52, clamped.
Vec3 wavelength_rgb(float nm) {
  float ii = (nm - 380.0f) * (1.0f / 5.0f);
  int i = std::isnan(ii) ? -1 : static_cast<int>(std::fmax(std::fmin(ii, 1e6f), -1e6f));
  Vec3 xyz;
  if (i >= 0 && i < 80) {
    ii -= static_cast<float>(i);
    xyz = interp(Vec3(kCie[i][0], kCie[i][1], kCie[i][2]), Vec3(kCie[i + 1][0], kCie[i + 1][1], kCie[i + 1][2]), ii);
  }
  return vmax(xyz_to_rgb(xyz) * (1.0f / 2.52f), Vec3());
}

Vec3 xyz_to_rgb(const Vec3& xyz) {
  return {kXyzToRgb[0][0] * xyz.x + kXyzToRgb[0][1] * xyz.y + kXyzToRgb[0][2] * xyz.z,
          kXyzToRgb[1][0] * xyz.x + kXyzToRgb[1][1] * xyz.y + kXyzToRgb[1][2] * xyz.z,
          kXyzToRgb[2][0] * xyz.x + kXyzToRgb[2][1] * xyz.y + kXyzToRgb[2][2] * xyz.z};
}

// util/transform.h euler_to_transform (R = Rz Ry Rx) applied to v, or its transpose.
Vec3 euler_rotate(const Vec3& e, const Vec3& v, bool transposed) {
  float cx = std::cos(e.x), cy = std::cos(e.y), cz = std::cos(e.z);
  float sx = std::sin(e.x), sy = std::sin(e.y), sz = std::sin(e.z);
  Vec3 r0(cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz);
  Vec3 r1(cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz);
  Vec3 r2(-sy, cy * sx, cy * cx);
  if (!transposed) return {dot(r0, v), dot(r1, v), dot(r2, v)};
  return r0 * v.x + r1 * v.y + r2 * v.z;
}

const OpSignature* math_family_signature(uint32_t op) {
  // Indexed by op - kFamilyMathBegin, in MathOp's order (a static_assert below keeps them in step).
  static const OpSignature kSignatures[] = {
      {"fff", "f", "ii", true},     // Math
      {"vvvf", "vf", "i", true},    // VectorMath
      {"fvv", "v", "iii", true},    // MixColor
      {"fff", "f", "i", true},      // MixFloat
      {"fvv", "v", "i", true},      // MixVector
      {"vvv", "v", "i", true},      // MixVectorNonUniform
      {"fv", "v", "", true},        // Invert
      {"ffffv", "v", "", true},     // HueSatVal
      {"vff", "v", "", true},       // BrightContrast
      {"vf", "v", "", true},        // Gamma
      {"fv", "v", "ti", true},      // Curves
      {"ff", "f", "ti", true},      // FloatCurve
      {"f", "vf", "ti", true},      // ColorRamp
      {"ffffff", "f", "ii", true},  // MapRange
      {"vvvvvv", "v", "ii", true},  // MapRangeVector
      {"fff", "f", "i", true},      // Clamp
      {"v", "fff", "i", true},      // SeparateColor
      {"fff", "v", "i", true},      // CombineColor
      {"v", "fff", "", true},       // SeparateXyz
      {"fff", "v", "", true},       // CombineXyz
      {"v", "f", "", true},         // RgbToBw
      {"f", "v", "", true},         // Wavelength
      {"f", "v", "", true},         // Blackbody
      {"vvvv", "v", "i", true},     // Mapping
      {"vvvfv", "v", "ii", true},   // VectorRotate
      {"vv", "vf", "", true},       // Normal
  };
  static_assert(sizeof(kSignatures) / sizeof(kSignatures[0]) == kMathFamilyEnd - kFamilyMathBegin,
                "one signature per maths opcode");
  if (op < kFamilyMathBegin || op >= kMathFamilyEnd) return nullptr;
  return &kSignatures[op - kFamilyMathBegin];
}

void exec_math_family(const Instr& in, Machine& m) {
  const uint32_t* i = in.in;
  const uint32_t* o = in.out;
  const uint32_t* p = in.param;
  switch (in.op) {
    case kOpMath: {
      float r = svm_math(static_cast<MathType>(p[0]), m.f(i[0]), m.f(i[1]), m.f(i[2]));
      m.set(o[0], p[1] ? saturatef(r) : r);
      return;
    }
    case kOpVectorMath: {
      Vec3 vec;
      float val;
      svm_vector_math(static_cast<VectorMathType>(p[0]), m.v(i[0]), m.v(i[1]), m.v(i[2]), m.f(i[3]), &vec, &val);
      m.set(o[0], vec);
      m.set(o[1], val);
      return;
    }
    case kOpMixColor: {
      float t = m.f(i[0]);
      if (p[1]) t = saturatef(t);
      Vec3 r = svm_mix(static_cast<MixBlend>(p[0]), t, m.v(i[1]), m.v(i[2]));
      m.set(o[0], p[2] ? saturate(r) : r);
      return;
    }
    case kOpMixFloat: {
      float t = m.f(i[0]);
      if (p[0]) t = saturatef(t);
      m.set(o[0], m.f(i[1]) * (1.0f - t) + m.f(i[2]) * t);
      return;
    }
    case kOpMixVector: {
      float t = m.f(i[0]);
      if (p[0]) t = saturatef(t);
      m.set(o[0], m.v(i[1]) * (1.0f - t) + m.v(i[2]) * t);
      return;
    }
    case kOpMixVectorNonUniform: {
      Vec3 t = m.v(i[0]);
      if (p[0]) t = saturate(t);
      m.set(o[0], m.v(i[1]) * (Vec3(1.0f) - t) + m.v(i[2]) * t);
      return;
    }
    case kOpInvert: {  // svm/invert.h
      float fac = m.f(i[0]);
      Vec3 c = m.v(i[1]);
      m.set(o[0], fac * (Vec3(1.0f) - c) + (1.0f - fac) * c);
      return;
    }
    case kOpHueSatVal: {  // svm/hsv.h
      float fac = m.f(i[3]);
      Vec3 in_color = m.v(i[4]);
      Vec3 c = rgb_to_hsv(in_color);
      c.x = fractf(c.x + m.f(i[0]) + 0.5f);
      c.y = saturatef(c.y * m.f(i[1]));
      c.z *= m.f(i[2]);
      c = hsv_to_rgb(c);
      c = fac * c + (1.0f - fac) * in_color;
      m.set(o[0], vmax(c, Vec3()));
      return;
    }
    case kOpBrightContrast: {  // svm/color_util.h svm_brightness_contrast
      float contrast = m.f(i[2]);
      float a = 1.0f + contrast, b = m.f(i[1]) - contrast * 0.5f;
      m.set(o[0], vmax(a * m.v(i[0]) + Vec3(b), Vec3()));
      return;
    }
    case kOpGamma: {  // svm/math_util.h svm_math_gamma_color
      Vec3 c = m.v(i[0]);
      float g = m.f(i[1]);
      if (g == 0.0f) {
        c = Vec3(1.0f);
      } else {
        for (int k = 0; k < 3; ++k)
          if (c[k] > 0.0f) c[k] = std::pow(c[k], g);
      }
      m.set(o[0], c);
      return;
    }
    case kOpCurves: {  // svm/ramp.h svm_node_curves; table: min_x, max_x, n RGB triples
      int count;
      const float* table = table_at(m, p[0], &count);
      int n = (count - 2) / 3;
      float fac = m.f(i[0]);
      Vec3 c = m.v(i[1]);
      if (n < 1) {
        m.set(o[0], c);
        return;
      }
      float min_x = table[0], range = table[1] - table[0];
      Vec3 rel = (c - Vec3(min_x)) / range;
      bool ex = p[1] != 0;
      Vec3 r(ramp_lookup(table + 2, n, 3, 0, rel.x, true, ex), ramp_lookup(table + 2, n, 3, 1, rel.y, true, ex),
             ramp_lookup(table + 2, n, 3, 2, rel.z, true, ex));
      m.set(o[0], (1.0f - fac) * c + fac * r);
      return;
    }
    case kOpFloatCurve: {  // svm/ramp.h svm_node_curve; table: min_x, max_x, n floats
      int count;
      const float* table = table_at(m, p[0], &count);
      int n = count - 2;
      float fac = m.f(i[0]);
      float x = m.f(i[1]);
      if (n < 1) {
        m.set(o[0], x);
        return;
      }
      float rel = (x - table[0]) / (table[1] - table[0]);
      float v = ramp_lookup(table + 2, n, 1, 0, rel, true, p[1] != 0);
      m.set(o[0], (1.0f - fac) * x + fac * v);
      return;
    }
    case kOpColorRamp: {  // svm/ramp.h svm_node_rgb_ramp (never extrapolates); table: n RGBA quadruples
      int count;
      const float* table = table_at(m, p[0], &count);
      int n = count / 4;
      float f = m.f(i[0]);
      bool lin = p[1] != 0;
      Vec3 c;
      float alpha = 0.0f;
      if (n >= 1) {
        c = {ramp_lookup(table, n, 4, 0, f, lin, false), ramp_lookup(table, n, 4, 1, f, lin, false),
             ramp_lookup(table, n, 4, 2, f, lin, false)};
        alpha = ramp_lookup(table, n, 4, 3, f, lin, false);
      }
      m.set(o[0], c);
      m.set(o[1], alpha);
      return;
    }
    case kOpMapRange: {
      float r =
          map_range(static_cast<MapRangeType>(p[0]), m.f(i[0]), m.f(i[1]), m.f(i[2]), m.f(i[3]), m.f(i[4]), m.f(i[5]));
      m.set(o[0], p[1] ? clamp_range(r, m.f(i[3]), m.f(i[4])) : r);
      return;
    }
    case kOpMapRangeVector: {
      Vec3 v = m.v(i[0]), fmin = m.v(i[1]), fmax = m.v(i[2]), tmin = m.v(i[3]), tmax = m.v(i[4]), st = m.v(i[5]);
      Vec3 r;
      for (int k = 0; k < 3; ++k)
        r[k] = map_range_component(static_cast<MapRangeType>(p[0]), v[k], fmin[k], fmax[k], tmin[k], tmax[k], st[k],
                                   p[1] != 0);
      m.set(o[0], r);
      return;
    }
    case kOpClamp: {  // svm/clamp.h
      float v = m.f(i[0]), lo = m.f(i[1]), hi = m.f(i[2]);
      bool range = static_cast<ClampType>(p[0]) == ClampType::Range;
      m.set(o[0], range ? clamp_range(v, lo, hi) : std::min(std::max(v, lo), hi));
      return;
    }
    case kOpSeparateColor: {  // svm/sepcomb_color.h
      Vec3 c = m.v(i[0]);
      auto mode = static_cast<ColorMode>(p[0]);
      if (mode == ColorMode::Hsv) c = rgb_to_hsv(c);
      if (mode == ColorMode::Hsl) c = rgb_to_hsl(c);
      m.set(o[0], c.x);
      m.set(o[1], c.y);
      m.set(o[2], c.z);
      return;
    }
    case kOpCombineColor: {
      Vec3 c(m.f(i[0]), m.f(i[1]), m.f(i[2]));
      auto mode = static_cast<ColorMode>(p[0]);
      if (mode == ColorMode::Hsv) c = hsv_to_rgb(c);
      if (mode == ColorMode::Hsl) c = hsl_to_rgb(c);
      m.set(o[0], c);
      return;
    }
    case kOpSeparateXyz: {
      Vec3 v = m.v(i[0]);
      m.set(o[0], v.x);
      m.set(o[1], v.y);
      m.set(o[2], v.z);
      return;
    }
    case kOpCombineXyz:
      m.set(o[0], Vec3(m.f(i[0]), m.f(i[1]), m.f(i[2])));
      return;
    case kOpRgbToBw:
      m.set(o[0], dot(m.v(i[0]), kLuma));
      return;
    case kOpWavelength:
      m.set(o[0], wavelength_rgb(m.f(i[0])));
      return;
    case kOpBlackbody:
      m.set(o[0], blackbody_rgb(m.f(i[0])));
      return;
    case kOpMapping:  // svm/mapping_util.h
      m.set(o[0], mapping(static_cast<MappingType>(p[0]), m.v(i[0]), m.v(i[1]), m.v(i[2]), m.v(i[3])));
      return;
    case kOpVectorRotate:  // svm/vector_rotate.h
      m.set(o[0], vector_rotate(static_cast<RotateType>(p[0]), p[1] != 0, m.v(i[0]), m.v(i[1]), m.v(i[2]), m.f(i[3]),
                                m.v(i[4])));
      return;
    case kOpNormal: {  // svm/normal.h: the node's direction, and its cosine with the input
      Vec3 dir = normalize(m.v(i[0]));
      m.set(o[0], dir);
      m.set(o[1], dot(dir, normalize(m.v(i[1]))));
      return;
    }
    default:
      return;
  }
}

}  // namespace lt
