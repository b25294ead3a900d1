// The procedural textures (shading/textures.cpp) against Cycles 3.4 renders
// (cycles_texture_reference.h), and their ranges, determinism and continuity.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cycles_texture_reference.h"
#include "program_builder.h"
#include "shading/image.h"
#include "shading/inputs.h"
#include "shading/textures.h"

namespace {

using namespace lt;

int operand_floats(char c) { return c == 'v' ? 3 : 1; }

// Runs one texture instruction on inputs given as flat floats (signature order) and returns the
// outputs flattened the same way. Inputs sit in registers, or in the constant pool when const_pool.
std::vector<float> run(uint32_t op, const std::vector<uint32_t>& params, const float* in, bool const_pool = false) {
  const OpSignature* sig = textures_family_signature(op);
  EXPECT_NE(sig, nullptr);
  EXPECT_EQ(std::strlen(sig->params), params.size());
  std::vector<float> regs(64, NAN), pool(64, NAN);
  std::vector<uint32_t> in_words, out_words;
  int at = 0;
  for (const char* c = sig->in; *c; c++) {
    int n = operand_floats(*c);
    float* dst = const_pool ? pool.data() : regs.data();
    for (int i = 0; i < n; i++) dst[at + i] = in[at + i];
    in_words.push_back(at | (uint32_t)n << 24 | (const_pool ? kConstBit : 0));
    at += n;
  }
  int out_at = 32, out_n = 0;
  for (const char* c = sig->out; *c; c++) {
    int n = operand_floats(*c);
    out_words.push_back(out_at | (uint32_t)n << 24);
    out_at += n;
    out_n += n;
  }
  Machine m{};
  m.r = regs.data();
  m.k = pool.data();
  Instr ins{
      op,           (int)in_words.size(), (int)out_words.size(), (int)params.size(), in_words.data(), out_words.data(),
      params.data()};
  exec_textures_family(ins, m);
  return std::vector<float>(regs.begin() + 32, regs.begin() + 32 + out_n);
}

int input_floats(uint32_t op) {
  int n = 0;
  for (const char* c = textures_family_signature(op)->in; *c; c++) n += operand_floats(*c);
  return n;
}

TEST(Textures, SignaturesCoverTheFamily) {
  EXPECT_EQ(textures_family_signature(kFamilyTexturesBegin - 1), nullptr);
  EXPECT_EQ(textures_family_signature(kTexturesFamilyEnd), nullptr);
  for (uint32_t op = kFamilyTexturesBegin; op < kTexturesFamilyEnd; op++) {
    const OpSignature* s = textures_family_signature(op);
    ASSERT_NE(s, nullptr) << op;
    EXPECT_TRUE(s->pure);
  }
  EXPECT_LE((uint32_t)kTexturesFamilyEnd, 320u);
}

// The hash itself is held to Cycles by the White Noise rows of MatchCyclesRenders (White Noise is
// the hash); here only its basic sanity: deterministic, and every argument matters.
TEST(Textures, HashArgumentsAllMatter) {
  EXPECT_EQ(tex::hash_uint(0), tex::hash_uint(0));
  EXPECT_NE(tex::hash_uint(0), tex::hash_uint(1));
  EXPECT_NE(tex::hash_uint2(1, 2), tex::hash_uint2(2, 1));
  EXPECT_NE(tex::hash_uint3(1, 2, 3), tex::hash_uint3(1, 2, 4));
  EXPECT_NE(tex::hash_uint4(1, 2, 3, 4), tex::hash_uint4(1, 2, 3, 5));
}

// Each row: Cycles' output for one node set-up, rendered through an Emission shader. Cycles runs
// its SSE noise path (a + t (b - a) interpolation) where Lantern runs the scalar one, so values
// agree to float rounding, not bit for bit (4.3e-6 at most, measured).
TEST(Textures, MatchCyclesRenders) {
  int checked = 0;
  for (const auto& c : cycles_ref::kTextureCases) {
    const OpSignature* sig = textures_family_signature(c.op);
    ASSERT_NE(sig, nullptr) << c.label;
    std::vector<uint32_t> params(c.params, c.params + std::strlen(sig->params));
    std::vector<float> got = run(c.op, params, c.in);
    for (size_t i = 0; i < got.size(); i++) {
      float want = c.out[i];
      if (std::isnan(want)) continue;  // an output the mode hides in Blender
      EXPECT_NEAR(got[i], want, 2e-5f + 2e-5f * std::fabs(want)) << c.label << " output float " << i;
    }
    checked++;
  }
  EXPECT_GT(checked, 100);
}

TEST(Textures, ConstantOperandsReadFromThePool) {
  const auto& c = cycles_ref::kTextureCases[0];
  std::vector<uint32_t> params(c.params, c.params + 1);
  EXPECT_EQ(run(c.op, params, c.in, false), run(c.op, params, c.in, true));
}

std::vector<float> noise_inputs(float x, float y, float z, float w) { return {x, y, z, w, 1.7f, 4.0f, 0.5f, 0.0f}; }

TEST(Textures, NoiseRangeDeterminismContinuity) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-50.0f, 50.0f);
  for (uint32_t dims = 1; dims <= 4; dims++) {
    float lo = 1, hi = 0;
    for (int i = 0; i < 2000; i++) {
      std::vector<float> in = noise_inputs(u(rng), u(rng), u(rng), u(rng));
      std::vector<float> a = run(kOpTexNoise, {dims}, in.data());
      EXPECT_EQ(a, run(kOpTexNoise, {dims}, in.data()));
      for (float v : a) {
        ASSERT_TRUE(std::isfinite(v));
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      // Continuity: a step of 1e-4 moves the value by little (the gradient is bounded).
      std::vector<float> in2 = in;
      in2[0] += 1e-4f;
      in2[3] += 1e-4f;
      std::vector<float> b = run(kOpTexNoise, {dims}, in2.data());
      EXPECT_NEAR(a[0], b[0], 0.02f) << dims;
    }
    // Fractal noise sits in [0, 1] and spreads over most of it.
    EXPECT_GE(lo, -0.05f) << dims;
    EXPECT_LE(hi, 1.05f) << dims;
    EXPECT_GT(hi - lo, 0.4f) << dims;
  }
}

