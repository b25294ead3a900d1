// Procedural textures: the textures family of the shader machine (opcodes 192-319), Cycles 3.4's
// kernel/svm/{noise,fractal_noise,noisetex,voronoi,musgrave,wave,magic,checker,brick,gradient,
// white_noise}.h and util/hash.h reproduced so that patterns match Cycles pixel for pixel.
//
// Every instruction is pure (reads only its inputs) and writes every output it declares; outputs a
// mode does not produce are written as Cycles leaves them (zero). Operands are listed in the order
// the add-on (addon/lantern/export/nodes/textures.py) emits them; "v" is a vec3 operand, "f" a float;
// textures_family_signature (program.h) holds the same shapes for the loader.
// Vector inputs arrive already defaulted by the add-on (Generated coordinates when unlinked, as
// Cycles does; White Noise keeps Cycles' zero vector).
#pragma once

#include <cstdint>

#include "shading/program.h"

namespace lt {

enum TextureOp : uint32_t {
  // Noise. in: vector v, w f, scale f, detail f, roughness f, distortion f; out: fac f, color v;
  // params: dimensions (1-4).
  kOpTexNoise = kFamilyTexturesBegin,
  // Voronoi. in: vector v, w f, scale f, smoothness f, exponent f, randomness f;
  // out: distance f, color v, position v, w f, radius f;
  // params: dimensions (1-4), feature (VoronoiFeature), metric (VoronoiMetric).
  kOpTexVoronoi,
  // Musgrave. in: vector v, w f, scale f, detail f, dimension f, lacunarity f, offset f, gain f;
  // out: fac f; params: dimensions (1-4), type (MusgraveType).
  kOpTexMusgrave,
  // Wave. in: vector v, scale f, distortion f, detail f, detail scale f, detail roughness f, phase f;
  // out: color v, fac f; params: type (0 bands, 1 rings), bands direction (0 X, 1 Y, 2 Z, 3 diagonal),
  // rings direction (0 X, 1 Y, 2 Z, 3 spherical), profile (0 sine, 1 saw, 2 triangle).
  kOpTexWave,
  // Magic. in: vector v, scale f, distortion f; out: color v, fac f; params: depth (0-10).
  kOpTexMagic,
  // Checker. in: vector v, color1 v, color2 v, scale f; out: color v, fac f.
  kOpTexChecker,
  // Brick. in: vector v, color1 v, color2 v, mortar v, scale f, mortar size f, mortar smooth f, bias f,
  // brick width f, row height f; out: color v, fac f;
  // params: offset frequency, squash frequency, offset amount (float bits), squash amount (float bits).
  kOpTexBrick,
  // Gradient. in: vector v; out: color v, fac f; params: type (GradientType).
  kOpTexGradient,
  // White Noise. in: vector v, w f; out: value f, color v; params: dimensions (1-4).
  kOpTexWhiteNoise,
  // Sky (shading/sky.h). in: vector v; out: color v; params: type (sky::SkyType; unknown types and
  // Hosek are Preetham), the node's settings as float bits (sky::kSettings words), table (the
  // loader computes it: prepare_textures_family).
  kOpTexSky,
  kTexturesFamilyEnd,
};

// Cycles' NodeVoronoiFeature / NodeVoronoiDistanceMetric / NodeMusgraveType / NodeGradientType order.
enum VoronoiFeature : uint32_t {
  kVoronoiF1,
  kVoronoiF2,
  kVoronoiSmoothF1,
  kVoronoiDistanceToEdge,
  kVoronoiNSphereRadius
};
enum VoronoiMetric : uint32_t { kVoronoiEuclidean, kVoronoiManhattan, kVoronoiChebychev, kVoronoiMinkowski };
enum MusgraveType : uint32_t {
  kMusgraveMultifractal,
  kMusgraveFbm,
  kMusgraveHybridMultifractal,
  kMusgraveRidgedMultifractal,
  kMusgraveHeteroTerrain,
};
enum GradientType : uint32_t {
  kGradientLinear,
  kGradientQuadratic,
  kGradientEasing,
  kGradientDiagonal,
  kGradientRadial,
  kGradientQuadraticSphere,
  kGradientSpherical,
};

// The Cycles functions themselves, for tests and for other families that need them.
namespace tex {
uint32_t hash_uint(uint32_t kx);
uint32_t hash_uint2(uint32_t kx, uint32_t ky);
uint32_t hash_uint3(uint32_t kx, uint32_t ky, uint32_t kz);
uint32_t hash_uint4(uint32_t kx, uint32_t ky, uint32_t kz, uint32_t kw);
float hash_float_to_float(float k);
float perlin(int dims, const float* p);  // unscaled Perlin noise, dims 1-4
void noise_texture(int dims, const float p[4], float detail, float roughness, float distortion, float* fac,
                   Vec3* color);
}  // namespace tex

}  // namespace lt
