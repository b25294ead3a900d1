#include "geometry/geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "geometry/terminator.h"

namespace lt {

namespace {

struct QueryContext {
  RTCIntersectContext ctx;     // must be first: Embree hands this pointer back to the filter
  const unsigned* visibility;  // per Embree instance id; null: every instance seen
  unsigned mask;
  // What the ray skips (Ray::self_*): its instance as Embree names it (the id of a flattened
  // mesh's geometry, or a motion segment's id past `instances`, mapped by segment_instance); an
  // instance's own scene (intersect_instance) names only the primitive.
  int self_instance, self_primitive;
  float self_tmax;
  bool own_scene;
  const std::vector<unsigned>* segment_instance;
  unsigned instances;
  const Geometry* geometry;
  Vec3 dir;  // the ray's, in world space
  float time;
};

// Whether a hit on the left triangle's own object, nearer than self_tmax, is one the ray's origin
// (drawn back behind the triangle's plane, hit.h) made: the ray then passes the other triangle in the
// sense it leaves its own (a neighbour in or near its plane, crossed from behind), or the other
// lies in its plane facing the other way (a face doubled back to back, a mesh flattened by a zero
// scale), where a neighbour it truly meets (a concave corner) faces it from another plane.
// World-space corners at the ray's time.
bool made_by_the_origin(const QueryContext& c, int primitive) {
  Vec3 a[3], b[3];
  c.geometry->triangle(c.self_instance, c.self_primitive, &a[0], &a[1], &a[2], c.time);
  c.geometry->triangle(c.self_instance, primitive, &b[0], &b[1], &b[2], c.time);
  const Vec3 na = cross(a[1] - a[0], a[2] - a[0]), nb = cross(b[1] - b[0], b[2] - b[0]);
  if ((dot(c.dir, na) > 0) == (dot(c.dir, nb) > 0)) return true;
  return length_squared(cross(na, nb)) <= 1e-6f * length_squared(na) * length_squared(nb);
}

// Rejects hits on instances that this kind of ray must not see (Cycles' ray visibility) and what
// a ray leaving a triangle skips (hit.h, leave): Embree sets tfar to the hit's distance first.
// Only installed when some instance hides from some ray kind or the ray leaves a triangle.
void query_filter(const RTCFilterFunctionNArguments* args) {
  const auto* c = reinterpret_cast<const QueryContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    unsigned inst = RTCHitN_instID(args->hit, args->N, i, 0);
    if (inst == RTC_INVALID_GEOMETRY_ID) inst = RTCHitN_geomID(args->hit, args->N, i);  // flattened (build_top)
    if (c->visibility && !(c->visibility[inst] & c->mask)) {
      args->valid[i] = 0;
      continue;
    }
    if (c->self_primitive < 0) continue;
    if (!c->own_scene && inst >= c->instances) inst = (*c->segment_instance)[inst - c->instances];
    if (!c->own_scene && int(inst) != c->self_instance) continue;
    const int prim = int(RTCHitN_primID(args->hit, args->N, i));
    if (prim == c->self_primitive ||
        (RTCRayN_tfar(args->ray, args->N, i) < c->self_tmax && made_by_the_origin(*c, prim)))
      args->valid[i] = 0;
  }
}

// A query's context: with per-instance visibility (null: every instance seen) and what the ray
// skips, query_filter keeps what rays of kind `mask` see.
void init_query(QueryContext* c, const Geometry* geometry, const unsigned* visibility, unsigned mask, const Ray& ray,
                const std::vector<unsigned>& segment_instance, size_t instances, bool own_scene = false) {
  rtcInitIntersectContext(&c->ctx);
  if (!visibility && ray.self_primitive < 0) return;
  c->ctx.filter = query_filter;
  c->visibility = visibility;
  c->mask = mask;
  c->self_instance = ray.self_instance;
  c->self_primitive = ray.self_primitive;
  c->self_tmax = ray.self_tmax;
  c->own_scene = own_scene;
  c->segment_instance = &segment_instance;
  c->instances = unsigned(instances);
  c->geometry = geometry;
  c->dir = ray.d;
  c->time = ray.time;
}

// Curves and spheres are entered, never left: a hit where the ray leaves the tube (the normal
// along the ray) comes from a ray that started inside it, off the same strand (hair's
// transmission); Cycles skips the strand it starts on the same way (its self-intersection test).
void front_face_filter(const RTCFilterFunctionNArguments* args) {
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const float d = RTCRayN_dir_x(args->ray, args->N, i) * RTCHitN_Ng_x(args->hit, args->N, i) +
                    RTCRayN_dir_y(args->ray, args->N, i) * RTCHitN_Ng_y(args->hit, args->N, i) +
                    RTCRayN_dir_z(args->ray, args->N, i) * RTCHitN_Ng_z(args->hit, args->N, i);
    if (d > 0) args->valid[i] = 0;
  }
}

void embree_error(void*, RTCError code, const char* message) {
  std::fprintf(stderr, "lantern: embree error %d: %s\n", int(code), message ? message : "");
}

}  // namespace

Geometry::Geometry() : generation_(next_motion_generation()) {
  device_ = rtcNewDevice(nullptr);
  if (!device_) throw std::runtime_error("could not create the Embree device");
  rtcSetDeviceErrorFunction(device_, embree_error, nullptr);
}

Geometry::~Geometry() {
  for (auto& m : meshes_)
    if (m.rtc) rtcReleaseScene(m.rtc);
  for (auto& b : baked_)
    if (b.rtc) rtcReleaseScene(b.rtc);
  if (top_) rtcReleaseScene(top_);
  rtcReleaseDevice(device_);
}

namespace {
// Steps a constant velocity makes redundant are left out to this relative tolerance (float
// rounding; drop_redundant_steps).
constexpr float kMidpointTolerance = 1e-6f;
// A deforming mesh's vertex steps the same way (Embree interpolates them linearly); its normals
// keep every step (they need not be linear when the positions are).
int redundant_vertex_stride(const Mesh& m) {
  const size_t n = m.positions.size();
  float scale = 1;
  for (const Vec3& p : m.motion_positions) scale = std::max({scale, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  return redundant_stride(m.motion_steps, [&](int a, int k, int b) {
    const Vec3 *pa = &m.motion_positions[size_t(a) * n], *pk = &m.motion_positions[size_t(k) * n],
               *pb = &m.motion_positions[size_t(b) * n];
    for (size_t i = 0; i < n; ++i) {
      const Vec3 d = (pa[i] + pb[i]) * 0.5f - pk[i];
      if (!(std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)}) <= kMidpointTolerance * scale)) return false;
    }
    return true;
  });
}
}  // namespace

// One Embree scene holding one triangle geometry (not committed: commit() or the caller does),
// with `steps` vertex buffers for deformation motion (Embree interpolates them linearly, as
// Cycles' motion triangles).
RTCScene Geometry::triangle_scene(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices, int steps,
                                  int stride) const {
  RTCScene scene = rtcNewScene(device_);
  RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  const size_t n = positions.size() / size_t(steps);
  const int kept = (steps - 1) / stride + 1;
  if (kept > 1) rtcSetGeometryTimeStepCount(g, unsigned(kept));
  for (int s = 0; s < kept; ++s) {
    float* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, unsigned(s), RTC_FORMAT_FLOAT3, 3 * sizeof(float), n));
    for (size_t i = 0; i < n; ++i) {
      const Vec3& p = positions[size_t(s * stride) * n + i];
      v[3 * i] = p.x;
      v[3 * i + 1] = p.y;
      v[3 * i + 2] = p.z;
    }
  }
  unsigned* idx = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), indices.size() / 3));
  std::copy(indices.begin(), indices.end(), idx);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(scene, g, 0);
  rtcReleaseGeometry(g);
  return scene;
}