TEST(Textures, VoronoiF1IsContinuousAndF2AboveF1) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-20.0f, 20.0f);
  for (uint32_t dims = 1; dims <= 4; dims++) {
    for (int i = 0; i < 300; i++) {
      float in[8] = {u(rng), u(rng), u(rng), u(rng), 1.0f, 1.0f, 1.0f, 1.0f};
      std::vector<float> f1 = run(kOpTexVoronoi, {dims, kVoronoiF1, kVoronoiEuclidean}, in);
      std::vector<float> f2 = run(kOpTexVoronoi, {dims, kVoronoiF2, kVoronoiEuclidean}, in);
      EXPECT_GE(f1[0], 0.0f);
      EXPECT_GE(f2[0], f1[0]);
      float in2[8];
      std::memcpy(in2, in, sizeof(in));
      in2[0] += 1e-4f;
      in2[3] += 1e-4f;
      EXPECT_NEAR(run(kOpTexVoronoi, {dims, kVoronoiF1, kVoronoiEuclidean}, in2)[0], f1[0], 3e-4f);
    }
  }
}

TEST(Textures, WhiteNoiseInUnitRange) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1e3f, 1e3f);
  double sum = 0;
  const int n = 4000;
  for (int i = 0; i < n; i++) {
    float in[4] = {u(rng), u(rng), u(rng), u(rng)};
    std::vector<float> v = run(kOpTexWhiteNoise, {3}, in);
    for (float x : v) {
      EXPECT_GE(x, 0.0f);
      EXPECT_LE(x, 1.0f);
    }
    sum += v[0];
  }
  EXPECT_NEAR(sum / n, 0.5, 0.02);
}

