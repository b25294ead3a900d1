#include "io/vdb.h"

#include <openvdb/openvdb.h>
#include <nanovdb/util/OpenToNanoVDB.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>

#include "core/error.h"

namespace lt {

namespace {

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

// Opens the file without delayed loading (no memory mapping: a file truncated or replaced later
// cannot fault a render) and returns the metadata of all grids.
openvdb::GridPtrVecPtr open_metadata(openvdb::io::File& file, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError("VDB file not found: " + quoted(path));
  if (std::filesystem::is_directory(path, ec)) throw IoError("VDB path is a directory, not a file: " + quoted(path));
  try {
    file.open(/*delayLoad=*/false);
    openvdb::GridPtrVecPtr grids = file.readAllGridMetadata();
    // OpenVDB does not check its stream while reading the header: a file cut inside the header
    // "opens" with zero grids. A real VDB file without grids is as useless, so both are errors.
    if (!grids || grids->empty()) throw std::runtime_error("the file contains no grids");
    return grids;
  } catch (const std::exception& e) {
    throw IoError("cannot read VDB file " + quoted(path) + " (corrupt, truncated or not a VDB file): " + e.what());
  }
}

std::string grid_list(const openvdb::GridPtrVec& grids) {
  if (grids.empty()) return "none";
  std::string s;
  for (const auto& g : grids) {
    if (!s.empty()) s += ", ";
    s += quoted(g->getName()) + " (" + g->valueType() + ")";
  }
  return s;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> list_vdb_grids(const std::string& path) {
  init_openvdb();
  openvdb::io::File file(path);
  openvdb::GridPtrVecPtr grids = open_metadata(file, path);
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& g : *grids) out.emplace_back(g->getName(), g->valueType());
  return out;
}

GridData load_density_grid(const std::string& path, const std::string& grid_name) {
  init_openvdb();
  openvdb::io::File file(path);
  openvdb::GridPtrVecPtr grids = open_metadata(file, path);

  openvdb::GridBase::Ptr meta;
  for (const auto& g : *grids)
    if (g->getName() == grid_name) {
      meta = g;
      break;
    }
  if (!meta)
    throw InvalidArgument("VDB file " + quoted(path) + " has no grid named " + quoted(grid_name) +
                          "; grids present: " + grid_list(*grids));
  if (!meta->isType<openvdb::FloatGrid>())
    throw InvalidArgument("VDB grid " + quoted(grid_name) + " in " + quoted(path) + " holds " + meta->valueType() +
                          " values; a float grid is required");

  openvdb::FloatGrid::Ptr grid;
  try {
    grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(grid_name));
    file.close();
  } catch (const std::exception& e) {
    throw IoError("cannot read grid " + quoted(grid_name) + " from VDB file " + quoted(path) +
                  " (corrupt or truncated): " + e.what());
  }
  if (!grid) throw IoError("cannot read grid " + quoted(grid_name) + " from VDB file " + quoted(path));
  if (grid->activeVoxelCount() == 0)
    throw InvalidArgument("VDB grid " + quoted(grid_name) + " in " + quoted(path) + " has no active voxels");
  const openvdb::math::Transform& xf = grid->transform();
  if (!xf.isLinear())
    throw InvalidArgument("VDB grid " + quoted(grid_name) + " in " + quoted(path) +
                          " has a non-linear (frustum) transform, which is not supported");
  for (auto it = grid->cbeginValueOn(); it; ++it)
    if (!std::isfinite(*it)) {
      openvdb::Coord c = it.getCoord();
      throw InvalidArgument("VDB grid " + quoted(grid_name) + " in " + quoted(path) + " has a non-finite value at (" +
                            std::to_string(c.x()) + ", " + std::to_string(c.y()) + ", " + std::to_string(c.z()) + ")");
    }

  GridData out;
  out.name = grid_name;
  // Index -> object: the transform's images of the origin and the unit index vectors (exact for
  // linear maps, whatever OpenVDB's row-vector matrix convention).
  const openvdb::Vec3d origin = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      openvdb::Vec3d e(0, 0, 0);
      e[c] = 1;
      out.index_to_object.m[r * 4 + c] = float(xf.indexToWorld(e)[r] - origin[r]);
    }
    out.index_to_object.m[r * 4 + 3] = float(origin[r]);
  }
  const openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
  // NanoVDB's conversion and the majorant grid compute bounds + 1: voxels at the edge of the int32
  // index space overflow them (fuzz_vdb: a tile moved there by one changed coordinate).
  constexpr int kMaxIndex = 1 << 30;
  for (int a = 0; a < 3; ++a)
    if (bbox.min()[a] < -kMaxIndex || bbox.max()[a] > kMaxIndex)
      throw InvalidArgument("VDB grid " + quoted(grid_name) + " in " + quoted(path) + " has active voxels at index " +
                            std::to_string(bbox.min()[a] < -kMaxIndex ? bbox.min()[a] : bbox.max()[a]) +
                            ", beyond the supported index range [-2^30, 2^30]");
  for (int a = 0; a < 3; ++a) {
    out.index_min[a] = bbox.min()[a];
    out.index_max[a] = bbox.max()[a];
  }
  out.active_voxels = grid->activeVoxelCount();
  out.background = grid->background();

  try {
    auto handle = std::make_shared<nanovdb::GridHandle<nanovdb::HostBuffer>>(
        nanovdb::openToNanoVDB(*grid, nanovdb::StatsMode::Default, nanovdb::ChecksumMode::Disable));
    const nanovdb::FloatGrid* nano = handle->grid<float>();
    if (!nano) throw std::runtime_error("conversion produced no float grid");
    out.nano_grid = nano;
    out.nano_bytes = handle->size();
    out.nano_owner = std::move(handle);
  } catch (const std::exception& e) {
    throw IoError("cannot convert VDB grid " + quoted(grid_name) + " in " + quoted(path) + " to NanoVDB: " + e.what());
  }
  return out;
}

}  // namespace lt