int Geometry::add_mesh(Mesh mesh, std::vector<std::string>& warnings) {
  if (committed_) throw StateError("the scene is committed; meshes can no longer be added");
  const size_t n = mesh.triangle_count();
  const int id = int(meshes_.size());
  // Drop triangles with non-finite or coincident corners: they have no area and no normal.
  size_t kept = 0, dropped = 0;
  for (size_t t = 0; t < n; ++t) {
    Vec3 p0 = mesh.positions[mesh.indices[3 * t]], p1 = mesh.positions[mesh.indices[3 * t + 1]],
         p2 = mesh.positions[mesh.indices[3 * t + 2]];
    float area2 = length(cross(p1 - p0, p2 - p0));
    if (!(area2 > 0) || !std::isfinite(area2) || !is_finite(p0) || !is_finite(p1) || !is_finite(p2)) {
      ++dropped;
      continue;
    }
    if (kept != t) {
      for (int c = 0; c < 3; ++c) {
        mesh.indices[3 * kept + c] = mesh.indices[3 * t + c];
        if (!mesh.corner_normals.empty()) mesh.corner_normals[3 * kept + c] = mesh.corner_normals[3 * t + c];
        if (!mesh.corner_uvs.empty()) mesh.corner_uvs[3 * kept + c] = mesh.corner_uvs[3 * t + c];
        for (int s = 0; s < mesh.motion_steps && !mesh.motion_corner_normals.empty(); ++s)
          mesh.motion_corner_normals[3 * (s * n + kept) + c] = mesh.motion_corner_normals[3 * (s * n + t) + c];
        for (MeshAttribute& a : mesh.attributes)
          std::copy_n(&a.values[(3 * t + c) * a.components], a.components, &a.values[(3 * kept + c) * a.components]);
      }
      if (!mesh.slots.empty()) mesh.slots[kept] = mesh.slots[t];
      if (!mesh.flat.empty()) mesh.flat[kept] = mesh.flat[t];
    }
    ++kept;
  }
  if (dropped) {
    warnings.push_back("mesh " + std::to_string(id) + ": dropped " + std::to_string(dropped) +
                       " degenerate or non-finite triangle(s)");
    mesh.indices.resize(3 * kept);
    if (!mesh.corner_normals.empty()) mesh.corner_normals.resize(3 * kept);
    if (!mesh.motion_corner_normals.empty()) {  // the steps' kept normals, packed
      for (int s = 1; s < mesh.motion_steps; ++s)
        std::copy_n(&mesh.motion_corner_normals[3 * s * n], 3 * kept, &mesh.motion_corner_normals[3 * s * kept]);
      mesh.motion_corner_normals.resize(3 * kept * size_t(mesh.motion_steps));
    }
    if (!mesh.corner_uvs.empty()) mesh.corner_uvs.resize(3 * kept);
    for (MeshAttribute& a : mesh.attributes) a.values.resize(3 * kept * a.components);
    if (!mesh.slots.empty()) mesh.slots.resize(kept);
    if (!mesh.flat.empty()) mesh.flat.resize(kept);
  }
  // Non-finite corner normals would poison shading: fall back to flat shading for the mesh.
  for (const Vec3& cn : mesh.corner_normals)
    if (!is_finite(cn) || length_squared(cn) == 0) {
      warnings.push_back("mesh " + std::to_string(id) + ": invalid normals, using flat shading");
      mesh.corner_normals.clear();
      break;
    }
  if (mesh.corner_normals.empty()) mesh.flat.clear();
  for (Vec3& cn : mesh.corner_normals) cn = normalize(cn);
  if (mesh.corner_normals.empty()) mesh.motion_corner_normals.clear();
  for (Vec3& cn : mesh.motion_corner_normals)
    cn = is_finite(cn) && length_squared(cn) > 0 ? normalize(cn) : Vec3(0, 0, 1);
  if (kept == 0) {
    if (n == 0) warnings.push_back("mesh " + std::to_string(id) + " has no triangles");
    meshes_.push_back(std::move(mesh));
    return id;
  }
  // Non-finite positions unreferenced by kept triangles are still read by Embree's BVH build.
  for (Vec3& p : mesh.positions)
    if (!is_finite(p)) p = Vec3(0.0f);

  if (mesh.motion_steps > 1) {
    ++motion_meshes_;
    mesh.rtc = triangle_scene(mesh.motion_positions, mesh.indices, mesh.motion_steps, redundant_vertex_stride(mesh));
  } else {
    mesh.rtc = triangle_scene(mesh.positions, mesh.indices);
  }
  meshes_.push_back(std::move(mesh));
  return id;
}

int CurveData::curve_of_segment(uint32_t segment) const {
  auto it = std::upper_bound(first_segment.begin(), first_segment.end(), segment);
  return int(it - first_segment.begin()) - 1;
}

void CurveData::key(size_t cp, float time, float out[4]) const {
  if (motion_steps < 2) {
    std::copy_n(&cps[4 * cp], 4, out);
    return;
  }
  // Embree's linear motion: step s and s + 1 around time (steps - 1).
  const float x = std::clamp(time, 0.0f, 1.0f) * float(motion_steps - 1);
  const int s = std::min(int(x), motion_steps - 2);
  const float f = x - float(s);
  const size_t n = cps.size();
  const float* a = &motion_cps[size_t(s) * n + 4 * cp];
  const float* b = a + n;
  for (int k = 0; k < 4; ++k) out[k] = (1 - f) * a[k] + f * b[k];
}

void catmull_rom(const CurveData& c, uint32_t i, float u, Vec3* p, Vec3* dp, float* radius, float time) {
  const float u2 = u * u, u3 = u2 * u;
  // Uniform Catmull-Rom basis (tension 1/2) and its derivative.
  const float b[4] = {0.5f * (-u3 + 2 * u2 - u), 0.5f * (3 * u3 - 5 * u2 + 2), 0.5f * (-3 * u3 + 4 * u2 + u),
                      0.5f * (u3 - u2)};
  const float d[4] = {0.5f * (-3 * u2 + 4 * u - 1), 0.5f * (9 * u2 - 10 * u), 0.5f * (-9 * u2 + 8 * u + 1),
                      0.5f * (3 * u2 - 2 * u)};
  Vec3 P(0.0f), D(0.0f);
  float r = 0;
  for (int k = 0; k < 4; ++k) {
    float key[4];
    c.key(i + k, time, key);
    const Vec3 q(key[0], key[1], key[2]);
    P += q * b[k];
    D += q * d[k];
    r += key[3] * b[k];
  }
  if (p) *p = P;
  if (dp) *dp = D;
  if (radius) *radius = std::max(r, 0.0f);
}

