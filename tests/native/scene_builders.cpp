#include "scene_builders.h"

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <utility>

namespace lt_test {

namespace {

V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 mul(V3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 normalize(V3 a) { return mul(a, 1.0f / std::sqrt(dot(a, a))); }

}  // namespace

int add_material(lt_scene* s, const ShaderCode& p) {
  lt_shader_program d = p.desc();
  int id = -1;
  check(lt_scene_add_material(s, &d, &id), "lt_scene_add_material");
  return id;
}

// ---- transforms ------------------------------------------------------------------------------

Xform identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}; }
Xform translate(V3 t) { return {1, 0, 0, t.x, 0, 1, 0, t.y, 0, 0, 1, t.z}; }
Xform scale(V3 s) { return {s.x, 0, 0, 0, 0, s.y, 0, 0, 0, 0, s.z, 0}; }

Xform rotate(V3 axis, float a) {
  V3 u = normalize(axis);
  float c = std::cos(a), s = std::sin(a), t = 1 - c;
  return {t * u.x * u.x + c,       t * u.x * u.y - s * u.z, t * u.x * u.z + s * u.y, 0,
          t * u.x * u.y + s * u.z, t * u.y * u.y + c,       t * u.y * u.z - s * u.x, 0,
          t * u.x * u.z - s * u.y, t * u.y * u.z + s * u.x, t * u.z * u.z + c,       0};
}

Xform compose(const Xform& a, const Xform& b) {
  Xform r{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      float v = j == 3 ? a[i * 4 + 3] : 0.0f;
      for (int k = 0; k < 3; ++k) v += a[i * 4 + k] * b[k * 4 + j];
      r[i * 4 + j] = v;
    }
  }
  return r;
}

Xform look_at(V3 eye, V3 target, V3 up) {
  V3 back = normalize(sub(eye, target));
  V3 right = cross(up, back);
  if (dot(right, right) < 1e-12f) right = cross(std::abs(back.x) < 0.9f ? V3{1, 0, 0} : V3{0, 1, 0}, back);
  right = normalize(right);
  V3 up2 = cross(back, right);
  return {right.x, up2.x, back.x, eye.x, right.y, up2.y, back.y, eye.y, right.z, up2.z, back.z, eye.z};
}

V3 apply_point(const Xform& m, V3 p) {
  return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
          m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

// ---- meshes ----------------------------------------------------------------------------------

lt_mesh_desc MeshData::desc() const {
  lt_mesh_desc d{};
  d.positions = positions.empty() ? nullptr : positions.data();
  d.vertex_count = vertex_count();
  d.triangles = triangles.empty() ? nullptr : triangles.data();
  d.triangle_count = triangle_count();
  d.corner_normals = corner_normals.empty() ? nullptr : corner_normals.data();
  d.corner_uvs = nullptr;
  d.material_slots = nullptr;
  return d;
}

MeshData box(V3 lo, V3 hi, bool open_top) {
  MeshData m;
  // Four corners per face, counter-clockwise seen from outside.
  const float x0 = lo.x, y0 = lo.y, z0 = lo.z, x1 = hi.x, y1 = hi.y, z1 = hi.z;
  const float faces[6][4][3] = {
      {{x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}},  // -Z
      {{x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}},  // -Y
      {{x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}},  // +X
      {{x1, y1, z0}, {x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}},  // +Y
      {{x0, y1, z0}, {x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}},  // -X
      {{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}},  // +Z
  };
  const int count = open_top ? 5 : 6;
  for (int f = 0; f < count; ++f) {
    int base = m.vertex_count();
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 3; ++k) m.positions.push_back(faces[f][c][k]);
    for (int i : {0, 1, 2, 0, 2, 3}) m.triangles.push_back(base + i);
  }
  return m;
}

MeshData plane(float size_x, float size_y) {
  MeshData m;
  float hx = 0.5f * size_x, hy = 0.5f * size_y;
  m.positions = {-hx, -hy, 0, hx, -hy, 0, hx, hy, 0, -hx, hy, 0};
  m.triangles = {0, 1, 2, 0, 2, 3};
  return m;
}

