#include "io/vdb.h"

#include <nanovdb/util/OpenToNanoVDB.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <vector>

#include "core/error.h"

namespace lt {

namespace {

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

// OpenVDB reads without checking its stream: from a file cut short it reads past the end and then
// allocates (and clears) what unset length fields say, gigabytes for some cuts, differently from
// run to run; a corrupt length field in a grid's metadata makes it allocate and copy up to 4 GB
// per entry before it fails (fuzz_vdb: 10 GB for a 20 kB file). The header's grid descriptors say
// where each grid's data ends (each descriptor is followed by its grid): a file shorter than that,
// or a length in the file's or a grid's metadata or a grid's transform type that runs past the
// end, is refused before OpenVDB reads it. Parses OpenVDB's File layout of versions 222 to 224
// (io/Archive.cc readHeader, MetaMap::readMeta, GridDescriptor::read, File::readGridDescriptors,
// File::readGridPartial); files of another layout are left to OpenVDB. The grids' compressed
// buffers are OpenVDB's to read (a block size beyond memory is a std::bad_alloc).
void refuse_truncated(const std::string& path) {
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  std::ifstream in(path, std::ios::binary);
  if (ec || !in) return;
  auto read = [&](void* p, size_t n) { return bool(in.read(static_cast<char*>(p), std::streamsize(n))); };
  auto truncated = [&](const std::string& what) {
    throw IoError("cannot read VDB file " + quoted(path) + " (truncated: " + what + ", the file ends at byte " +
                  std::to_string(size) + ")");
  };
  int64_t magic = 0;
  uint32_t version = 0, library[2];
  char offsets = 0, uuid[36];
  if (!read(&magic, 8) || magic != int64_t(openvdb::OPENVDB_MAGIC) || !read(&version, 4) || version < 222 ||
      version > 224 || !read(library, 8) || !read(&offsets, 1) || !offsets || !read(uuid, 36))
    return;
  // From here on every field is the layout's: a read that fails is a read past the end.
  auto skip = [&](uint64_t n) {
    if (uint64_t(in.tellg()) + n > size) truncated("a header field runs past the end");
    in.seekg(std::streamoff(n), std::ios::cur);
  };
  auto u32 = [&] {
    uint32_t v = 0;
    if (!read(&v, 4)) truncated("the header is cut");
    return v;
  };
  auto string = [&] {
    const uint32_t n = u32();
    if (n > size) truncated("the header is cut");  // before allocating what the field says
    std::string v(n, '\0');
    if (!read(v.data(), n)) truncated("the header is cut");
    return v;
  };
  // A metadata map: count, then name, type name, byte count and value per entry. OpenVDB reads a
  // registered fixed-size type (an empty one has a size) by its size, whatever the byte count
  // says; strings, delayed-load data and unknown types by the byte count.
  auto metadata = [&] {
    for (uint32_t i = 0, n = u32(); i < n; ++i) {
      string();
      const std::string type = string();
      const uint32_t bytes = u32();
      const uint32_t fixed =
          openvdb::Metadata::isRegisteredType(type) ? openvdb::Metadata::createMetadata(type)->size() : 0;
      skip(fixed ? fixed : bytes);
    }
  };
  metadata();  // the file's
  const uint32_t grids = u32();
  std::vector<int64_t> starts;
  for (uint32_t i = 0; i < grids; ++i) {
    const std::string name = string();
    string();        // type
    string();        // instance parent
    int64_t pos[3];  // grid, block, end
    if (!read(pos, sizeof(pos))) truncated("the header is cut");
    const std::string shown = quoted(name.substr(0, name.find('\x1e')));  // unique names: name, 0x1e, number
    if (pos[2] < 0 || uint64_t(pos[2]) > size) truncated("grid " + shown + " ends at byte " + std::to_string(pos[2]));
    if (pos[0] < 0 || pos[0] > pos[2]) truncated("grid " + shown + " starts at byte " + std::to_string(pos[0]));
    starts.push_back(pos[0]);
    in.seekg(pos[2]);
  }
  for (int64_t start : starts) {  // each grid: compression flags, metadata, transform type name
    in.seekg(start);
    u32();
    metadata();
    string();
  }
}

// Opens the file without delayed loading (no memory mapping: a file truncated or replaced later
// cannot fault a render) and returns the metadata of all grids.
openvdb::GridPtrVecPtr open_metadata(openvdb::io::File& file, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError("VDB file not found: " + quoted(path));
  if (std::filesystem::is_directory(path, ec)) throw IoError("VDB path is a directory, not a file: " + quoted(path));
  refuse_truncated(path);
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

namespace {

// Reads the float grid `grid_name` of an open file whose metadata is `grids` and converts it to
// NanoVDB (load_grids' checks and errors, one grid).
GridData read_grid(openvdb::io::File& file, const openvdb::GridPtrVec& grids, const std::string& path,
                   const std::string& grid_name) {
  openvdb::GridBase::Ptr meta;
  for (const auto& g : grids)
    if (g->getName() == grid_name) {
      meta = g;
      break;
    }
  if (!meta)
    throw InvalidArgument("VDB file " + quoted(path) + " has no grid named " + quoted(grid_name) +
                          "; grids present: " + grid_list(grids));
  if (!meta->isType<openvdb::FloatGrid>())
    throw InvalidArgument("VDB grid " + quoted(grid_name) + " in " + quoted(path) + " holds " + meta->valueType() +
                          " values; a float grid is required");

  openvdb::FloatGrid::Ptr grid;
  try {
    grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(grid_name));
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

}  // namespace

std::vector<GridData> load_grids(const std::string& path, const std::vector<std::string>& names) {
  init_openvdb();
  openvdb::io::File file(path);
  openvdb::GridPtrVecPtr grids = open_metadata(file, path);
  std::vector<GridData> out;
  for (const std::string& name : names) out.push_back(read_grid(file, *grids, path, name));
  file.close();
  return out;
}

GridData load_density_grid(const std::string& path, const std::string& grid_name) {
  return std::move(load_grids(path, {grid_name}).front());
}

}  // namespace lt
