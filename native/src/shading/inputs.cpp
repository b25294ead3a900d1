#include "shading/inputs.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "geometry/geometry.h"
#include "shading/bsdf.h"
#include "shading/image.h"
#include "shading/material.h"

namespace lt {

namespace {

const OpSignature kSignatures[] = {
    {"", "vvvvvvv", "tti", false},      // texture coordinate
    {"", "vvvvvvfff", "i", false},      // geometry
    {"v", "vf", "gi", false},           // image
    {"fv", "f", "", false},             // fresnel
    {"fv", "ff", "", false},            // layer weight
    {"", "ffffffffffffff", "", false},  // light path
    {"v", "f", "i", true},              // to float
    {"f", "v", "", true},               // to vector
    {"", "vff", "iii", false},          // attribute
    {"", "v", "iii", false},            // tangent
    {"fv", "v", "ii", false},           // normal map
    {"", "vvfff", "", false},           // object info
    {"fffffv", "v", "i", false},        // bump
    {"", "vff", "t", false},            // camera data
    {"ff", "fff", "", false},           // light falloff
    {"v", "vf", "giii", false},         // image, other projections
    {"v", "v", "iiit", false},          // vector transform
    {"v", "", "", false},               // set normal
    {"fffv", "v", "i", false},          // displacement
    {"vff", "v", "ii", false},          // vector displacement
    {"v", "vf", "gii", false},          // environment
    {"f", "f", "ii", false},            // wireframe
    {"vfv", "vf", "ii", false},         // ambient occlusion
    {"fv", "v", "i", false},            // bevel
};

Vec3 normal_or_default(const Machine& m, uint32_t operand) {
  Vec3 n = m.v(operand);
  return dot(n, n) > 0 ? n : m.ctx->N;
}

// A table's matrix rows applied to a point (12 floats: 3 rows of 4).
Vec3 affine(const float* t, const Vec3& p) {
  return {t[0] * p.x + t[1] * p.y + t[2] * p.z + t[3], t[4] * p.x + t[5] * p.y + t[6] * p.z + t[7],
          t[8] * p.x + t[9] * p.y + t[10] * p.z + t[11]};
}

// Cycles' fresnel_dielectric_cos: unpolarised Fresnel reflectance, 1 beyond the critical angle.
float fresnel_cos(float cosi, float eta) {
  const float c = std::abs(cosi);
  float g = eta * eta - 1 + c * c;
  if (!(g > 0)) return 1.0f;
  g = std::sqrt(g);
  const float a = (g - c) / (g + c), b = (c * (g + c) - 1) / (c * (g - c) + 1);
  return 0.5f * a * a * (1 + b * b);
}

void tex_coord(const Instr& in, Machine& m) {
  const ShadingContext& c = m.at(in.param[2]);
  m.set(in.out[0], c.generated);
  m.set(in.out[1], c.object_normal());
  m.set(in.out[2], Vec3(c.uv.x, c.uv.y, 0.0f));
  const float* object = m.k + in.param[0];
  m.set(in.out[3], object[0] == 12 ? affine(object + 1, c.P) : c.object_P);
  const float* camera = m.k + in.param[1];
  if (camera[0] == 28) {
    // A world ray's P is its direction: Cycles' Camera and Window read the point that far from the
    // camera (svm_node_tex_coord, camera_world_to_ndc). The camera's position: -R^T t.
    const float* r = camera + 1;
    const Vec3 P = c.background
                       ? c.P - Vec3(r[0] * r[3] + r[4] * r[7] + r[8] * r[11], r[1] * r[3] + r[5] * r[7] + r[9] * r[11],
                                    r[2] * r[3] + r[6] * r[7] + r[10] * r[11])
                       : c.P;
    m.set(in.out[4], affine(camera + 1, P));
    // Cycles' Window output: the NDC position (x, y in [0, 1] across the frame), z 0.
    const float* p = camera + 13;
    const float x = p[0] * P.x + p[1] * P.y + p[2] * P.z + p[3];
    const float y = p[4] * P.x + p[5] * P.y + p[6] * P.z + p[7];
    const float w = p[12] * P.x + p[13] * P.y + p[14] * P.z + p[15];
    m.set(in.out[5], w != 0 ? Vec3(x / w, y / w, 0.0f) : Vec3(0.0f));
  } else {
    m.set(in.out[4], Vec3(0.0f));
    m.set(in.out[5], Vec3(0.0f));
  }
  // Without an object Cycles' Reflection is I.
  m.set(in.out[6], c.background ? c.I : 2.0f * dot(c.N, c.I) * c.N - c.I);
}

// An attribute at the shading point: 4 floats (unused ones 0, alpha 1) and its component count
// (0: missing).
int fetch_attribute(const ShadingContext& c, int domain, int id, float v[4]) {
  v[0] = v[1] = v[2] = 0;
  v[3] = 1;
  if (domain == 1) {
    const InstanceAttribute* a = c.instance ? c.instance->attribute(id) : nullptr;
    if (!a) return 0;
    std::copy(a->value, a->value + 4, v);
    return 4;
  }
  int n = 0;
  if (c.mesh) c.mesh->interpolate(id, c.primitive, c.bary.x, c.bary.y, v, &n);
  v[3] = n == 4 ? v[3] : 1.0f;
  return n;
}

// Cycles' svm_node_attr (and svm_node_vertex_color for domain 2: a missing one has alpha 0).
void attribute(const Instr& in, Machine& m) {
  const int domain = int(in.param[1]);
  float v[4];
  const int n = fetch_attribute(m.at(in.param[2]), domain == 1 ? 1 : 0, int(in.param[0]), v);
  Vec3 vec(v[0], v[1], v[2]);
  float fac = (v[0] + v[1] + v[2]) * (1.0f / 3.0f);
  if (n == 1) {
    vec = Vec3(v[0]);
    fac = v[0];
  } else if (n == 2) {
    fac = v[0];
  } else if (n == 0) {
    fac = 0;
    v[3] = domain == 2 ? 0.0f : 1.0f;
  }
  m.set(in.out[0], vec);
  m.set(in.out[1], fac);
  m.set(in.out[2], v[3]);
}

Vec3 normalized_or_zero(const Vec3& v) {
  const float l = length(v);
  return l > 0 && std::isfinite(l) ? v / l : Vec3(0.0f);
}

// Cycles' svm_node_tangent: a UV map's tangent or one around an axis of Generated, made normal to N.
void tangent(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  Vec3 t;
  if (in.param[0] == 1) {
    float v[4];
    if (fetch_attribute(c, 0, int(in.param[2]), v) == 0 || !c.instance) {
      m.set(in.out[0], Vec3(0.0f));
      return;
    }
    t = Vec3(v[0], v[1], v[2]);
  } else {
    const Vec3 g = c.generated - Vec3(0.5f);
    t = in.param[1] == 0 ? Vec3(0.0f, -g.z, g.y) : in.param[1] == 1 ? Vec3(-g.z, 0.0f, g.x) : Vec3(-g.y, g.x, 0.0f);
  }
  if (c.instance) t = normalized_or_zero(c.pose.normal_to_world(t));
  const Vec3 r = cross(c.N, normalize(cross(t, c.N)));
  m.set(in.out[0], is_finite(r) ? r : Vec3(0.0f));
}

// Cycles' svm_node_normal_map (kernel/svm/tex_coord.h).
void normal_map(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  const Vec3 rgb = m.v(in.in[1]);
  Vec3 color = 2.0f * (rgb - Vec3(0.5f));
  const uint32_t space = in.param[0];
  Vec3 N;
  if (space == 0) {
    float t[4];
    if (!c.mesh || !c.instance || fetch_attribute(c, 0, int(in.param[1]), t) != 4) {
      m.set(in.out[0], c.N);  // no tangents: the unperturbed normal
      return;
    }
    const Vec3 tangent(t[0], t[1], t[2]);
    const float sign = t[3];
    // Object space, not normalised; a flat face's geometric normal before facing the ray.
    Vec3 normal;
    const Mesh& mesh = *c.mesh;
    if (!mesh.corner_normals.empty()) {
      const Vec3* cn = &mesh.corner_normals[3 * size_t(c.primitive)];
      normal = cn[0] * (1 - c.bary.x - c.bary.y) + cn[1] * c.bary.x + cn[2] * c.bary.y;
    } else {
      normal = normalized_or_zero(c.pose.normal_to_object(c.backfacing ? -c.Ng : c.Ng));
    }
    const Vec3 B = sign * cross(normal, tangent);
    N = normalized_or_zero(color.x * tangent + color.y * B + color.z * normal);
    N = normalized_or_zero(c.pose.normal_to_world(N));
  } else {
    if (space == 3 || space == 4) {  // Blender's convention: Y and Z flipped
      color.y = -color.y;
      color.z = -color.z;
    }
    N = (space == 1 || space == 3) && c.instance ? normalized_or_zero(c.pose.normal_to_world(color))
                                                 : normalized_or_zero(color);
  }
  if (c.backfacing) N = -N;
  float strength = m.f(in.in[0]);
  if (strength != 1.0f) {
    strength = std::max(strength, 0.0f);
    N = normalized_or_zero(c.N + (N - c.N) * strength);
  }
  if (!(dot(N, N) > 0)) N = c.N;
  m.set(in.out[0], N);
}

// Cycles' svm_node_object_info.
void object_info(const Instr& in, Machine& m) {
  const Instance* inst = m.ctx->instance;
  if (!inst) {
    m.set(in.out[0], Vec3(0.0f));
    m.set(in.out[1], Vec3(0.0f));
    for (int k = 2; k < 5; ++k) m.set(in.out[k], 0.0f);
    return;
  }
  m.set(in.out[0], Vec3(inst->xf.m[3], inst->xf.m[7], inst->xf.m[11]));
  m.set(in.out[1], Vec3(inst->color[0], inst->color[1], inst->color[2]));
  m.set(in.out[2], inst->color[3]);
  m.set(in.out[3], inst->pass_index);
  m.set(in.out[4], inst->random);
}

// The inverse of an instance's linear part applied to v (rows of the inverse: the columns' cross
// products over the determinant); v itself when singular.
Vec3 inverse_linear(const Transform& t, const Vec3& v) {
  const Vec3 c0 = t.column(0), c1 = t.column(1), c2 = t.column(2);
  const float det = t.determinant();
  if (!(std::abs(det) > 0)) return v;
  return Vec3(dot(cross(c1, c2), v), dot(cross(c2, c0), v), dot(cross(c0, c1), v)) / det;
}

// Cycles 3.4's svm_node_set_bump (Mikkelsen's bump mapping from finite differences): the heights at
// the point and moved by the footprint's two differentials in the surface, scaled by Distance.
void bump(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  Vec3 n_in = normal_or_default(m, in.in[5]);
  Vec3 dx, dy;
  orthonormals(c.Ng, &dx, &dy);
  dx *= c.footprint;
  dy *= c.footprint;
  const bool object_space = (in.param[0] & 2) && c.instance;
  if (object_space) {
    n_in = normalized_or_zero(c.pose.normal_to_object(n_in));
    dx = inverse_linear(c.pose.xf, dx);
    dy = inverse_linear(c.pose.xf, dy);
  }
  const Vec3 rx = cross(dy, n_in), ry = cross(n_in, dx);
  const float hc = m.f(in.in[2]), hx = m.f(in.in[3]), hy = m.f(in.in[4]);
  const float det = dot(dx, rx);
  const Vec3 surfgrad = (hx - hc) * rx + (hy - hc) * ry;
  const float scale = (in.param[0] & 1) ? -m.f(in.in[1]) : m.f(in.in[1]);
  const float strength = std::max(m.f(in.in[0]), 0.0f);
  Vec3 out = std::abs(det) * n_in - scale * (det < 0 ? -1.0f : (det > 0 ? 1.0f : 0.0f)) * surfgrad;
  const float len = length(out);
  out = len > 0 && std::isfinite(len) ? normalize(strength * (out / len) + (1 - strength) * n_in) : n_in;
  if (object_space) out = normalized_or_zero(c.pose.normal_to_world(out));
  const Vec3 tilted = ensure_valid_reflection(c.Ng, c.I, out);
  m.set(in.out[0], tilted);
  if (m.bumps < Machine::kMaxBumps) {
    m.bump_out[m.bumps] = tilted;
    m.bump_raw[m.bumps++] = out;
  }
}

// Cycles' svm_node_enter_bump_eval: P at the undisplaced mesh's point (its position attribute
// ATTR_STD_POSITION_UNDISPLACED), dP the compact footprint of that attribute's differentials
// (the same barycentric moves over the undisplaced triangle); the moved copies follow.
void bump_eval(const Instr& in, Machine& m) {
  if (!m.undisplaced) return;
  if (in.param[0] == 1) {
    if (m.entered[0]) {
      m.ctx = m.entered[0];
      for (int k = 0; k < 2; ++k) m.bumped[k] = m.entered[k + 1];
      m.entered[0] = nullptr;
    }
    return;
  }
  const ShadingContext& c = *m.ctx;
  if (m.entered[0] || !c.mesh || c.mesh->undisplaced.empty() || c.primitive < 0 || !c.mesh->is_triangles()) return;
  const Mesh& mesh = *c.mesh;
  const uint32_t* tri = &mesh.indices[3 * size_t(c.primitive)];
  const Vec3 u0 = mesh.undisplaced[tri[0]], e1 = mesh.undisplaced[tri[1]] - u0, e2 = mesh.undisplaced[tri[2]] - u0;
  ShadingContext* u = m.undisplaced;
  u[0] = c;
  u[0].object_P = u0 + e1 * c.bary.x + e2 * c.bary.y;
  u[0].P = c.pose.xf.point(u[0].object_P);
  float footprint = 0;
  for (int k = 0; k < 2; ++k) {
    const Vec2& b = c.offset[k].bary;
    footprint += 0.5f * length(c.pose.xf.vector(e1 * b.x + e2 * b.y));
  }
  const float ratio = c.footprint > 0 ? footprint / c.footprint : 0.0f;
  u[0].footprint = footprint;
  for (int k = 0; k < 2; ++k) {
    u[0].offset[k].P = c.offset[k].P * ratio;  // along the displaced surface's frame, as Cycles'
    u[0].offset[k].object_P = c.offset[k].object_P * ratio;
  }
  m.entered[0] = m.ctx;
  m.ctx = &u[0];
  for (int k = 0; k < 2; ++k) {
    m.entered[k + 1] = m.bumped[k];
    if (!m.bumped[k]) continue;
    u[k + 1] = *m.bumped[k];
    u[k + 1].P = u[0].P + u[0].offset[k].P;
    u[k + 1].object_P = u[0].object_P + u[0].offset[k].object_P;
    u[k + 1].footprint = footprint;
    m.bumped[k] = &u[k + 1];
  }
}

// Cycles' svm_node_tex_image_box: the object-space normal's components pick (and near the edges of
// the cube's faces, blend) three planar lookups, mapped so that no face is mirrored.
void image_box(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  const Image& image = *(*m.images)[in.param[0]];
  const bool unassociate = in.param[1] != 0;
  float blend;
  std::memcpy(&blend, &in.param[3], 4);
  const Vec3 signed_N = c.instance ? normalized_or_zero(c.pose.normal_to_object(c.N)) : c.N;
  Vec3 N(std::abs(signed_N.x), std::abs(signed_N.y), std::abs(signed_N.z));
  const float sum = N.x + N.y + N.z;
  N = sum > 0 ? N / sum : Vec3(1.0f, 0.0f, 0.0f);
  Vec3 w(0.0f);
  const float limit = 0.5f * (1.0f + blend);
  if (N.x > limit * (N.x + N.y) && N.x > limit * (N.x + N.z)) {
    w.x = 1;
  } else if (N.y > limit * (N.x + N.y) && N.y > limit * (N.y + N.z)) {
    w.y = 1;
  } else if (N.z > limit * (N.x + N.z) && N.z > limit * (N.y + N.z)) {
    w.z = 1;
  } else if (blend > 0) {
    if (N.z < (1 - limit) * (N.y + N.x)) {  // between two faces
      w.x = clamp((N.x / (N.x + N.y) - 0.5f * (1 - blend)) / blend, 0.0f, 1.0f);
      w.y = 1 - w.x;
    } else if (N.x < (1 - limit) * (N.y + N.z)) {
      w.y = clamp((N.y / (N.y + N.z) - 0.5f * (1 - blend)) / blend, 0.0f, 1.0f);
      w.z = 1 - w.y;
    } else if (N.y < (1 - limit) * (N.x + N.z)) {
      w.x = clamp((N.x / (N.x + N.z) - 0.5f * (1 - blend)) / blend, 0.0f, 1.0f);
      w.z = 1 - w.x;
    } else {  // all three
      w = ((2 - limit) * N + Vec3(limit - 1)) / (2 * limit - 1);
    }
  } else {
    w.x = 1;  // Cycles' fallback where no face wins
  }
  const Vec3 co = m.v(in.in[0]);
  Vec3 color(0.0f);
  float alpha = 0;
  auto add = [&](float weight, float u, float v) {
    if (!(weight > 0)) return;
    color += weight * image.lookup(Vec2{u, v}, unassociate);
    alpha += weight * image.lookup_alpha(Vec2{u, v});
  };
  add(w.x, signed_N.x < 0 ? 1 - co.y : co.y, co.z);
  add(w.y, signed_N.y > 0 ? 1 - co.x : co.x, co.z);
  add(w.z, signed_N.z > 0 ? 1 - co.y : co.y, co.x);
  m.set(in.out[0], color);
  m.set(in.out[1], alpha);
}

// Cycles' map_to_sphere and map_to_tube (util/math) of a vector remapped from [0, 1] to [-1, 1]
// (svm_node_tex_image's texco_remap_square).
void image_sphere_tube(const Instr& in, Machine& m) {
  const Image& image = *(*m.images)[in.param[0]];
  const Vec3 co = (m.v(in.in[0]) - Vec3(0.5f)) * 2.0f;
  Vec2 uv{0, 0};
  if (in.param[2] == 1) {
    const float l = length(co);
    if (l > 0) {
      uv.x = co.x == 0 && co.y == 0 ? 0.0f : (1 - std::atan2(co.x, co.y) / kPi) / 2;
      uv.y = 1 - std::acos(clamp(co.z / l, -1.0f, 1.0f)) / kPi;
    }
  } else {
    const float l = std::sqrt(co.x * co.x + co.y * co.y);
    if (l > 0) uv = {(1 - std::atan2(co.x / l, co.y / l) / kPi) * 0.5f, (co.z + 1) * 0.5f};
  }
  m.set(in.out[0], image.lookup(uv, in.param[1] != 0));
  m.set(in.out[1], image.lookup_alpha(uv));
}

// Cycles' svm_node_vector_transform (normals are transformed as directions, then normalised).
void vector_transform(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  const bool direction = in.param[0] != 0;
  const uint32_t from = in.param[1], to = in.param[2];
  const float* camera = m.k + in.param[3];
  const bool has_camera = camera[0] == 24;
  const Instance* inst = c.instance;
  Vec3 v = m.v(in.in[0]);
  auto by_table = [&](const float* t) {
    return direction ? Vec3(t[0] * v.x + t[1] * v.y + t[2] * v.z, t[4] * v.x + t[5] * v.y + t[6] * v.z,
                            t[8] * v.x + t[9] * v.y + t[10] * v.z)
                     : affine(t, v);
  };
  auto to_object = [&] {
    if (inst) v = direction ? inverse_linear(inst->xf, v) : inverse_linear(inst->xf, v - inst->xf.column(3));
  };
  if (from == 0) {  // world
    if (to == 2 && has_camera) v = by_table(camera + 1);
    if (to == 1) to_object();
  } else if (from == 2) {  // camera
    if ((to == 0 || to == 1) && has_camera) v = by_table(camera + 13);
    if (to == 1) to_object();
  } else if (from == 1) {  // object
    if ((to == 0 || to == 2) && inst) v = direction ? inst->xf.vector(v) : inst->xf.point(v);
    if (to == 2 && has_camera) v = by_table(camera + 1);
  }
  if (in.param[0] == 2) v = normalize(v);  // Cycles' normalize: NaN for a zero vector
  m.set(in.out[0], v);
}

// Cycles' SetNormal (the normal its bump from displacement made becomes sd->N): the point and its
// bump-moved copies shade with the new normal from here on.
void set_normal(const Instr& in, Machine& m) {
  const Vec3 n = m.v(in.in[0]);
  if (!m.displaced || !(dot(n, n) > 0) || !is_finite(n)) return;
  const Vec3 N = normalize(n);
  m.displaced_raw = normalize(m.untilted(n));
  ShadingContext* displaced = m.displaced->make(*m.ctx);
  set_shading_normal(displaced, N);
  m.ctx = displaced;
  if (m.moved)
    for (int k = 0; k < 2; ++k) set_shading_normal(&m.moved[k], N);
}

// Cycles' svm_node_displacement: height along the normal, in object or world units.
void displacement(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  const float h = (m.f(in.in[0]) - m.f(in.in[1])) * m.f(in.in[2]);
  const Vec3 n = normal_or_default(m, in.in[3]);
  Vec3 d = n * h;
  if (in.param[0] == 0 && c.instance) d = c.pose.xf.vector(normalized_or_zero(c.pose.normal_to_object(n)) * h);
  m.set(in.out[0], d);
}

// Cycles' svm_node_vector_displacement: (vector - midlevel) scale in tangent (the active UV map's
// tangent, the object-space normal and their bitangent), object or world space.
void vector_displacement(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  const float mid = m.f(in.in[1]);
  Vec3 d = (m.v(in.in[0]) - Vec3(mid)) * m.f(in.in[2]);
  const uint32_t space = in.param[0];
  if (space == 0) {
    const Vec3 normal = c.instance ? normalized_or_zero(c.pose.normal_to_object(c.N)) : c.N;
    float t[4];
    Vec3 tangent;
    float sign = 1;
    if (fetch_attribute(c, 0, int(in.param[1]), t) == 4) {
      tangent = Vec3(t[0], t[1], t[2]);
      sign = t[3];
    } else if (c.mesh && c.instance && !c.mesh->is_triangles()) {
      tangent = normalized_or_zero(c.dpdu);  // curves: Cycles' dPdu, the curve's tangent
    } else if (c.mesh && c.instance) {
      // No UV map: Cycles' normalize(sd->dPdu), the triangle's first edge in world space (Cycles
      // mixes it with the object-space normal as is), reversed on a back face.
      const uint32_t* tri = &c.mesh->indices[3 * size_t(c.primitive)];
      tangent = normalized_or_zero(c.pose.xf.vector(c.mesh->positions[tri[1]] - c.mesh->positions[tri[0]]));
      if (c.backfacing) tangent = -tangent;
    }
    const Vec3 bitangent = normalized_or_zero(cross(normal, tangent)) * sign;
    d = tangent * d.x + normal * d.y + bitangent * d.z;
  }
  if (space != 2 && c.instance) d = c.pose.xf.vector(d);
  m.set(in.out[0], d);
}

const OpSignature kCurveSignatures[] = {
    {"", "ffffvf", "", false},  // hair info
    {"", "vff", "", false},     // point info
};

// Hair Info on curves: the key attributes Cycles interpolates linearly over a segment (intercept
// from the distance along the keys, as Cycles' particle and Curves export), the thickness
// (twice the radius between the keys), the view direction made normal to the curve.
void hair_info(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  float strand = 0, intercept = 0, len = 0, thickness = 0, random = 0;
  Vec3 tangent_normal(0.0f);
  if (c.mesh && c.mesh->kind == GeometryKind::Curves && c.curve >= 0 && c.primitive >= 0) {
    const CurveData& d = c.mesh->curves;
    const uint32_t i = d.segments[size_t(c.primitive)] + 1;  // the segment's first key
    const uint32_t last = d.segments[d.first_segment[size_t(c.curve) + 1] - 1] + 2;
    const float u = c.bary.x;
    strand = 1;
    len = d.arc[last];
    intercept = len > 0 ? (d.arc[i] * (1 - u) + d.arc[i + 1] * u) / len : 0.0f;
    thickness = 2 * (d.radius(i) * (1 - u) + d.radius(i + 1) * u);
    random = d.random[size_t(c.curve)];
    const float l2 = length_squared(c.dpdu);
    if (l2 > 0) tangent_normal = normalized_or_zero(c.I - c.dpdu * (dot(c.dpdu, c.I) / l2));
  }
  m.set(in.out[0], strand);
  m.set(in.out[1], intercept);
  m.set(in.out[2], len);
  m.set(in.out[3], thickness);
  m.set(in.out[4], tangent_normal);
  m.set(in.out[5], random);
}

// Cycles' wireframe(): whether p lies within sqrt(width2) of an edge line of the triangle (|e x
// (p - c)|^2 / |e|^2 is the squared distance to the line through c along e).
float near_edge(const Vec3* corners, const Vec3& p, float width2) {
  for (int i = 0; i < 3; ++i) {
    const Vec3 edge = corners[i] - corners[i ? i - 1 : 2];
    const Vec3 crs = cross(edge, p - corners[i]);
    if (dot(crs, crs) < dot(edge, edge) * width2) return 1.0f;
  }
  return 0.0f;
}

// Wireframe on triangles (zero on curves and points, as Cycles). Half the size on each side: the
// neighbouring triangle draws the other half.
void wireframe(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  if (!c.mesh || !c.mesh->is_triangles() || c.primitive < 0) {
    m.set(in.out[0], 0.0f);
    return;
  }
  float width = 1;
  if (in.param[0] != 0) {
    // The footprint's two differentials projected onto the plane normal to the view, averaged.
    width = 0;
    for (const ShadingContext::Offset& o : c.offset) width += 0.5f * length(o.P - c.I * dot(o.P, c.I));
  }
  width *= 0.5f * m.f(in.in[0]);
  float f = near_edge(c.corners, c.P, width * width);
  const uint32_t bump = in.param[1];
  if (bump == 1 || bump == 2) {
    // Cycles' svm_node_wireframe at a bump offset: f plus its one-sided difference toward -d.
    const Vec3 d = c.offset[bump - 1].P;
    const float l = length(d);
    if (l > 0) f += (f - near_edge(c.corners, c.P - d, width * width)) / l;
  }
  m.set(in.out[0], f);
}

// Whether a ray meets the instance `instance` before its end.
bool occluded_by(const Geometry& g, const Ray& ray, int instance) {
  Hit hit;
  return g.intersect_instance(ray, instance, &hit);
}

// Cycles' svm_ao: `samples` rays cosine-distributed about the normal (flipped: Inside), within the
// distance; 1 where nothing is traced (no scene, no object, no distance).
float ambient_occlusion(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  const float dist = m.f(in.in[1]);
  const int samples = int(std::min<uint32_t>(in.param[0], 1024));
  if (!c.geometry || !c.instance || c.primitive < 0 || !(dist > 0) || samples < 1) return 1.0f;
  Vec3 n = normal_or_default(m, in.in[2]);
  if (in.param[1] & 2) n = -n;
  Vec3 t, b;
  orthonormals(n, &t, &b);
  const bool local = in.param[1] & 1;
  const int instance = int(c.instance - &c.geometry->instance(0));
  int unoccluded = 0;
  for (int k = 0; k < samples; ++k) {
    // The node's rays are the first `samples` points of one scrambled 2D sequence: stratified.
    const Vec3 d = sample_cosine_hemisphere(sobol_owen_2d(reverse_bits(uint32_t(k)), c.trace_seed));
    Ray ray;
    ray.d = t * d.x + b * d.y + n * d.z;
    ray.o = offset_ray_origin(c.P, dot(ray.d, c.Ng) >= 0 ? c.Ng : -c.Ng);
    ray.tmin = 0;
    ray.tmax = dist;
    ray.time = c.time;
    if (!(local ? occluded_by(*c.geometry, ray, instance) : c.geometry->occluded(ray))) ++unoccluded;
  }
  return float(unoccluded) / float(samples);
}

// Cycles' svm_bevel_cubic_eval: the planar cubic BSSRDF falloff 10 (R - r)^3 / (pi R^5), which is
// also the density of its disk samples.
float bevel_cubic(float radius, float r) {
  if (r >= radius) return 0.0f;
  const float f = radius - r;
  return 10.0f * f * f * f / (radius * radius * radius * radius * radius * kPi);
}

// Cycles' svm_bevel_cubic_quintic_root_find: x with 10x^2 - 20x^3 + 15x^4 - 4x^5 = xi (the
// falloff's radial CDF at x R), by Newton's method from 0.25 as Cycles iterates it.
float bevel_cubic_root(float xi) {
  float x = 0.25f;
  for (int i = 0; i < 10; ++i) {
    const float x2 = x * x, x3 = x2 * x, nx = 1 - x;
    const float f = 10 * x2 - 20 * x3 + 15 * x2 * x2 - 4 * x2 * x3 - xi;
    const float df = 20 * (x * nx) * (nx * nx);
    if (std::abs(f) < 1e-6f || df == 0) break;
    x = clamp(x - f / df, 0.0f, 1.0f);
  }
  return x;
}

// Cycles' svm_bevel (kernel/svm/bevel.h; the sampling of King et al., "BSSRDF Importance
// Sampling", 2013): rays through a disk around the point along the normal or one of two tangents,
// hitting the same object within the falloff, the hits' normals weighted by the falloff over the
// sample's density (power heuristic over the three axes). The shading normal where nothing is
// traced (no object, no radius, a path that was blurry before: Cycles' min_ray_pdf < 8).
Vec3 bevel_normal(const ShadingContext& c, float radius, int samples) {
  if (!(radius > 0) || samples < 1 || !c.instance || c.primitive < 0 || !c.mesh || !c.mesh->is_triangles() ||
      c.min_ray_pdf < 8)
    return c.N;
  constexpr int kMaxHits = 4;  // Cycles' LOCAL_MAX_HITS: a uniform subset of the hits beyond it
  const int instance = int(c.instance - &c.geometry->instance(0));
  const uint64_t seed = mix_u64(c.trace_seed ^ 0x64c6a40eULL);
  Pcg32 subset(seed, 0x2545f4914f6cdd1dULL);
  Vec3 sum(0.0f);
  for (int k = 0; k < samples; ++k) {
    Vec2 u = sobol_owen_2d(reverse_bits(uint32_t(k)), seed);
    // The disk's normal and its two tangents, each with its chance of being picked as the normal:
    // Ng half the time, the tangents a quarter each.
    Vec3 axes[3];
    axes[0] = c.Ng;
    orthonormals(axes[0], &axes[1], &axes[2]);
    float pick[3] = {0.5f, 0.25f, 0.25f};
    int axis = 0;
    if (u.x < 0.5f) {
      u.x *= 2;
    } else if (u.x < 0.75f) {
      axis = 1;
      u.x = (u.x - 0.5f) * 4;
    } else {
      axis = 2;
      u.x = (u.x - 0.75f) * 4;
    }
    std::swap(axes[0], axes[axis]);
    std::swap(pick[0], pick[axis]);
    const float phi = 2 * kPi * u.x;
    const float disk_r = bevel_cubic_root(u.y) * radius;
    const float height = std::sqrt(std::max(radius * radius - disk_r * disk_r, 0.0f));
    const float disk_pdf = bevel_cubic(radius, disk_r);
    if (!(disk_pdf > 0)) continue;
    Ray ray;
    ray.o = c.P + axes[0] * height + (axes[1] * std::cos(phi) + axes[2] * std::sin(phi)) * disk_r;
    ray.d = -axes[0];
    ray.tmin = 0;
    ray.tmax = 2 * height;
    ray.time = c.time;
    SurfacePoint kept[kMaxHits];
    int hits = 0;
    c.geometry->local_hits(ray, instance, [&](const Hit& hit) {
      // Reservoir sampling as Cycles' local intersection keeps at most kMaxHits of them.
      const int slot = hits < kMaxHits ? hits : int(subset.next_u32() % uint32_t(hits + 1));
      ++hits;
      if (slot < kMaxHits) kept[slot] = c.geometry->surface(hit);
      return true;
    });
    for (int h = 0; h < std::min(hits, kMaxHits); ++h) {
      const SurfacePoint& sp = kept[h];
      float pdf[3];
      for (int a = 0; a < 3; ++a) pdf[a] = pick[a] * std::abs(dot(axes[a], sp.ng));
      float w = pdf[0] / (pdf[0] * pdf[0] + pdf[1] * pdf[1] + pdf[2] * pdf[2]);
      if (hits > kMaxHits) w *= float(hits) / float(kMaxHits);
      w *= bevel_cubic(radius, length(sp.p - c.P)) / disk_pdf;
      if (std::isfinite(w)) sum += sp.ns * w;
    }
  }
  const float l = length(sum);
  if (!(l > 0) || !std::isfinite(l)) return c.N;
  return c.backfacing ? -sum / l : sum / l;
}

// Bevel: light samples and shadow rays (no geometry to trace) see the shading normal, unblended,
// as Cycles' shadow and light evaluations, which leave out its ray-tracing nodes.
Vec3 bevel(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  if (!c.geometry) return c.N;
  const Vec3 n = bevel_normal(c, m.f(in.in[0]), int(std::min<uint32_t>(in.param[0], 1024)));
  const Vec3 ref = m.v(in.in[1]);
  if (dot(ref, ref) == 0) return n;
  const Vec3 blended = ref + (n - c.N);  // Cycles keeps a linked Normal: the bevel's change added
  const float l = length(blended);
  return l > 0 ? blended / l : c.N;
}

// Point Info on points (zero elsewhere, as Cycles).
void point_info(const Instr& in, Machine& m) {
  const ShadingContext& c = *m.ctx;
  Vec3 centre(0.0f);
  float radius = 0, random = 0;
  if (c.mesh && c.mesh->kind == GeometryKind::Points && c.primitive >= 0) {
    const CurveData& d = c.mesh->curves;
    const size_t i = size_t(c.primitive);
    centre = d.point(i);
    radius = d.radius(i);
    if (c.instance) {
      centre = c.pose.xf.point(centre);
      // Cycles applies the transform of a point cloud only one still object uses to its points,
      // scaling radii by cbrt |det| (PointCloud::apply_transform); others go through the object's
      // transform in point_radius.
      radius = c.mesh->users == 1 && c.instance->motion.empty()
                   ? radius * std::cbrt(std::abs(c.pose.xf.determinant()))
                   : length(c.pose.xf.vector(Vec3(radius / std::sqrt(3.0f))));
    }
    random = i < d.random.size() ? d.random[i] : 0.0f;
  }
  m.set(in.out[0], centre);
  m.set(in.out[1], radius);
  m.set(in.out[2], random);
}

}  // namespace

const OpSignature* inputs_family_signature(uint32_t op) {
  if (op >= kFamilyCurveInputsBegin && op < kFamilyCurveInputsEnd)
    return op == kOpHairInfo ? &kCurveSignatures[0] : (op == kOpPointInfo ? &kCurveSignatures[1] : nullptr);
  static const OpSignature kSetDisplacement = {"v", "", "", false}, kBumpEval = {"", "", "i", false};
  if (op == kOpSetDisplacement) return &kSetDisplacement;
  if (op == kOpBumpEval) return &kBumpEval;
  if (op < kOpTexCoord || op > kOpBevel) return nullptr;
  return &kSignatures[op - kOpTexCoord];
}

void exec_inputs_family(const Instr& in, Machine& m) {
  if (in.op == kOpHairInfo) {
    hair_info(in, m);
    return;
  }
  if (in.op == kOpPointInfo) {
    point_info(in, m);
    return;
  }
  if (in.op == kOpWireframe) {
    wireframe(in, m);
    return;
  }
  if (in.op == kOpAmbientOcclusion) {
    const float ao = ambient_occlusion(in, m);
    m.set(in.out[0], m.v(in.in[0]) * ao);
    m.set(in.out[1], ao);
    return;
  }
  if (in.op == kOpBevel) {
    m.set(in.out[0], bevel(in, m));
    return;
  }
  if (in.op == kOpToFloat) {
    const Vec3 v = m.v(in.in[0]);
    m.set(in.out[0],
          in.param[0] == 1 ? (v.x + v.y + v.z) * (1.0f / 3.0f) : 0.2126f * v.x + 0.7152f * v.y + 0.0722f * v.z);
    return;
  }
  if (in.op == kOpToVector) {
    m.set(in.out[0], Vec3(m.f(in.in[0])));
    return;
  }
  const ShadingContext& c = *m.ctx;
  switch (in.op) {
    case kOpTexCoord:
      tex_coord(in, m);
      break;
    case kOpGeometry:
      m.set(in.out[0], m.at(in.param[0]).P);
      m.set(in.out[1], c.N);
      m.set(in.out[2], c.surface_tangent());
      m.set(in.out[3], c.Ng);
      m.set(in.out[4], c.I);
      m.set(in.out[5], Vec3(1 - c.bary.x - c.bary.y, c.bary.x, 0.0f));
      m.set(in.out[6], c.backfacing ? 1.0f : 0.0f);
      m.set(in.out[7], 0.5f);  // pointiness is not computed: Cycles' value on a flat mesh
      m.set(in.out[8], 0.0f);
      break;
    case kOpImage: {
      const Image& image = *(*m.images)[in.param[0]];
      const Vec3 p = m.v(in.in[0]);
      m.set(in.out[0], image.lookup(Vec2{p.x, p.y}, in.param[1] != 0));
      m.set(in.out[1], image.lookup_alpha(Vec2{p.x, p.y}));
      break;
    }
    case kOpEnvironment: {
      const Image& image = *(*m.images)[in.param[0]];
      const Vec3 d = m.v(in.in[0]);
      const float l = length(d);
      const Vec3 co = l > 0 && std::isfinite(l) ? d / l : Vec3(0.0f);
      const Vec2 uv = in.param[2] == 1 ? direction_to_mirrorball(co) : direction_to_equirectangular(co);
      m.set(in.out[0], image.lookup(uv, in.param[1] != 0));
      m.set(in.out[1], image.lookup_alpha(uv));
      break;
    }
    case kOpFresnel: {
      float eta = std::max(m.f(in.in[0]), 1e-5f);
      eta = c.backfacing ? 1 / eta : eta;
      m.set(in.out[0], fresnel_cos(dot(c.I, normal_or_default(m, in.in[1])), eta));
      break;
    }
    case kOpLayerWeight: {
      float blend = m.f(in.in[0]);
      const Vec3 n = normal_or_default(m, in.in[1]);
      float eta = std::max(1 - blend, 1e-5f);
      eta = c.backfacing ? eta : 1 / eta;
      m.set(in.out[0], fresnel_cos(dot(c.I, n), eta));
      float f = std::abs(dot(c.I, n));
      if (blend != 0.5f) {
        blend = clamp(blend, 0.0f, 1 - 1e-5f);
        blend = blend < 0.5f ? 2 * blend : 0.5f / (1 - blend);
        f = std::pow(f, blend);
      }
      m.set(in.out[1], 1 - f);
      break;
    }
    case kOpAttribute:
      attribute(in, m);
      break;
    case kOpTangent:
      tangent(in, m);
      break;
    case kOpNormalMap:
      normal_map(in, m);
      break;
    case kOpObjectInfo:
      object_info(in, m);
      break;
    case kOpBump:
      bump(in, m);
      break;
    case kOpCameraData: {
      const float* camera = m.k + in.param[0];
      const Vec3 v = camera[0] == 28 ? affine(camera + 1, c.P) : Vec3(0.0f);
      const float d = length(v);
      m.set(in.out[0], d > 0 ? v / d : Vec3(0.0f));
      m.set(in.out[1], v.z);
      m.set(in.out[2], d);
      break;
    }
    case kOpImageProjected:
      if (in.param[2] == 0)
        image_box(in, m);
      else
        image_sphere_tube(in, m);
      break;
    case kOpVectorTransform:
      vector_transform(in, m);
      break;
    case kOpSetNormal:
      set_normal(in, m);
      break;
    case kOpDisplacement:
      displacement(in, m);
      break;
    case kOpVectorDisplacement:
      vector_displacement(in, m);
      break;
    case kOpSetDisplacement:
      if (m.displacement) *m.displacement += m.v(in.in[0]);
      break;
    case kOpBumpEval:
      bump_eval(in, m);
      break;
    case kOpLightFalloff: {
      float strength = m.f(in.in[0]);
      const float smooth = m.f(in.in[1]), squared = c.ray_length * c.ray_length;
      if (smooth > 0 && std::isfinite(squared)) strength *= squared / (smooth + squared);
      m.set(in.out[0], strength);
      m.set(in.out[1], strength * c.ray_length);
      m.set(in.out[2], strength * squared);
      break;
    }
    case kOpLightPath: {
      const float v[14] = {float(c.camera_ray),
                           float(c.shadow_ray),
                           float(c.diffuse_ray),
                           float(c.glossy_ray),
                           float(c.singular_ray),
                           float(c.reflection_ray),
                           float(c.transmission_ray),
                           0.0f,
                           c.ray_length,
                           float(c.ray_depth),
                           float(c.diffuse_depth),
                           float(c.glossy_depth),
                           float(c.transparent_depth),
                           float(c.transmission_depth)};
      for (int k = 0; k < 14; ++k) m.set(in.out[k], v[k]);
      break;
    }
    default:
      break;
  }
}

}  // namespace lt
