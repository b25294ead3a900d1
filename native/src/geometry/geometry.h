// Triangle meshes and their instances in an Embree 3 two-level BVH. Integrators reach geometry
// only through intersect(), occluded() and surface().
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/math.h"
#include "geometry/hit.h"
#include "geometry/motion.h"

namespace lt {

// A named attribute (UV map, colour, generic values, tangent with its sign); the add-on turns
// names into ids per scene. components 1-4. Triangles: per corner, 3 per triangle. Curves: per
// curve, or per_point laid out as CurveData::cps (ends duplicated). Points: per point.
struct MeshAttribute {
  int id = -1;
  int components = 0;
  bool per_point = false;
  std::vector<float> values;  // components per element
};
constexpr int kMaxAttributeId = 1 << 16;

// What a Mesh holds: triangles, or (Cycles' thick hair and point clouds) Embree round curves and
// spheres (docs/architecture.md, "Curves and points").
enum class GeometryKind : uint8_t { Triangles, Curves, Points };

// Curves: uniform Catmull-Rom splines of varying radius (RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE,
// what Cycles 3.4 builds for its 3D curve shape); points: spheres (RTC_GEOMETRY_TYPE_SPHERE_POINT).
// 4 + 4 + 4 bytes per control point (cps, arc) and 4 per segment besides Embree's BVH.
struct CurveData {
  // x, y, z, radius per control point, object space. Curves: each curve's keys with the first and
  // last duplicated (Catmull-Rom needs a point beyond each end; Cycles' bvh/embree.cpp does the same).
  std::vector<float> cps;
  std::vector<uint32_t> segments;       // curves: the first control point of each segment (Embree's index buffer)
  std::vector<uint32_t> first_segment;  // curves: each curve's first segment, then the segment count
  std::vector<float> arc;               // curves: distance along the keys from the curve's root, per control point
  std::vector<float> random;            // per curve (points: per point): Cycles' hash_uint2_to_float(index, 0)
  std::vector<Vec2> uv;                 // curves: the default UV map per curve, or empty ((0, 0))
  // Curves: Generated from each curve's root key through the mesh's texture space (particle
  // hair); otherwise the object-space point.
  bool generated_from_root = false;
  // Deformation motion blur: motion_steps (0, or 3 to 129) sets of control points laid out as
  // cps, equally spaced over the shutter, step by step; cps stays the centre step's. Embree
  // interpolates the keys linearly between steps, and so do key() and catmull_rom().
  int motion_steps = 0;
  std::vector<float> motion_cps;
  size_t curve_count() const { return first_segment.empty() ? 0 : first_segment.size() - 1; }
  int curve_of_segment(uint32_t segment) const;  // binary search over first_segment
  Vec3 point(size_t cp) const { return {cps[4 * cp], cps[4 * cp + 1], cps[4 * cp + 2]}; }
  float radius(size_t cp) const { return cps[4 * cp + 3]; }
  // Control point cp (x, y, z, radius) at time (0 .. 1 over the shutter).
  void key(size_t cp, float time, float out[4]) const;
};
// The Catmull-Rom point at u in [0, 1] of the segment starting at control point i, its
// derivative and radius (Embree's and Cycles' uniform basis), at time (0 .. 1 over the shutter).
void catmull_rom(const CurveData& c, uint32_t i, float u, Vec3* p, Vec3* dp, float* radius, float time = 0.5f);

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;     // 3 per triangle
  std::vector<Vec3> corner_normals;  // 3 per triangle, or empty (flat)
  std::vector<Vec2> corner_uvs;      // 3 per triangle, or empty
  std::vector<int> slots;            // per triangle, or empty
  // Per triangle with corner_normals: 1 for a flat-shaded one (its corners hold its face normal);
  // empty: none. True displacement recomputes them (shading/displacement.h).
  std::vector<uint8_t> flat;
  // True displacement (Geometry::set_displaced): the positions before it, which Generated reads
  // (Cycles' generated attribute is the undisplaced mesh's); empty otherwise.
  std::vector<Vec3> undisplaced;
  // Texture space (Blender's texspace_location and texspace_size): Generated = (p - loc) / (2 size) + 0.5.
  Vec3 texspace_location{0.0f}, texspace_size{1.0f};
  std::vector<MeshAttribute> attributes;
  // Deformation motion blur: motion_steps (0, or 2 to 129) sets of positions, equally spaced over
  // the shutter (vertex_count each, step by step), and of corner normals when the mesh has them.
  // positions stays the centre step's.
  int motion_steps = 0;
  std::vector<Vec3> motion_positions, motion_corner_normals;
  int users = 0;  // instances of the mesh (Cycles applies a single user's transform to its geometry)
  RTCScene rtc = nullptr;
  GeometryKind kind = GeometryKind::Triangles;
  CurveData curves;  // kind Curves or Points; slots then hold one slot per curve
  size_t triangle_count() const { return indices.size() / 3; }
  bool is_triangles() const { return kind == GeometryKind::Triangles; }
  const MeshAttribute* attribute(int id) const {
    for (const MeshAttribute& a : attributes)
      if (a.id == id) return &a;
    return nullptr;
  }
  // An attribute interpolated over triangle t at barycentrics (b1, b2) into out[0..3] (unused
  // components 0, alpha 1); false (out zero) when the mesh lacks it. Curves: t the segment, b1
  // its u (Cycles' curve_attribute_*: per-point values linear between the segment's keys);
  // points: t the point.
  bool interpolate(int id, int t, float b1, float b2, float out[4], int* components = nullptr) const;
};

