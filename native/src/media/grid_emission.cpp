#include "media/grid_emission.h"

#include <string>

#include "core/error.h"
#include "media/grid_lookup.h"
#include "media/volume_material.h"

namespace lt {

GridEmission::GridEmission(std::vector<std::shared_ptr<const GridData>> grids,
                           std::vector<EmissionComponent> components, const Transform& density_index_to_object)
    : grids_(std::move(grids)), components_(std::move(components)) {
  if (grids_.size() > size_t(kMaxGrids))
    throw InvalidArgument("volume emission reads " + std::to_string(grids_.size()) + " grids; at most " +
                          std::to_string(kMaxGrids) + " are supported");
  const int n = int(grids_.size());
  for (const EmissionComponent& c : components_) {
    for (int g : {c.strength.grid, c.blackbody.grid, c.temperature.grid, c.temperature_attribute})
      if (g < -1 || g >= n) throw InvalidArgument("volume emission: grid index " + std::to_string(g) + " out of range");
    if (!std::isfinite(c.strength.value) || !std::isfinite(c.blackbody.value) || !std::isfinite(c.temperature.value) ||
        !is_finite(c.color) || !is_finite(c.tint))
      throw InvalidArgument("volume emission parameters must be finite");
  }
  for (const auto& g : grids_) {
    if (!g) throw InvalidArgument("volume emission: null grid");
    const Transform t = compose(affine_inverse(g->index_to_object), density_index_to_object);
    to_grid_.push_back(t);
    same_space_.push_back(t.is_identity());
  }
}

size_t GridEmission::memory_bytes() const {
  size_t n = 0;
  for (const auto& g : grids_) n += g->memory_bytes();
  return n + region_.memory_bytes();
}

GridEmission::Lookup::Lookup(const GridEmission& e) : e_(&e) {
  samplers_.reserve(e.grids_.size());
  for (const auto& g : e.grids_) samplers_.emplace_back(*g);
}

GridEmission::Lookup::~Lookup() = default;

Spectrum GridEmission::Lookup::operator()(const Vec3& q) {
  if (e_->has_region_ && !e_->region_.contains(q)) return Spectrum(0.0f);
  float v[kMaxGrids];
  for (size_t g = 0; g < samplers_.size(); ++g) v[g] = samplers_[g](e_->same_space_[g] ? q : e_->to_grid_[g].point(q));
  auto param = [&](const EmissionParam& p) { return p.grid < 0 ? p.value : p.value * v[p.grid]; };
  Spectrum E(0.0f);
  for (const EmissionComponent& c : e_->components_) {
    float T = param(c.temperature);
    if (c.temperature_attribute >= 0) T *= v[c.temperature_attribute];  // >= 0 (GridSampler clamps)
    E += principled_volume_emission(param(c.strength), c.color, param(c.blackbody), c.tint, T);
  }
  return E;
}

}  // namespace lt
