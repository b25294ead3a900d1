// Writes seed corpora for the fuzz targets (docs/testing.md, "Fuzzing"):
//   make_fuzz_seeds generated DIR   DIR/exr: EXR parts of small renders as fuzz_exr_merge reads them
//                                   (4-byte length, first part, second part); DIR/vdb: small VDB
//                                   files without zip (so that mutations reach OpenVDB's parser
//                                   rather than only the decompressor; inactive values are still
//                                   left out, or a one-voxel file is 160 kB) and one with zip
//   make_fuzz_seeds abi DIR         the ABI seeds kept in tests/fuzz/corpus/abi (abi_stream.h
//                                   programs): rerun when the stream format changes
#include <openvdb/openvdb.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../native/program_builder.h"
#include "abi_stream.h"
#include "lantern/lantern.h"
#include "shading/inputs.h"

namespace fs = std::filesystem;
using lt_fuzz::Op;
using lt_fuzz::Writer;

namespace {

void save(const fs::path& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!f) throw std::runtime_error("cannot write " + path.string());
}

std::vector<uint8_t> load(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void ok(int status, const char* what) {
  if (status != LT_OK) throw std::runtime_error(std::string(what) + ": " + lt_last_error());
}

// ---- ABI seeds: writers mirroring fuzz_abi.cpp's reads, field by field ----------------------

const float kIdentity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

void translation(Writer& w, float x, float y, float z) {
  const float m[12] = {1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z};
  w.floats(m, 12);
}

// A shader program as fuzz_abi.cpp reads it.
void program(Writer& w, const ShaderCode& p) {
  w.u8(uint8_t(p.code.size()));
  for (uint32_t word : p.code) w.u32(word);
  w.u8(uint8_t(p.k.size()));
  w.floats(p.k.data(), int(p.k.size()));
  w.u8(uint8_t((p.registers + 3) / 4));
}

void material(Writer& w, const ShaderCode& p) {
  w.op(lt_fuzz::kAddMaterial);
  program(w, p);
}

ShaderCode diffuse(float r, float g, float b) {
  ShaderCode p;
  p.diffuse(p.one(), {r, g, b});
  return p;
}

ShaderCode emission(float strength) {
  ShaderCode p;
  p.emission(p.one(), {1, 1, 1}, strength);
  return p;
}

ShaderCode transparent() {
  ShaderCode p;
  p.transparent(p.one(), {1, 1, 1});
  return p;
}

// A box [-s, s]^3 around (cx, cy, cz): 8 vertices, 12 triangles, outward winding; parts as the
// stream's bit field (1: corner normals, 2: corner UVs, 4: material slots).
void box(Writer& w, float s, uint8_t parts = 0) {
  static const int kTris[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                   {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  w.op(lt_fuzz::kAddMesh);
  w.u8(8);
  w.u8(12);
  w.u8(parts);
  for (int v = 0; v < 8; ++v) {
    const float p[3] = {(v == 1 || v == 2 || v == 5 || v == 6) ? s : -s,
                        (v == 2 || v == 3 || v == 6 || v == 7) ? s : -s, v >= 4 ? s : -s};
    w.floats(p, 3);
  }
  for (const auto& t : kTris)
    for (int k : t) w.i8(k);
  // Per corner: 12 triangles x 3 corners, 3 floats for a normal, 2 for a UV (fuzz_abi.cpp's reads).
  if (parts & 1)
    for (int c = 0; c < 108; ++c) w.f32(c % 3 == 2 ? 1.0f : 0.0f);
  if (parts & 2)
    for (int c = 0; c < 72; ++c) w.f32(float((c / 2) % 3 == 1) * 0.5f + float(c % 2) * 0.25f);
  if (parts & 4)
    for (int t = 0; t < 12; ++t) w.i8(t % 2);
}

// A square [-s, s]^2 at z = 0, normal +Z.
void quad(Writer& w, float s) {
  w.op(lt_fuzz::kAddMesh);
  w.u8(4);
  w.u8(2);
  w.u8(2);  // UVs
  const float p[12] = {-s, -s, 0, s, -s, 0, s, s, 0, -s, s, 0};
  w.floats(p, 12);
  for (int k : {0, 1, 2, 0, 2, 3}) w.i8(k);
  const float uv[12] = {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1};
  w.floats(uv, 12);
}

void instance(Writer& w, int mesh, std::vector<int> materials, float x = 0, float y = 0, float z = 0) {
  w.op(lt_fuzz::kAddInstance);
  w.i8(mesh);
  translation(w, x, y, z);
  w.u8(uint8_t(materials.size()));
  for (int m : materials) w.i8(m);
  w.u8(LT_VISIBLE_ALL);
}

void light(Writer& w, int type, float power, float x, float y, float z, int shape = 0, float size = 0.5f) {
  w.op(lt_fuzz::kAddLight);
  w.i8(type);
  const float c[3] = {power, power, power};
  w.floats(c, 3);
  translation(w, x, y, z);  // looks down -Z
  w.f32(0.25f);             // radius
  w.f32(1.0f);              // spot size
  w.f32(0.25f);             // spot blend
  w.i8(shape);
  w.f32(size);
  w.f32(size);
  w.f32(0.125f);  // sun angle
  w.u8(LT_VISIBLE_ALL);
  w.f32(1.0f);  // an area light's spread (radians)
}

void camera(Writer& w, int type = LT_CAMERA_PERSPECTIVE) {
  w.op(lt_fuzz::kSetCamera);
  w.i8(type);
  translation(w, 0, 0, 6);  // looks down -Z at the origin
  w.f32(50);
  w.f32(36);
  w.f32(24);
  w.i8(LT_SENSOR_AUTO);
  w.f32(4);  // ortho scale
  w.f32(0);
  w.f32(0);
  w.f32(0.125f);
  w.f32(100);
  w.f32(1);
}

// camera()'s fields as kSetCameraLens, then depth of field (focus 5, F/0.5, 5 blades) and the
// panorama settings (Blender's defaults; type `panorama`).
void camera_lens(Writer& w, int type, bool dof, int panorama) {
  w.op(lt_fuzz::kSetCameraLens);
  w.i8(type);
  translation(w, 0, 0, 6);
  w.f32(50);
  w.f32(36);
  w.f32(24);
  w.i8(LT_SENSOR_AUTO);
  w.f32(4);
  w.f32(0);
  w.f32(0);
  w.f32(0.125f);
  w.f32(100);
  w.f32(1);
  w.u8(dof ? 1 : 0);
  w.f32(5);
  w.f32(0.5f);
  w.i8(5);
  w.f32(0.25f);
  w.f32(1.5f);
  w.i8(panorama);
  w.f32(3.125f);
  w.f32(10.5f);
  w.f32(-1.5f);
  w.f32(1.5f);
  w.f32(-3);
  w.f32(3);
}

void world(Writer& w, float strength, int image = -1) {
  w.op(lt_fuzz::kSetWorld);
  const float c[3] = {0.5f, 0.625f, 0.75f};
  w.floats(c, 3);
  w.f32(strength);
  w.i8(image);
  w.f32(0.5f);
  w.u8(LT_VISIBLE_ALL);
}

void volume_components(Writer& w, float density) {
  w.u8(1);
  w.i8(LT_VOLUME_PRINCIPLED);
  const float color[3] = {0.75f, 0.75f, 0.75f}, absorption[3] = {0.5f, 0.5f, 0.5f}, zero[3] = {0, 0, 0};
  w.floats(color, 3);
  w.f32(density);
  w.floats(absorption, 3);
  w.f32(0.25f);  // anisotropy
  w.f32(0);      // emission strength
  w.floats(zero, 3);
  w.f32(0);  // blackbody
  w.floats(zero, 3);
  w.f32(1000);
}

struct Render {
  int width = 4, height = 4, samples = 2, integrator = LT_INTEGRATOR_PATH;
  int bounces = 4, strategy_depth = 0, volume_bounces = 1, estimator = LT_VOLUME_TRACKING;
  int threads = 1, adaptive = 0;
  float noise_target = 0;
  bool border = false;
};

void render(Writer& w, const Render& r) {
  w.op(lt_fuzz::kRender);
  w.u8(uint8_t(r.width - 1));
  w.u8(uint8_t(r.height - 1));
  w.u8(r.border ? 1 : 0);
  if (r.border)
    for (int b : {1, 3, 0, 2}) w.u8(uint8_t(b));
  w.u8(uint8_t(r.samples - 1));
  w.u8(7);  // seed
  w.u8(0);  // sample offset
  w.u8(uint8_t(r.integrator));
  for (int k = 0; k < 5; ++k) w.u8(uint8_t(r.bounces));
  w.f32(0);
  w.f32(0);
  w.u8(uint8_t(r.threads - 1));
  w.u8(LT_FILTER_BLACKMAN_HARRIS);
  w.f32(1.5f);
  w.u8(0);
  w.u8(uint8_t(r.bounces - 1));  // camera length
  w.u8(uint8_t(r.bounces));      // light length
  w.u8(LT_MIS_POWER);
  w.u8(uint8_t(r.strategy_depth));
  w.u8(uint8_t(r.volume_bounces));
  w.u8(uint8_t(r.estimator));
  w.f32(0);
  w.f32(r.noise_target);
  w.u8(uint8_t(r.adaptive));
  w.u8(0);  // min samples 1
}

// Diffuse box on a floor under a point light, rendered by every integrator.
std::vector<uint8_t> seed_basic() {
  Writer w;
  material(w, diffuse(0.75f, 0.5f, 0.25f));
  material(w, emission(4));
  box(w, 1);
  quad(w, 4);
  instance(w, 0, {0});
  instance(w, 1, {0, 1}, 0, 0, -1);
  light(w, LT_LIGHT_POINT, 100, 2, 2, 4);
  camera(w);
  world(w, 0.5f);
  w.op(lt_fuzz::kCommit);
  Render r;
  render(w, r);
  r.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
  r.strategy_depth = 2;
  r.threads = 2;
  render(w, r);
  r.integrator = LT_INTEGRATOR_VOLPATH;
  r.border = true;
  render(w, r);
  return w.bytes;
}

// The basic scene through a lens with depth of field (PATH and BDPT, whose light tracing samples
// the lens) and through each panorama with depth of field.
std::vector<uint8_t> seed_cameras() {
  Writer w;
  material(w, diffuse(0.75f, 0.5f, 0.25f));
  box(w, 1);
  quad(w, 4);
  instance(w, 0, {0});
  instance(w, 1, {0});
  light(w, LT_LIGHT_POINT, 100, 2, 2, 4);
  camera_lens(w, LT_CAMERA_PERSPECTIVE, true, 0);
  w.op(lt_fuzz::kCommit);
  Render r;
  render(w, r);
  r.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
  render(w, r);
  for (int panorama :
       {LT_PANORAMA_EQUIRECTANGULAR, LT_PANORAMA_FISHEYE_EQUIDISTANT, LT_PANORAMA_FISHEYE_EQUISOLID,
        LT_PANORAMA_MIRRORBALL, LT_PANORAMA_FISHEYE_LENS_POLYNOMIAL, LT_PANORAMA_EQUIANGULAR_CUBEMAP_FACE}) {
    camera_lens(w, LT_CAMERA_PANORAMA, true, panorama);
    render(w, r);
  }
  return w.bytes;
}

// A glowing box of smoke in a thin world volume, by VOLPATH, BDPT and the debug view.
std::vector<uint8_t> seed_volume() {
  Writer w;
  material(w, transparent());
  material(w, diffuse(0.5f, 0.5f, 0.5f));
  w.op(lt_fuzz::kSetMaterialVolume);
  w.i8(0);
  w.u8(1);  // null surface
  volume_components(w, 2);
  w.op(lt_fuzz::kSetWorldVolume);
  volume_components(w, 0.125f);
  box(w, 1);
  quad(w, 4);
  instance(w, 0, {0});
  instance(w, 1, {1}, 0, 0, -1);
  light(w, LT_LIGHT_SPOT, 200, 0, 0, 4);
  camera(w);
  w.op(lt_fuzz::kCommit);
  Render r;
  r.integrator = LT_INTEGRATOR_VOLPATH;
  render(w, r);
  r.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
  render(w, r);
  r.integrator = LT_INTEGRATOR_VOLUME_DEBUG;
  render(w, r);
  return w.bytes;
}

// Textures, every light type, a node tree, and incremental edits between renders.
std::vector<uint8_t> seed_textures_edits() {
  Writer w;
  w.op(lt_fuzz::kAddImage);
  w.u8(3);  // 4 x 4
  w.u8(3);
  w.i8(3);
  for (int i = 0; i < 48; ++i) w.f32(float(i % 5) * 0.25f);
  w.u8(1);  // sRGB
  w.i8(LT_INTERP_LINEAR);
  w.i8(LT_EXTENSION_REPEAT);
  {  // Mix Shader(0.5, Glossy, Glass)
    ShaderCode p;
    auto [a, b] = p.mix(p.one(), 0.5f);
    p.glossy(a, {0.75f, 0.75f, 0.75f}, 0.25f);
    p.glass(b, {1, 1, 1}, 0, 1.5f);
    material(w, p);
  }
  {  // an image texture at the UV (with a folded Math node on its way) into a Diffuse
    ShaderCode p;
    auto uv = p.emit(lt::kOpTexCoord, {}, {3, 3, 3, 3, 3, 3, 3}, {uint32_t(p.k.size()), uint32_t(p.k.size()), 0});
    p.k.push_back(0);  // the two empty tables
    auto tex = p.emit(lt::kOpImage, {uv[2]}, {3, 1}, {0, 0});
    p.emit(lt::kOpDiffuse, {p.one(), p.c3({0, 0, 0}), tex[0], p.c1(0)}, {});
    material(w, p);
  }
  {
    ShaderCode p;
    p.principled(p.one(), {0.5f, 0.25f, 0.125f}, 0.5f, 0.5f, 0.5f);
    material(w, p);
  }
  box(w, 1, 7);
  quad(w, 4);
  instance(w, 0, {0, 2});
  instance(w, 1, {1}, 0, 0, -1);
  light(w, LT_LIGHT_AREA, 50, 0, 0, 3, LT_AREA_DISK);
  light(w, LT_LIGHT_SUN, 2, 0, 0, 5);
  camera(w, LT_CAMERA_ORTHOGRAPHIC);
  {  // a world program: Background(Environment Texture of image 0 along the direction), 16 x 8 map
    w.op(lt_fuzz::kSetWorldProgram);
    w.i8(16);
    w.u8(LT_VISIBLE_ALL);
    ShaderCode p;
    p.emit_color(p.one(), p.environment(p.tex_coord()[0], 0), 2);
    program(w, p);
  }
  w.op(lt_fuzz::kCommit);
  Render r;
  r.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
  render(w, r);
  w.op(lt_fuzz::kSetInstanceTransform);
  w.i8(0);
  translation(w, 0.5f, 0, 0);
  w.op(lt_fuzz::kSetInstanceValues);
  w.i8(0);
  w.u8(LT_VISIBLE_ALL & ~LT_VISIBLE_SHADOW);
  for (float c : {0.2f, 0.4f, 0.8f, 1.0f}) w.f32(c);
  w.i8(3);
  w.i8(1);
  w.i8(5);
  w.i8(6);
  for (int k = 0; k < 8; ++k) w.f32(0.1f * float(k));
  w.op(lt_fuzz::kSetInstanceMotion);  // sliding over the shutter
  w.i8(0);
  w.i8(5);
  for (int k = 0; k < 5; ++k) translation(w, 0.1f * float(k), 0, 0);
  w.op(lt_fuzz::kSetMaterial);
  w.i8(1);
  program(w, emission(2));
  w.op(lt_fuzz::kClearLights);
  light(w, LT_LIGHT_POINT, 20, 1, 1, 3);
  w.op(lt_fuzz::kCommit);
  r.integrator = LT_INTEGRATOR_PATH;
  r.samples = 4;
  r.noise_target = 0.5f;
  r.adaptive = 1;
  render(w, r);
  return w.bytes;
}

void write_abi(const fs::path& dir) {
  fs::create_directories(dir);
  save(dir / "basic", seed_basic());
  save(dir / "volume", seed_volume());
  save(dir / "textures_edits", seed_textures_edits());
  save(dir / "cameras", seed_cameras());
}

// ---- EXR seeds: parts of small renders, as lt_merge_exr reads them ---------------------------

// A diffuse floor under a point light; `integrator`, samples [offset, offset + samples).
std::vector<uint8_t> render_part(const fs::path& path, int integrator, int offset, int samples) {
  lt_scene* scene = nullptr;
  ok(lt_scene_create(&scene), "scene");
  const float pos[12] = {-4, -4, 0, 4, -4, 0, 4, 4, 0, -4, 4, 0};
  const int tris[6] = {0, 1, 2, 0, 2, 3};
  lt_mesh_desc mesh = {pos, 4, tris, 2, nullptr, nullptr, nullptr};
  int mesh_id = 0, mat = 0;
  ok(lt_scene_add_mesh(scene, &mesh, &mesh_id), "mesh");
  const ShaderCode grey = diffuse(0.8f, 0.8f, 0.8f);
  const lt_shader_program grey_desc = grey.desc();
  ok(lt_scene_add_material(scene, &grey_desc, &mat), "material");
  lt_instance_desc inst = {mesh_id, {}, &mat, 1, LT_VISIBLE_ALL};
  std::copy(kIdentity, kIdentity + 12, inst.transform);
  int inst_id = 0;
  ok(lt_scene_add_instance(scene, &inst, &inst_id), "instance");
  lt_light_desc l = {};
  l.type = LT_LIGHT_POINT;
  l.color[0] = l.color[1] = l.color[2] = 100;
  std::copy(kIdentity, kIdentity + 12, l.transform);
  l.transform[11] = 3;
  l.visibility = LT_VISIBLE_ALL;
  ok(lt_scene_add_light(scene, &l), "light");
  lt_camera_desc cam = {};
  cam.type = LT_CAMERA_PERSPECTIVE;
  std::copy(kIdentity, kIdentity + 12, cam.transform);
  cam.transform[11] = 5;
  cam.focal_length = 50, cam.sensor_width = 36, cam.sensor_height = 24, cam.ortho_scale = 1;
  cam.clip_start = 0.1f, cam.clip_end = 100, cam.pixel_aspect = 1;
  ok(lt_scene_set_camera(scene, &cam), "camera");
  ok(lt_scene_commit(scene), "commit");
  lt_render_settings s;
  lt_render_settings_default(&s);
  s.width = s.height = 4;
  s.samples = samples;
  s.sample_offset = offset;
  s.integrator = integrator;
  s.threads = 1;
  lt_render* job = nullptr;
  ok(lt_render_start(scene, &s, &job), "render");
  ok(lt_render_wait(job), "wait");
  const char* attrs[] = {"lantern/scene", "fuzz-seed", nullptr};
  ok(lt_render_write_exr_attributes(job, path.c_str(), attrs), "write exr");
  lt_render_destroy(job);
  lt_scene_destroy(scene);
  std::vector<uint8_t> bytes = load(path);
  fs::remove(path);
  return bytes;
}

std::vector<uint8_t> exr_input(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  std::vector<uint8_t> out(4);
  const uint32_t n = uint32_t(a.size());
  for (int k = 0; k < 4; ++k) out[k] = uint8_t(n >> (8 * k));
  out.insert(out.end(), a.begin(), a.end());
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

void write_exr(const fs::path& dir) {
  fs::create_directories(dir);
  const fs::path tmp = dir / "part.tmp.exr";
  const auto bd0 = render_part(tmp, LT_INTEGRATOR_BIDIRECTIONAL, 0, 1);
  const auto bd1 = render_part(tmp, LT_INTEGRATOR_BIDIRECTIONAL, 1, 2);
  const auto pt0 = render_part(tmp, LT_INTEGRATOR_PATH, 0, 2);
  const auto pt1 = render_part(tmp, LT_INTEGRATOR_PATH, 2, 1);
  save(dir / "bdpt_two_parts", exr_input(bd0, bd1));
  save(dir / "path_two_parts", exr_input(pt0, pt1));
  save(dir / "path_one_part", exr_input(pt0, {}));
}

// ---- VDB seeds ----------------------------------------------------------------------------------

void write_vdb(const fs::path& path, const openvdb::GridPtrVec& grids, uint32_t compression) {
  openvdb::io::File file(path.string());
  file.setCompression(compression);
  file.write(grids);
  file.close();
}

void write_vdbs(const fs::path& dir) {
  fs::create_directories(dir);
  openvdb::initialize();
  auto one = openvdb::FloatGrid::create(0.0f);
  one->setName("density");
  one->tree().setValue(openvdb::Coord(1, 2, 3), 1.5f);
  auto ramp = openvdb::FloatGrid::create(0.0f);
  ramp->setName("density");
  ramp->setTransform(openvdb::math::Transform::createLinearTransform(0.25));
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) ramp->tree().setValue(openvdb::Coord(i, j, k), 0.1f * float(i + j + k));
  auto tile = openvdb::FloatGrid::create(0.0f);
  tile->setName("density");
  tile->tree().addTile(1, openvdb::Coord(0, 0, 0), 0.5f, true);  // an 8^3 tile in a lower node
  auto vec = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  vec->setName("density");
  vec->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));
  auto temperature = one->deepCopy();
  temperature->setName("temperature");
  const uint32_t none = openvdb::io::COMPRESS_ACTIVE_MASK,
                 zip = openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK;
  write_vdb(dir / "one_voxel.vdb", {one}, none);
  write_vdb(dir / "ramp.vdb", {ramp}, none);
  write_vdb(dir / "ramp_zip.vdb", {ramp}, zip);
  write_vdb(dir / "tile.vdb", {tile}, none);
  write_vdb(dir / "vector.vdb", {vec}, none);
  write_vdb(dir / "two_grids.vdb", {temperature, one}, none);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc == 3 ? argv[1] : "";
  try {
    if (mode == "generated") {
      write_exr(fs::path(argv[2]) / "exr");
      write_vdbs(fs::path(argv[2]) / "vdb");
    } else if (mode == "abi") {
      write_abi(argv[2]);
    } else {
      std::fprintf(stderr, "usage: make_fuzz_seeds generated DIR | make_fuzz_seeds abi DIR\n");
      return 2;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