// The object-space point at barycentrics (b1, b2) of triangle t before true displacement (what
// Generated reads); `displaced` (the point now) when the mesh was not displaced.
inline Vec3 undisplaced_point(const Mesh& m, int t, float b1, float b2, const Vec3& displaced) {
  if (m.undisplaced.empty()) return displaced;
  const uint32_t* i = &m.indices[3 * size_t(t)];
  return m.undisplaced[i[0]] * (1 - b1 - b2) + m.undisplaced[i[1]] * b1 + m.undisplaced[i[2]] * b2;
}

// Values an object carries for the Object Info and Attribute (object type) nodes.
struct InstanceAttribute {
  int id = -1;
  float value[4] = {0, 0, 0, 0};
};

// The visibility mask of a ray that sees only shadow catchers (Cycles' PATH_RAY_SHADOW_CATCHER_PASS
// rays, SHADOW_CATCHER_PATH_VISIBILITY): the kinds shifted past the 5 lt_visibility bits.
constexpr unsigned catcher_only_visibility(unsigned visibility) { return visibility << 8; }

// xf (the Pose) is the transform at the shutter's centre (time 0.5).
struct Instance : Pose {
  int mesh = -1;
  std::vector<int> materials;  // material id per slot
  unsigned visibility = 31;
  bool holdout = false;         // camera rays see it as Cycles' holdout objects (integrators/path_state.h)
  bool shadow_catcher = false;  // Cycles' Object.is_shadow_catcher (integrators/path.cpp's catcher split)
  int lightgroup = -1;          // the light group of its emission (-1: none)
  // Cycles' shadow terminator settings (geometry/terminator.h): Geometry Offset (0: off) and the
  // Shading Offset's cosine frequency multiplier 1 / (1 - offset / 2) (1: off).
  float terminator_geometry = 0, terminator_frequency = 1;
  // Object Info: Object.color, pass_index, and Cycles' random number of the instance.
  float color[4] = {1, 1, 1, 1};
  float pass_index = 0, random = 0;
  // Cryptomatte ids (cryptomatte_id of the object's and its asset's name hashes; 0: none).
  float crypto_object = 0, crypto_asset = 0;
  std::vector<InstanceAttribute> attributes;
  const InstanceAttribute* attribute(int id) const {
    for (const InstanceAttribute& a : attributes)
      if (a.id == id) return &a;
    return nullptr;
  }
  int material_for(int slot) const { return slot >= 0 && slot < int(materials.size()) ? materials[slot] : -1; }
  // Transform motion blur: 0, or 2 to 129 transforms equally spaced over the shutter (time 0 to
  // 1), the centre one xf; decomposed for interpolation (geometry/motion.h).
  std::vector<Transform> motion;
  std::vector<DecomposedTransform> motion_decomposed;
};

