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

#include "abi_stream.h"
#include "lantern/lantern.h"

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

// One node; inputs other than the given ones are zero constants.
struct Node {
  int type;
  float color[3] = {0, 0, 0};
  int color_image = -1;
  float roughness = 0, fac = 0, metallic = 0, specular = 0, transmission = 0, strength = 0;
  float emission[3] = {0, 0, 0};
  float ior = 1.5f;
  int child[2] = {-1, -1};
};

void input(Writer& w, const float* v3, int image = -1) {
  w.floats(v3, 3);
  w.i8(image);
}
void input(Writer& w, float v) {
  const float v3[3] = {v, 0, 0};
  input(w, v3);
}

void nodes(Writer& w, const std::vector<Node>& v, int root) {
  w.u8(uint8_t(v.size() - 1));
  for (const Node& n : v) {
    w.i8(n.type);
    input(w, n.color, n.color_image);
    input(w, n.roughness);
    input(w, n.fac);
    input(w, n.metallic);
    input(w, n.specular);
    input(w, n.transmission);
    input(w, n.emission);
    input(w, n.strength);
    w.f32(n.ior);
    w.i8(n.child[0]);
    w.i8(n.child[1]);
  }
  w.i8(root);
}

void material(Writer& w, const std::vector<Node>& v, int root = 0) {
  w.op(lt_fuzz::kAddMaterial);
  nodes(w, v, root);
}

Node diffuse(float r, float g, float b) {
  Node n{LT_NODE_DIFFUSE};
  n.color[0] = r, n.color[1] = g, n.color[2] = b;
  return n;
}

Node emission(float strength) {
  Node n{LT_NODE_EMISSION};
  n.color[0] = n.color[1] = n.color[2] = 1;
  n.strength = strength;
  return n;
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
  if (parts & 1)
    for (int c = 0; c < 36; ++c) w.f32(c % 3 == 2 ? 1.0f : 0.0f);
  if (parts & 2)
    for (int c = 0; c < 36; ++c) w.f32(float((c / 2) % 3 == 1) * 0.5f + float(c % 2) * 0.25f);
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
  material(w, {diffuse(0.75f, 0.5f, 0.25f)});
  material(w, {emission(4)});
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

// A glowing box of smoke in a thin world volume, by VOLPATH, BDPT and the debug view.
std::vector<uint8_t> seed_volume() {
  Writer w;
  material(w, {Node{LT_NODE_TRANSPARENT}});
  material(w, {diffuse(0.5f, 0.5f, 0.5f)});
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
  Node tex = diffuse(1, 1, 1);
  tex.color_image = 0;
  Node glossy{LT_NODE_GLOSSY};
  glossy.color[0] = glossy.color[1] = glossy.color[2] = 0.75f;
  glossy.roughness = 0.25f;
  Node glass{LT_NODE_GLASS};
  glass.color[0] = glass.color[1] = glass.color[2] = 1;
  glass.ior = 1.5f;
  Node mix{LT_NODE_MIX};
  mix.fac = 0.5f;
  mix.child[0] = 1, mix.child[1] = 2;
  material(w, {mix, glossy, glass}, 0);
  material(w, {tex});
  Node principled{LT_NODE_PRINCIPLED};
  principled.color[0] = 0.5f, principled.color[1] = 0.25f, principled.color[2] = 0.125f;
  principled.metallic = 0.5f, principled.roughness = 0.5f, principled.specular = 0.5f;
  principled.emission[0] = 1, principled.strength = 0.5f;
  material(w, {principled});
  box(w, 1, 7);
  quad(w, 4);
  instance(w, 0, {0, 2});
  instance(w, 1, {1}, 0, 0, -1);
  light(w, LT_LIGHT_AREA, 50, 0, 0, 3, LT_AREA_DISK);
  light(w, LT_LIGHT_SUN, 2, 0, 0, 5);
  camera(w, LT_CAMERA_ORTHOGRAPHIC);
  world(w, 1, 0);
  w.op(lt_fuzz::kCommit);
  Render r;
  r.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
  render(w, r);
  w.op(lt_fuzz::kSetInstanceTransform);
  w.i8(0);
  translation(w, 0.5f, 0, 0);
  w.op(lt_fuzz::kSetMaterial);
  w.i8(1);
  nodes(w, {emission(2)}, 0);
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
  lt_shader_node n = {};
  n.type = LT_NODE_DIFFUSE;
  n.color.value[0] = n.color.value[1] = n.color.value[2] = 0.8f;
  for (lt_input* in :
       {&n.color, &n.roughness, &n.fac, &n.metallic, &n.specular, &n.transmission, &n.emission, &n.strength})
    in->image = -1;
  n.child[0] = n.child[1] = -1;
  n.ior = 1.45f;
  ok(lt_scene_add_material(scene, &n, 1, 0, &mat), "material");
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
