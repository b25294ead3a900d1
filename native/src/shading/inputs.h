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
  //         16 world-to-NDC, rows)
  kOpTexCoord = kFamilyInputsBegin,
  // out: position, normal, tangent, true normal, incoming, parametric (all v), backfacing,
  //      pointiness, random per island (f)
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
};

}  // namespace lt