struct Bounds {
  Vec3 lo{INFINITY}, hi{-INFINITY};
  void extend(const Vec3& p) {
    lo = vmin(lo, p);
    hi = vmax(hi, p);
  }
  bool empty() const { return lo.x > hi.x; }
  bool contains(const Vec3& p) const {
    return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y && p.z <= hi.z;
  }
};

// Embree 3 traverses only rays whose origin and direction components lie within FLT_LARGE
// (RayK::valid() in its kernels/common/ray.h; Debian's build asserts on others). Geometry, lamps
// and cameras beyond it get a warning (Scene::commit, the camera), and rays outside it miss.
constexpr float kTraceableRange = 1.844e18f;
inline bool within_traceable_range(const Vec3& p) {
  return std::abs(p.x) <= kTraceableRange && std::abs(p.y) <= kTraceableRange && std::abs(p.z) <= kTraceableRange;
}

class Geometry {
 public:
  Geometry();
  ~Geometry();
  Geometry(const Geometry&) = delete;
  Geometry& operator=(const Geometry&) = delete;

  // Takes a validated mesh (see api/): drops degenerate triangles (at the centre step) and
  // reports them in warnings.
  int add_mesh(Mesh mesh, std::vector<std::string>& warnings);
  // An instance with motion whose transforms are not all finite and invertible (Embree's
  // instances need an inverse at every step) keeps its centre transform, with a warning.
  int add_instance(Instance instance, std::vector<std::string>& warnings);
  // Takes curves or points (mesh.kind, mesh.curves filled but for first_segment, arc and the
  // duplicated end points: given the keys and, per curve, offsets into them in `offsets`; with
  // motion, motion_cps holds motion_steps sets of the keys). Curves with a non-finite key (at any
  // step) or fewer than 2 keys, and non-finite or zero-radius points, are dropped and counted in
  // warnings; negative or non-finite radii become 0.
  int add_curves(Mesh mesh, const std::vector<uint32_t>& offsets, std::vector<std::string>& warnings);
  // True displacement, before the first commit: the mesh's new positions (and motion steps') and
  // corner normals (shading/displacement.h); it keeps its old positions in Mesh::undisplaced.
  void set_displaced(int mesh, std::vector<Vec3> positions, std::vector<Vec3> motion_positions,
                     std::vector<Vec3> corner_normals, std::vector<Vec3> motion_corner_normals);
  // Moves an instance (also after commit): the next commit rebuilds only the top-level BVH over
  // the meshes' existing BVHs.
  void set_instance_transform(int instance, const Transform& xf);
  // Replaces an instance's motion steps (also after commit; none: still at its transform), checked
  // as add_instance checks them; the next commit rebuilds the top level.
  void set_instance_motion(int instance, std::vector<Transform> motion, std::vector<std::string>& warnings);
  // The ray visibility, Object Info's colour and pass index and the object attributes of
  // `values`; nothing else. A changed visibility rebuilds the top level at the next commit.
  void set_instance_values(int instance, Instance&& values);
  // First call: builds every mesh's BVH and the top level; later calls rebuild the top level
  // if an instance moved, and nothing else.
  void commit();
  // How often mesh BVHs and the top-level BVH were built (tests and benchmarks of incremental
  // updates).
  uint64_t mesh_builds() const { return mesh_builds_; }
  uint64_t top_builds() const { return top_builds_; }

