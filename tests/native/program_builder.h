// Shader programs as the add-on compiles them (native/src/shading/program.h), for the native tests
// and the fuzz seeds: constants, closures with their weights (one(): weight 1), Mix Shader weights.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "lantern/lantern.h"
#include "shading/inputs.h"
#include "shading/program.h"
#include "shading/shaders.h"
#include "shading/textures.h"

struct Rgb {
  float x, y, z;
};

struct ShaderCode {
  std::vector<uint32_t> code;
  std::vector<float> k;
  int registers = 0;

  uint32_t c1(float v) {
    k.push_back(v);
    return lt::kConstBit | (1u << 24) | uint32_t(k.size() - 1);
  }
  uint32_t c3(Rgb v) {
    k.push_back(v.x);  // three push_backs: GCC 12 warns falsely on inserting an initializer list
    k.push_back(v.y);
    k.push_back(v.z);
    return lt::kConstBit | (3u << 24) | uint32_t(k.size() - 3);
  }
  // Appends an instruction; returns its output operands.
  std::vector<uint32_t> emit(uint32_t op, const std::vector<uint32_t>& in, const std::vector<int>& out_sizes,
                             const std::vector<uint32_t>& params = {}) {
    std::vector<uint32_t> outs;
    for (int size : out_sizes) {
      outs.push_back(uint32_t(size) << 24 | uint32_t(registers));
      registers += size;
    }
    code.push_back(op);
    code.push_back(uint32_t(in.size()) | uint32_t(outs.size()) << 8 | uint32_t(params.size()) << 16);
    code.insert(code.end(), in.begin(), in.end());
    code.insert(code.end(), outs.begin(), outs.end());
    code.insert(code.end(), params.begin(), params.end());
    return outs;
  }
  // A table in the pool (its length first); returns its offset for a 't' param.
  uint32_t table(const std::vector<float>& t) {
    k.push_back(float(t.size()));
    k.insert(k.end(), t.begin(), t.end());
    return uint32_t(k.size() - t.size() - 1);
  }
  // Texture Coordinate's outputs (Generated, Normal, UV, Object, Camera, Window, Reflection);
  // object_table: a world-to-object matrix (12 floats, rows) for Object, or none.
  std::vector<uint32_t> tex_coord(const std::vector<float>& object_table = {}) {
    const uint32_t object = table(object_table), camera = table({});
    return emit(lt::kOpTexCoord, {}, {3, 3, 3, 3, 3, 3, 3}, {object, camera, 0});
  }
  // Environment Texture's colour: projection 0 equirectangular, 1 mirror ball.
  uint32_t environment(uint32_t vector, uint32_t image, uint32_t projection = 0) {
    return emit(lt::kOpEnvironment, {vector}, {3, 1}, {image, 0, projection})[0];
  }
  // Emission (a world's Background) of a colour operand.
  void emit_color(uint32_t weight, uint32_t color, float strength = 1) {
    emit(lt::kOpEmission, {weight, color, c1(strength)}, {});
  }
  lt_shader_program desc() const { return {code.data(), int(code.size()), k.data(), int(k.size()), registers}; }
  uint32_t one() { return c3({1, 1, 1}); }
  void diffuse(uint32_t weight, Rgb color, float roughness = 0) {
    emit(lt::kOpDiffuse, {weight, c3({0, 0, 0}), c3(color), c1(roughness)}, {});
  }
  void glossy(uint32_t weight, Rgb color, float roughness) {
    emit(lt::kOpGlossy, {weight, c3({0, 0, 0}), c3(color), c1(roughness)}, {}, {lt::kDistGGX});
  }
  void glass(uint32_t weight, Rgb color, float roughness, float ior, uint32_t distribution = lt::kDistGGX) {
    emit(lt::kOpGlass, {weight, c3({0, 0, 0}), c3(color), c1(roughness), c1(ior)}, {}, {distribution});
  }
  // Refraction BSDF (distribution kDistSharp, kDistGGX or kDistBeckmann).
  void refraction(uint32_t weight, Rgb color, float roughness, float ior, uint32_t distribution = lt::kDistGGX) {
    emit(lt::kOpRefraction, {weight, c3({0, 0, 0}), c3(color), c1(roughness), c1(ior)}, {}, {distribution});
  }
  void emission(uint32_t weight, Rgb color, float strength) {
    emit(lt::kOpEmission, {weight, c3(color), c1(strength)}, {});
  }
  void transparent(uint32_t weight, Rgb color) { emit(lt::kOpTransparent, {weight, c3(color)}, {}); }
  // Principled BSDF with these inputs and Blender's defaults for the others.
  // normal: its Normal input (world space; zero: the shading point's).
  void principled(uint32_t weight, Rgb base, float metallic, float roughness, float specular = 0.5f,
                  float transmission = 0, float ior = 1.45f, float transmission_roughness = 0, Rgb normal = {0, 0, 0},
                  uint32_t distribution = lt::kDistGGX) {
    const uint32_t z3 = c3({0, 0, 0}), z = c1(0);
    // Operand order of kOpPrincipled (shading/shaders.h).
    emit(lt::kOpPrincipled,
         {weight,
          c3(normal),
          c3(base),
          z,
          c3({1, 0.2f, 0.1f}),
          c3(base),
          c1(1.4f),
          z,
          c1(metallic),
          c1(specular),
          z,
          c1(roughness),
          z,
          z,
          z,
          c1(0.5f),
          z,
          c1(0.03f),
          c1(ior),
          c1(transmission),
          c1(transmission_roughness),
          z3,
          c1(1),
          c1(1),
          z3,
          z3},
         {}, {distribution, 0});
  }
  // The weights Mix Shader hands its two inputs.
  std::pair<uint32_t, uint32_t> mix(uint32_t weight, float fac) {
    auto w = emit(lt::kOpMixWeights, {weight, c1(fac)}, {3, 3});
    return {w[0], w[1]};
  }
};

// A procedural world: a Noise texture of the direction (the Generated output), its colour as the
// Background colour, strength 3.
inline ShaderCode noise_world() {
  ShaderCode p;
  const uint32_t generated = p.tex_coord()[0];
  const std::vector<uint32_t> noise =
      p.emit(lt::kOpTexNoise, {generated, p.c1(0), p.c1(2.5f), p.c1(3), p.c1(0.5f), p.c1(0)}, {1, 3}, {3});
  p.emit_color(p.one(), noise[1], 3);
  return p;
}