int Geometry::add_curves(Mesh mesh, const std::vector<uint32_t>& offsets, std::vector<std::string>& warnings) {
  if (committed_) throw StateError("the scene is committed; curves can no longer be added");
  const int id = int(meshes_.size());
  CurveData& c = mesh.curves;
  const std::string name = std::string(mesh.kind == GeometryKind::Curves ? "curves " : "points ") + std::to_string(id);
  const int steps = c.motion_steps > 1 ? c.motion_steps : 0;
  const size_t keys = c.cps.size() / 4;
  for (std::vector<float>* v : {&c.cps, &c.motion_cps})
    for (size_t i = 0; i < v->size(); i += 4) {
      float& r = (*v)[i + 3];
      if (!(r >= 0) || !std::isfinite(r)) r = 0;
    }
  // Key i at step s (the centre's without motion).
  auto key_at = [&](int s, size_t i) { return steps ? &c.motion_cps[(size_t(s) * keys + i) * 4] : &c.cps[4 * i]; };
  auto finite_at_every_step = [&](size_t i) {
    bool ok = is_finite(c.point(i));
    for (int s = 0; s < steps && ok; ++s) {
      const float* k = key_at(s, i);
      ok = is_finite(Vec3(k[0], k[1], k[2]));
    }
    return ok;
  };
  size_t dropped = 0, kept = 0;
  if (mesh.kind == GeometryKind::Points) {
    // Spheres: drop the non-finite and the radius-0 ones (nothing to hit).
    std::vector<float> motion;
    motion.reserve(c.motion_cps.size());
    std::vector<size_t> keep;
    for (size_t i = 0; i < keys; ++i) {
      if (!finite_at_every_step(i) || !(c.radius(i) > 0)) {
        ++dropped;
        continue;
      }
      keep.push_back(i);
    }
    for (int s = 0; s < steps; ++s)
      for (size_t i : keep) motion.insert(motion.end(), key_at(s, i), key_at(s, i) + 4);
    for (MeshAttribute& a : mesh.attributes) {
      const size_t n = size_t(a.components);
      for (size_t j = 0; j < keep.size(); ++j) std::copy_n(&a.values[keep[j] * n], n, &a.values[j * n]);
      a.values.resize(keep.size() * n);
    }
    for (size_t i : keep) {
      std::copy_n(&c.cps[4 * i], 4, &c.cps[4 * kept]);
      c.random[kept] = c.random[i];
      ++kept;
    }
    c.cps.resize(4 * kept);
    c.random.resize(kept);
    c.motion_cps = std::move(motion);
    if (dropped)
      warnings.push_back(name + ": dropped " + std::to_string(dropped) +
                         " point(s) with a non-finite position or zero radius");
  } else {
    // Curves: keys with the end points duplicated, segments, cumulative key distances.
    std::vector<float> cps;
    cps.reserve(c.cps.size() + 8 * (offsets.size() - 1));
    std::vector<float> random;
    std::vector<int> slots;
    c.first_segment.clear();
    c.segments.clear();
    c.arc.clear();
    std::vector<uint32_t> kept_curves;  // the curves kept, for the motion steps' keys
    size_t bad = 0, short_curves = 0, flat = 0;
    for (size_t k = 0; k + 1 < offsets.size(); ++k) {
      const uint32_t a = offsets[k], e = offsets[k + 1];
      bool finite = true, thick = false;
      float len = 0;
      for (uint32_t i = a; i < e; ++i) {
        finite = finite && finite_at_every_step(i);
        thick = thick || c.radius(i) > 0;
        if (i > a) len += length(c.point(i) - c.point(i - 1));
      }
      if (e - a < 2) {
        ++short_curves;
        continue;
      }
      if (!finite || !std::isfinite(len)) {
        ++bad;
        continue;
      }
      if (!(len > 0) || !thick) {
        ++flat;
        continue;
      }
      c.first_segment.push_back(uint32_t(c.segments.size()));
      const uint32_t base = uint32_t(cps.size() / 4);
      cps.insert(cps.end(), &c.cps[4 * a], &c.cps[4 * a + 4]);
      c.arc.push_back(0);
      float s = 0;
      for (uint32_t i = a; i < e; ++i) {
        if (i > a) s += length(c.point(i) - c.point(i - 1));
        cps.insert(cps.end(), &c.cps[4 * i], &c.cps[4 * i + 4]);
        c.arc.push_back(s);
      }
      cps.insert(cps.end(), &c.cps[4 * (e - 1)], &c.cps[4 * e]);
      c.arc.push_back(s);
      for (uint32_t j = 0; j + 1 < e - a; ++j) c.segments.push_back(base + j);
      kept_curves.push_back(uint32_t(k));
      random.push_back(c.random[k]);
      slots.push_back(mesh.slots.empty() ? 0 : mesh.slots[k]);
    }
    c.first_segment.push_back(uint32_t(c.segments.size()));
    // Each step's keys laid out as cps: the kept curves, their ends duplicated.
    std::vector<float> motion;
    motion.reserve(size_t(steps) * cps.size());
    for (int s = 0; s < steps; ++s)
      for (uint32_t k : kept_curves) {
        const uint32_t a = offsets[k], e = offsets[k + 1];
        motion.insert(motion.end(), key_at(s, a), key_at(s, a) + 4);
        for (uint32_t i = a; i < e; ++i) motion.insert(motion.end(), key_at(s, i), key_at(s, i) + 4);
        motion.insert(motion.end(), key_at(s, e - 1), key_at(s, e - 1) + 4);
      }
    c.motion_cps = std::move(motion);
    // Attributes and UVs of the kept curves; per-point values laid out as the keys.
    for (MeshAttribute& a : mesh.attributes) {
      const size_t n = size_t(a.components);
      const float* at = a.values.data();
      std::vector<float> v;
      for (uint32_t k : kept_curves) {
        if (!a.per_point) {
          v.insert(v.end(), at + k * n, at + (k + 1) * n);
          continue;
        }
        const uint32_t first = offsets[k], end = offsets[k + 1];
        v.insert(v.end(), at + first * n, at + (first + 1) * n);
        v.insert(v.end(), at + first * n, at + end * n);
        v.insert(v.end(), at + (end - 1) * n, at + end * n);
      }
      a.values = std::move(v);
    }
    if (!c.uv.empty()) {
      std::vector<Vec2> uv;
      for (uint32_t k : kept_curves) uv.push_back(c.uv[k]);
      c.uv = std::move(uv);
    }
    c.cps = std::move(cps);
    c.random = std::move(random);
    mesh.slots = std::move(slots);
    if (bad) warnings.push_back(name + ": dropped " + std::to_string(bad) + " curve(s) with non-finite positions");
    if (short_curves)
      warnings.push_back(name + ": dropped " + std::to_string(short_curves) + " curve(s) of fewer than 2 points");
    if (flat)
      warnings.push_back(name + ": dropped " + std::to_string(flat) + " curve(s) of zero length or zero radius");
    kept = c.curve_count();
  }
  if (!steps) c.motion_cps.clear();
  c.motion_steps = steps;
  if (kept == 0)
    warnings.push_back(name + " has nothing to render");
  else
    mesh.rtc = curve_scene(mesh);
  if (kept && steps) ++motion_meshes_;
  meshes_.push_back(std::move(mesh));
  return id;
}

// Embree reads the control points and segments from the mesh's own arrays (no copy): a Mesh's
// vectors keep their storage when the mesh moves into meshes_.
RTCScene Geometry::curve_scene(const Mesh& m) const {
  RTCScene scene = rtcNewScene(device_);
  const CurveData& c = m.curves;
  const bool curves = m.kind == GeometryKind::Curves;
  RTCGeometry g =
      rtcNewGeometry(device_, curves ? RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE : RTC_GEOMETRY_TYPE_SPHERE_POINT);
  const size_t n = c.cps.size() / 4;
  if (c.motion_steps > 1) {
    rtcSetGeometryTimeStepCount(g, unsigned(c.motion_steps));
    for (int s = 0; s < c.motion_steps; ++s)
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, unsigned(s), RTC_FORMAT_FLOAT4, c.motion_cps.data(),
                                 size_t(s) * n * 4 * sizeof(float), 4 * sizeof(float), n);
  } else {
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, c.cps.data(), 0, 4 * sizeof(float), n);
  }
  if (curves)
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, c.segments.data(), 0, sizeof(uint32_t),
                               c.segments.size());
  rtcSetGeometryIntersectFilterFunction(g, front_face_filter);
  rtcSetGeometryOccludedFilterFunction(g, front_face_filter);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(scene, g, 0);
  rtcReleaseGeometry(g);
  return scene;
}