TEST(Textures, UnknownModesDoNotCrash) {
  float in[24] = {0.3f, 0.2f, 0.1f, 0.5f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f,
                  1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f};
  for (uint32_t op = kFamilyTexturesBegin; op < kTexturesFamilyEnd; op++) {
    if (op == kOpTexSky) continue;  // its table exists only through the loader: test_sky.cpp
    std::vector<uint32_t> params(std::strlen(textures_family_signature(op)->params), 7u);
    ASSERT_LE(input_floats(op), 24);
    for (float v : run(op, params, in)) EXPECT_FALSE(std::isnan(v)) << op;
  }
}

// Every Cycles row as a real program (the loader validates the instruction against the signature
// and folds it, its inputs being constant) whose Fac/Value/Distance... drives an Emission: the
// emitted value is the row's first output where it is a float, else the colour.
TEST(Textures, CyclesRowsThroughTheProgramLoader) {
  int checked = 0;
  for (const auto& c : cycles_ref::kTextureCases) {
    const OpSignature* sig = textures_family_signature(c.op);
    ShaderCode p;
    std::vector<uint32_t> ins;
    int at = 0;
    for (const char* t = sig->in; *t; t++) {
      ins.push_back(*t == 'v' ? p.c3({c.in[at], c.in[at + 1], c.in[at + 2]}) : p.c1(c.in[at]));
      at += operand_floats(*t);
    }
    std::vector<int> sizes;
    for (const char* t = sig->out; *t; t++) sizes.push_back(operand_floats(*t));
    std::vector<uint32_t> outs =
        p.emit(c.op, ins, sizes, std::vector<uint32_t>(c.params, c.params + std::strlen(sig->params)));
    // The first output, as a colour.
    uint32_t shown = outs[0];
    Vec3 want{c.out[0], c.out[0], c.out[0]};
    if (sig->out[0] == 'v') {
      want = {c.out[0], c.out[1], c.out[2]};
    } else {
      shown = p.emit(kOpToVector, {outs[0]}, {3})[0];
    }
    if (std::isnan(want.x)) continue;
    p.emit(kOpEmission, {p.one(), shown, p.c1(1.0f)}, {});
    Program prog(p.code, p.k, p.registers, 0);
    ShadingContext ctx{};
    std::vector<std::unique_ptr<Image>> images;
    Spectrum e = prog.run(ctx, images, nullptr, nullptr);
    EXPECT_NEAR(e[0], want.x, 2e-5f + 2e-5f * std::fabs(want.x)) << c.label;
    EXPECT_NEAR(e[2], want.z, 2e-5f + 2e-5f * std::fabs(want.z)) << c.label;
    checked++;
  }
  EXPECT_GT(checked, 100);
}

// A texture fed by a register (the Generated coordinates) is not folded: it runs per shading point.
TEST(Textures, RunsOnRegisterInputs) {
  ShaderCode p;
  p.k.push_back(0);  // an empty table (the shaded object; no camera), at offset 0
  std::vector<uint32_t> tc = p.emit(kOpTexCoord, {}, {3, 3, 3, 3, 3, 3, 3}, {0, 0, 0});
  std::vector<uint32_t> noise =
      p.emit(kOpTexNoise, {tc[0], p.c1(0), p.c1(3.0f), p.c1(2.0f), p.c1(0.5f), p.c1(0)}, {1, 3}, {3});
  p.emit(kOpEmission, {p.one(), noise[1], p.c1(1.0f)}, {});
  Program prog(p.code, p.k, p.registers, 0);
  std::vector<std::unique_ptr<Image>> images;
  for (Vec3 g : {Vec3{0.1f, 0.2f, 0.3f}, Vec3{0.7f, 0.4f, 0.9f}}) {
    ShadingContext ctx{};
    ctx.generated = g;
    Spectrum e = prog.run(ctx, images, nullptr, nullptr);
    float in[8] = {g.x, g.y, g.z, 0, 3.0f, 2.0f, 0.5f, 0};
    std::vector<float> want = run(kOpTexNoise, {3}, in);
    EXPECT_FLOAT_EQ(e[0], want[1]);
    EXPECT_FLOAT_EQ(e[1], want[2]);
    EXPECT_FLOAT_EQ(e[2], want[3]);
  }
}

}  // namespace
