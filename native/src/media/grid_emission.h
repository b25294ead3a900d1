// The emission of a Volume object whose material reads grids beside its density (Cycles 3.4's
// svm_node_principled_volume with the object's volume attributes: Attribute nodes feeding Emission
// Strength, Blackbody Intensity or Temperature, and the Principled Volume's Temperature Attribute).
// Evaluated per lookup at points of the medium's density index space; each grid keeps its own
// index space (grids of one file may differ in voxel size or offset).
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "core/math.h"
#include "media/density_grid.h"
#include "media/leaf_region.h"

namespace lt {

class GridSampler;  // media/grid_lookup.h

// A parameter: `value`, times the grid's interpolated value at the point when `grid` >= 0.
struct EmissionParam {
  float value = 0;
  int grid = -1;  // index into GridEmission::grids()
};

// One volume component's emission (volume_material.h: principled_volume_emission): strength x
// colour, plus blackbody with T = temperature x max(0, temperature_attribute grid) where given.
struct EmissionComponent {
  EmissionParam strength;
  Spectrum color{0.0f};
  EmissionParam blackbody, temperature;
  int temperature_attribute = -1;
  Spectrum tint{0.0f};
};

class GridEmission {
 public:
  static constexpr int kMaxGrids = 8;

  // density_index_to_object: the density grid's index -> object transform (each grid's own maps
  // density index space to its index space). Throws InvalidArgument for more than kMaxGrids grids,
  // a null grid, a grid index out of range or non-finite parameters.
  GridEmission(std::vector<std::shared_ptr<const GridData>> grids, std::vector<EmissionComponent> components,
               const Transform& density_index_to_object);

  // Confines the emission to `r` (finished, in the density's index space): Cycles' volume mesh
  // (media/leaf_region.h). Without it the emission reaches wherever the medium's domain does.
  void set_region(LeafRegion r) {
    region_ = std::move(r);
    has_region_ = true;
  }
  const LeafRegion* region() const { return has_region_ ? &region_ : nullptr; }

  // Emission per unit length at density index-space points (0 outside the region); holds the
  // grids' accessors, so one per thread and estimator call.
  class Lookup {
   public:
    explicit Lookup(const GridEmission& e);
    ~Lookup();
    Spectrum operator()(const Vec3& q);

   private:
    const GridEmission* e_;
    std::vector<GridSampler> samplers_;
  };

  const std::vector<std::shared_ptr<const GridData>>& grids() const { return grids_; }
  const std::vector<EmissionComponent>& components() const { return components_; }
  size_t memory_bytes() const;

 private:
  std::vector<std::shared_ptr<const GridData>> grids_;
  std::vector<EmissionComponent> components_;
  std::vector<Transform> to_grid_;   // density index -> grid index
  std::vector<uint8_t> same_space_;  // to_grid_ is the identity
  LeafRegion region_;
  bool has_region_ = false;
};

}  // namespace lt
