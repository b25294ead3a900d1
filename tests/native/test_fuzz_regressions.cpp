// Inputs the fuzz targets (tests/fuzz, docs/testing.md) found, kept as tests: each failed before
// its fix.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "core/error.h"
#include "io/exr.h"
#include "program_builder.h"
#include "scene_builders.h"

namespace {

void write_bytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

void append(std::vector<uint8_t>& out, const std::string& s) {
  out.insert(out.end(), s.begin(), s.end());
  out.push_back(0);
}

void append_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// An empty float grid named "density" (OpenVDB initialised), and writing it uncompressed (its
// values as plain bytes a test can find and change) to path; read back as a string of bytes.
openvdb::FloatGrid::Ptr density_grid() {
  openvdb::initialize();
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  return grid;
}

std::string write_and_read_back(const std::string& path, const openvdb::FloatGrid::Ptr& grid) {
  {
    openvdb::io::File file(path);
    file.setCompression(openvdb::io::COMPRESS_NONE);
    file.write({grid});
    file.close();
  }
  return read_bytes(path);
}

// Adds `path` as a Volume object's density grid through the ABI (scattering, identity transform):
// the status, and in *seconds (optional) the time the call took.
int add_density_vdb(const std::string& path, double* seconds = nullptr) {
  lt_test::ScenePtr s = lt_test::new_scene();
  const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  lt_volume_desc d = lt_test::volume(LT_VOLUME_SCATTER, 1);
  int id = -1;
  const auto start = std::chrono::steady_clock::now();
  const int status = lt_scene_add_volume_grid(s.get(), path.c_str(), "density", identity, 0, 0.001f, 0.0f, &d, 1, &id);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return status;
}

// The file is refused (LT_ERROR_IO, a message containing `expect`) within 0.5 s: before anything
// allocates what a corrupt length says (seconds and gigabytes).
void expect_vdb_refused_at_once(const std::string& path, const std::string& expect) {
  double seconds = 0;
  EXPECT_EQ(add_density_vdb(path, &seconds), LT_ERROR_IO);
  EXPECT_NE(std::string(lt_last_error()).find(expect), std::string::npos) << lt_last_error();
  EXPECT_LT(seconds, 0.5);
}

// An EXR file's start: magic and version 2 (single part, scanlines); the header follows.
std::vector<uint8_t> exr_start() {
  std::vector<uint8_t> bytes;
  append_u32(bytes, 20000630u);
  append_u32(bytes, 2);
  return bytes;
}

// read_exr refuses the file within 0.5 s, saying the attribute `owner` claims 2147483632 bytes.
void expect_exr_owner_refused_at_once(const std::string& path, bool pixels) {
  const auto start = std::chrono::steady_clock::now();
  try {
    lt::read_exr(path, pixels);
    ADD_FAILURE() << "read " << path;
  } catch (const lt::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("header attribute 'owner' claims 2147483632 bytes"), std::string::npos)
        << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 0.5);
}

// A 4 x 4 plane of the material `material` makes, transformed by xf, under a uniform grey world of
// strength `world`, seen from (0, -3, 2); rendered at w x h with `samples` by `integrator`.
lt_test::Passes render_plane(const std::function<int(lt_scene*)>& material, float world, int integrator, int w, int h,
                             int samples, const lt_test::Xform& xf = lt_test::identity()) {
  using namespace lt_test;
  ScenePtr s = new_scene();
  add_object(s.get(), plane(4, 4), material(s.get()), xf);
  set_world(s.get(), {0.5f, 0.5f, 0.5f}, world);
  set_camera(s.get(), perspective_camera(look_at({0, -3, 2}, {0, 0, 0})));
  check(lt_scene_commit(s.get()), "commit");
  lt_render_settings rs = render_settings(w, h, samples);
  rs.integrator = integrator;
  return render(s.get(), rs);
}

}  // namespace