  // Closest hit among instances visible to rays of the given visibility bit. A ray outside
  // kTraceableRange, or beyond what an instance's object space holds (ray_origin_limit_), or with
  // a NaN direction or extent, hits nothing and is occluded.
  bool intersect(const Ray& ray, unsigned visibility, Hit* hit) const;
  // Any hit among instances visible to rays of the given visibility bit (default: those that cast
  // shadows).
  bool occluded(const Ray& ray, unsigned visibility = 16u) const;
  // The hits of a ray on one instance alone, nearest first, whatever else the ray meets (Cycles'
  // scene_intersect_local: the object's own BVH; hits at the same distance count once); stops
  // when visit(hit) returns false or after 256 queries. Embree tests a triangle's distance
  // against tmin before rounding it, so it may report a crossing at or below tmin again: such a
  // hit is not visited again (a Burley disk probe would weigh that exit once per visit), and tmin
  // moves on from where it was.
  template <class Visit>
  void local_hits(Ray ray, int instance, Visit visit) const {
    Hit hit;
    float last = -INFINITY;
    for (int k = 0; k < 256 && intersect_instance(ray, instance, &hit); ++k) {
      if (hit.t > last) {
        if (!visit(hit)) return;
        last = hit.t;
      }
      ray.tmin = std::nextafter(std::max(hit.t, ray.tmin), ray.tmax);
    }
  }
  // Closest hit on one instance alone (local_hits' step).
  bool intersect_instance(const Ray& ray, int instance, Hit* hit) const;
  // The hit's surface at the hit's time.
  SurfacePoint surface(const Hit& hit) const;
  // Whether the triangle touches another object's at p (find_contacts: in the box where they
  // overlap).
  bool touches(int instance, int primitive, const Vec3& p) const {
    if (size_t(instance) >= contacts_.size()) return false;  // before the first commit
    const auto& c = contacts_[size_t(instance)];
    if (c.empty()) return false;
    const auto it = std::lower_bound(c.begin(), c.end(), primitive,
                                     [](const std::pair<int, Bounds>& e, int prim) { return e.first < prim; });
    return it != c.end() && it->first == primitive && it->second.contains(p);
  }
  // The hit's material alone (surface(hit).material): whether a point needs shading at all is
  // asked before its surface is worked out (an opaque occluder of a shadow ray, a medium boundary).
  int material(const Hit& hit) const;
  // The origin of a next-event shadow ray from sp towards wi (the ray skips what hit.h's
  // skip_self says): leave_origin, or spawn_origin from the point moved first by the
  // instance's shadow terminator Geometry Offset on smooth-shaded triangles (Cycles'
  // shadow_ray_offset, geometry/terminator.h). n, ng: the shading normal (after a displacement's
  // bump) and geometric normal facing the incoming ray (Cycles' sd->N, sd->Ng). *moved: whether
  // the offset applied; the shadow ray then also decides which side of the triangle's plane the
  // light may lie on (Cycles evaluates the BSDF without a geometric test): the origin may sit
  // above the plane of a light just below it, which the offset exists to let through.
  Vec3 shadow_origin(const SurfacePoint& sp, const Vec3& n, const Vec3& ng, const Vec3& wi,
                     bool* moved = nullptr) const;
  // The instance's transform at time (0 .. 1 over the shutter).
  Pose pose(int instance, float time) const;
  // Whether anything moves or deforms (the render then draws a time per camera sample), and how
  // many instances and meshes do.
  bool has_motion() const { return motion_instances_ > 0 || motion_meshes_ > 0; }
  size_t motion_instances() const { return motion_instances_; }
  size_t motion_meshes() const { return motion_meshes_; }