namespace {
bool finite_transform(const Transform& xf) {
  bool finite = std::isfinite(xf.determinant());
  for (float x : xf.m) finite = finite && std::isfinite(x);
  return finite;
}
// Embree instances need an inverse.
bool invertible(const Transform& xf) { return std::abs(xf.determinant()) > 1e-30f; }
// The scale of an instance's inverse (its linear part's row-sum norm), which Embree applies to
// every ray reaching the instance; INFINITY when it passes kMaxInverseNorm or takes the origin
// beyond half the traceable range (such an instance is baked into world space).
constexpr float kMaxInverseNorm = 1e8f;
float inverse_norm(const Transform& xf) {
  if (!invertible(xf)) return INFINITY;  // e.g. a motion step's instant scaled to nothing
  const Transform inv = affine_inverse(xf);
  float norm = 0, offset = 0;
  for (int row = 0; row < 3; ++row) {
    const float* m = &inv.m[4 * row];
    norm = std::max(norm, std::abs(m[0]) + std::abs(m[1]) + std::abs(m[2]));
    offset = std::max(offset, std::abs(m[3]));
  }
  return norm <= kMaxInverseNorm && offset <= kTraceableRange / 2 ? norm : INFINITY;  // NaN: INFINITY
}
// Whether Embree can instance this transform (else the mesh is baked into world space).
bool instanceable(const Transform& xf) { return invertible(xf) && std::isfinite(inverse_norm(xf)); }
// Whether any triangle keeps an area: the linear part has rank 2 or more, i.e. its cofactor
// matrix (the normal rows) is not zero. Objects scaled to a line or a point (often how animators
// hide them) are left out rather than baked.
bool keeps_area(const Instance& inst) {
  for (const Vec3& r : inst.normal_rows)
    if (r.x != 0 || r.y != 0 || r.z != 0) return true;
  return false;
}
const Transform kIdentity;
bool same_rotation(const std::vector<DecomposedTransform>& steps) {
  for (const DecomposedTransform& d : steps)
    for (int k = 0; k < 4; ++k)
      if (std::abs(d.q[k] - steps[0].q[k]) > 1e-7f) return false;
  return true;
}

// A moving instance whose rotation stays the same (its matrices interpolate linearly, as Embree's
// matrix motion) and whose undeforming mesh is not too large to copy can be traced through motion
// triangles baked into world space: vertex i at step k is M_k p_i, and Embree's linear
// interpolation of those is M(t) p_i, since M(t) is linear between steps. build_top does so when
// every moving instance can: the top level then needs no motion BVH, whose traversal by every ray
// was most of such an object's cost (a translating box: +9 % -> +1 %; subdivided to 49k
// triangles, +5 % -> +0 %). Beside a turning object, whose motion BVH stays, Embree's matrix
// motion shares it for nothing and baking was slower (bench/README.md, motion blur).
constexpr size_t kBakedMotionShared = 4096, kBakedMotionOwn = size_t(1) << 20;  // triangles: the copy's memory
bool bakes_motion(const Instance& inst, const Mesh& m) {
  const size_t limit = m.users == 1 ? kBakedMotionOwn : kBakedMotionShared;
  return !inst.motion.empty() && m.is_triangles() && m.motion_steps < 2 && m.triangle_count() <= limit &&
         same_rotation(inst.motion_decomposed);
}
// Beside Embree's motion, still triangle meshes are traced in world space from the top level
// (Cycles' applied transforms): a still instance in the moving ones' motion BVH made every ray
// that entered it interpolate and invert its two equal steps (Embree's motion instance entries
// were most of motion blur's extra time in perf), and kept apart it cost a second instance
// traversal. Sponza with a sliding and a turning object, motion blur on: 3.80 -> 3.23 s, the
// still render's time (bench/README.md, motion blur; flattening that too gained nothing). Up to
// kFlattenedTriangles in all (each copy's BVH is memory beside the mesh's own); the rest, and
// curves, points and deforming meshes, stay instances.
constexpr size_t kFlattenedTriangles = size_t(1) << 21;
bool flattens_beside_motion(const Instance& inst, const Mesh& m) {
  const size_t limit = m.users == 1 ? kBakedMotionOwn : kBakedMotionShared;
  return inst.motion.empty() && m.is_triangles() && m.motion_steps < 2 && m.triangle_count() <= limit;
}
// The most still instances build_top puts in the moving ones' motion BVH.
constexpr size_t kStillInstancesInMotionBvh = 256;

void set_transform(Instance& inst, const Transform& xf) { static_cast<Pose&>(inst) = Pose::of(xf); }

// Steps a constant velocity makes redundant (a translation, a linear shape key: Cycles' 3 steps
// by default) are left out, to float rounding: Embree's motion BVHs and traversal cost more with
// every time segment, and the motion between the steps kept is the same. Not for a turning
// object, whose bounds over a longer segment grow (a slower BVH).
void drop_redundant_steps(Instance& inst) {
  if (!same_rotation(inst.motion_decomposed)) return;
  const int stride = redundant_stride(int(inst.motion.size()), [&](int a, int k, int b) {
    const Transform mid = interpolate_motion(decompose_motion({inst.motion[size_t(a)], inst.motion[size_t(b)]}), 0.5f);
    const Transform& m = inst.motion[size_t(k)];
    float scale = 1;
    for (float x : m.m) scale = std::max(scale, std::abs(x));
    for (int i = 0; i < 12; ++i)
      if (!(std::abs(mid.m[i] - m.m[i]) <= kMidpointTolerance * scale)) return false;
    return true;
  });
  if (stride == 1) return;
  std::vector<Transform> kept;
  for (size_t s = 0; s < inst.motion.size(); s += size_t(stride)) kept.push_back(inst.motion[s]);
  inst.motion = std::move(kept);
  inst.motion_decomposed = decompose_motion(inst.motion);
}

// Decomposes the instance's motion steps (add_instance, set_instance_motion), or clears them and
// says why when one cannot be used.
void prepare_motion(Instance& inst, int id, std::vector<std::string>& warnings) {
  inst.motion_decomposed.clear();
  if (inst.motion.empty()) return;
  bool usable = inst.motion.size() >= 2 && finite_transform(inst.xf) && instanceable(inst.xf);
  // A step may scale the object to nothing (growing from or shrinking to nothing, as Cycles
  // blurs it): Embree inverts the interpolated transform only at rays' times, where it has
  // an inverse but at that step's instant.
  for (const Transform& m : inst.motion)
    usable = usable && finite_transform(m) && (instanceable(m) || scaled_to_nothing(m));
  if (usable) {
    inst.motion_decomposed = decompose_motion(inst.motion);
    drop_redundant_steps(inst);
  } else {
    warnings.push_back("instance " + std::to_string(id) +
                       ": a motion step's transform is not finite or not invertible; rendered without motion "
                       "blur at its centre transform");
    inst.motion.clear();
  }
}
}  // namespace

int Geometry::add_instance(Instance inst, std::vector<std::string>& warnings) {
  if (committed_) throw StateError("the scene is committed; instances can no longer be added");
  const int id = int(instances_.size());
  set_transform(inst, inst.xf);
  prepare_motion(inst, id, warnings);
  motion_instances_ += !inst.motion.empty();
  ++meshes_[size_t(inst.mesh)].users;
  instances_.push_back(inst);
  baked_.emplace_back();
  instance_visibility_.push_back(0);
  set_ray_visibility(size_t(id));
  has_shadow_catcher_ = has_shadow_catcher_ || inst.shadow_catcher;
  return id;
}

void Geometry::set_displaced(int id, std::vector<Vec3> positions, std::vector<Vec3> motion_positions,
                             std::vector<Vec3> corner_normals, std::vector<Vec3> motion_corner_normals) {
  if (committed_) throw StateError("the scene is committed; meshes can no longer be displaced");
  Mesh& mesh = meshes_.at(size_t(id));
  mesh.undisplaced = std::move(mesh.positions);
  mesh.positions = std::move(positions);
  mesh.motion_positions = std::move(motion_positions);
  mesh.corner_normals = std::move(corner_normals);
  mesh.motion_corner_normals = std::move(motion_corner_normals);
  if (mesh.rtc) rtcReleaseScene(mesh.rtc);
  mesh.rtc = mesh.motion_steps > 1 ? triangle_scene(mesh.motion_positions, mesh.indices, mesh.motion_steps)
                                   : triangle_scene(mesh.positions, mesh.indices);
}

void Geometry::set_instance_transform(int instance, const Transform& xf) {
  set_transform(instances_.at(size_t(instance)), xf);
  generation_ = next_motion_generation();
  top_dirty_ = true;
}

void Geometry::set_instance_motion(int instance, std::vector<Transform> motion, std::vector<std::string>& warnings) {
  Instance& inst = instances_.at(size_t(instance));
  motion_instances_ -= !inst.motion.empty();
  inst.motion = std::move(motion);
  prepare_motion(inst, instance, warnings);
  motion_instances_ += !inst.motion.empty();
  generation_ = next_motion_generation();
  top_dirty_ = true;
}

void Geometry::set_instance_values(int instance, Instance&& values) {
  Instance& inst = instances_.at(size_t(instance));
  std::copy(values.color, values.color + 4, inst.color);
  inst.pass_index = values.pass_index;
  inst.attributes = std::move(values.attributes);
  const unsigned vis = values.visibility & 31u;
  if (vis == inst.visibility) return;
  inst.visibility = vis;
  set_ray_visibility(size_t(instance));
  // Every ray seeing every instance again: no filter, the same hits as a scene built so (the
  // meshes keep the flag, unread without a filter).
  partial_visibility_ =
      std::any_of(instance_visibility_.begin(), instance_visibility_.end(), [](unsigned v) { return v != 31u; });
  top_dirty_ = true;  // the top level holds a copy (rtc_visibility_)
}

