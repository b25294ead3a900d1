// OpenVDB loading. The only translation unit that includes OpenVDB (its headers are heavy); grids
// are converted to NanoVDB at load time and sampled through NanoVDB afterwards (media/density_grid.h).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "media/density_grid.h"

namespace lt {

// Reads the float grid `grid_name` from the .vdb file at `path` and converts it to NanoVDB.
// GridData::index_to_object is the grid's (linear) index-to-world transform, index_min/max its
// active voxels' bounding box; the density is taken as zero outside that box widened by one voxel.
// Errors (never a crash):
//   IoError          file missing or unreadable, not a VDB file, truncated or corrupt;
//   InvalidArgument  no grid of that name (the message lists the grids present with their value
//                    types), a grid that is not float, a grid without active voxels, a
//                    non-linear (frustum) transform, or non-finite active values.
GridData load_density_grid(const std::string& path, const std::string& grid_name = "density");
// The float grids `names` of one .vdb file (a Volume object's density and the grids its emission
// reads), each as load_density_grid reads it, in that order; the file is opened once.
std::vector<GridData> load_grids(const std::string& path, const std::vector<std::string>& names);

// (name, value type) of every grid in a .vdb file; throws IoError like load_density_grid.
std::vector<std::pair<std::string, std::string>> list_vdb_grids(const std::string& path);

}  // namespace lt