  size_t mesh_count() const { return meshes_.size(); }
  size_t instance_count() const { return instances_.size(); }
  const Mesh& mesh(int i) const { return meshes_[i]; }
  const Instance& instance(int i) const { return instances_[i]; }
  // Whether some instance is a shadow catcher: only then do integrators split paths.
  bool has_shadow_catcher() const { return has_shadow_catcher_; }
  // The ray kinds (lt_visibility bits) that see an instance.
  unsigned instance_visibility(int i) const {
    return i >= 0 && size_t(i) < instance_visibility_.size() ? instance_visibility_[size_t(i)] : 31u;
  }
  Bounds bounds() const { return bounds_; }
  // Object-space corners of a mesh's triangle at time (a deforming mesh's interpolated).
  void object_corners(const Mesh& m, int prim, float time, Vec3* p0, Vec3* p1, Vec3* p2) const;
  // Object-space corner normals of a triangle of a smooth mesh at time (a deforming mesh's
  // interpolated, not normalised).
  void object_corner_normals(const Mesh& m, int prim, float time, Vec3 n[3]) const;
  // World-space triangle corners of an instance's triangle at time (0 .. 1 over the shutter).
  void triangle(int instance, int prim, Vec3* p0, Vec3* p1, Vec3* p2, float time = 0.5f) const;

 private:
  RTCDevice device_ = nullptr;
  RTCScene top_ = nullptr;
  std::vector<Mesh> meshes_;
  std::vector<Instance> instances_;
  std::vector<unsigned> instance_visibility_;
  // Embree's top-level geometry ids are the instances' indices, then a moving instance's further
  // motion segments (attach_moving): those segments' instances, and every id's visibility.
  std::vector<unsigned> segment_instance_, rtc_visibility_;
  void attach_moving(RTCScene object, const Instance& inst, unsigned id, bool lone);
  // Instances whose transform flattens the mesh (zero scale on an axis: no inverse, which Embree's
  // instancing needs), or whose inverse would take rays beyond what Embree traverses (a scale
  // below 1e-8, an extreme shear), are traced through a copy of the mesh baked into world space,
  // rebuilt when the transform changes (Cycles 3.4 renders flattened objects black); so are
  // moving instances that do not turn, at each motion step (bakes_motion in geometry.cpp).
  struct Baked {
    RTCScene rtc = nullptr;
    std::vector<Transform> steps;  // the transform, or the motion steps, it was baked with
  };
  std::vector<Baked> baked_;  // per instance
  // Embree takes a ray into an instance's object space by the inverse transform and needs it
  // within kTraceableRange there too: world rays are kept within these limits, set by build_top
  // from the largest inverse among Embree's instances (instances whose inverse is larger than
  // kMaxInverseNorm are baked instead, so the limits stay far beyond any scene's size).
  float ray_origin_limit_ = kTraceableRange, ray_direction_limit_ = kTraceableRange;
  bool traceable(const Ray& r) const;
  void set_ray_visibility(size_t i);
  Bounds bounds_;
  bool partial_visibility_ = false;
  bool has_shadow_catcher_ = false;
  bool committed_ = false, top_dirty_ = false;
  uint64_t mesh_builds_ = 0, top_builds_ = 0;
  size_t motion_instances_ = 0, motion_meshes_ = 0;
  uint64_t generation_;  // pose()'s per-thread cache key: new for each geometry and edit
  void build_top();
  // The triangles that lie in another object's triangle's plane and overlap it (in contact: a
  // glass resting on a table, the table under it), per instance (empty: none), sorted by
  // primitive, each with the box where they overlap; rays leaving them there meet what touches
  // them (hit.h, leave). Found at each top-level build (find_contacts).
  std::vector<std::vector<std::pair<int, Bounds>>> contacts_;
  void find_contacts();
  // steps sets of positions (vertex_count each, step by step): Embree's vertex motion, from
  // every stride-th step.
  RTCScene triangle_scene(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices, int steps = 1,
                          int stride = 1) const;
  RTCScene curve_scene(const Mesh& mesh) const;
  SurfacePoint curve_surface(const Hit& hit, const Instance& inst, const Mesh& m) const;
  // A primitive's material slot: a triangle's, a strand segment's curve's (that curve in *curve), a
  // point's (0: one slot).
  int slot_of(const Mesh& m, int primitive, int* curve = nullptr) const;
  RTCScene baked_scene(int instance);
};

}  // namespace lt
