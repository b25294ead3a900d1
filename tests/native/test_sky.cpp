// The Sky Texture (shading/sky.*, kOpTexSky): the Nishita precompute's structure and physics, the
// table the loader builds into a program's pool, and the sun disc the world's map reads. Its
// values against Cycles: tests/blender/test_nodes_textures.py (test_sky) and the nishita_world scene.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "core/error.h"
#include "program_builder.h"
#include "scene/scene.h"
#include "shading/image.h"
#include "shading/nodes_math.h"
#include "shading/sky.h"

namespace lt {
namespace {

uint32_t bits(float f) {
  uint32_t w;
  std::memcpy(&w, &f, sizeof w);
  return w;
}

// A program: the Sky Texture of Texture Coordinate's output `coord` (0: Generated, a world's
// direction) into a Background of strength 1.
ShaderCode sky_program(uint32_t type, const std::vector<float>& settings, int coord = 0) {
  ShaderCode p;
  const std::vector<uint32_t> tc = p.tex_coord();
  std::vector<uint32_t> params = {type};
  for (float s : settings) params.push_back(bits(s));
  params.push_back(0);  // the table: the loader's
  const uint32_t color = p.emit(kOpTexSky, {tc[size_t(coord)]}, {3}, params)[0];
  p.emit_color(p.one(), color);
  return p;
}

Spectrum eval(const Program& prog, const Vec3& dir) {
  ShadingContext c;
  c.N = c.Ng = c.I = dir;
  c.P = c.generated = dir;
  const std::vector<std::unique_ptr<Image>> none;
  return prog.run(c, none, nullptr, nullptr);
}

Vec3 dir_at(float elevation, float azimuth) {
  return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
}

TEST(Sky, NishitaTextureIsMirroredAndDarkWithoutAtmosphere) {
  const std::vector<float> t = sky::nishita_texture(0.3f, 100.0f, 1.0f, 1.0f, 1.0f);
  ASSERT_EQ(t.size(), size_t(sky::kNishitaWidth) * sky::kNishitaHeight * 3);
  for (int y : {0, 40, 127})
    for (int x : {0, 17, 255})
      for (int c = 0; c < 3; ++c) {
        const size_t row = size_t(y) * sky::kNishitaWidth;
        EXPECT_EQ(t[3 * (row + x) + c], t[3 * (row + sky::kNishitaWidth - 1 - x) + c]);
        EXPECT_GT(t[3 * (row + x) + c], 0.0f);
      }
  // Toward the sun (longitude 0: the middle columns) the horizon row is brighter than away from it.
  EXPECT_GT(t[3 * (sky::kNishitaWidth / 2) + 1], t[1]);
  // No air, dust or ozone: nothing scatters.
  for (float v : sky::nishita_texture(0.3f, 100.0f, 0.0f, 0.0f, 0.0f)) EXPECT_EQ(v, 0.0f);
}

TEST(Sky, SunWithoutAtmosphereIsTheSolarSpectrumPerSolidAngle) {
  // With no air or dust the disc's radiance is the top-of-atmosphere irradiance over its solid
  // angle: Y = 20 nm x sum(E(l) ybar(l)) / omega, the same at its bottom and top.
  const float diameter = 0.01f;
  Vec3 bottom, top;
  sky::nishita_sun(0.4f, diameter, 1.0f, 0.0f, 0.0f, &bottom, &top);
  const float omega = 2 * kPi * (1 - std::cos(diameter / 2));
  EXPECT_NEAR(bottom.y * omega, top.y * omega, 1e-3f * top.y * omega);
  // sum(E ybar) x 20 nm of sky_nishita.cpp's irradiance and CIE 1931 ybar at 380, 400, ... 780 nm.
  EXPECT_NEAR(top.y * omega, 184.368f, 0.01f);
  // Through the atmosphere the low edge is redder and darker than the high one.
  sky::nishita_sun(0.02f, diameter, 1.0f, 1.0f, 1.0f, &bottom, &top);
  EXPECT_LT(bottom.y, top.y);
  EXPECT_LT(bottom.z / bottom.x, top.z / top.x);
}

TEST(Sky, ProgramShowsTheSunDiscWithLimbDarkening) {
  // Sun disc on, 0.1 rad across, intensity 2, elevation 0.5, rotation 0.25, altitude 10 m.
  const std::vector<float> s = {1, 0.1f, 2, 0.5f, 0.25f, 10, 1, 1, 1};
  const ShaderCode p = sky_program(sky::kSkyNishita, s);
  const Program prog(p.code, p.k, p.registers, 0);
  // Cycles' node turns the rotation around: the disc is at azimuth (2 pi - rotation) + pi / 2.
  const float azimuth = 2 * kPi - 0.25f + kPi / 2;
  const std::vector<Program::SunDisc> discs = prog.sun_discs();
  ASSERT_EQ(discs.size(), 1u);
  EXPECT_NEAR(dot(discs[0].dir, dir_at(0.5f, azimuth)), 1.0f, 1e-6f);
  EXPECT_FLOAT_EQ(discs[0].half_angle, 0.05f);
  // A sky reading other coordinates (Normal here) has its disc elsewhere: the world ignores it.
  const ShaderCode mapped = sky_program(sky::kSkyNishita, s, 1);
  EXPECT_TRUE(Program(mapped.code, mapped.k, mapped.registers, 0).sun_discs().empty());
  Vec3 bottom, top;
  sky::nishita_sun(0.5f, 0.1f, 10.0f, 1, 1, &bottom, &top);
  const Vec3 centre = xyz_to_rgb((bottom + top) * 0.5f) * 2.0f;
  const Spectrum at_centre = eval(prog, dir_at(0.5f, azimuth));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(at_centre[c], centre[c], 1e-4f * centre[c]);
  // Near the edge, 0.6 darker (limb darkening to 1 - 0.6 at the rim); beyond it the sky, far dimmer.
  const Spectrum near_rim = eval(prog, dir_at(0.5f, azimuth + 0.0499f / std::cos(0.5f)));
  EXPECT_LT(near_rim.y, 0.5f * at_centre.y);
  EXPECT_GT(near_rim.y, 0.3f * at_centre.y);
  const Spectrum sky = eval(prog, dir_at(0.5f, azimuth + 0.06f / std::cos(0.5f)));
  EXPECT_LT(sky.y, 1e-2f * at_centre.y);
  EXPECT_GT(sky.y, 0.0f);
  // Sun disc off: the sky there, and no disc for the world's map.
  std::vector<float> off = s;
  off[0] = 0;
  const ShaderCode q = sky_program(sky::kSkyNishita, off);
  const Program no_disc(q.code, q.k, q.registers, 0);
  EXPECT_TRUE(no_disc.sun_discs().empty());
  EXPECT_LT(eval(no_disc, dir_at(0.5f, azimuth)).y, 1e-2f * at_centre.y);
  // Below the horizon: the horizon fading to black at z = -0.4.
  const Spectrum horizon = eval(no_disc, dir_at(0.0f, 1.0f)), low = eval(no_disc, dir_at(-0.2f, 1.0f));
  EXPECT_GT(horizon.y, low.y);
  EXPECT_GT(low.y, 0.0f);
  EXPECT_EQ(eval(no_disc, dir_at(-0.5f, 1.0f)).y, 0.0f);
}

TEST(Sky, LoaderComputesTheTableWhateverTheProgramSays) {
  // The add-on's table param is overwritten: a program cannot hand the op a table of its own.
  ShaderCode p = sky_program(sky::kSkyNishita, {1, 0.1f, 1, 0.5f, 0, 1, 1, 1, 1});
  p.code[p.code.size() - 1 - 5] = 123456;  // the sky's table word (the Background's 5 words follow)
  EXPECT_NO_THROW(Program(p.code, p.k, p.registers, 0));
  // An unknown type renders Preetham's sky (the op's documented default), finite.
  const ShaderCode odd = sky_program(7, {0.2f, -0.5f, 0.6f, 2.0f, 0, 0, 0, 0, 0});
  const Program odd_prog(odd.code, odd.k, odd.registers, 0);
  const Spectrum v = eval(odd_prog, normalize(Vec3(0.1f, 0.2f, 0.9f)));
  EXPECT_TRUE(std::isfinite(v.x) && v.y > 0.0f);
  // Non-finite settings are refused.
  const ShaderCode bad = sky_program(sky::kSkyNishita, {1, 0.1f, 1, NAN, 0, 1, 1, 1, 1});
  EXPECT_THROW(Program(bad.code, bad.k, bad.registers, 0), InvalidArgument);
}

TEST(Sky, WorldMapFindsASunDiscBetweenItsPixelCentres) {
  // A sun 0.3 degrees across centred on a corner of the 1024 x 512 map's pixels: no pixel centre
  // sees it, yet the map must give it its share of samples (World::build's supersampling).
  const int w = 1024, h = 512;
  const Vec3 sun = equirectangular_to_direction({300.0f / w, 380.0f / h});
  const float elevation = std::asin(sun.z), azimuth = std::atan2(sun.y, sun.x);
  const float size = 0.3f * kPi / 180;
  const ShaderCode p = sky_program(sky::kSkyNishita, {1, size, 1, elevation, 2.5f * kPi - azimuth, 1, 1, 1, 1});
  Scene scene;
  scene.world.set_program(std::make_shared<const Program>(p.code, p.k, p.registers, 0), w);
  scene.world_set = true;
  scene.commit();
  ASSERT_TRUE(scene.world.has_map());
  const Spectrum centre = scene.world.radiance(sun);
  ASSERT_GT(centre.y, 1e3f);   // the disc, not the sky
  for (int i = 0; i < 2; ++i)  // the nearest pixel centres see the sky
    EXPECT_LT(average(scene.world.radiance(equirectangular_to_direction({(300 - i + 0.5f) / w, 380.5f / h}))),
              1e-2f * average(centre));
  // Its share of the world's power, and the fraction of samples landing in it.
  const float omega = 2 * kPi * (1 - std::cos(size / 2));
  const float share = 0.8f * average(centre) * omega / (scene.world.mean() * 4 * kPi);  // limb: 2/3 x 0.6
  ASSERT_GT(share, 0.5f);
  int inside = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    LightSample ls;
    if (world_sample(scene.world, Vec2{(i + 0.5f) / n, std::fmod(i * 0.6180339887f, 1.0f)}, &ls) &&
        dot(ls.wi, sun) > std::cos(size / 2))
      ++inside;
  }
  // Samples fall in the four pixels around the disc with its share, uniformly within them: the
  // disc's part of their solid angle lands in it.
  const float pixels = 4 * (2 * kPi / w) * (kPi / h) * std::sqrt(1 - sun.z * sun.z);
  EXPECT_GT(float(inside) / n, 0.8f * share * omega / pixels);
  EXPECT_GT(world_pdf(scene.world, sun), 1e3f * world_pdf(scene.world, Vec3(0, 0, 1)));
}

// Mean and squared standard error of a sample.
struct Estimate {
  double mean, se2;
};
template <class F>
Estimate estimate(int n, F sample) {
  double s = 0, s2 = 0;
  for (int i = 0; i < n; ++i) {
    const double v = sample();
    s += v;
    s2 += v * v;
  }
  const double m = s / n;
  return {m, std::max(s2 / n - m * m, 0.0) / n};
}

TEST(Sky, WorldSamplingMixesTheSunConeWithoutBias) {
  // world_sample draws the disc's cone or the map, world_pdf gives their mixture: E[L / pdf] over
  // its samples is the integral of L over the sphere, here computed apart: the cone by uniform
  // samples in it, the rest by uniform samples of the sphere (fixed seeds; 4.5 standard errors).
  const float size = 0.02f, elevation = 0.4f;
  const ShaderCode p = sky_program(sky::kSkyNishita, {1, size, 1, elevation, 1.0f, 1, 1, 1, 1});
  Scene scene;
  scene.world.set_program(std::make_shared<const Program>(p.code, p.k, p.registers, 0), 256);
  scene.world_set = true;
  scene.commit();
  const World& w = scene.world;
  ASSERT_GT(w.sun_probability(), 0.2f);
  const Vec3 sun = Program(p.code, p.k, p.registers, 0).sun_discs().at(0).dir;
  const float one_minus_cos = 2 * std::sin(size / 4) * std::sin(size / 4);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  auto u2 = [&] { return Vec2{uni(rng), uni(rng)}; };
  auto lum = [&](const Vec3& d) { return double(average(w.radiance(d))); };
  const int n = 200000;
  const Estimate cone = estimate(n, [&] {
    const float t = uni(rng) * one_minus_cos, phi = 2 * kPi * uni(rng), st = std::sqrt(t * (2 - t));
    return lum(Frame(sun).to_world(Vec3(st * std::cos(phi), st * std::sin(phi), 1 - t))) * 2 * kPi * one_minus_cos;
  });
  const Estimate rest = estimate(n, [&] {
    const Vec3 d = sample_uniform_sphere(u2());
    return 0.5f * length_squared(d - sun) <= one_minus_cos ? 0.0 : lum(d) * 4 * kPi;
  });
  const Estimate sampled = estimate(n, [&] {
    LightSample ls;
    if (!world_sample(w, u2(), &ls)) return 0.0;
    EXPECT_NEAR(ls.pdf, world_pdf(w, ls.wi), 1e-4f * ls.pdf);
    return double(average(ls.radiance)) / ls.pdf;
  });
  const double truth = cone.mean + rest.mean;
  EXPECT_GT(cone.mean, rest.mean);  // the sun dominates
  EXPECT_LT(std::abs(sampled.mean - truth), 4.5 * std::sqrt(cone.se2 + rest.se2 + sampled.se2))
      << sampled.mean << " vs " << truth;
}

TEST(Sky, PreethamFollowsTheSun) {
  const Vec3 sun = normalize(Vec3(0.3f, -0.6f, 0.5f));
  const ShaderCode p = sky_program(sky::kSkyPreetham, {sun.x, sun.y, sun.z, 2.5f, 0, 0, 0, 0, 0});
  const Program prog(p.code, p.k, p.registers, 0);
  EXPECT_TRUE(prog.sun_discs().empty());
  const Spectrum toward = eval(prog, sun), away = eval(prog, normalize(Vec3(-0.3f, 0.6f, 0.5f)));
  EXPECT_GT(toward.y, 2 * away.y);
  EXPECT_GT(away.z, 0.0f);
}

}  // namespace
}  // namespace lt
