// Materials: a flattened shader tree (from Blender's node tree) evaluated at a surface point into
// BSDF lobes and emitted radiance.
#pragma once

#include <memory>
#include <vector>

#include "core/math.h"
#include "shading/bsdf.h"
#include "shading/image.h"

namespace lt {

enum class NodeType : int { Diffuse, Glossy, Glass, Emission, Mix, Add, Principled, Transparent, Count };

struct Input {
  Vec3 value{0.0f};
  int image = -1;
};

struct ShaderNode {
  NodeType type = NodeType::Diffuse;
  Input color, roughness, fac, metallic, specular, transmission, emission, strength;
  float ior = 1.45f;
  int child[2] = {-1, -1};
};

class Material {
 public:
  // Validates the tree (node types, child indices, no cycles, image ids) and throws
  // InvalidArgument with the offending node's index otherwise.
  Material(std::vector<ShaderNode> nodes, int root, size_t image_count);
  // Lantern's (and Cycles') default surface: diffuse grey 0.8.
  static Material default_surface();

  // Fills bsdf with the lobes at a point and returns the emitted radiance there (both sides).
  // backface: the ray arrives from behind the geometric normal (glass uses 1/ior then).
  Spectrum evaluate(const std::vector<std::unique_ptr<Image>>& images, Vec2 uv, bool backface, Bsdf* bsdf) const;
  // Emitted radiance only (for light sampling, without building lobes).
  Spectrum emission(const std::vector<std::unique_ptr<Image>>& images, Vec2 uv) const;
  bool emissive() const { return emissive_; }
  // A rough scalar for how bright the emission is, for picking lights by power.
  float emission_power_estimate() const { return emission_estimate_; }

 private:
  Material() = default;
  template <bool kLobes>
  Spectrum walk(const std::vector<std::unique_ptr<Image>>& images, Vec2 uv, bool backface, Bsdf* bsdf) const;
  std::vector<ShaderNode> nodes_;
  int root_ = 0;
  bool emissive_ = false;
  float emission_estimate_ = 0;
};

}  // namespace lt