MeshData icosphere(float radius, int subdivisions) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<V3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                       {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (V3& p : v) p = normalize(p);
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      V3 p = normalize(mul(V3{v[a].x + v[b].x, v[a].y + v[b].y, v[a].z + v[b].z}, 0.5f));
      v.push_back(p);
      mid[key] = int(v.size()) - 1;
      return int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    next.reserve(f.size() * 4);
    for (const auto& tri : f) {
      int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f.swap(next);
  }
  MeshData m;
  for (const V3& p : v) {
    m.positions.push_back(p.x * radius);
    m.positions.push_back(p.y * radius);
    m.positions.push_back(p.z * radius);
  }
  for (const auto& tri : f)
    for (int i : tri) m.triangles.push_back(i);
  return m;
}

MeshData uv_sphere(float radius, int segments, int rings, bool smooth_normals) {
  MeshData m;
  const float pi = 3.14159265358979323846f;
  // Vertex 0: south pole; then (rings - 1) latitude circles of `segments` vertices; north pole.
  auto vertex = [&](float theta, float phi) {
    m.positions.push_back(radius * std::sin(theta) * std::cos(phi));
    m.positions.push_back(radius * std::sin(theta) * std::sin(phi));
    m.positions.push_back(-radius * std::cos(theta));
  };
  vertex(0, 0);
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) vertex(pi * r / rings, 2 * pi * s / segments);
  vertex(pi, 0);
  const int north = m.vertex_count() - 1;
  auto ring_vertex = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) {
    m.triangles.insert(m.triangles.end(), {0, ring_vertex(1, s + 1), ring_vertex(1, s)});
    for (int r = 1; r < rings - 1; ++r) {
      int a = ring_vertex(r, s), b = ring_vertex(r, s + 1), c = ring_vertex(r + 1, s + 1), d = ring_vertex(r + 1, s);
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
    }
    m.triangles.insert(m.triangles.end(), {ring_vertex(rings - 1, s), ring_vertex(rings - 1, s + 1), north});
  }
  if (smooth_normals) {
    for (int i : m.triangles) {
      V3 n = normalize(V3{m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]});
      m.corner_normals.insert(m.corner_normals.end(), {n.x, n.y, n.z});
    }
  }
  return m;
}

void flip_winding(MeshData& m) {
  for (size_t t = 0; t + 2 < m.triangles.size(); t += 3) std::swap(m.triangles[t + 1], m.triangles[t + 2]);
  for (size_t t = 0; t + 8 < m.corner_normals.size(); t += 9)
    for (int k = 0; k < 3; ++k) std::swap(m.corner_normals[t + 3 + k], m.corner_normals[t + 6 + k]);
  for (float& n : m.corner_normals) n = -n;
}

void transform_mesh(MeshData& m, const Xform& xf) {
  for (size_t i = 0; i + 2 < m.positions.size(); i += 3) {
    V3 p = apply_point(xf, {m.positions[i], m.positions[i + 1], m.positions[i + 2]});
    m.positions[i] = p.x;
    m.positions[i + 1] = p.y;
    m.positions[i + 2] = p.z;
  }
  m.corner_normals.clear();  // callers needing normals under non-rigid transforms rebuild them
}

void append(MeshData& dst, const MeshData& src) {
  const int base = dst.vertex_count();
  const bool normals = !dst.corner_normals.empty() || dst.triangles.empty();
  dst.positions.insert(dst.positions.end(), src.positions.begin(), src.positions.end());
  for (int i : src.triangles) dst.triangles.push_back(base + i);
  if (normals && !src.corner_normals.empty())
    dst.corner_normals.insert(dst.corner_normals.end(), src.corner_normals.begin(), src.corner_normals.end());
  else
    dst.corner_normals.clear();
}

// ---- scene -----------------------------------------------------------------------------------

void check(int status, const char* what) {
  if (status != LT_OK) throw std::runtime_error(std::string(what) + ": " + lt_last_error());
}

ScenePtr new_scene() {
  lt_scene* s = nullptr;
  check(lt_scene_create(&s), "lt_scene_create");
  return ScenePtr(s);
}

