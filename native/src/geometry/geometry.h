// Triangle meshes and their instances in an Embree 3 two-level BVH. Integrators reach geometry
// only through intersect(), occluded() and surface().
#pragma once

#include <embree3/rtcore.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/math.h"
#include "geometry/hit.h"

namespace lt {

// A named per-corner attribute (UV map, colour, generic values, tangent with its sign); the
// add-on turns names into ids per scene. components 1-4, 3 corners per triangle.
struct MeshAttribute {
  int id = -1;
  int components = 0;
  std::vector<float> values;  // components per corner
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
  size_t curve_count() const { return first_segment.empty() ? 0 : first_segment.size() - 1; }
  int curve_of_segment(uint32_t segment) const;  // binary search over first_segment
  Vec3 point(size_t cp) const { return {cps[4 * cp], cps[4 * cp + 1], cps[4 * cp + 2]}; }
  float radius(size_t cp) const { return cps[4 * cp + 3]; }
};
// The Catmull-Rom point at u in [0, 1] of the segment starting at control point i, its
// derivative and radius (Embree's and Cycles' uniform basis).
void catmull_rom(const CurveData& c, uint32_t i, float u, Vec3* p, Vec3* dp, float* radius);

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;     // 3 per triangle
  std::vector<Vec3> corner_normals;  // 3 per triangle, or empty (flat)
  std::vector<Vec2> corner_uvs;      // 3 per triangle, or empty
  std::vector<int> slots;            // per triangle, or empty
  // Texture space (Blender's texspace_location and texspace_size): Generated = (p - loc) / (2 size) + 0.5.
  Vec3 texspace_location{0.0f}, texspace_size{1.0f};
  std::vector<MeshAttribute> attributes;
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
  // components 0, alpha 1); false (out zero) when the mesh lacks it.
  bool interpolate(int id, int t, float b1, float b2, float out[4], int* components = nullptr) const;
};

// Values an object carries for the Object Info and Attribute (object type) nodes.
struct InstanceAttribute {
  int id = -1;
  float value[4] = {0, 0, 0, 0};
};

struct Instance {
  int mesh = -1;
  Transform xf;
  std::vector<int> materials;  // material id per slot
  unsigned visibility = 31;
  bool flipped = false;  // negative determinant: winding flips the geometric normal
  // Object Info: Object.color, pass_index, and Cycles' random number of the instance.
  float color[4] = {1, 1, 1, 1};
  float pass_index = 0, random = 0;
  std::vector<InstanceAttribute> attributes;
  const InstanceAttribute* attribute(int id) const {
    for (const InstanceAttribute& a : attributes)
      if (a.id == id) return &a;
    return nullptr;
  }
  Vec3 normal_rows[3];  // inverse transpose of the linear part (up to scale), for normals
  Vec3 normal_to_world(const Vec3& n) const {
    return {dot(normal_rows[0], n), dot(normal_rows[1], n), dot(normal_rows[2], n)};
  }
  // The inverse of normal_to_world up to scale: the linear part's transpose.
  Vec3 normal_to_object(const Vec3& n) const {
    const float* m = xf.m;
    return {m[0] * n.x + m[4] * n.y + m[8] * n.z, m[1] * n.x + m[5] * n.y + m[9] * n.z,
            m[2] * n.x + m[6] * n.y + m[10] * n.z};
  }
  int material_for(int slot) const { return slot >= 0 && slot < int(materials.size()) ? materials[slot] : -1; }
};

struct Bounds {
  Vec3 lo{INFINITY}, hi{-INFINITY};
  void extend(const Vec3& p) {
    lo = vmin(lo, p);
    hi = vmax(hi, p);
  }
  bool empty() const { return lo.x > hi.x; }
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

  // Takes a validated mesh (see api/): drops degenerate triangles and reports them in warnings.
  int add_mesh(Mesh mesh, std::vector<std::string>& warnings);
  // Takes curves or points (mesh.kind, mesh.curves filled but for first_segment, arc and the
  // duplicated end points: given the keys and, per curve, offsets into them in `offsets`).
  // Curves with a non-finite key or fewer than 2 keys, and non-finite or zero-radius points, are
  // dropped and counted in warnings; negative or non-finite radii become 0.
  int add_curves(Mesh mesh, const std::vector<uint32_t>& offsets, std::vector<std::string>& warnings);
  int add_instance(Instance instance);
  // Moves an instance (also after commit): the next commit rebuilds only the top-level BVH over
  // the meshes' existing BVHs.
  void set_instance_transform(int instance, const Transform& xf);
  // First call: builds every mesh's BVH and the top level; later calls rebuild the top level
  // if an instance moved, and nothing else.
  void commit();
  // How often mesh BVHs and the top-level BVH were built (tests and benchmarks of incremental
  // updates).
  uint64_t mesh_builds() const { return mesh_builds_; }
  uint64_t top_builds() const { return top_builds_; }

  // Closest hit among instances visible to rays of the given visibility bit. A ray outside
  // kTraceableRange (or with a NaN direction or extent) hits nothing and is occluded.
  bool intersect(const Ray& ray, unsigned visibility, Hit* hit) const;
  // Any hit among instances that cast shadows.
  bool occluded(const Ray& ray) const;
  SurfacePoint surface(const Hit& hit) const;

  size_t mesh_count() const { return meshes_.size(); }
  size_t instance_count() const { return instances_.size(); }
  const Mesh& mesh(int i) const { return meshes_[i]; }
  const Instance& instance(int i) const { return instances_[i]; }
  Bounds bounds() const { return bounds_; }
  // World-space triangle corners of an instance's triangle.
  void triangle(int instance, int prim, Vec3* p0, Vec3* p1, Vec3* p2) const;

 private:
  RTCDevice device_ = nullptr;
  RTCScene top_ = nullptr;
  std::vector<Mesh> meshes_;
  std::vector<Instance> instances_;
  std::vector<unsigned> rtc_to_instance_;  // Embree instance geometry id -> our instance index
  std::vector<unsigned> instance_visibility_;
  // Instances whose transform flattens the mesh (zero scale on an axis: no inverse, which Embree's
  // instancing needs) are traced through a copy of the mesh baked into world space, rebuilt when
  // the transform changes (Cycles 3.4 renders such objects black).
  struct Baked {
    RTCScene rtc = nullptr;
    Transform xf;
  };
  std::vector<Baked> baked_;  // per instance
  Bounds bounds_;
  bool partial_visibility_ = false;
  bool committed_ = false, top_dirty_ = false;
  uint64_t mesh_builds_ = 0, top_builds_ = 0;
  void build_top();
  RTCScene triangle_scene(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices) const;
  RTCScene curve_scene(const Mesh& mesh) const;
  SurfacePoint curve_surface(const Hit& hit, const Instance& inst, const Mesh& m) const;
  RTCScene baked_scene(int instance);
};

}  // namespace lt
