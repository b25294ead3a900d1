// Shading cost per shading point (issue 13's benchmark): Material::evaluate of a constant
// Principled BSDF, of a 10-node and of a 40-node material, on one thread, at varied points. Run:
//   build/bench/shading_cost --benchmark_min_time=0.5
// The 10-node material is what a textured user material looks like (Texture Coordinate, Mapping,
// Noise, Math, Mix, Hue/Saturation, Principled); the 40-node one adds a second noise and a chain
// of 28 Math nodes (procedural masks as Node Wrangler set-ups grow them).
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "../tests/native/program_builder.h"
#include "shading/inputs.h"
#include "shading/material.h"
#include "shading/nodes_math.h"
#include "shading/textures.h"

namespace {

using lt::kOpMath;

uint32_t math(ShaderCode& p, lt::MathType type, uint32_t a, uint32_t b) {
  return p.emit(kOpMath, {a, b, p.c1(0)}, {1}, {uint32_t(type), 0})[0];
}

// Principled with Base Color and Roughness from operands, the rest constant (Blender's defaults).
void principled(ShaderCode& p, uint32_t base, uint32_t roughness) {
  const uint32_t z3 = p.c3({0, 0, 0}), z = p.c1(0);
  p.emit(lt::kOpPrincipled,
         {p.one(),
          z3,
          base,
          z,
          p.c3({1, 0.2f, 0.1f}),
          p.c3({0.8f, 0.8f, 0.8f}),
          p.c1(1.4f),
          z,
          z,
          p.c1(0.5f),
          z,
          roughness,
          z,
          z,
          z,
          p.c1(0.5f),
          z,
          p.c1(0.03f),
          p.c1(1.45f),
          z,
          z,
          z3,
          p.c1(1),
          p.c1(1),
          z3,
          z3},
         {}, {lt::kDistGGX, 0});
}

ShaderCode constant_material() {
  ShaderCode p;
  principled(p, p.c3({0.8f, 0.5f, 0.3f}), p.c1(0.4f));
  return p;
}

ShaderCode textured_material(int extra_math) {
  ShaderCode p;
  const uint32_t table = uint32_t(p.k.size());
  p.k.push_back(0);  // empty tables: Texture Coordinate of the shaded object, no camera
  auto tc = p.emit(lt::kOpTexCoord, {}, {3, 3, 3, 3, 3, 3, 3}, {table, table, 0});
  auto mapped = p.emit(lt::kOpVectorMath, {tc[3], p.c3({2, 2, 2}), p.c3({0.1f, 0.2f, 0}), p.c1(1)}, {3, 1}, {4})[0];
  auto noise = p.emit(lt::kOpTexNoise, {mapped, p.c1(0), p.c1(5), p.c1(2), p.c1(0.5f), p.c1(0)}, {1, 3}, {3});
  uint32_t mask = math(p, lt::MathType::Multiply, noise[0], p.c1(1.5f));
  if (extra_math > 0) {
    auto noise2 = p.emit(lt::kOpTexNoise, {tc[0], p.c1(0), p.c1(11), p.c1(4), p.c1(0.6f), p.c1(0.2f)}, {1, 3}, {3});
    for (int i = 0; i < extra_math; ++i)
      mask = math(p, i % 3 == 0 ? lt::MathType::Add : (i % 3 == 1 ? lt::MathType::Multiply : lt::MathType::Subtract),
                  mask, i % 2 ? noise2[0] : p.c1(0.1f * float(i % 5)));
  }
  const uint32_t rough = math(p, lt::MathType::Add, math(p, lt::MathType::Multiply, mask, p.c1(0.5f)), p.c1(0.2f));
  auto colour = p.emit(lt::kOpMixColor, {mask, p.c3({0.8f, 0.2f, 0.1f}), noise[1]}, {3}, {0, 1, 0})[0];
  auto tinted = p.emit(lt::kOpHueSatVal, {p.c1(0.55f), p.c1(1.1f), p.c1(1), p.c1(1), colour}, {3})[0];
  principled(p, tinted, rough);
  return p;
}

void run(benchmark::State& state, const ShaderCode& code) {
  const lt::Material material(lt::Program(code.code, code.k, code.registers, 0));
  const std::vector<std::unique_ptr<lt::Image>> images;
  lt::ShadingContext ctx;
  ctx.N = ctx.Ng = lt::Vec3(0, 0, 1);
  ctx.I = lt::normalize(lt::Vec3(0.3f, 0.2f, 1));
  lt::Bsdf bsdf;
  lt::ShadingFrame frame;
  float x = 0;
  for (auto _ : state) {
    x += 0.0137f;
    ctx.P = ctx.object_P = ctx.generated = lt::Vec3(x, 0.5f * x, 0.25f);
    frame.n = ctx.N;
    benchmark::DoNotOptimize(material.evaluate(ctx, images, &bsdf, &frame));
    benchmark::DoNotOptimize(bsdf.count());
  }
  state.counters["instructions"] = double(material.program().instruction_count());
}

void BM_ConstantPrincipled(benchmark::State& state) { run(state, constant_material()); }
void BM_TenNodes(benchmark::State& state) { run(state, textured_material(0)); }
void BM_FortyNodes(benchmark::State& state) { run(state, textured_material(28)); }

BENCHMARK(BM_ConstantPrincipled);
BENCHMARK(BM_TenNodes);
BENCHMARK(BM_FortyNodes);

}  // namespace

BENCHMARK_MAIN();