int add_diffuse(lt_scene* s, V3 color, float roughness) {
  ShaderCode p;
  p.diffuse(p.one(), {color.x, color.y, color.z}, roughness);
  return add_material(s, p);
}

int add_glossy(lt_scene* s, V3 color, float roughness) {
  ShaderCode p;
  p.glossy(p.one(), {color.x, color.y, color.z}, roughness);
  return add_material(s, p);
}

int add_emission(lt_scene* s, V3 color, float strength) {
  ShaderCode p;
  p.emission(p.one(), {color.x, color.y, color.z}, strength);
  return add_material(s, p);
}

int add_glass(lt_scene* s, V3 color, float roughness, float ior) {
  ShaderCode p;
  p.glass(p.one(), {color.x, color.y, color.z}, roughness, ior);
  return add_material(s, p);
}

int add_mesh(lt_scene* s, const MeshData& m) {
  lt_mesh_desc d = m.desc();
  int id = -1;
  check(lt_scene_add_mesh(s, &d, &id), "lt_scene_add_mesh");
  return id;
}

int add_instance(lt_scene* s, int mesh, int material, const Xform& xf, unsigned visibility, int lightgroup,
                 bool shadow_catcher) {
  lt_instance_desc d{};
  d.mesh = mesh;
  std::copy(xf.begin(), xf.end(), d.transform);
  d.materials = &material;
  d.material_count = 1;
  d.visibility = visibility;
  d.lightgroup = lightgroup;
  d.shadow_catcher = shadow_catcher;
  int id = -1;
  check(lt_scene_add_instance(s, &d, &id), "lt_scene_add_instance");
  return id;
}

int add_object(lt_scene* s, const MeshData& m, int material, const Xform& xf, unsigned visibility,
               bool shadow_catcher) {
  return add_instance(s, add_mesh(s, m), material, xf, visibility, 0, shadow_catcher);
}

lt_camera_desc perspective_camera(const Xform& xf, float focal_mm, float sensor_mm) {
  lt_camera_desc c{};
  c.type = LT_CAMERA_PERSPECTIVE;
  std::copy(xf.begin(), xf.end(), c.transform);
  c.focal_length = focal_mm;
  c.sensor_width = sensor_mm;
  c.sensor_height = sensor_mm * 2.0f / 3.0f;  // Blender's default 36 x 24
  c.sensor_fit = LT_SENSOR_AUTO;
  c.ortho_scale = 1;
  c.clip_start = 1e-3f;
  c.clip_end = 1e4f;
  c.pixel_aspect = 1;
  return c;
}

lt_camera_desc orthographic_camera(const Xform& xf, float ortho_scale) {
  lt_camera_desc c = perspective_camera(xf);
  c.type = LT_CAMERA_ORTHOGRAPHIC;
  c.ortho_scale = ortho_scale;
  c.clip_start = 0;
  return c;
}

lt_camera_desc panorama_camera(const Xform& xf, int panorama_type) {
  lt_camera_desc c = perspective_camera(xf);
  c.type = LT_CAMERA_PANORAMA;
  c.panorama_type = panorama_type;
  c.fisheye_fov = float(M_PI);
  c.fisheye_lens = 10.5f;
  c.latitude_min = -float(M_PI / 2);
  c.latitude_max = float(M_PI / 2);
  c.longitude_min = -float(M_PI);
  c.longitude_max = float(M_PI);
  // Cycles' default lens polynomial (a 50 mm lens on a 36 mm sensor).
  const float k[5] = {-1.1735143712967577e-05f, -0.019988736953434998f, -3.3525322965709175e-06f,
                      3.099275275886036e-06f, -2.6064646454854524e-08f};
  std::copy(k, k + 5, c.fisheye_polynomial);
  return c;
}

lt_camera_desc with_dof(lt_camera_desc c, float focus_distance, float fstop, int blades, float rotation, float ratio) {
  c.use_dof = 1;
  c.focus_distance = focus_distance;
  c.aperture_fstop = fstop;
  c.aperture_blades = blades;
  c.aperture_rotation = rotation;
  c.aperture_ratio = ratio;
  return c;
}

