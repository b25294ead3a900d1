// The inputs family of the shader machine: implicit socket conversions, and nodes that read the shading point (Cycles'
// svm_node_tex_coord, svm_node_geometry, svm_node_light_path, svm_node_fresnel,
// svm_node_layer_weight) and image textures. A Normal input of (0, 0, 0) stands for the unlinked
// socket: the shading point's normal.
#pragma once

#include "shading/program.h"

namespace lt {

enum InputOp : uint32_t {
  // out: generated, normal, uv, object, camera, window, reflection (all v);
  // params: object table (0 floats: the shaded object; 12: a world-to-object matrix, rows),
  //         camera table (0 floats, or 12 world-to-camera (Cycles' camera space, +Z forward) then
  //         16 world-to-NDC, rows), bump (0 the point, 1 and 2 moved by its differentials: Bump)
  kOpTexCoord = kFamilyInputsBegin,
  // out: position, normal, tangent, true normal, incoming, parametric (all v), backfacing,
  //      pointiness, random per island (f); param: bump (Position moved as Texture Coordinate's)
  kOpGeometry,
  // in: vector v; out: color v, alpha f; params: image id, unassociate (the Alpha output is used:
  // colours divided by alpha, as Cycles)
  kOpImage,
  kOpFresnel,      // in: ior f, normal v; out: fac f
  kOpLayerWeight,  // in: blend f, normal v; out: fresnel f, facing f
  // out: is camera, shadow, diffuse, glossy, singular, reflection, transmission, volume scatter
  //      ray, ray length, ray depth, diffuse depth, glossy depth, transparent depth, transmission
  //      depth (all f)
  kOpLightPath,
  // Implicit conversions between linked sockets of different types (Cycles' svm_node_convert):
  kOpToFloat,   // in: v; out: f; param: 0 colour to float (Rec. 709 luma), 1 vector to float (average)
  kOpToVector,  // in: f; out: v (x, x, x)
  // Named attributes (Cycles' svm_node_attr): out: vector/colour v, fac f, alpha f; params: the
  // attribute id, the domain (0 the mesh's corners, 1 the instance's values), bump (as Texture
  // Coordinate's: the attribute where the moved point lies). By components: 1
  // (f, f, f) f 1; 2 (x, y, 0) x 1; 3 xyz average 1; 4 rgb average(rgb) w; missing: 0 0 1.
  kOpAttribute,
  // Tangent node (Cycles' svm_node_tangent): out: tangent v; params: direction (0 radial, 1 UV
  // map), axis (0 X, 1 Y, 2 Z), the UV map's tangent attribute id (4 components: tangent, sign).
  kOpTangent,
  // Normal Map (Cycles' svm_node_normal_map): in: strength f, colour v; out: normal v; params:
  // space (0 tangent, 1 object, 2 world, 3 Blender object, 4 Blender world), tangent attribute id.
  kOpNormalMap,
  // Object Info (Cycles' svm_node_object_info): out: location v, colour v, alpha f, object index
  // f, random f (Material Index is a constant of the material).
  kOpObjectInfo,
  // Bump (Cycles' svm_node_set_bump): in: strength f, distance f, height f, height at the dx
  // offset f, at the dy offset f, normal v; out: normal v; param: flags (1 invert, 2 in object
  // space: Cycles' use_object_space, the bump of the method Displacement and Bump). The add-on compiles the
  // Height input three times, the copies' position-reading ops with bump params 1 and 2.
  kOpBump,
  // Camera Data (Cycles' svm_node_camera): out: view vector v, view Z depth f, view distance f;
  // param: camera table (as Texture Coordinate's; 0 floats: zeros).
  kOpCameraData,
  // Light Falloff (Cycles' svm_node_light_falloff): in: strength f, smooth f; out: quadratic f,
  // linear f, constant f (strength times 1, the ray length, its square; smoothed).
  kOpLightFalloff,
  // Image Texture's other projections: in: vector v; out: color v, alpha f; params: image id,
  // unassociate (as kOpImage's), projection (0 box: Cycles' svm_node_tex_image_box, three lookups
  // along the object axes weighted by the object-space shading normal; 1 sphere, 2 tube: Cycles'
  // map_to_sphere and map_to_tube of the vector remapped from [0, 1] to [-1, 1]), blend (box; float
  // bits).
  kOpImageProjected,
  // Vector Transform (Cycles' svm_node_vector_transform): in: vector v; out: vector v; params:
  // type (0 point, 1 vector, 2 normal: as a vector, then normalised), from, to (0 world, 1 object,
  // 2 camera), camera table (0 floats: camera space is world space; 24: world to Cycles' camera
  // space then camera to world, 3 rows of 4 each).
  kOpVectorTransform,
  // The Material Output's Displacement as bump (Cycles' SetNormal after its bump from
  // displacement): in: normal v. Replaces the shading point's normal (ShadingContext::N and what
  // depends on it) for every instruction after it.
  kOpSetNormal,
  // Displacement node (Cycles' svm_node_displacement): in: height f, midlevel f, scale f, normal v;
  // out: displacement v; param: space (0 object, 1 world).
  kOpDisplacement,
  // Vector Displacement node (Cycles' svm_node_vector_displacement): in: vector v, midlevel f,
  // scale f; out: displacement v; params: space (0 tangent, 1 object, 2 world), the active UV
  // map's tangent attribute id.
  kOpVectorDisplacement,
  // Environment Texture (Cycles' svm_node_tex_environment): in: vector v (normalised here); out:
  // color v, alpha f; params: image id, unassociate (as Image's), projection (0 equirectangular,
  // 1 mirror ball).
  kOpEnvironment,
  // Wireframe (Cycles' svm_node_wireframe): in: size f; out: fac f (1 within size / 2 of an edge of
  // the shading point's triangle, else 0); params: pixel size (size in pixels: times the ray
  // footprint seen across the view), bump (1, 2: Cycles' one-sided difference along dx, dy).
  kOpWireframe,
  // Ambient Occlusion (Cycles' svm_node_ao / svm_ao): in: color v, distance f, normal v; out:
  // color v (times ao), ao f (the fraction of `samples` cosine-distributed rays within distance
  // that reach nothing); params: samples, flags (1 only local, 2 inside).
  kOpAmbientOcclusion,
  // Bevel (Cycles' svm_node_bevel / svm_bevel): in: radius f, normal v (zero: unlinked); out: normal
  // v (the normals of the same object's surface within radius, weighted by a cubic falloff);
  // params: samples.
  kOpBevel,
  // The Material Output's Displacement in a true-displacement program (Cycles'
  // svm_node_set_displacement: sd->P += dP): in: the world-space offset v, added to
  // Machine::displacement (Program::displacement; elsewhere nothing).
  kOpSetDisplacement = 58,
  // Cycles' svm_node_enter_bump_eval / leave_bump_eval (the method Displacement and Bump): param
  // 0 enter: the point (and its bump-moved copies) as if undisplaced, at the displaced mesh's
  // Mesh::undisplaced position with the footprint of its differentials; 1 leave: back.
  kOpBumpEval = 59,
};

// Curve and point inputs: numbers 100-107 (program.cpp hands them to this family).
constexpr uint32_t kFamilyCurveInputsBegin = 100, kFamilyCurveInputsEnd = 108;
enum CurveInputOp : uint32_t {
  // Hair Info (Cycles' svm_node_hair_info and its curve attributes): out: is strand f,
  // intercept f, length f, thickness f, tangent normal v, random f.
  kOpHairInfo = 100,  // kFamilyCurveInputsBegin
  // Point Info (svm_node_point_info, geom/point.h): out: world-space centre v, radius f (the
  // object-space radius through the transform as Cycles' point_radius), random f.
  kOpPointInfo = 104,
};

}  // namespace lt
