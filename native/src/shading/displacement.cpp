#include "shading/displacement.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace lt {

namespace {

Vec3 normalized_or(const Vec3& v, const Vec3& fallback) {
  const float l = length(v);
  return l > 0 && std::isfinite(l) ? v / l : fallback;
}

const Vec3* corners_of(const Mesh& m, const std::vector<Vec3>& p, size_t t, Vec3 out[3]) {
  for (int c = 0; c < 3; ++c) out[c] = p[m.indices[3 * t + size_t(c)]];
  return out;
}

// Cycles' compute_face_normal (mesh_displace.cpp): (1, 0, 0) for a triangle without area.
Vec3 face_normal(const Vec3 q[3]) { return normalized_or(cross(q[1] - q[0], q[2] - q[0]), Vec3(1, 0, 0)); }

// Blender's vertex normals (angle-weighted face normals, BKE_mesh_normals): what Cycles'
// displacement reads at a flat face's vertex, for which Lantern keeps no smooth normal. Over
// triangles, which weighs a planar polygon's corners as Blender does.
std::vector<Vec3> vertex_normals(const Mesh& m) {
  std::vector<Vec3> n(m.positions.size(), Vec3(0.0f));
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    Vec3 q[3];
    corners_of(m, m.positions, t, q);
    const Vec3 fn = normalized_or(cross(q[1] - q[0], q[2] - q[0]), Vec3(0.0f));
    for (int c = 0; c < 3; ++c) {
      const Vec3 a = normalized_or(q[(c + 1) % 3] - q[c], Vec3(0.0f)),
                 b = normalized_or(q[(c + 2) % 3] - q[c], Vec3(0.0f));
      n[m.indices[3 * t + size_t(c)]] += fn * std::acos(clamp(dot(a, b), -1.0f, 1.0f));
    }
  }
  for (Vec3& v : n) v = normalized_or(v, Vec3(0, 0, 1));
  return n;
}

bool smooth_triangle(const Mesh& m, size_t t) { return !m.corner_normals.empty() && (m.flat.empty() || !m.flat[t]); }

}  // namespace

std::vector<Vec3> displacement_offsets(const Mesh& mesh, const Instance& inst,
                                       const std::vector<const Material*>& triangle_materials,
                                       const std::vector<std::unique_ptr<Image>>& images) {
  const size_t nv = mesh.positions.size(), nt = mesh.triangle_count();
  // Each vertex's corner: the first displacing triangle holding it (Cycles' fill_shader_input).
  std::vector<int64_t> corner(nv, -1);
  bool flat_corners = false;
  for (size_t t = 0; t < nt; ++t) {
    if (!triangle_materials[t]) continue;
    for (int c = 0; c < 3; ++c) {
      int64_t& at = corner[mesh.indices[3 * t + size_t(c)]];
      if (at >= 0) continue;
      at = int64_t(3 * t) + c;
      flat_corners = flat_corners || !smooth_triangle(mesh, t);
    }
  }
  const std::vector<Vec3> vn = flat_corners ? vertex_normals(mesh) : std::vector<Vec3>();
  const Pose& pose = inst;  // the transform at the shutter's centre, Cycles' time 0.5
  const Transform to_object = affine_inverse(inst.xf);
  std::vector<Vec3> offsets(nv, Vec3(0.0f));
  tbb::parallel_for(size_t(0), nv, [&](size_t v) {
    if (corner[v] < 0) return;
    const size_t t = size_t(corner[v]) / 3;
    const int c = int(corner[v] % 3);
    Vec3 q[3];
    corners_of(mesh, mesh.positions, t, q);
    // Cycles' shader_setup_from_displace: the corner's point with the smooth normal forced, the
    // face's normal as Ng, I = N, no ray.
    ShadingContext ctx;
    ctx.pose = pose;
    ctx.mesh = &mesh;
    ctx.instance = &inst;
    ctx.primitive = int(t);
    ctx.bary = c == 1 ? Vec2{1, 0} : (c == 2 ? Vec2{0, 1} : Vec2{0, 0});
    ctx.object_P = mesh.positions[v];
    ctx.P = inst.xf.point(ctx.object_P);
    const Vec3 g = (ctx.object_P - mesh.texspace_location) / (2.0f * mesh.texspace_size);
    ctx.generated = Vec3(g.x + 0.5f, g.y + 0.5f, g.z + 0.5f);
    if (!mesh.corner_uvs.empty()) ctx.uv = mesh.corner_uvs[size_t(corner[v])];
    ctx.Ng = normalized_or(pose.normal_to_world(cross(q[1] - q[0], q[2] - q[0])), Vec3(0, 0, 1));
    const Vec3 n = smooth_triangle(mesh, t) ? mesh.corner_normals[size_t(corner[v])] : vn[v];
    const Vec3 N = normalized_or(pose.normal_to_world(n), ctx.Ng);
    set_shading_normal(&ctx, N);
    ctx.I = N;
    ctx.camera_ray = false;
    ctx.ray_length = 0;
    for (ShadingContext::Offset& o : ctx.offset) o = ShadingContext::Offset{};
    const Program& program = *triangle_materials[t]->displacement();
    // kernel_displace: the offset back in object space; Cycles' ensure_finite per component.
    Vec3 d = to_object.vector(program.displacement(ctx, images));
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(d[k])) d[k] = 0;
    offsets[v] = d;
  });
  return offsets;
}