void set_camera(lt_scene* s, const lt_camera_desc& c) { check(lt_scene_set_camera(s, &c), "lt_scene_set_camera"); }

lt_world_desc world(V3 color, float strength) {
  lt_world_desc w{};
  w.color[0] = color.x;
  w.color[1] = color.y;
  w.color[2] = color.z;
  w.strength = strength;
  w.image = -1;
  w.rotation_z = 0;
  w.visibility = LT_VISIBLE_ALL;
  return w;
}

void set_world(lt_scene* s, V3 color, float strength) {
  lt_world_desc w = world(color, strength);
  check(lt_scene_set_world(s, &w), "lt_scene_set_world");
}

lt_light_desc light(int type, V3 color, const Xform& xf) {
  lt_light_desc l{};
  l.type = type;
  l.color[0] = color.x;
  l.color[1] = color.y;
  l.color[2] = color.z;
  std::copy(xf.begin(), xf.end(), l.transform);
  l.spot_size = 0.785398163f;  // Blender's default 45 degrees
  l.spot_blend = 0.15f;
  l.shape = LT_AREA_SQUARE;
  l.size_x = l.size_y = 1;
  l.visibility = LT_VISIBLE_ALL & ~unsigned(LT_VISIBLE_CAMERA);  // as lights made through Python
  return l;
}

lt_volume_desc volume(int node, float density, float color, float g) {
  lt_volume_desc d{};
  d.node = node;
  d.color[0] = d.color[1] = d.color[2] = color;
  d.density = density;
  d.anisotropy = g;
  return d;
}

int add_volume_material(lt_scene* s, const lt_volume_desc& d) { return add_volume_material(s, &d, 1); }

int add_volume_material(lt_scene* s, const lt_volume_desc* components, int count) {
  ShaderCode p;
  p.transparent(p.one(), {1, 1, 1});
  int id = add_material(s, p);
  check(lt_scene_set_material_volume(s, id, components, count, 1), "set_material_volume");
  return id;
}

lt_light_desc point_light(V3 position, float watts) {
  return light(LT_LIGHT_POINT, {watts, watts, watts}, translate(position));
}

lt_light_desc spot_light(V3 position, V3 target, float watts, float size_radians, float blend) {
  lt_light_desc l = light(LT_LIGHT_SPOT, {watts, watts, watts}, look_at(position, target));
  l.spot_size = size_radians;
  l.spot_blend = blend;
  return l;
}

lt_light_desc sun_light(V3 dir, float strength, float angle_radians) {
  // The sun shines along its local -Z: place a frame looking along `dir`.
  lt_light_desc l = light(LT_LIGHT_SUN, {strength, strength, strength}, look_at({0, 0, 0}, dir));
  l.angle = angle_radians;
  return l;
}

lt_light_desc area_light(int shape, float size_x, float size_y, const Xform& xf, float watts) {
  lt_light_desc l = light(LT_LIGHT_AREA, {watts, watts, watts}, xf);
  l.shape = shape;
  l.size_x = size_x;
  l.size_y = size_y;
  return l;
}

void add_light(lt_scene* s, const lt_light_desc& l) { check(lt_scene_add_light(s, &l), "lt_scene_add_light"); }

lt_render_settings volpath_settings(int width, int height, int samples, unsigned seed) {
  lt_render_settings r = render_settings(width, height, samples, seed);
  r.integrator = LT_INTEGRATOR_VOLPATH;
  return r;
}

lt_render_settings render_settings(int width, int height, int samples, unsigned seed) {
  lt_render_settings r;
  lt_render_settings_default(&r);
  r.width = width;
  r.height = height;
  r.samples = samples;
  r.seed = seed;
  return r;
}

// ---- rendering -------------------------------------------------------------------------------