// The ray kinds that see instance i. A shadow catcher is also seen by the catcher-only rays
// (catcher_only_visibility), as Cycles' SHADOW_CATCHER_OBJECT_VISIBILITY. The first instance some
// rays miss turns on query_filter's visibility test.
void Geometry::set_ray_visibility(size_t i) {
  const Instance& inst = instances_[i];
  const unsigned vis = inst.visibility & 31u;
  instance_visibility_[i] = inst.shadow_catcher ? vis | catcher_only_visibility(vis) : vis;
  if (vis != 31u || inst.shadow_catcher) partial_visibility_ = true;
}

void Geometry::commit() {
  if (committed_ && !top_dirty_) return;
  if (!committed_) {
    for (auto& m : meshes_) {
      if (!m.rtc) continue;
      // Strands: Embree's compact curve leaves (indices into the control points, not copies of
      // them), as Cycles' memory implies: 42 against 118 bytes a segment (bench/README.md, hair).
      const int compact = m.kind == GeometryKind::Curves ? RTC_SCENE_FLAG_COMPACT : RTC_SCENE_FLAG_NONE;
      rtcSetSceneFlags(m.rtc, RTCSceneFlags(compact | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION));
      rtcCommitScene(m.rtc);
      ++mesh_builds_;
    }
  }
  build_top();
  committed_ = true;
  top_dirty_ = false;
}

// Embree two-level instancing: the top level holds one instance geometry per object instance,
// each pointing at its mesh's committed scene, so rebuilding it never touches a mesh BVH.
void Geometry::build_top() {
  if (top_) rtcReleaseScene(top_);
  top_ = rtcNewScene(device_);
  // Every scene a ray enters carries the flag: most rays leave a triangle (query_filter), and
  // Debian's Embree asserts it in every scene a filtered ray enters.
  rtcSetSceneFlags(top_, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
  bounds_ = Bounds();
  segment_instance_.clear();
  rtc_visibility_ = instance_visibility_;
  // Instances Embree traces (not the curves and spheres of a flattened object), those that move,
  // and how many move.
  const auto traced = [&](const Instance& inst) {
    const Mesh& m = meshes_[inst.mesh];
    return m.rtc && finite_transform(inst.xf) && keeps_area(inst) && (instanceable(inst.xf) || m.is_triangles());
  };
  const auto moves = [&](const Instance& inst) { return instanceable(inst.xf) && !inst.motion.empty(); };
  const bool bake_motion = std::none_of(instances_.begin(), instances_.end(), [&](const Instance& x) {
    return traced(x) && moves(x) && !bakes_motion(x, meshes_[x.mesh]);
  });
  const size_t moving_count = bake_motion ? 0
                                          : std::count_if(instances_.begin(), instances_.end(),
                                                          [&](const Instance& x) { return traced(x) && moves(x); });
  // With Embree's motion at the top level, still triangle meshes are flattened into it
  // (flattens_beside_motion), and a few other still instances (curves, points, deforming or large
  // meshes) join the moving ones' motion BVH as two equal steps: Embree keeps static and motion
  // primitives in two BVHs, and each ray then traverses both (motion_blur, 5 instances: 4.75-4.81
  // -> 4.56-4.60 s before the flattening). With many the motion BVH's dearer nodes cost more than
  // the second traversal (1600 more: 5.20-5.37 -> 5.47-5.48 s; 100 and 400: the same).
  // bench/README.md, motion blur.
  std::vector<bool> flattened(instances_.size(), false);
  size_t flattened_triangles = 0, still_instances = 0;
  for (size_t i = 0; i < instances_.size(); ++i) {
    const Instance& inst = instances_[i];
    const Mesh& m = meshes_[inst.mesh];
    if (!traced(inst) || moves(inst) || moving_count == 0) continue;
    if (!instanceable(inst.xf)) {  // baked in world space anyway (flat): no copy to count
      flattened[i] = true;
    } else if (flattens_beside_motion(inst, m) && flattened_triangles + m.triangle_count() <= kFlattenedTriangles) {
      flattened[i] = true;
      flattened_triangles += m.triangle_count();
    }
    still_instances += !flattened[i];
  }
  const bool one_motion_bvh = moving_count > 0 && still_instances <= kStillInstancesInMotionBvh;
  // The moving instance alone in its motion BVH (attach_moving).
  const bool lone = moving_count == 1 && (!one_motion_bvh || still_instances == 0);
  float largest = 0;  // inverse_norm over Embree's instances, their motion steps and between them
  for (size_t i = 0; i < instances_.size(); ++i) {
    const Instance& inst = instances_[i];
    const Mesh& m = meshes_[inst.mesh];
    if (!traced(inst)) continue;
    const bool flat = !instanceable(inst.xf);
    const bool moving = moves(inst);
    const bool baked = flat || flattened[i] || (moving && bake_motion);  // traced in world space
    // An edit made it instanceable again, or motion went away.
    if (!baked && baked_[i].rtc) {
      rtcReleaseScene(baked_[i].rtc);
      baked_[i].rtc = nullptr;
    }
    if (!baked) largest = std::max(largest, inverse_norm(inst.xf));  // finite: instanceable
    if (moving && !baked) {  // Embree interpolates the decomposition: its inverse between steps, sampled (capped)
      const int n = 8 * int(inst.motion.size());
      for (int k = 0; k <= n; ++k)
        largest = std::max(
            largest,
            std::min(inverse_norm(interpolate_motion(inst.motion_decomposed, float(k) / float(n))), kMaxInverseNorm));
    }
    RTCScene object = baked ? baked_scene(int(i)) : m.rtc;
    if (moving && !baked) {
      attach_moving(object, inst, unsigned(i), lone);
    } else if (flattened[i]) {  // its world-space triangles in the top level, by the instance's id
      rtcAttachGeometryByID(top_, rtcGetGeometry(object, 0), unsigned(i));
    } else {
      RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(g, object);
      const unsigned steps = one_motion_bvh ? 2 : 1;
      rtcSetGeometryTimeStepCount(g, steps);
      // Embree's RTC_FORMAT_FLOAT3X4_ROW_MAJOR is exactly our layout; the baked copy is in world space.
      for (unsigned k = 0; k < steps; ++k)
        rtcSetGeometryTransform(g, k, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, (baked ? kIdentity : inst.xf).m);
      rtcCommitGeometry(g);
      rtcAttachGeometryByID(top_, g, unsigned(i));
      rtcReleaseGeometry(g);
    }
    // Bounds over the motion steps' vertices (between steps the motion stays near them), and
    // the curves' and points' keys grown by their radius.
    const std::vector<Vec3>& ps = m.motion_steps > 1 ? m.motion_positions : m.positions;
    const std::vector<Transform> still{inst.xf};
    for (const Transform& xf : moving ? inst.motion : still) {
      for (const Vec3& p : ps) bounds_.extend(xf.point(p));
      const std::vector<float>& keys = m.curves.motion_steps > 1 ? m.curves.motion_cps : m.curves.cps;
      for (size_t k = 0; k + 3 < keys.size(); k += 4) {
        const Vec3 p(keys[k], keys[k + 1], keys[k + 2]);
        bounds_.extend(xf.point(p - Vec3(keys[k + 3])));
        bounds_.extend(xf.point(p + Vec3(keys[k + 3])));
      }
    }
  }
  rtcCommitScene(top_);
  ++top_builds_;
  find_contacts();
  // |L^-1 o + L^-1 t| <= norm |o| + |L^-1 t| (the latter <= half the range): origins within half the
  // range over the norm stay traceable in every instance, directions within the range over it.
  const float norm = std::max(largest, 1.0f);
  ray_origin_limit_ = largest > 0 ? kTraceableRange / 2 / norm : kTraceableRange;
  ray_direction_limit_ = largest > 0 ? kTraceableRange / norm : kTraceableRange;
}

// Triangles of different still instances in one plane whose extents overlap there (their boxes
// in the plane's other two axes, shrunk by the tolerance so that tiles meeting at an edge do not
// count): world-space triangles keyed by their plane's normal (to 1e-4) and offset (to 1e-5 of the
// scene's size), sorted by key, each key's run swept along one axis with the next key's (a plane
// rounded across the offset cell's edge). A moving or deforming object is not looked at (its rays
// keep the offset).
void Geometry::find_contacts() {
  contacts_.assign(instances_.size(), {});
  struct Tri {
    uint64_t key;
    int instance, prim, axis;  // axis: the normal's largest component
    Bounds box;                // in world space
  };
  const float scale = std::max(1.0f, length(bounds_.hi - bounds_.lo)), tol = 1e-5f * scale;
  std::vector<Tri> tris;
  size_t count = 0;
  for (const Instance& inst : instances_) count += meshes_[inst.mesh].triangle_count();
  tris.reserve(count);
  for (size_t i = 0; i < instances_.size(); ++i) {
    const Instance& inst = instances_[i];
    const Mesh& m = meshes_[inst.mesh];
    if (!m.rtc || !m.is_triangles() || !inst.motion.empty() || m.motion_steps > 1 || !finite_transform(inst.xf))
      continue;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
      Tri tri{0, int(i), int(t), 0, Bounds()};
      Vec3 p[3];
      for (int k = 0; k < 3; ++k) tri.box.extend(p[k] = inst.xf.point(m.positions[m.indices[3 * t + size_t(k)]]));
      Vec3 n = cross(p[1] - p[0], p[2] - p[0]);
      const float len = length(n);
      if (!(len > 0) || !is_finite(n)) continue;
      n = n / len;
      for (int k = 1; k < 3; ++k)
        if (std::abs(n[k]) > std::abs(n[tri.axis])) tri.axis = k;
      if (n[tri.axis] < 0) n = -n;  // one key for both windings
      const double d = double(dot(n, p[0])) / double(tol);
      if (!(std::abs(d) < 1e15)) continue;
      uint64_t key = uint64_t(tri.axis);
      for (int k = 0; k < 3; ++k) key = key * 20011u + uint64_t(std::lround(n[k] * 1e4f) + 10001);
      tri.key = key * 1000003u + uint64_t(int64_t(std::floor(d)));  // the next offset cell: key + 1
      tris.push_back(tri);
    }
  }
  std::sort(tris.begin(), tris.end(), [](const Tri& a, const Tri& b) { return a.key < b.key; });
  std::vector<std::pair<std::pair<int, int>, Bounds>> found;  // (instance, primitive), where
  std::vector<Tri> run;
  for (size_t a = 0, b; a < tris.size(); a = b) {
    for (b = a + 1; b < tris.size() && tris[b].key == tris[a].key;) ++b;
    size_t c = b;
    while (c < tris.size() && tris[c].key == tris[a].key + 1) ++c;
    if (c - a < 2) continue;
    run.assign(tris.begin() + long(a), tris.begin() + long(c));
    const int u = (run[0].axis + 1) % 3, v = (run[0].axis + 2) % 3;
    std::sort(run.begin(), run.end(), [u](const Tri& x, const Tri& y) { return x.box.lo[u] < y.box.lo[u]; });
    for (size_t x = 0; x < run.size(); ++x)
      for (size_t y = x + 1; y < run.size() && run[y].box.lo[u] + tol < run[x].box.hi[u] - tol; ++y) {
        const Tri &p = run[x], &q = run[y];
        if (p.instance == q.instance || p.axis != q.axis) continue;
        if (!(std::max(p.box.lo[v], q.box.lo[v]) + tol < std::min(p.box.hi[v], q.box.hi[v]) - tol)) continue;
        Bounds where;  // the two boxes' overlap, grown by the tolerance
        where.lo = vmax(p.box.lo, q.box.lo) - Vec3(tol);
        where.hi = vmin(p.box.hi, q.box.hi) + Vec3(tol);
        found.push_back({{p.instance, p.prim}, where});
        found.push_back({{q.instance, q.prim}, where});
      }
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [id, where] : found) {
    auto& c = contacts_[size_t(id.first)];
    if (!c.empty() && c.back().first == id.second) {  // one box around all of the triangle's overlaps
      c.back().second.extend(where.lo);
      c.back().second.extend(where.hi);
    } else {
      c.push_back({id.second, where});
    }
  }
}