std::vector<Vec3> displaced_corner_normals(const Mesh& m, const std::vector<Vec3>& p,
                                           const std::vector<Vec3>& corner_normals,
                                           const std::vector<uint8_t>& true_triangles) {
  if (corner_normals.empty()) return {};  // every face flat: the geometric normal, as Cycles'
  const size_t nt = m.triangle_count();
  std::vector<Vec3> fn(nt), vn(p.size(), Vec3(0.0f));
  std::vector<uint8_t> touched(p.size(), 0);
  for (size_t t = 0; t < nt; ++t) {
    Vec3 q[3];
    fn[t] = face_normal(corners_of(m, p, t, q));
    if (!true_triangles[t]) continue;
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = m.indices[3 * t + size_t(c)];
      vn[v] += fn[t];  // Cycles sums the face normals unweighted
      touched[v] = 1;
    }
  }
  std::vector<Vec3> out = corner_normals;
  for (size_t t = 0; t < nt; ++t)
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = m.indices[3 * t + size_t(c)];
      Vec3& n = out[3 * t + size_t(c)];
      if (!smooth_triangle(m, t))
        n = fn[t];
      else if (touched[v])
        n = normalized_or(vn[v], fn[t]);
    }
  return out;
}

void displace_meshes(Geometry& geometry, const std::vector<Material>& materials,
                     const std::vector<std::unique_ptr<Image>>& images) {
  auto displaces = [&](int mat) {
    return mat >= 0 && mat < int(materials.size()) &&
           materials[size_t(mat)].displacement_method() != DisplacementMethod::None;
  };
  bool any_material = false;
  for (size_t m = 0; m < materials.size(); ++m) any_material = any_material || displaces(int(m));
  if (!any_material) return;  // the common case: nothing to look at
  std::vector<int> first(geometry.mesh_count(), -1);
  for (size_t i = 0; i < geometry.instance_count(); ++i) {
    int& f = first[size_t(geometry.instance(int(i)).mesh)];
    if (f < 0) f = int(i);
  }
  for (size_t id = 0; id < geometry.mesh_count(); ++id) {
    const Mesh& mesh = geometry.mesh(int(id));
    if (first[id] < 0 || !mesh.is_triangles() || !mesh.rtc) continue;
    const Instance& inst = geometry.instance(first[id]);
    bool any_slot = false;
    for (int mat : inst.materials) any_slot = any_slot || displaces(mat);
    if (!any_slot) continue;
    const size_t nt = mesh.triangle_count();
    std::vector<const Material*> displacing(nt, nullptr);
    std::vector<uint8_t> true_triangles(nt, 0);
    bool any = false;
    for (size_t t = 0; t < nt; ++t) {
      const int mat = inst.material_for(mesh.slots.empty() ? 0 : mesh.slots[t]);
      if (!displaces(mat)) continue;
      const Material& m = materials[size_t(mat)];
      displacing[t] = &m;
      true_triangles[t] = m.displacement_method() == DisplacementMethod::True;
      any = true;
    }
    if (!any) continue;
    const std::vector<Vec3> offsets = displacement_offsets(mesh, inst, displacing, images);
    std::vector<Vec3> positions = mesh.positions, motion_positions = mesh.motion_positions;
    const size_t nv = positions.size();
    for (size_t v = 0; v < nv; ++v) positions[v] += offsets[v];
    for (size_t k = 0; k < motion_positions.size(); ++k) motion_positions[k] += offsets[k % nv];
    std::vector<Vec3> normals = displaced_corner_normals(mesh, positions, mesh.corner_normals, true_triangles);
    // A deforming mesh: every step moves by the centre's offsets (Cycles' read_shader_output), its
    // normals recomputed from the step's positions.
    std::vector<Vec3> motion_normals;
    if (!mesh.motion_corner_normals.empty()) {
      for (int s = 0; s < mesh.motion_steps; ++s) {
        const std::vector<Vec3> p(motion_positions.begin() + long(s * nv),
                                  motion_positions.begin() + long((s + 1) * nv));
        const std::vector<Vec3> cn(mesh.motion_corner_normals.begin() + long(3 * s * nt),
                                   mesh.motion_corner_normals.begin() + long(3 * (s + 1) * nt));
        const std::vector<Vec3> n = displaced_corner_normals(mesh, p, cn, true_triangles);
        motion_normals.insert(motion_normals.end(), n.begin(), n.end());
      }
    }
    geometry.set_displaced(int(id), std::move(positions), std::move(motion_positions), std::move(normals),
                           std::move(motion_normals));
  }
}

}  // namespace lt
