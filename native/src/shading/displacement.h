// True displacement (Cycles 3.4's scene/mesh_displace.cpp with kernel/bake's kernel_displace): at
// the scene's first commit, before the BVHs are built, each mesh whose triangles' materials use
// the Displacement methods True or Both has its vertices moved by the Material Output's
// Displacement, evaluated once per vertex, and its normals recomputed as Cycles does.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "geometry/geometry.h"
#include "shading/image.h"
#include "shading/material.h"

namespace lt {

// Object-space offsets of a mesh's vertices (zero where no triangle displaces), evaluated as
// Cycles: the mesh's first instance gives the object (transform, material slots); each vertex is
// evaluated once, at its corner of the first triangle (in index order) whose material displaces,
// with that material's program and that corner's normal, UV and attributes.
// triangle_materials: each triangle's displacing material, or null.
std::vector<Vec3> displacement_offsets(const Mesh& mesh, const Instance& instance,
                                       const std::vector<const Material*>& triangle_materials,
                                       const std::vector<std::unique_ptr<Image>>& images);

// The corner normals after displacement for positions `p` (one motion step): a smooth corner whose
// vertex belongs to a True triangle takes the normalised sum of those triangles' face normals
// (Cycles' recomputed vertex normal), a flat triangle's corners its face normal; other corners
// keep `corner_normals`' (Both keeps the undisplaced smooth normals, which its bump perturbs).
std::vector<Vec3> displaced_corner_normals(const Mesh& mesh, const std::vector<Vec3>& p,
                                           const std::vector<Vec3>& corner_normals,
                                           const std::vector<uint8_t>& true_triangles);

// Displaces every mesh that needs it: one run of a displacement program per vertex of a mesh whose
// first instance has a displacing material; other meshes cost a look at their instance's slots.
void displace_meshes(Geometry& geometry, const std::vector<Material>& materials,
                     const std::vector<std::unique_ptr<Image>>& images);

}  // namespace lt