// A moving instance: its motion steps, as Cycles gives them to Embree. One alone in its motion
// BVH (build_top) is split instead into one Embree instance per motion segment, each valid over
// its segment's time range (rtcSetGeometryTimeRange; two steps are split at their middle, exact
// since Embree interpolates within a segment as across it): Embree tests no bounds at the root of
// a BVH that holds one primitive, so a lone moving object, its motion BVH's only primitive, made
// every ray interpolate and invert its transform (30-40 % of a render; bench/README.md). With
// other primitives in that BVH, the split added more than it saved.
void Geometry::attach_moving(RTCScene object, const Instance& inst, unsigned id, bool lone) {
  const bool matrices = same_rotation(inst.motion_decomposed);
  const size_t n = inst.motion.size();
  const size_t segments = lone ? std::max<size_t>(n - 1, 2) : 1;
  const unsigned steps = segments == 1 ? unsigned(n) : 2;
  const bool halves = segments == 2 && n == 2;  // two steps split at their middle
  for (size_t k = 0; k < segments; ++k) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, object);
    rtcSetGeometryTimeStepCount(g, steps);
    if (segments > 1) rtcSetGeometryTimeRange(g, float(k) / float(segments), float(k + 1) / float(segments));
    for (unsigned end = 0; end < steps; ++end) {
      // A step, or with halves the start, middle or end of the two (point 0, 1, 2).
      const size_t point = k + end;
      const bool middle = halves && point == 1;
      const size_t step = halves ? point / 2 : point;
      if (matrices) {
        // No rotation changes: interpolating the matrices linearly is Cycles' interpolation (M =
        // T + R S is linear in T and S), and Embree traverses it faster than quaternion motion.
        Transform xf = inst.motion[step];
        if (middle)
          for (int e = 0; e < 12; ++e) xf.m[e] = 0.5f * (inst.motion[0].m[e] + inst.motion[1].m[e]);
        rtcSetGeometryTransform(g, end, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xf.m);
      } else {
        // Cycles' instance motion on Embree (bvh/embree.cpp): one quaternion decomposition a step.
        const DecomposedTransform d =
            middle ? interpolate_decomposed(inst.motion_decomposed, 0.5f) : inst.motion_decomposed[step];
        RTCQuaternionDecomposition q;
        rtcInitQuaternionDecomposition(&q);
        rtcQuaternionDecompositionSetQuaternion(&q, d.q[3], d.q[0], d.q[1], d.q[2]);
        rtcQuaternionDecompositionSetScale(&q, d.scale[0], d.scale[1], d.scale[2]);
        rtcQuaternionDecompositionSetSkew(&q, d.skew[0], d.skew[1], d.skew[2]);
        rtcQuaternionDecompositionSetTranslation(&q, d.translation.x, d.translation.y, d.translation.z);
        rtcSetGeometryTransformQuaternion(g, end, &q);
      }
    }
    rtcCommitGeometry(g);
    const unsigned rtc_id = k == 0 ? id : unsigned(instances_.size() + segment_instance_.size());
    rtcAttachGeometryByID(top_, g, rtc_id);
    rtcReleaseGeometry(g);
    if (k > 0) {
      segment_instance_.push_back(id);
      rtc_visibility_.push_back(instance_visibility_[id]);
    }
  }
}