std::string Passes::first_non_finite() const {
  const std::pair<const char*, const std::vector<float>*> all[] = {{"Combined", &combined},
                                                                   {"Depth", &depth},
                                                                   {"Normal", &normal},
                                                                   {"Albedo", &albedo},
                                                                   {"Variance", &variance},
                                                                   {"SampleCount", &sample_count},
                                                                   {"Noisy Image", &noisy},
                                                                   {"Denoising Normal", &denoising_normal},
                                                                   {"Denoising Albedo", &denoising_albedo},
                                                                   {"Denoising Depth", &denoising_depth}};
  for (const auto& [name, v] : all)
    for (float x : *v)
      if (!std::isfinite(x)) return name;
  for (int p = LT_PASS_DIFFUSE_DIRECT; p < LT_PASS_COUNT; ++p)
    for (float x : pass(p))
      if (!std::isfinite(x)) return "pass " + std::to_string(p);
  return "";
}

Passes read_passes(lt_render* r, int width, int height) {
  Passes p;
  p.width = width;
  p.height = height;
  const size_t n = size_t(width) * height;
  std::vector<float>* bufs[] = {&p.combined,         &p.depth,          &p.normal, &p.albedo,
                                &p.variance,         &p.sample_count,   &p.noisy,  &p.denoising_normal,
                                &p.denoising_albedo, &p.denoising_depth};
  static_assert(sizeof bufs / sizeof bufs[0] == LT_PASS_DIFFUSE_DIRECT, "one buffer per pass");
  for (int pass = 0; pass < LT_PASS_COUNT; ++pass) {
    std::vector<float>* buf = pass < LT_PASS_DIFFUSE_DIRECT ? bufs[pass] : &p.more[pass - LT_PASS_DIFFUSE_DIRECT];
    buf->assign(n * lt_pass_channels(pass), 0.0f);
    const int status = lt_render_read_pass(r, pass, buf->data(), buf->size());
    if (pass >= LT_PASS_DIFFUSE_DIRECT && status == LT_ERROR_STATE)
      buf->clear();  // a light or data pass the render does not keep
    else
      check(status, "lt_render_read_pass");
  }
  check(lt_render_poll(r, &p.status), "lt_render_poll");
  return p;
}

Passes render(lt_scene* s, const lt_render_settings& settings) {
  lt_render* raw = nullptr;
  check(lt_render_start(s, &settings, &raw), "lt_render_start");
  RenderPtr r(raw);
  check(lt_render_wait(r.get()), "lt_render_wait");
  const bool full =
      settings.border[0] == 0 && settings.border[1] == 0 && settings.border[2] == 0 && settings.border[3] == 0;
  const int w = full ? settings.width : settings.border[1] - settings.border[0];
  const int h = full ? settings.height : settings.border[3] - settings.border[2];
  return read_passes(r.get(), w, h);
}

RegionStats region_stats(const Passes& p, int c, int x0, int x1, int y0, int y1) {
  RegionStats st;
  double sum = 0, var = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      sum += p.rgba(x, y)[c];
      var += p.var(x, y)[c];
      ++st.pixels;
    }
  if (st.pixels) {
    st.mean = sum / st.pixels;
    st.standard_error = std::sqrt(var) / st.pixels;
  }
  return st;
}

std::string differing_tiles(const Passes& a, const Passes& b, int tile, double z) {
  std::string report;
  for (int ty = 0; ty < a.height / tile; ++ty)
    for (int tx = 0; tx < a.width / tile; ++tx)
      for (int c = 0; c < 3; ++c) {
        RegionStats ra = region_stats(a, c, tx * tile, (tx + 1) * tile, ty * tile, (ty + 1) * tile);
        RegionStats rb = region_stats(b, c, tx * tile, (tx + 1) * tile, ty * tile, (ty + 1) * tile);
        double se = std::hypot(ra.standard_error, rb.standard_error);
        if (std::abs(ra.mean - rb.mean) > z * se + 1e-6)
          report += "tile " + std::to_string(tx) + "," + std::to_string(ty) + " channel " + std::to_string(c) + ": " +
                    std::to_string(ra.mean) + " vs " + std::to_string(rb.mean) + " (" + std::to_string(z) +
                    " se = " + std::to_string(z * se) + ")\n";
      }
  return report;
}