// fuzz_exr_merge: an EXR header attribute whose size field says 2 GB made OpenEXR allocate (and
// clear) 2 GB before it found the file too short: seconds and gigabytes for a 40-byte file.
// fuzz_abi (on CI): a table whose length word was 2e34 was converted to size_t before the bounds
// check, which is undefined behaviour for floats beyond the integer range.
TEST(FuzzRegressions, TableLengthBeyondTheIntegerRangeIsRefused) {
  for (float length : {2.08506e34f, 1e10f, 3.0f, INFINITY, NAN, -1.0f}) {
    ShaderCode c;
    c.tex_coord();
    c.k[0] = length;  // the Object table's length (the pool holds it and the Camera table: 2 floats)
    EXPECT_THROW(lt::Program(c.code, c.k, c.registers, 0), lt::InvalidArgument) << length;
  }
  ShaderCode fine;
  fine.tex_coord();
  EXPECT_NO_THROW(lt::Program(fine.code, fine.k, fine.registers, 0));
}

TEST(FuzzRegressions, ExrAttributeSizeBeyondTheFileIsRefusedBeforeAllocating) {
  lt_test::TempDir dir;
  const std::string path = dir.path + "/huge_attribute.exr";
  std::vector<uint8_t> bytes = exr_start();
  append(bytes, "owner");
  append(bytes, "string");
  append_u32(bytes, 0x7ffffff0u);  // 2 GB
  bytes.insert(bytes.end(), 16, uint8_t('x'));
  write_bytes(path, bytes);
  for (bool pixels : {false, true}) expect_exr_owner_refused_at_once(path, pixels);
  // Through the ABI, as `lantern merge` reads its parts.
  const std::string out = dir.path + "/merged.exr";
  const char* parts[] = {path.c_str()};
  EXPECT_EQ(lt_merge_exr(out.c_str(), parts, 1), LT_ERROR_IO);
  EXPECT_NE(std::string(lt_last_error()).find("claims"), std::string::npos) << lt_last_error();
}

// fuzz_vdb (on CI): a VDB header whose file-metadata name length said 4 GB made Lantern's own
// truncation check (io/vdb.cpp) allocate and clear 4 GB before comparing the length with the
// file's: 7-10 s and 4 GB for a 70-byte file. The length is now checked first.
TEST(FuzzRegressions, VdbHeaderLengthBeyondTheFileIsRefusedBeforeAllocating) {
  lt_test::TempDir dir;
  const std::string path = dir.path + "/huge_name.vdb";
  std::vector<uint8_t> bytes;
  append_u32(bytes, uint32_t(openvdb::OPENVDB_MAGIC));  // int64 magic
  append_u32(bytes, 0);
  append_u32(bytes, 224);  // file format version
  append_u32(bytes, 10);   // library version 10.0
  append_u32(bytes, 0);
  bytes.push_back(1);                           // grid offsets present
  bytes.insert(bytes.end(), 36, uint8_t('0'));  // UUID
  append_u32(bytes, 1);                         // one file metadata entry, whose name length is
  append_u32(bytes, 0xfffffff0u);               // 4 GB
  bytes.insert(bytes.end(), 16, uint8_t('x'));
  write_bytes(path, bytes);
  expect_vdb_refused_at_once(path, "truncated: the header is cut");
}

// fuzz_vdb: a length in a grid's metadata (past the header Lantern checked) that ran past the end
// of the file made OpenVDB allocate and copy it (8-10 GB, 16-20 s) before failing. Each grid's
// metadata is now walked before OpenVDB reads it.
TEST(FuzzRegressions, VdbGridMetadataLengthBeyondTheFileIsRefusedBeforeAllocating) {
  lt_test::TempDir dir;
  const std::string path = dir.path + "/huge_metadata.vdb";
  auto grid = density_grid();
  grid->tree().setValue(openvdb::Coord(1, 2, 3), 1.0f);
  grid->insertMeta("note", openvdb::StringMetadata("#note#"));
  std::string bytes = write_and_read_back(path, grid);
  const size_t at = bytes.find("#note#");
  ASSERT_NE(at, std::string::npos);
  const uint32_t huge = 0xfffffff0u;  // the value's byte count, just before it
  std::memcpy(&bytes[at - 4], &huge, 4);
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  expect_vdb_refused_at_once(path, "runs past the end");
}