// The instance's mesh in world space, its triangles in the mesh's order (hits keep their
// primitive ids; surface() transforms the mesh's own corners), at each of its motion steps if
// it moves (bakes_motion). Triangles flattened to no area become single points, which rays
// never hit (a moving baked instance is invertible at every step: none are).
RTCScene Geometry::baked_scene(int instance) {
  const Instance& inst = instances_[size_t(instance)];
  Baked& b = baked_[size_t(instance)];
  const auto same = [](const Transform& a, const Transform& c) { return std::equal(a.m, a.m + 12, c.m); };
  const std::vector<Transform> steps = inst.motion.empty() ? std::vector<Transform>{inst.xf} : inst.motion;
  if (b.rtc && std::equal(b.steps.begin(), b.steps.end(), steps.begin(), steps.end(), same)) return b.rtc;
  if (b.rtc) rtcReleaseScene(b.rtc);
  const Mesh& m = meshes_[size_t(inst.mesh)];
  const size_t n = m.positions.size();
  std::vector<Vec3> positions(n * steps.size());
  for (size_t k = 0; k < steps.size(); ++k)
    for (size_t i = 0; i < n; ++i) positions[k * n + i] = steps[k].point(m.positions[i]);
  std::vector<uint32_t> indices = m.indices;
  for (size_t t = 0; t < m.triangle_count() && steps.size() == 1; ++t) {
    const Vec3 &p0 = positions[indices[3 * t]], &p1 = positions[indices[3 * t + 1]],
               &p2 = positions[indices[3 * t + 2]];
    if (!(length(cross(p1 - p0, p2 - p0)) > 0)) indices[3 * t + 1] = indices[3 * t + 2] = indices[3 * t];
  }
  b.rtc = triangle_scene(positions, indices, int(steps.size()));
  rtcSetSceneFlags(b.rtc, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
  rtcCommitScene(b.rtc);
  ++mesh_builds_;  // a BVH over the mesh: moving such an object costs a mesh build
  b.steps = steps;
  return b.rtc;
}

bool Geometry::traceable(const Ray& r) const {
  const auto within = [](const Vec3& v, float limit) {
    return std::abs(v.x) <= limit && std::abs(v.y) <= limit && std::abs(v.z) <= limit;
  };
  return within(r.o, ray_origin_limit_) && within(r.d, ray_direction_limit_) && !std::isnan(r.tmin) &&
         !std::isnan(r.tmax);
}

namespace {

// The closest hit in `scene` along (o, d) over the ray's extent at its time: t (the same along
// (o, d) as along the ray), Embree's instance id (for a still flattened into the top level its
// geometry id; none in a mesh's own scene), primitive, barycentrics, and the world position.
bool closest_hit(RTCScene scene, RTCIntersectContext* ctx, const Ray& ray, const Vec3& o, const Vec3& d, Hit* hit) {
  RTCRayHit rh;
  rh.ray.org_x = o.x;
  rh.ray.org_y = o.y;
  rh.ray.org_z = o.z;
  rh.ray.dir_x = d.x;
  rh.ray.dir_y = d.y;
  rh.ray.dir_z = d.z;
  rh.ray.tnear = ray.tmin;
  rh.ray.tfar = ray.tmax;
  rh.ray.mask = 0xffffffffu;
  rh.ray.flags = 0;
  rh.ray.time = ray.time;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit->t = rh.ray.tfar;
  hit->instance = int(rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rh.hit.instID[0] : rh.hit.geomID);
  hit->primitive = int(rh.hit.primID);
  hit->u = rh.hit.u;
  hit->v = rh.hit.v;
  hit->time = ray.time;
  hit->p = ray.o + ray.d * rh.ray.tfar;
  return true;
}
}  // namespace

bool Geometry::intersect(const Ray& ray, unsigned visibility, Hit* hit) const {
  if (!traceable(ray)) return false;
  QueryContext c;
  init_query(&c, this, partial_visibility_ ? rtc_visibility_.data() : nullptr, visibility, ray, segment_instance_,
             instances_.size());
  if (!closest_hit(top_, &c.ctx, ray, ray.o, ray.d, hit)) return false;
  if (size_t(hit->instance) >= instances_.size())  // a motion segment's own id
    hit->instance = int(segment_instance_[size_t(hit->instance) - instances_.size()]);
  return true;
}

bool Geometry::intersect_instance(const Ray& ray, int instance, Hit* hit) const {
  if (!traceable(ray) || instance < 0 || size_t(instance) >= instances_.size()) return false;
  // The instance's own scene: its mesh's in object space (the ray taken there by the pose's inverse,
  // which keeps t), or the copy baked into world space.
  RTCScene scene = size_t(instance) < baked_.size() ? baked_[size_t(instance)].rtc : nullptr;
  Vec3 o = ray.o, d = ray.d;
  if (!scene) {
    scene = meshes_[size_t(instances_[size_t(instance)].mesh)].rtc;
    const Transform inv = affine_inverse(pose(instance, ray.time).xf);
    o = inv.point(o);
    d = inv.vector(d);
  }
  if (!scene) return false;
  QueryContext c;
  Ray own = ray;  // skips its triangle only if it leaves this instance
  if (own.self_instance != instance) own.self_primitive = -1;
  init_query(&c, this, nullptr, 0, own, segment_instance_, instances_.size(), true);
  if (!closest_hit(scene, &c.ctx, ray, o, d, hit)) return false;
  hit->instance = instance;
  return true;
}

bool Geometry::occluded(const Ray& ray, unsigned visibility) const {
  if (!traceable(ray)) return true;
  QueryContext c;
  init_query(&c, this, partial_visibility_ ? rtc_visibility_.data() : nullptr, visibility, ray, segment_instance_,
             instances_.size());
  RTCRay r;
  r.org_x = ray.o.x;
  r.org_y = ray.o.y;
  r.org_z = ray.o.z;
  r.dir_x = ray.d.x;
  r.dir_y = ray.d.y;
  r.dir_z = ray.d.z;
  r.tnear = ray.tmin;
  r.tfar = ray.tmax;
  r.mask = 0xffffffffu;
  r.flags = 0;
  r.time = ray.time;
  rtcOccluded1(top_, &c.ctx, &r);
  return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

void Geometry::object_corners(const Mesh& m, int prim, float time, Vec3* p0, Vec3* p1, Vec3* p2) const {
  const uint32_t* idx = &m.indices[3 * size_t(prim)];
  if (m.motion_steps < 2) {
    *p0 = m.positions[idx[0]];
    *p1 = m.positions[idx[1]];
    *p2 = m.positions[idx[2]];
    return;
  }
  int step;
  float t;
  motion_step(m.motion_steps, time, &step, &t);
  const size_t n = m.positions.size();
  const Vec3* a = &m.motion_positions[size_t(step) * n];
  const Vec3* b = a + n;
  *p0 = lerp(t, a[idx[0]], b[idx[0]]);
  *p1 = lerp(t, a[idx[1]], b[idx[1]]);
  *p2 = lerp(t, a[idx[2]], b[idx[2]]);
}

Pose Geometry::pose(int instance, float time) const {
  const Instance& inst = instances_[size_t(instance)];
  if (inst.motion.empty()) return inst;
  // A hit's surface and then its shading ask for the same pose: the last one is kept per thread
  // (a pure function of its key, so renders stay deterministic).
  thread_local struct {
    uint64_t generation = 0;
    int instance = -1;
    float time = -1;
    Pose pose;
  } last;
  if (last.generation != generation_ || last.instance != instance || last.time != time) {
    last.pose = Pose::of(interpolate_motion(inst.motion_decomposed, time));
    last.generation = generation_;
    last.instance = instance;
    last.time = time;
  }
  return last.pose;
}

void Geometry::triangle(int instance, int prim, Vec3* p0, Vec3* p1, Vec3* p2, float time) const {
  const Instance& inst = instances_[instance];
  const Mesh& m = meshes_[inst.mesh];
  object_corners(m, prim, time, p0, p1, p2);
  const Transform xf = inst.motion.empty() ? inst.xf : pose(instance, time).xf;
  *p0 = xf.point(*p0);
  *p1 = xf.point(*p1);
  *p2 = xf.point(*p2);
}

bool Mesh::interpolate(int id, int t, float b1, float b2, float out[4], int* components) const {
  out[0] = out[1] = out[2] = 0;
  out[3] = 1;
  const MeshAttribute* a = attribute(id);
  if (components) *components = a ? a->components : 0;
  if (!a) {
    out[3] = 0;
    return false;
  }
  const int n = a->components;
  if (kind != GeometryKind::Triangles) {
    size_t element = size_t(t);  // points: the point
    if (kind == GeometryKind::Curves && a->per_point) {
      const float* k0 = &a->values[(size_t(curves.segments[size_t(t)]) + 1) * n];
      for (int k = 0; k < n; ++k) out[k] = (1 - b1) * k0[k] + b1 * k0[n + k];
      return true;
    }
    if (kind == GeometryKind::Curves) element = size_t(curves.curve_of_segment(uint32_t(t)));
    std::copy_n(&a->values[element * n], n, out);
    return true;
  }
  const float* v = &a->values[size_t(3 * t) * n];
  const float b0 = 1 - b1 - b2;
  for (int k = 0; k < n; ++k) out[k] = v[k] * b0 + v[n + k] * b1 + v[2 * n + k] * b2;
  return true;
}

// Cycles' curve_shader_setup and point_shader_setup (thick curves, spheres): the normal points
// from the curve's centre line at u (the sphere's centre) to the hit.
SurfacePoint Geometry::curve_surface(const Hit& hit, const Instance& inst, const Mesh& m) const {
  SurfacePoint sp;
  const CurveData& c = m.curves;
  Vec3 centre, dp(0.0f);
  float r;
  int curve = -1;
  const int slot = slot_of(m, hit.primitive, &curve);
  if (m.kind == GeometryKind::Curves) {
    const uint32_t seg = uint32_t(hit.primitive);
    catmull_rom(c, c.segments[seg], hit.u, &centre, &dp, &r, hit.time);
    sp.curve = curve;
    sp.bary = {hit.u, 0};
    if (!c.uv.empty()) sp.uv = c.uv[size_t(curve)];
  } else {
    float key[4];
    c.key(size_t(hit.primitive), hit.time, key);
    centre = Vec3(key[0], key[1], key[2]);
    r = key[3];
    sp.curve = hit.primitive;
  }
  // At the hit's time: the strands' keys (above) and a moving instance's transform.
  const Pose pose = inst.motion.empty() ? Pose(inst) : this->pose(hit.instance, hit.time);
  const Vec3 centre_w = pose.xf.point(centre);
  sp.p = hit.p;
  sp.time = hit.time;
  Vec3 n = normalize(sp.p - centre_w);
  if (!is_finite(n)) n = Vec3(0, 0, 1);
  sp.ng = sp.ns = n;
  sp.dpdu = pose.xf.vector(dp);
  // Object space: the centre plus the radius along the normal (no inverse transform per hit).
  const Vec3 no = pose.normal_to_object(n);
  sp.po = length_squared(no) > 0 ? centre + normalize(no) * r : centre;
  // Cycles: particle hair's Generated from the root (sync_particle_hair), else svm_node_attr's
  // fallback to object space.
  sp.generated = sp.po;
  if (m.kind == GeometryKind::Curves && c.generated_from_root) {
    const Vec3 root = c.point(c.segments[c.first_segment[size_t(curve)]] + 1);  // after the duplicated end
    for (int k = 0; k < 3; ++k) {
      const float size = m.texspace_size[k];
      sp.generated[k] = size != 0 ? (root[k] - m.texspace_location[k]) / (2 * size) + 0.5f : 0.5f;
    }
  }
  sp.material = inst.material_for(slot);
  sp.instance = hit.instance;
  sp.primitive = hit.primitive;
  return sp;
}

void Geometry::object_corner_normals(const Mesh& m, int prim, float time, Vec3 n[3]) const {
  const Vec3* cn = &m.corner_normals[3 * size_t(prim)];
  if (m.motion_corner_normals.empty()) {
    std::copy_n(cn, 3, n);
    return;
  }
  // The steps' normals, interpolated as the positions.
  int step;
  float u;
  motion_step(m.motion_steps, time, &step, &u);
  const Vec3* a = &m.motion_corner_normals[3 * (size_t(step) * m.triangle_count() + size_t(prim))];
  const Vec3* b = a + 3 * m.triangle_count();
  for (int k = 0; k < 3; ++k) n[k] = lerp(u, a[k], b[k]);
}

Vec3 Geometry::shadow_origin(const SurfacePoint& sp, const Vec3& n, const Vec3& ng, const Vec3& wi, bool* moved) const {
  if (moved) *moved = false;
  const Instance& inst = instances_[size_t(sp.instance)];
  const Mesh& m = meshes_[size_t(inst.mesh)];
  const float cutoff = inst.terminator_geometry;
  if (!(cutoff > 0) || !m.is_triangles() || m.corner_normals.empty()) return leave_origin(sp, wi);
  Vec3 cn[3];
  object_corner_normals(m, sp.primitive, sp.time, cn);
  // Flat faces (the add-on gives their three corners the face's normal) keep the triangle.
  if (same_vector(cn[0], cn[1]) && same_vector(cn[1], cn[2])) return leave_origin(sp, wi);
  float nl = dot(n, wi);
  const Vec3 side = nl < 0 ? -ng : ng;
  const float amount = terminator_offset_amount(cutoff, std::abs(nl), dot(side, wi));
  if (!(amount > 0)) return leave_origin(sp, wi);
  Vec3 v[3];
  object_corners(m, sp.primitive, sp.time, &v[0], &v[1], &v[2]);
  const Pose pose = inst.motion.empty() ? Pose(inst) : this->pose(sp.instance, sp.time);
  Vec3 offset;
  if (m.users == 1 && inst.motion.empty()) {
    // Cycles applies a single still user's transform to the mesh: it works in world space.
    for (int k = 0; k < 3; ++k) {
      v[k] = pose.xf.point(v[k]);
      cn[k] = normalize(pose.normal_to_world(cn[k]));
    }
    offset = smooth_surface_offset(v, cn, sp.bary.x, sp.bary.y, side);
  } else {
    // In object space, the offset then moved as a direction (Cycles' object_dir_transform); the
    // object-space normal of `side`'s side keeps the sign of its dot with the normals.
    const Vec3 g = cross(v[1] - v[0], v[2] - v[0]);
    const Vec3 side_object = dot(pose.normal_to_world(g), side) >= 0 ? g : -g;
    offset = pose.xf.vector(smooth_surface_offset(v, cn, sp.bary.x, sp.bary.y, side_object));
  }
  const Vec3 p = sp.p + offset * amount;
  if (!is_finite(p)) return leave_origin(sp, wi);
  if (moved) *moved = true;
  return offset_ray_origin(p, dot(wi, sp.ng) >= 0 ? sp.ng : -sp.ng);
}

SurfacePoint Geometry::surface(const Hit& hit) const {
  SurfacePoint sp;
  const Instance& inst = instances_[hit.instance];
  const Mesh& m = meshes_[inst.mesh];
  if (!m.is_triangles()) return curve_surface(hit, inst, m);
  const int t = hit.primitive;
  // At the hit's time: a moving instance's transform, a deforming mesh's corners and normals.
  Vec3 p0, p1, p2;
  object_corners(m, t, hit.time, &p0, &p1, &p2);
  const Pose pose = inst.motion.empty() ? Pose(inst) : this->pose(hit.instance, hit.time);
  const float b1 = hit.u, b2 = hit.v, b0 = 1 - b1 - b2;
  // Interpolate in object space, transform once.
  sp.po = p0 * b0 + p1 * b1 + p2 * b2;
  sp.p = pose.xf.point(sp.po);
  sp.time = hit.time;
  sp.bary = {b1, b2};
  const Vec3 g = (undisplaced_point(m, t, b1, b2, sp.po) - m.texspace_location) / (2.0f * m.texspace_size);
  sp.generated = Vec3(g.x + 0.5f, g.y + 0.5f, g.z + 0.5f);
  sp.ng = normalize(pose.normal_to_world(cross(p1 - p0, p2 - p0)));
  if (!m.corner_normals.empty()) {
    Vec3 cn[3];
    object_corner_normals(m, t, hit.time, cn);
    Vec3 ns = cn[0] * b0 + cn[1] * b1 + cn[2] * b2;
    ns = normalize(pose.normal_to_world(ns));
    sp.ns = is_finite(ns) ? ns : sp.ng;
    if (dot(sp.ns, sp.ng) < 0) sp.ns = -sp.ns;  // keep the shading normal on the geometric side
  } else {
    sp.ns = sp.ng;
  }
  if (!m.corner_uvs.empty()) {
    const Vec2* uv = &m.corner_uvs[3 * t];
    sp.uv = {uv[0].x * b0 + uv[1].x * b1 + uv[2].x * b2, uv[0].y * b0 + uv[1].y * b1 + uv[2].y * b2};
  }
  sp.material = inst.material_for(slot_of(m, t));
  sp.instance = hit.instance;
  sp.primitive = t;
  sp.touching = touches(hit.instance, t, sp.p);
  return sp;
}

int Geometry::material(const Hit& hit) const {
  const Instance& inst = instances_[hit.instance];
  return inst.material_for(slot_of(meshes_[inst.mesh], hit.primitive));
}

int Geometry::slot_of(const Mesh& m, int primitive, int* curve) const {
  if (m.is_triangles()) return m.slots.empty() ? 0 : m.slots[size_t(primitive)];
  if (m.kind != GeometryKind::Curves) return 0;  // points: one slot
  const int k = m.curves.curve_of_segment(uint32_t(primitive));
  if (curve) *curve = k;
  return m.slots.empty() ? 0 : m.slots[size_t(k)];
}

}  // namespace lt