TempDir::TempDir() {
  const char* base = std::getenv("TMPDIR");
  std::string tmpl = std::string(base && *base ? base : "/tmp") + "/lantern_test_XXXXXX";
  std::vector<char> buf(tmpl.begin(), tmpl.end());
  buf.push_back('\0');
  if (!mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed for " + tmpl);
  path = buf.data();
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path, ec);
}

// A scene that exercises most of the path tracer: diffuse, glossy, glass and emissive surfaces, an
// area light, a soft point light, a sun and the world; with fog, a fog box around the glossy sphere.
ScenePtr varied_scene(bool fog) {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  int floor = add_diffuse(s, {0.7f, 0.6f, 0.5f});
  add_object(s, plane(20, 20), floor);
  add_object(s, box({-1.5f, -0.5f, 0}, {-0.5f, 0.5f, 1}), add_diffuse(s, {0.2f, 0.5f, 0.8f}, 0.5f));

  const int glossy_id = add_glossy(s, {0.9f, 0.9f, 0.9f}, 0.3f);
  add_object(s, icosphere(0.5f, 3), glossy_id, translate({0.3f, 0, 0.5f}));
  if (fog)
    add_object(s, box({-0.5f, -0.8f, 0.01f}, {1.1f, 0.8f, 1.2f}),
               add_volume_material(s, volume(LT_VOLUME_PRINCIPLED, 1.5f, 0.8f, 0.3f)));

  const int glass_id = add_glass(s, {1, 1, 1}, 0, 1.5f);
  add_object(s, uv_sphere(0.4f, 24, 12, true), glass_id, translate({1.3f, -0.3f, 0.4f}));

  add_object(s, plane(0.5f, 0.5f), add_emission(s, {1, 0.8f, 0.6f}, 5),
             compose(translate({0, 1.5f, 1}), rotate({1, 0, 0}, 1.2f)));
  add_light(s, area_light(LT_AREA_RECTANGLE, 1, 0.5f, look_at({0, -1, 3}, {0, 0, 0}), 300));
  lt_light_desc pt = point_light({-1, -2, 2}, 200);
  pt.radius = 0.2f;
  add_light(s, pt);
  add_light(s, sun_light({0.3f, 0.2f, -1}, 2, 0.05f));
  set_world(s, {0.2f, 0.3f, 0.5f}, 0.5f);
  set_camera(s, perspective_camera(look_at({0.5f, -5, 2.5f}, {0, 0, 0.5f}), 35));
  check(lt_scene_commit(s), "commit");
  return sp;
}

ScenePtr cornell_scene() {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  const float half_pi = float(kPi / 2);
  const int white = add_diffuse(s, {0.73f, 0.73f, 0.73f}), red = add_diffuse(s, {0.65f, 0.05f, 0.05f});
  const int green = add_diffuse(s, {0.12f, 0.45f, 0.15f});
  add_object(s, plane(2, 2), white);                                                                 // floor
  add_object(s, plane(2, 2), white, compose(translate({0, 0, 2}), rotate({1, 0, 0}, 2 * half_pi)));  // ceiling
  add_object(s, plane(2, 2), white, compose(translate({0, 1, 1}), rotate({1, 0, 0}, half_pi)));      // back
  add_object(s, plane(2, 2), red, compose(translate({-1, 0, 1}), rotate({0, 1, 0}, half_pi)));
  add_object(s, plane(2, 2), green, compose(translate({1, 0, 1}), rotate({0, 1, 0}, -half_pi)));
  add_object(s, box({-0.65f, -0.05f, 0}, {-0.1f, 0.5f, 1.2f}), white);
  add_object(s, box({0.1f, -0.6f, 0}, {0.65f, -0.05f, 0.6f}), white);
  add_light(s, area_light(LT_AREA_SQUARE, 0.5f, 0.5f, look_at({0, 0, 1.98f}, {0, 0, 0}, {0, 1, 0}), 60));
  set_camera(s, perspective_camera(look_at({0, -3.0f, 1}, {0, 0, 1}), 40));
  check(lt_scene_commit(s), "commit");
  return sp;
}

}  // namespace lt_test