// fuzz_exr_merge: a channel list whose size field said more than its channels took. OpenEXR reads
// a channel list to its empty name, whatever the size says, and then read the next bytes as a
// string attribute of 2 GB (1.1-1.5 s, 1.8-2 GB); Lantern's check skipped by the size field and
// saw nothing wrong. The check now walks known types as OpenEXR reads them.
TEST(FuzzRegressions, ExrChannelListShorterThanItsSizeIsWalkedAsOpenExrReadsIt) {
  lt_test::TempDir dir;
  const std::string path = dir.path + "/short_chlist.exr";
  std::vector<uint8_t> bytes = exr_start();
  append(bytes, "channels");
  append(bytes, "chlist");
  append_u32(bytes, 19 + 17);  // the channel's 19 bytes and the next attribute's 17: a walk by size
  append(bytes, "R");          // lands on the end of the header below
  bytes.insert(bytes.end(), 16, 0);
  bytes.push_back(0);  // end of the channel list
  append(bytes, "owner");
  append(bytes, "string");
  append_u32(bytes, 0x7ffffff0u);  // 2 GB
  bytes.push_back(0);              // (end of the header, for a walk by size)
  bytes.insert(bytes.end(), 16, uint8_t('x'));
  write_bytes(path, bytes);
  expect_exr_owner_refused_at_once(path, false);
}

// fuzz_exr_merge: a part with LightTracing.R but not its G and B channels (a renamed channel)
// passed every check and the merge read the missing channels through a null pointer (UBSan; a
// segmentation fault in Release). Such parts are refused.
TEST(FuzzRegressions, MergeRefusesAPartWithOneLightTracingChannel) {
  lt_test::TempDir dir;
  const std::string part = dir.path + "/part.exr", out = dir.path + "/merged.exr";
  std::vector<lt::ExrChannel> channels;
  for (const char* name : {"A", "B", "G", "R", "SampleCount.X", "LightTracing.R"})
    channels.push_back({name, std::vector<float>(4, 1.0f)});
  lt::write_exr(part, 2, 2, channels,
                {{"lantern/samples", "1"}, {"lantern/sample_ranges", "0-1"}, {"lantern/light_paths", "4"}});
  const char* parts[] = {part.c_str()};
  EXPECT_EQ(lt_merge_exr(out.c_str(), parts, 1), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(lt_last_error()).find("1 of the LightTracing R, G and B channels"), std::string::npos)
      << lt_last_error();
}

// fuzz_exr_merge (a local run, 2026-12-06): a light pass with its Colour's three channels but not
// all three of its own (DiffDir.R alone) passed the checks, and the merge divided by reading the
// missing channels' sums at index -1 (UBSan's pointer overflow). Such parts are refused.
TEST(FuzzRegressions, MergeRefusesALightPassMissingSomeOfItsChannels) {
  lt_test::TempDir dir;
  const std::string part = dir.path + "/part.exr", out = dir.path + "/merged.exr";
  std::vector<lt::ExrChannel> channels;
  for (const char* name : {"A", "B", "G", "R", "SampleCount.X", "DiffDir.R", "DiffCol.B", "DiffCol.G", "DiffCol.R"})
    channels.push_back({name, std::vector<float>(4, 1.0f)});
  lt::write_exr(part, 2, 2, channels, {{"lantern/samples", "1"}, {"lantern/sample_ranges", "0-1"}});
  const char* parts[] = {part.c_str()};
  EXPECT_EQ(lt_merge_exr(out.c_str(), parts, 1), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(lt_last_error()).find("DiffDir.R without"), std::string::npos) << lt_last_error();
}

// fuzz_abi: a bidirectional render of a scene without any light (no lamp, no emissive surface, a
// black world) took the s = 1 strategy anyway and picked a light from the empty set: a read
// through a null pointer (UBSan; a segmentation fault in Release builds).
TEST(FuzzRegressions, BidirectionalRenderWithoutLightsIsBlack) {
  using namespace lt_test;
  const Passes p = render_plane(
      [](lt_scene* s) {
        return add_diffuse(s, {0.8f, 0.8f, 0.8f});
      },
      0, LT_INTEGRATOR_BIDIRECTIONAL, 8, 6, 2);
  EXPECT_EQ(p.status.state, LT_STATE_DONE);
  ASSERT_EQ(p.first_non_finite(), "");
  for (size_t i = 0; i < p.combined.size(); i += 4)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(p.combined[i + c], 0.0f);
}

