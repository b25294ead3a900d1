// The maths family of the shader machine (shading/nodes_math.*): every Math and Vector Math
// operation, the blend modes, colour conversions and converters, checked against closed forms
// computed here independently (hand-derived values, double precision) at chosen points.
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <string>
#include <vector>

#include "shading/nodes_math.h"

namespace lt {
namespace {

// Builds one instruction over registers: each input is copied into fresh registers.
struct Bench {
  std::vector<float> regs = std::vector<float>(256, -999.0f);
  std::vector<float> pool;
  std::vector<uint32_t> in, out, param;
  int next = 0;

  uint32_t operand(int size) {
    uint32_t w = static_cast<uint32_t>(next) | (static_cast<uint32_t>(size) << 24);
    next += size;
    return w;
  }
  Bench& f(float x) {
    uint32_t w = operand(1);
    regs[operand_index(w)] = x;
    in.push_back(w);
    return *this;
  }
  Bench& v(Vec3 x) {
    uint32_t w = operand(3);
    for (int k = 0; k < 3; ++k) regs[operand_index(w) + k] = x[k];
    in.push_back(w);
    return *this;
  }
  Bench& out_f() {
    out.push_back(operand(1));
    return *this;
  }
  Bench& out_v() {
    out.push_back(operand(3));
    return *this;
  }
  Bench& params(std::initializer_list<uint32_t> p) {
    param = p;
    return *this;
  }
  // Checks the operands against the opcode's signature (as the loader does), then runs it.
  void run(uint32_t op) {
    const OpSignature* sig = math_family_signature(op);
    ASSERT_NE(sig, nullptr);
    ASSERT_TRUE(sig->pure);
    ASSERT_EQ(std::string(sig->in), sizes(in));
    ASSERT_EQ(std::string(sig->out), sizes(out));
    ASSERT_EQ(std::string(sig->params).size(), param.size());
    Instr ins{op,
              static_cast<int>(in.size()),
              static_cast<int>(out.size()),
              static_cast<int>(param.size()),
              in.data(),
              out.data(),
              param.data()};
    Machine m{};
    m.r = regs.data();
    m.k = pool.data();
    exec_math_family(ins, m);
  }
  static std::string sizes(const std::vector<uint32_t>& ops) {
    std::string s;
    for (uint32_t w : ops) s += operand_size(w) == 3 ? 'v' : 'f';
    return s;
  }
  // A table as the compiler lays it out: its float count, then the floats; returns the offset.
  uint32_t table(std::initializer_list<float> t) {
    uint32_t offset = static_cast<uint32_t>(pool.size());
    pool.push_back(static_cast<float>(t.size()));
    pool.insert(pool.end(), t);
    return offset;
  }
  float rf(int i) const { return regs[operand_index(out[i])]; }
  Vec3 rv(int i) const {
    const float* p = &regs[operand_index(out[i])];
    return {p[0], p[1], p[2]};
  }
};

float math(MathType t, float a, float b, float c = 0, bool clamp_result = false) {
  Bench b_;
  b_.f(a).f(b).f(c).out_f().params({static_cast<uint32_t>(t), clamp_result ? 1u : 0u}).run(kOpMath);
  return b_.rf(0);
}

struct VmResult {
  Vec3 v;
  float f;
};
VmResult vmath(VectorMathType t, Vec3 a, Vec3 b, Vec3 c = Vec3(), float s = 0) {
  Bench b_;
  b_.v(a).v(b).v(c).f(s).out_v().out_f().params({static_cast<uint32_t>(t)}).run(kOpVectorMath);
  return {b_.rv(0), b_.rf(1)};
}

void expect_near_rel(double got, double want, double rel = 1e-5) {
  EXPECT_NEAR(got, want, rel * std::max(1.0, std::fabs(want)));
}
void expect_vec(const Vec3& got, double x, double y, double z, double rel = 1e-5) {
  expect_near_rel(got.x, x, rel);
  expect_near_rel(got.y, y, rel);
  expect_near_rel(got.z, z, rel);
}

TEST(NodesMath, EveryMathOperation) {
  using M = MathType;
  const double pi = 3.14159265358979323846;
  struct Case {
    M op;
    float a, b, c;
    double want;
  };
  const Case cases[] = {
      {M::Add, 1.5f, 2.25f, 0, 3.75},
      {M::Subtract, 1.5f, 2.25f, 0, -0.75},
      {M::Multiply, 1.5f, -2.0f, 0, -3.0},
      {M::Divide, 3.0f, 4.0f, 0, 0.75},
      {M::Divide, 3.0f, 0.0f, 0, 0.0},  // safe divide
      {M::MultiplyAdd, 2.0f, 3.0f, 0.5f, 6.5},
      {M::Power, 2.0f, 10.0f, 0, 1024.0},
      {M::Power, -2.0f, 3.0f, 0, -8.0},  // integer exponent of a negative base
      {M::Power, -2.0f, 0.5f, 0, 0.0},   // fractional: 0 as Cycles
      {M::Logarithm, 8.0f, 2.0f, 0, 3.0},
      {M::Logarithm, -1.0f, 2.0f, 0, 0.0},
      {M::Sqrt, 2.25f, 0, 0, 1.5},
      {M::Sqrt, -4.0f, 0, 0, 0.0},
      {M::InverseSqrt, 4.0f, 0, 0, 0.5},
      {M::Absolute, -3.5f, 0, 0, 3.5},
      {M::Exponent, 1.0f, 0, 0, 2.718281828459045},
      {M::Minimum, 1.0f, -2.0f, 0, -2.0},
      {M::Maximum, 1.0f, -2.0f, 0, 1.0},
      {M::LessThan, 1.0f, 2.0f, 0, 1.0},
      {M::LessThan, 2.0f, 1.0f, 0, 0.0},
      {M::GreaterThan, 2.0f, 1.0f, 0, 1.0},
      {M::GreaterThan, 1.0f, 1.0f, 0, 0.0},
      {M::Sign, -0.3f, 0, 0, -1.0},
      {M::Sign, 0.0f, 0, 0, 0.0},
      {M::Sign, 7.0f, 0, 0, 1.0},
      {M::Compare, 1.0f, 1.05f, 0.1f, 1.0},
      {M::Compare, 1.0f, 1.2f, 0.1f, 0.0},
      // smooth min: h = max(k - |a - b|, 0) / k = 0.5, min - h^3 k / 6 = 1 - 0.125 / 6
      {M::SmoothMin, 1.0f, 1.5f, 1.0f, 1.0 - 0.125 / 6.0},
      {M::SmoothMax, 1.0f, 1.5f, 1.0f, 1.5 + 0.125 / 6.0},
      {M::SmoothMin, 1.0f, 1.5f, 0.0f, 1.0},
      {M::Round, 2.5f, 0, 0, 3.0},
      {M::Round, -2.5f, 0, 0, -2.0},  // floor(a + 0.5)
      {M::Floor, -1.25f, 0, 0, -2.0},
      {M::Ceil, -1.25f, 0, 0, -1.0},
      {M::Trunc, -1.75f, 0, 0, -1.0},
      {M::Trunc, 1.75f, 0, 0, 1.0},
      {M::Fract, -1.25f, 0, 0, 0.75},
      {M::Modulo, -5.5f, 2.0f, 0, -1.5},  // truncated (C fmod)
      {M::Modulo, 5.5f, 0.0f, 0, 0.0},
      {M::Wrap, 5.5f, 2.0f, 0.0f, 1.5},   // value, max, min
      {M::Wrap, -0.5f, 3.0f, 1.0f, 1.5},  // into [1, 3)
      {M::Wrap, 4.0f, 1.0f, 1.0f, 1.0},   // empty range: min
      {M::Snap, 7.3f, 2.0f, 0, 6.0},
      {M::Snap, -0.5f, 2.0f, 0, -2.0},
      {M::PingPong, 3.0f, 2.0f, 0, 1.0},  // up to 2, back down: 3 -> 1
      {M::PingPong, 5.0f, 2.0f, 0, 1.0},
      {M::PingPong, 1.5f, 0.0f, 0, 0.0},
      {M::Sine, 0.5f, 0, 0, std::sin(0.5)},
      {M::Cosine, 0.5f, 0, 0, std::cos(0.5)},
      {M::Tangent, 0.5f, 0, 0, std::tan(0.5)},
      {M::Arcsine, 0.5f, 0, 0, pi / 6},
      {M::Arcsine, 2.0f, 0, 0, pi / 2},  // clamped input
      {M::Arccosine, 0.5f, 0, 0, pi / 3},
      {M::Arccosine, -3.0f, 0, 0, pi},
      {M::Arctangent, 1.0f, 0, 0, pi / 4},
      {M::Arctan2, 1.0f, -1.0f, 0, 3 * pi / 4},
      {M::Sinh, 1.0f, 0, 0, (std::exp(1.0) - std::exp(-1.0)) / 2},
      {M::Cosh, 1.0f, 0, 0, (std::exp(1.0) + std::exp(-1.0)) / 2},
      {M::Tanh, 1.0f, 0, 0, (std::exp(2.0) - 1) / (std::exp(2.0) + 1)},
      {M::Radians, 180.0f, 0, 0, pi},
      {M::Degrees, 1.0f, 0, 0, 180.0 / pi},
  };
  bool seen[static_cast<int>(M::Count)] = {};
  for (const Case& c : cases) {
    SCOPED_TRACE(static_cast<int>(c.op));
    expect_near_rel(math(c.op, c.a, c.b, c.c), c.want);
    seen[static_cast<int>(c.op)] = true;
  }
  for (int i = 0; i < static_cast<int>(M::Count); ++i) EXPECT_TRUE(seen[i]) << "math operation " << i << " untested";
}

TEST(NodesMath, MathClampOption) {
  EXPECT_EQ(math(MathType::Add, 0.75f, 0.5f, 0, true), 1.0f);
  EXPECT_EQ(math(MathType::Subtract, 0.25f, 0.5f, 0, true), 0.0f);
  EXPECT_FLOAT_EQ(math(MathType::Add, 0.25f, 0.5f, 0, true), 0.75f);
}

TEST(NodesMath, EveryVectorMathOperation) {
  using V = VectorMathType;
  const Vec3 a(1.5f, -2.0f, 0.5f), b(2.0f, 0.5f, -1.0f), c(0.25f, 1.0f, 4.0f);
  bool seen[static_cast<int>(V::Count)] = {};
  auto check = [&](V op, const Vec3& got, double x, double y, double z) {
    SCOPED_TRACE(static_cast<int>(op));
    expect_vec(got, x, y, z);
    seen[static_cast<int>(op)] = true;
  };
  auto checkf = [&](V op, float got, double want) {
    SCOPED_TRACE(static_cast<int>(op));
    expect_near_rel(got, want);
    seen[static_cast<int>(op)] = true;
  };
  check(V::Add, vmath(V::Add, a, b).v, 3.5, -1.5, -0.5);
  check(V::Subtract, vmath(V::Subtract, a, b).v, -0.5, -2.5, 1.5);
  check(V::Multiply, vmath(V::Multiply, a, b).v, 3.0, -1.0, -0.5);
  check(V::Divide, vmath(V::Divide, a, Vec3(3.0f, 0.0f, -0.5f)).v, 0.5, 0.0, -1.0);
  check(V::MultiplyAdd, vmath(V::MultiplyAdd, a, b, c).v, 3.25, 0.0, 3.5);
  // a x b = (ay bz - az by, az bx - ax bz, ax by - ay bx) = (2 - 0.25, 1 + 1.5, 0.75 + 4)
  check(V::CrossProduct, vmath(V::CrossProduct, a, b).v, 1.75, 2.5, 4.75);
  // project a onto b: (a.b / b.b) b = (1.5 / 5.25) b
  {
    double k = 1.5 / 5.25;
    check(V::Project, vmath(V::Project, a, b).v, 2 * k, 0.5 * k, -k);
  }
  // reflect a about the unit z axis: flip z
  check(V::Reflect, vmath(V::Reflect, a, Vec3(0, 0, 2)).v, 1.5, -2.0, -0.5);
  // refract (0.6, 0, -0.8) through +z at eta 1/1.5: tangential part scales by eta
  {
    double eta = 1 / 1.5, sin_t = 0.6 * eta, cos_t = std::sqrt(1 - sin_t * sin_t);
    check(V::Refract, vmath(V::Refract, Vec3(0.6f, 0, -0.8f), Vec3(0, 0, 3), Vec3(), float(eta)).v, sin_t, 0, -cos_t);
    EXPECT_TRUE(is_black(vmath(V::Refract, Vec3(0.8f, 0, -0.6f), Vec3(0, 0, 1), Vec3(), 1.5f).v));  // total internal
  }
  // faceforward(a, incident b, reference c): c.b = 0.5 + 0.5 - 4 < 0 keeps a
  check(V::Faceforward, vmath(V::Faceforward, a, b, c).v, 1.5, -2.0, 0.5);
  EXPECT_EQ(vmath(V::Faceforward, a, b, -c).v.x, -1.5f);
  checkf(V::DotProduct, vmath(V::DotProduct, a, b).f, 3.0 - 1.0 - 0.5);
  checkf(V::Distance, vmath(V::Distance, a, b).f, std::sqrt(0.25 + 6.25 + 2.25));
  checkf(V::Length, vmath(V::Length, a, b).f, std::sqrt(2.25 + 4 + 0.25));
  check(V::Scale, vmath(V::Scale, a, b, c, -2.0f).v, -3.0, 4.0, -1.0);
  {
    double l = std::sqrt(6.5);
    check(V::Normalize, vmath(V::Normalize, a, b).v, 1.5 / l, -2 / l, 0.5 / l);
    EXPECT_TRUE(is_black(vmath(V::Normalize, Vec3(), b).v));
  }
  check(V::Absolute, vmath(V::Absolute, a, b).v, 1.5, 2.0, 0.5);
  check(V::Minimum, vmath(V::Minimum, a, b).v, 1.5, -2.0, -1.0);
  check(V::Maximum, vmath(V::Maximum, a, b).v, 2.0, 0.5, 0.5);
  check(V::Floor, vmath(V::Floor, a, b).v, 1.0, -2.0, 0.0);
  check(V::Ceil, vmath(V::Ceil, Vec3(1.5f, -2.5f, 0.5f), b).v, 2.0, -2.0, 1.0);
  check(V::Fraction, vmath(V::Fraction, Vec3(1.25f, -2.25f, 0.5f), b).v, 0.25, 0.75, 0.5);
  check(V::Modulo, vmath(V::Modulo, Vec3(5.5f, -5.5f, 3.0f), Vec3(2.0f, 2.0f, 0.0f)).v, 1.5, -1.5, 0.0);
  check(V::Wrap, vmath(V::Wrap, Vec3(5.5f, -0.5f, 4.0f), Vec3(2.0f, 3.0f, 1.0f), Vec3(0.0f, 1.0f, 1.0f)).v, 1.5, 1.5,
        1.0);
  check(V::Snap, vmath(V::Snap, Vec3(7.3f, -0.5f, 1.0f), Vec3(2.0f, 2.0f, 0.0f)).v, 6.0, -2.0, 0.0);
  check(V::Sine, vmath(V::Sine, a, b).v, std::sin(1.5), std::sin(-2.0), std::sin(0.5));
  check(V::Cosine, vmath(V::Cosine, a, b).v, std::cos(1.5), std::cos(-2.0), std::cos(0.5));
  check(V::Tangent, vmath(V::Tangent, a, b).v, std::tan(1.5), std::tan(-2.0), std::tan(0.5));
  for (int i = 0; i < static_cast<int>(V::Count); ++i) EXPECT_TRUE(seen[i]) << "vector math operation " << i;
}

Vec3 mix(MixBlend t, float fac, Vec3 a, Vec3 b, bool clamp_fac = true, bool clamp_res = false) {
  Bench b_;
  b_.f(fac).v(a).v(b).out_v().params({static_cast<uint32_t>(t), clamp_fac, clamp_res}).run(kOpMixColor);
  return b_.rv(0);
}

TEST(NodesMath, MixBlendModes) {
  using B = MixBlend;
  const Vec3 a(0.2f, 0.6f, 0.9f), b(0.5f, 0.25f, 0.0f);
  const float t = 0.4f;
  auto lerp3 = [&](double x0, double x1, double y0, double y1, double z0, double z1) {
    return std::vector<double>{x0 + t * (x1 - x0), y0 + t * (y1 - y0), z0 + t * (z1 - z0)};
  };
  auto check = [&](B mode, std::vector<double> w) {
    SCOPED_TRACE(static_cast<int>(mode));
    expect_vec(mix(mode, t, a, b), w[0], w[1], w[2]);
  };
  check(B::Mix, lerp3(0.2, 0.5, 0.6, 0.25, 0.9, 0.0));
  check(B::Add, lerp3(0.2, 0.7, 0.6, 0.85, 0.9, 0.9));
  check(B::Multiply, lerp3(0.2, 0.1, 0.6, 0.15, 0.9, 0.0));
  check(B::Subtract, lerp3(0.2, -0.3, 0.6, 0.35, 0.9, 0.9));
  check(B::Difference, lerp3(0.2, 0.3, 0.6, 0.35, 0.9, 0.9));
  check(B::Darken, lerp3(0.2, 0.2, 0.6, 0.25, 0.9, 0.0));
  check(B::Lighten, lerp3(0.2, 0.5, 0.6, 0.6, 0.9, 0.9));
  // screen: 1 - (1 - t + t (1 - b)) (1 - a) = 1 - (1 - t b)(1 - a)
  check(B::Screen, {1 - (1 - t * 0.5) * 0.8, 1 - (1 - t * 0.25) * 0.4, 1 - 1.0 * 0.1});
  // overlay: a < 0.5 -> a (1 - t + 2 t b); else 1 - (1 - t + 2 t (1 - b)) (1 - a)
  check(B::Overlay, {0.2 * (0.6 + 0.8 * 0.5), 1 - (0.6 + 0.8 * 0.75) * 0.4, 1 - (0.6 + 0.8) * 0.1});
  // divide: component-wise, skipping zero divisors
  check(B::Divide, {0.6 * 0.2 + t * 0.2 / 0.5, 0.6 * 0.6 + t * 0.6 / 0.25, 0.9});
  // dodge: a / (1 - t b), capped at 1
  check(B::Dodge, {0.2 / (1 - t * 0.5), 0.6 / (1 - t * 0.25), 0.9});
  // burn: 1 - (1 - a) / (1 - t + t b), clamped to [0, 1]
  check(B::Burn, {0.0, 1 - 0.4 / 0.7, 1 - 0.1 / 0.6});
  // soft light: (1 - t) a + t ((1 - a) b a + a (1 - (1 - b)(1 - a)))
  auto soft = [&](double x, double y) { return (1 - t) * x + t * ((1 - x) * y * x + x * (1 - (1 - y) * (1 - x))); };
  check(B::SoftLight, {soft(0.2, 0.5), soft(0.6, 0.25), soft(0.9, 0.0)});
  // linear light: a + t (2 b - 1)
  check(B::LinearLight, {0.2 + t * 0.0, 0.6 + t * -0.5, 0.9 - t});
  // value: HSV value blended, hue and saturation of a. a's hsv: v 0.9, s (0.9 - 0.2) / 0.9
  {
    double v = 0.6 * 0.9 + t * 0.5, k = v / 0.9;  // scales a uniformly
    check(B::Value, {0.2 * k, 0.6 * k, 0.9 * k});
  }
  // hue / colour / saturation against a grey b leave a unchanged (b has no hue)
  expect_vec(mix(B::Hue, t, a, Vec3(0.3f)), 0.2, 0.6, 0.9);
  expect_vec(mix(B::Color, t, a, Vec3(0.3f)), 0.2, 0.6, 0.9);
  // saturation: s -> (1 - t) s_a + t s_b (b is fully saturated), a's hue and value
  {
    double s = (1 - t) * (0.7 / 0.9) + t * 1.0, v = 0.9;
    // a's hue lies where blue is max and red min; green sits g_frac of the way from min to max
    double g_frac = (0.6 - 0.2) / 0.7;  // where g sits between min and max
    double mn = v * (1 - s);
    check(B::Saturation, {mn, mn + g_frac * (v - mn), v});
  }
  // hue: pure red b on a: a keeps s and v, takes hue 0 -> (v, min, min)
  {
    double mn = 0.2;
    expect_vec(mix(B::Hue, 1.0f, a, Vec3(1, 0, 0)), 0.9, mn, mn);
    expect_vec(mix(B::Color, 1.0f, a, Vec3(1, 0, 0)), 0.9, 0.0, 0.0);  // also b's saturation 1
  }
  // clamp factor and result
  expect_vec(mix(B::Mix, 2.0f, a, b, true), 0.5, 0.25, 0.0);
  expect_vec(mix(B::Mix, 2.0f, a, b, false), 0.8, -0.1, -0.9);
  expect_vec(mix(B::Add, 1.0f, a, b, true, true), 0.7, 0.85, 0.9);
  expect_vec(mix(B::Add, 1.0f, Vec3(0.8f), Vec3(0.5f), true, true), 1.0, 1.0, 1.0);
}

TEST(NodesMath, MixFloatAndVector) {
  Bench f;
  f.f(1.5f).f(2.0f).f(4.0f).out_f().params({0}).run(kOpMixFloat);
  EXPECT_FLOAT_EQ(f.rf(0), 5.0f);
  Bench fc;
  fc.f(1.5f).f(2.0f).f(4.0f).out_f().params({1}).run(kOpMixFloat);
  EXPECT_FLOAT_EQ(fc.rf(0), 4.0f);
  Bench v;
  v.f(0.25f).v(Vec3(0, 4, 8)).v(Vec3(4, 0, 8)).out_v().params({1}).run(kOpMixVector);
  expect_vec(v.rv(0), 1, 3, 8);
  Bench n;
  n.v(Vec3(0, 0.5f, 2)).v(Vec3(0, 4, 8)).v(Vec3(4, 0, 0)).out_v().params({0}).run(kOpMixVectorNonUniform);
  expect_vec(n.rv(0), 0, 2, -8);
}

TEST(NodesMath, ColourConversionsRoundTrip) {
  // Known values: orange (1, 0.5, 0) is hue 30 degrees, full saturation.
  Vec3 hsv = rgb_to_hsv(Vec3(1, 0.5f, 0));
  expect_vec(hsv, 30.0 / 360, 1, 1);
  Vec3 hsl = rgb_to_hsl(Vec3(1, 0.5f, 0));
  expect_vec(hsl, 30.0 / 360, 1, 0.5);
  for (Vec3 c : {Vec3(0.2f, 0.6f, 0.9f), Vec3(0.9f, 0.1f, 0.3f), Vec3(0.4f, 0.4f, 0.1f), Vec3(0.5f)}) {
    expect_vec(hsv_to_rgb(rgb_to_hsv(c)), c.x, c.y, c.z);
    expect_vec(hsl_to_rgb(rgb_to_hsl(c)), c.x, c.y, c.z);
  }
  Bench sep;
  sep.v(Vec3(1, 0.5f, 0)).out_f().out_f().out_f().params({static_cast<uint32_t>(ColorMode::Hsl)}).run(kOpSeparateColor);
  expect_near_rel(sep.rf(0), 30.0 / 360);
  expect_near_rel(sep.rf(2), 0.5);
  Bench comb;
  comb.f(0.5f).f(1.0f).f(0.5f).out_v().params({static_cast<uint32_t>(ColorMode::Hsv)}).run(kOpCombineColor);
  expect_vec(comb.rv(0), 0, 0.5, 0.5);  // cyan at half value
  Bench bw;
  bw.v(Vec3(1, 2, 3)).out_f().run(kOpRgbToBw);
  expect_near_rel(bw.rf(0), 0.2126 + 2 * 0.7152 + 3 * 0.0722);
}

TEST(NodesMath, ColourAdjustments) {
  Bench inv;
  inv.f(0.25f).v(Vec3(0.2f, 1, 0)).out_v().run(kOpInvert);
  expect_vec(inv.rv(0), 0.75 * 0.2 + 0.25 * 0.8, 0.75, 0.25);
  Bench bc;  // a = 1 + contrast, b = bright - contrast / 2, clamped at 0
  bc.v(Vec3(0.5f, 0.1f, 1)).f(0.1f).f(0.5f).out_v().run(kOpBrightContrast);
  expect_vec(bc.rv(0), 0.75 - 0.15, 0.0, 1.5 - 0.15);
  Bench g;
  g.v(Vec3(0.25f, -1, 4)).f(0.5f).out_v().run(kOpGamma);
  expect_vec(g.rv(0), 0.5, -1, 2);
  Bench hsv;  // hue +0.5 shifts by half a turn: (1, 0.5, 0) orange -> hue 0.583 (azure), sat 1, value x 0.5
  hsv.f(1.0f).f(1.0f).f(0.5f).f(1.0f).v(Vec3(1, 0.5f, 0)).out_v().run(kOpHueSatVal);
  expect_vec(hsv.rv(0), 0, 0.25, 0.5);
}

TEST(NodesMath, RampsAndCurves) {
  // ColorRamp table of 3 entries: black, (1, 0.5, 0, 0.5), white.
  const std::initializer_list<float> ramp = {0, 0, 0, 1, 1, 0.5f, 0, 0.5f, 1, 1, 1, 1};
  Bench r;
  r.f(0.25f).out_v().out_f().params({r.table(ramp), 1}).run(kOpColorRamp);
  expect_vec(r.rv(0), 0.5, 0.25, 0);
  expect_near_rel(r.rf(1), 0.75);
  Bench rc;  // constant: the entry below
  rc.f(0.75f).out_v().out_f().params({rc.table(ramp), 0}).run(kOpColorRamp);
  expect_vec(rc.rv(0), 1, 0.5, 0);
  Bench ro;  // never extrapolated
  ro.f(2.0f).out_v().out_f().params({ro.table(ramp), 1}).run(kOpColorRamp);
  expect_vec(ro.rv(0), 1, 1, 1);
  // Float curve over x in [0, 2]: table y = x^2 at 0, 1, 2 (linear between), extrapolated.
  const std::initializer_list<float> curve = {0, 2, 0, 1, 4};
  Bench fcv;
  fcv.f(1.0f).f(1.5f).out_f().params({fcv.table(curve), 1}).run(kOpFloatCurve);
  expect_near_rel(fcv.rf(0), 2.5);
  Bench fe;  // slope 3 beyond 2: 7 at x = 3; fac 0.5
  fe.f(0.5f).f(3.0f).out_f().params({fe.table(curve), 1}).run(kOpFloatCurve);
  expect_near_rel(fe.rf(0), 0.5 * 3 + 0.5 * 7);
  Bench fb;  // below the range: slope 1 from 0 down
  fb.f(1.0f).f(-1.0f).out_f().params({fb.table(curve), 1}).run(kOpFloatCurve);
  expect_near_rel(fb.rf(0), -1);
  Bench fn;  // held at the end
  fn.f(1.0f).f(3.0f).out_f().params({fn.table(curve), 0}).run(kOpFloatCurve);
  expect_near_rel(fn.rf(0), 4);
  // RGB curves: channel c reads its own column.
  Bench cv;
  cv.f(1.0f).v(Vec3(0.5f, 0.25f, 1)).out_v().params({cv.table({0, 1, 0, 0, 1, 1, 2, 0.5f}), 0}).run(kOpCurves);
  expect_vec(cv.rv(0), 0.5, 0.5, 0.5);
  Bench cr;  // over x in [-1, 1]: identity table, so the output is the input
  cr.f(1.0f).v(Vec3(-0.5f, 0.25f, 0.75f)).out_v().params({cr.table({-1, 1, -1, -1, -1, 1, 1, 1}), 1}).run(kOpCurves);
  expect_vec(cr.rv(0), -0.5, 0.25, 0.75);
}

TEST(NodesMath, MapRangeAndClamp) {
  auto mr = [](MapRangeType t, float v, float fmin, float fmax, float tmin, float tmax, float steps, bool clamp_) {
    Bench b;
    b.f(v).f(fmin).f(fmax).f(tmin).f(tmax).f(steps).out_f().params({static_cast<uint32_t>(t), clamp_}).run(kOpMapRange);
    return b.rf(0);
  };
  using T = MapRangeType;
  expect_near_rel(mr(T::Linear, 0.25f, 0, 1, 10, 20, 4, false), 12.5);
  expect_near_rel(mr(T::Linear, 1.5f, 0, 1, 10, 20, 4, false), 25);
  expect_near_rel(mr(T::Linear, 1.5f, 0, 1, 20, 10, 4, true), 10);
  expect_near_rel(mr(T::Linear, 1.5f, 1, 1, 20, 10, 4, false), 0);    // empty source range
  expect_near_rel(mr(T::Stepped, 0.3f, 0, 1, 0, 1, 4, false), 0.25);  // floor(0.3 * 5) / 4
  expect_near_rel(mr(T::SmoothStep, 0.25f, 0, 1, 0, 1, 0, false), 3 * 0.0625 - 2 * 0.015625);
  expect_near_rel(mr(T::SmoothStep, 0.25f, 1, 0, 0, 1, 0, false), 1 - (3 * 0.0625 - 2 * 0.015625));  // reversed
  double x = 0.25;
  expect_near_rel(mr(T::SmootherStep, 0.25f, 0, 1, 0, 1, 0, false), x * x * x * (x * (6 * x - 15) + 10));
  Bench v;
  v.v(Vec3(0.25f, 2, 0.5f))
      .v(Vec3(0))
      .v(Vec3(1, 1, 0))
      .v(Vec3(0))
      .v(Vec3(2))
      .v(Vec3(4))
      .out_v()
      .params({static_cast<uint32_t>(T::Linear), 1})
      .run(kOpMapRangeVector);
  expect_vec(v.rv(0), 0.5, 2, 0);
  auto cl = [](ClampType t, float v, float lo, float hi) {
    Bench b;
    b.f(v).f(lo).f(hi).out_f().params({static_cast<uint32_t>(t)}).run(kOpClamp);
    return b.rf(0);
  };
  EXPECT_EQ(cl(ClampType::MinMax, 5, 0, 1), 1);
  EXPECT_EQ(cl(ClampType::MinMax, 0.5f, 1, 0), 0);  // min then max: max wins
  EXPECT_EQ(cl(ClampType::Range, 0.5f, 1, 0), 0.5f);
}

TEST(NodesMath, MappingAndRotation) {
  const float h = kPi / 2;
  auto map = [](MappingType t, Vec3 v, Vec3 loc, Vec3 rot, Vec3 s) {
    Bench b;
    b.v(v).v(loc).v(rot).v(s).out_v().params({static_cast<uint32_t>(t)}).run(kOpMapping);
    return b.rv(0);
  };
  // Rotating x by 90 degrees about z gives y.
  expect_vec(map(MappingType::Point, Vec3(1, 0, 0), Vec3(1, 2, 3), Vec3(0, 0, h), Vec3(2)), 1, 4, 3);
  expect_vec(map(MappingType::Vector, Vec3(1, 0, 0), Vec3(1, 2, 3), Vec3(0, 0, h), Vec3(2)), 0, 2, 0);
  // Texture is the inverse of Point.
  expect_vec(map(MappingType::Texture, Vec3(1, 4, 3), Vec3(1, 2, 3), Vec3(0, 0, h), Vec3(2)), 1, 0, 0);
  expect_vec(map(MappingType::Normal, Vec3(0, 0, 3), Vec3(5), Vec3(h, 0, 0), Vec3(1)), 0, -1, 0);
  // XYZ Euler order: x first, then y, then z. (0, 0, 1) about x by 90 -> (0, -1, 0); about z by 90 -> (1, 0, 0).
  expect_vec(euler_rotate(Vec3(h, 0, h), Vec3(0, 0, 1), false), 1, 0, 0);
  auto rot = [](RotateType t, bool inv, Vec3 v, Vec3 center, Vec3 axis, float angle, Vec3 euler) {
    Bench b;
    b.v(v).v(center).v(axis).f(angle).v(euler).out_v().params({static_cast<uint32_t>(t), inv}).run(kOpVectorRotate);
    return b.rv(0);
  };
  expect_vec(rot(RotateType::ZAxis, false, Vec3(2, 0, 0), Vec3(1, 0, 0), Vec3(), h, Vec3()), 1, 1, 0);
  expect_vec(rot(RotateType::ZAxis, true, Vec3(2, 0, 0), Vec3(1, 0, 0), Vec3(), h, Vec3()), 1, -1, 0);
  expect_vec(rot(RotateType::AxisAngle, false, Vec3(0, 1, 0), Vec3(), Vec3(3, 0, 0), h, Vec3()), 0, 0, 1);
  expect_vec(rot(RotateType::AxisAngle, false, Vec3(0, 1, 0), Vec3(), Vec3(), h, Vec3()), 0, 1, 0);  // no axis
  expect_vec(rot(RotateType::XAxis, false, Vec3(0, 1, 0), Vec3(), Vec3(), h, Vec3()), 0, 0, 1);
  expect_vec(rot(RotateType::YAxis, false, Vec3(0, 0, 1), Vec3(), Vec3(), h, Vec3()), 1, 0, 0);
  expect_vec(rot(RotateType::EulerXyz, false, Vec3(0, 0, 1), Vec3(), Vec3(), 0, Vec3(h, 0, h)), 1, 0, 0);
  expect_vec(rot(RotateType::EulerXyz, true, Vec3(1, 0, 0), Vec3(), Vec3(), 0, Vec3(h, 0, h)), 0, 0, 1);
}

TEST(NodesMath, ConvertersAndNormal) {
  Bench sx;
  sx.v(Vec3(1, 2, 3)).out_f().out_f().out_f().run(kOpSeparateXyz);
  EXPECT_EQ(sx.rf(2), 3);
  Bench cx;
  cx.f(1).f(2).f(3).out_v().run(kOpCombineXyz);
  expect_vec(cx.rv(0), 1, 2, 3);
  Bench n;
  n.v(Vec3(0, 0, 2)).v(Vec3(0, 1, 1)).out_v().out_f().run(kOpNormal);
  expect_vec(n.rv(0), 0, 0, 1);
  expect_near_rel(n.rf(1), std::sqrt(0.5));
  // Blackbody: 6500 K is near white in Rec. 709 (the fit's own value there), warmer below.
  Vec3 d65 = blackbody_rgb(6500);
  EXPECT_NEAR(d65.x / d65.z, 1.0, 0.1);
  Vec3 warm = blackbody_rgb(2000);
  EXPECT_GT(warm.x, warm.y);
  EXPECT_GT(warm.y, warm.z);
  expect_vec(blackbody_rgb(20000), 0.8262954810464208, 0.9945080501520986, 1.566307710274283);
  // Wavelength: 380 nm is the first CIE row; outside the table black.
  Vec3 w = wavelength_rgb(380);
  double X = 0.0014, Y = 0.0, Z = 0.0065;
  expect_vec(w, std::max(0.0, (3.2404548 * X - 1.5371389 * Y - 0.4985315 * Z) / 2.52),
             std::max(0.0, (-0.9692664 * X + 1.8760109 * Y + 0.0415561 * Z) / 2.52),
             std::max(0.0, (0.0556434 * X - 0.2040259 * Y + 1.0572252 * Z) / 2.52), 1e-4);
  EXPECT_TRUE(is_black(wavelength_rgb(800)));
  EXPECT_TRUE(is_black(wavelength_rgb(300)));
  Vec3 green = wavelength_rgb(530);
  EXPECT_GT(green.y, green.x);
  EXPECT_GT(green.y, green.z);
}

TEST(NodesMath, SignaturesCoverTheFamily) {
  for (uint32_t op = kFamilyMathBegin; op < kMathFamilyEnd; ++op) {
    const OpSignature* sig = math_family_signature(op);
    ASSERT_NE(sig, nullptr) << op;
    EXPECT_TRUE(sig->pure);
    EXPECT_GT(std::string(sig->out).size(), 0u);
  }
  EXPECT_EQ(math_family_signature(kMathFamilyEnd), nullptr);
  EXPECT_EQ(math_family_signature(kFamilyMathBegin - 1), nullptr);
  EXPECT_EQ(math_family_signature(kFamilyTexturesBegin), nullptr);
}

TEST(NodesMath, UnknownModesAreHarmless) {
  EXPECT_EQ(math(static_cast<MathType>(1000), 1, 2), 0.0f);
  EXPECT_TRUE(is_black(mix(static_cast<MixBlend>(1000), 0.5f, Vec3(1), Vec3(1))));
  Bench b;
  b.v(Vec3(1, 2, 3)).out_f().out_f().out_f().params({77}).run(kOpSeparateColor);
  EXPECT_EQ(b.rf(1), 2.0f);
}

}  // namespace
}  // namespace lt
