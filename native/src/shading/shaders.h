// The shaders family of the shader machine: closures (Cycles' Shader nodes) and the weights Mix
// Shader hands its inputs. A closure's first input is its weight (Mix Shader factors folded in);
// a Normal input of (0, 0, 0) stands for the unlinked socket: the shading point's normal.
#pragma once

#include "shading/program.h"

namespace lt {

enum ShaderOp : uint32_t {
  kOpEmission = kFamilyShadersBegin + 1,  // in: weight v, color v, strength f
  kOpDiffuse,                             // in: weight v, normal v, color v, roughness f
  kOpGlossy,                              // in: weight v, normal v, color v, roughness f; param: distribution
  kOpGlass,                               // in: weight v, normal v, color v, roughness f, ior f; param: distribution
  kOpTransparent,                         // in: weight v, color v
  // in: weight v, normal v, base color v, subsurface f, subsurface radius v, subsurface color v,
  // subsurface ior f, subsurface anisotropy f, metallic f, specular f, specular tint f,
  // roughness f, anisotropic f, anisotropic rotation f, sheen f, sheen tint f, clearcoat f,
  // clearcoat roughness f, ior f, transmission f, transmission roughness f, emission v,
  // emission strength f, alpha f, clearcoat normal v, tangent v; params: distribution, subsurface method
  kOpPrincipled,
  kOpMixWeights,  // in: weight v, fac f; out: weight * (1 - fac) v, weight * fac v (fac clamped to [0, 1])
  kOpHoldout,     // in: weight v (no lobe: Bsdf::add_holdout; opaque to shadow rays, as Cycles')
  // in: weight v, normal v, color v, roughness f, anisotropy f, rotation f, tangent v; param: distribution
  kOpAnisotropic,
  kOpVelvet,       // in: weight v, normal v, color v, sigma f
  kOpTranslucent,  // in: weight v, normal v, color v
  kOpToon,         // in: weight v, normal v, color v, size f, smooth f; param: component (0 diffuse, 1 glossy)
  // AOV Output (no closure): adds to AOV `index` of ShadingContext::aovs, when set: a value (its
  // first float), or a colour and 1 (Cycles' film_write_aov_pass_value / _color).
  kOpAovValue,  // in: value f; param: index
  kOpAovColor,  // in: color v; param: index
};

// Closures numbered 16-19 of the family.
enum RefractionShaderOp : uint32_t {
  // Refraction BSDF: in: weight v, normal v, color v, roughness f, ior f; param: distribution
  // (Sharp, GGX, Beckmann)
  kOpRefraction = kFamilyShadersBegin + 16,
};

// Subsurface Scattering node (number 22 of the family): in: weight v, normal v, color v, scale f,
// radius v, ior f, anisotropy f; param: falloff (a SubsurfaceMethod, bsdf.h). The Principled
// BSDF's second param is its subsurface_method the same way.
enum SubsurfaceShaderOp : uint32_t {
  kOpSubsurface = kFamilyShadersBegin + 22,
};

// Hair closures (numbers 20-27 of the family): lobes on curves (bsdf_hair.cpp).
enum HairShaderOp : uint32_t {
  // in: weight v, color v, melanin f, melanin redness f, tint v, absorption coefficient v,
  // roughness f, radial roughness f, coat f, ior f, offset f, random color f, random roughness f,
  // random f; params: parametrization (kHairReflectance, kHairMelanin, kHairAbsorption), random
  // linked (0: the curve's Random, as Cycles' ATTR_STD_CURVE_RANDOM, on curves)
  kOpPrincipledHair = kFamilyShadersBegin + 20,
  // in: weight v, color v, offset f, roughness u f, roughness v f, tangent v (zero: unlinked);
  // param: component (0 reflection, 1 transmission)
  kOpHairBsdf,
};
// Principled Hair parametrizations, as Cycles' NodePrincipledHairParametrization.
enum HairParametrization : uint32_t { kHairReflectance = 0, kHairMelanin = 1, kHairAbsorption = 2 };

// Glossy, Glass and Principled distributions (the param), as the node's enum.
enum Distribution : uint32_t {
  kDistSharp = 0,
  kDistGGX = 1,
  kDistBeckmann = 2,
  kDistAshikhminShirley = 3,
  kDistMultiGGX = 4,
};

}  // namespace lt