// fuzz_vdb: a VDB whose root tile sits at the edge of the int32 index space (one coordinate
// changed in the file) overflowed `index_max + 1` and `origin + dim - 1` while the majorant grid
// was built (UBSan: signed overflow), and bounds spanning the index space asked for billions of
// majorant cells; NanoVDB's conversion overflows there too. Such a file is refused with
// LT_ERROR_IO and a message.
TEST(FuzzRegressions, VdbTileAtTheEdgeOfTheIndexSpace) {
  lt_test::TempDir dir;
  const std::string path = dir.path + "/edge_tile.vdb";
  auto grid = density_grid();
  grid->tree().addTile(3, openvdb::Coord(0, 0, 0), 1.0f, true);  // 4096^3 root tiles
  grid->tree().addTile(3, openvdb::Coord(4096, 0, 0), 1.0f, true);
  std::string bytes = write_and_read_back(path, grid);
  // A root tile is stored as its origin (3 x int32), value (float) and active flag (1 byte): move
  // the second to x = 2^31 - 4096, the last tile origin whose voxels all fit in int32.
  const std::string tile("\0\x10\0\0\0\0\0\0\0\0\0\0\0\0\x80\x3f\x01", 17);
  const size_t at = bytes.find(tile);
  ASSERT_NE(at, std::string::npos) << "root tile not found in the file";
  const int32_t edge = INT32_MAX - 4095;
  std::memcpy(&bytes[at], &edge, 4);
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));

  EXPECT_EQ(add_density_vdb(path), LT_ERROR_IO);
  EXPECT_NE(std::string(lt_last_error()).find("beyond the supported index range"), std::string::npos)
      << lt_last_error();
}

// fuzz_abi: a Diffuse BSDF of colour 1.7e38 (finite) under BIDIRECTIONAL at 3 samples: the Diffuse
// Color pass's float sum overflowed to infinity (Combined keeps a running mean, the light passes
// sums). The render job checked only a sample's Combined, Albedo and Normal for NaN; now every
// value a sample writes must lie within kMaxSampleValue (1e15), else the sample is dropped and
// counted (lt_render_status::nan_samples), for each integrator.
TEST(FuzzRegressions, ClosureColourNearTheFloatLimitLeavesEveryPassFinite) {
  using namespace lt_test;
  const auto huge = [](lt_scene* s) {
    ShaderCode p;
    p.diffuse(p.one(), {1.7e38f, 0.5f, -3.375f});
    return add_material(s, p);
  };
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL, LT_INTEGRATOR_VOLPATH}) {
    const Passes out = render_plane(huge, 1, integrator, 8, 6, 3);
    EXPECT_EQ(out.status.state, LT_STATE_DONE);
    EXPECT_EQ(out.first_non_finite(), "") << "integrator " << integrator;
    EXPECT_GT(out.status.nan_samples, 0u) << "integrator " << integrator;
  }
}

// fuzz_abi (on CI): an instance sheared by 1e34 (x += 1e34 z; determinant 1, so invertible) took
// the camera's rays into its object space beyond what Embree traverses, and Debian's Embree
// asserts there (RayK::valid()): an abort. Such an instance is now baked into world space (as a
// flattened one); the plane at z = 0 it transforms is the same plane, so it renders as the plain
// one does.
TEST(FuzzRegressions, ExtremeShearRendersAsItsWorldSpaceShape) {
  using namespace lt_test;
  const auto grey = [](lt_scene* s) { return add_diffuse(s, {0.8f, 0.8f, 0.8f}); };
  const auto render_plane_at = [&](const Xform& xf) {
    return render_plane(grey, 1, LT_INTEGRATOR_PATH, 16, 12, 4, xf);
  };
  const Passes plain = render_plane_at(identity());
  Xform shear = identity();
  shear[2] = 1.04657e34f;
  const Passes sheared = render_plane_at(shear);
  ASSERT_EQ(sheared.status.state, LT_STATE_DONE);
  ASSERT_EQ(sheared.first_non_finite(), "");
  double a = 0, b = 0;
  for (size_t i = 0; i < plain.combined.size(); ++i) {
    a += plain.combined[i];
    b += sheared.combined[i];
  }
  EXPECT_GT(a, 0);
  EXPECT_NEAR(b, a, 1e-4 * a);
}
