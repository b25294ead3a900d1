// Shader programs: a material's node tree, compiled by the add-on (addon/lantern/export/nodes/),
// runs on a small register machine here, in the spirit of Cycles' SVM (kernel/svm/svm.h). One
// evaluation context serves every node; new nodes need an opcode, not a new ABI entry point.
//
// Encoding (uint32 words; floats live in the constant pool). An instruction is
//   [opcode] [n_in | n_out << 8 | n_param << 16] [inputs...] [outputs...] [params...]
// An input operand is a float or a vector (3 floats) in the registers or, with kConstBit set, in
// the constant pool; an output names registers. Operand word: index (bits 0-23) | size (1 or 3,
// bits 24-27) | kConstBit. Params are raw words the opcode defines (modes, table offsets into the
// pool). Registers are written once (the compiler allocates fresh ones), so a pure instruction whose
// inputs are all constant is folded at load: run once, its outputs moved into the pool.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/room.h"
#include "core/sampling.h"
#include "geometry/motion.h"

namespace lt {

class Image;
class Bsdf;
class Geometry;
struct Mesh;
struct Instance;

constexpr uint32_t kConstBit = 0x80000000u;
constexpr uint32_t kIndexMask = 0x00ffffffu;
constexpr int kMaxRegisters = 4096;  // floats; larger programs are refused
constexpr int kMaxProgramWords = 1 << 20;

inline uint32_t operand_size(uint32_t w) { return (w >> 24) & 0xfu; }
inline uint32_t operand_index(uint32_t w) { return w & kIndexMask; }

// What the nodes see at a shading point (Cycles' ShaderData). World space unless named otherwise.
struct ShadingContext {
  Vec3 P;          // position
  Vec3 N;          // smooth shading normal, facing the incoming ray (Cycles' sd->N)
  Vec3 Ng;         // geometric normal, facing the incoming ray
  Vec3 I;          // toward the viewer: the incoming ray's reversed direction
  Vec2 uv;         // the active render UV map
  Vec2 bary;       // barycentrics of the triangle's second and third vertices
  Vec3 generated;  // object-space position in the mesh's texture space (Cycles' Generated)
  Vec3 object_P;   // object-space position
  // Object-space N, and Cycles' Geometry Tangent (around the generated Z axis, normal to N; a
  // curve's direction): worked out from N when first read after set_shading_normal, since most
  // programs read neither (material.cpp); set_normal_values gives fixed ones.
  Vec3 object_normal() const;
  Vec3 surface_tangent() const;
  void set_normal_values(const Vec3& object_N, const Vec3& tangent) {
    object_N_ = object_N;
    tangent_ = tangent;
    derived_ = true;
  }
  bool backfacing = false;
  bool background = false;  // a world ray's point (world_context): no object, P is the direction
  // Bump and Wireframe (add_differentials): the ray footprint (Cycles' compact sd->dP) and what the
  // shading point changes by when moved along the footprint's two differentials in the surface
  // (Cycles' differential_from_compact(Ng, dP)): [0] dx, [1] dy; a triangle's corners in world space.
  float footprint = 0;
  struct Offset {
    Vec3 P, object_P, generated;
    Vec2 uv, bary;
  } offset[2];
  Vec3 corners[3];
  const Mesh* mesh = nullptr;
  const Instance* instance = nullptr;
  Pose pose;  // the instance's transform at the ray's time (motion blur); identity without an instance
  int primitive = -1;
  // Light Path: the ray that reached this point and the bounces before it.
  bool camera_ray = true, shadow_ray = false, diffuse_ray = false, glossy_ray = false, singular_ray = false;
  bool reflection_ray = false, transmission_ray = false;
  float ray_length = 0;
  int ray_depth = 0, diffuse_depth = 0, glossy_depth = 0, transparent_depth = 0, transmission_depth = 0;
  // Curves and points (mesh->kind): the curve (point) index and the curve's tangent dP/du in
  // world space (Cycles' sd->dPdu; zero elsewhere). Hair Info and the hair closures read them.
  int curve = -1;
  Vec3 dpdu{0.0f};
  // Cycles' AOV Output: where this point's program adds its AOV values (4 floats per AOV, of
  // aov_count), set only where Cycles writes them (a camera path before its first opaque surface).
  float* aovs = nullptr;
  int aov_count = 0;
  // Ambient Occlusion's and Bevel's rays (add_tracing): the scene they meet (null: AO is 1 and
  // Bevel the normal, as Cycles' light and shadow evaluations), the ray's time, a number scrambling
  // the nodes' ray patterns, and the smallest pdf of the bounces before (Cycles' min_ray_pdf; delta
  // lobes infinite): Bevel traces nothing below 8, on paths that were blurry.
  const Geometry* geometry = nullptr;
  float time = 0.5f;
  uint64_t trace_seed = 0;
  float min_ray_pdf = INFINITY;
  // Subsurface scattering closures make a BSSRDF (LobeType::Subsurface) only where the path
  // tracers set this: a path with no diffuse bounce before (Cycles turns them into a diffuse of
  // their colour after one, PATH_RAY_DIFFUSE_ANCESTOR). Elsewhere (BDPT, AO, displacement) that
  // diffuse, the radius-0 limit.
  bool subsurface = false;

 private:
  friend void set_shading_normal(ShadingContext* ctx, const Vec3& n);
  void derive_normal_values() const;
  mutable Vec3 object_N_, tangent_;
  mutable bool derived_ = false;
};

// The machine an instruction runs on: read inputs, write outputs.
struct Machine {
  float* r = nullptr;        // registers
  const float* k = nullptr;  // constant pool
  const ShadingContext* ctx = nullptr;
  const std::vector<std::unique_ptr<Image>>* images = nullptr;
  Bsdf* bsdf = nullptr;  // null: emission only (light sampling)
  Spectrum emitted;
  Vec3 shading_normal;  // set by closures with a Normal input (one normal per shading point)
  bool has_shading_normal = false;
  // Cycles' ensure_valid_reflection tilts normals for the viewer (ctx->I) in Bump and in the
  // closures; ShadingFrame::raw keeps the normal untilted. Bump outputs and their untilted values:
  static constexpr int kMaxBumps = 4;
  Vec3 bump_out[kMaxBumps], bump_raw[kMaxBumps];
  int bumps = 0;
  Vec3 shading_normal_raw, displaced_raw;  // the untilted shading_normal and SetNormal's normal
  // n untilted if a Bump made it (an unchanged copy of its output), else n.
  Vec3 untilted(const Vec3& n) const {
    for (int k = 0; k < bumps; ++k)
      if (bump_out[k].x == n.x && bump_out[k].y == n.y && bump_out[k].z == n.z) return bump_raw[k];
    return n;
  }
  Vec3 shading_tangent{0.0f};  // set by anisotropic closures: the frame's +X

  // The context moved by each bump differential (set when the program has a Bump node): ops that
  // read the position take a bump param, 0 (ctx), 1 (dx) or 2 (dy).
  const ShadingContext* bumped[2] = {nullptr, nullptr};
  // Room for the point with the normal a displacement's bump sets (SetNormal), and the moved copies
  // (bumped) it updates too; null while folding constants.
  Room<ShadingContext>* displaced = nullptr;
  ShadingContext* moved = nullptr;
  // Where SetDisplacement adds the Material Output's Displacement (Program::displacement only).
  Vec3* displacement = nullptr;
  // BumpEval's room for the undisplaced point and its moved copies (3), and the contexts it
  // replaced (ctx, bumped) until it leaves; null while folding constants.
  ShadingContext* undisplaced = nullptr;
  const ShadingContext* entered[3] = {nullptr, nullptr, nullptr};
  const ShadingContext& at(uint32_t bump) const {
    return bump == 0 || bump > 2 || !bumped[bump - 1] ? *ctx : *bumped[bump - 1];
  }

  float f(uint32_t w) const { return w & kConstBit ? k[w & kIndexMask] : r[w & kIndexMask]; }
  Vec3 v(uint32_t w) const {
    const float* p = w & kConstBit ? k + (w & kIndexMask) : r + (w & kIndexMask);
    return {p[0], p[1], p[2]};
  }
  void set(uint32_t w, float x) const { r[w & kIndexMask] = x; }
  void set(uint32_t w, const Vec3& x) const {
    float* p = r + (w & kIndexMask);
    p[0] = x.x;
    p[1] = x.y;
    p[2] = x.z;
  }
};

// A decoded instruction: pointers into the code.
struct Instr {
  uint32_t op;
  int n_in, n_out, n_param;
  const uint32_t* in;
  const uint32_t* out;
  const uint32_t* param;
};

// Opcode ranges, one per node family (each family's file executes its range and declares its
// opcodes, with each instruction's operands in emission order):
//   0-31     shaders.h: closures (Shader nodes) and closure weights
//   32-63    inputs.h: nodes that read the shading point (Texture Coordinate, Geometry...), images
//   64-191   nodes_math.h: Math, Vector Math, Mix, colour, converters (but 100-107: inputs.h's
//            curve and point inputs, Hair Info)
//   192-319  textures.h: procedural textures
constexpr uint32_t kFamilyShadersBegin = 0;
constexpr uint32_t kFamilyInputsBegin = 32;
constexpr uint32_t kFamilyMathBegin = 64;
constexpr uint32_t kFamilyTexturesBegin = 192;
constexpr uint32_t kOpEnd = 320;

// An opcode's operands, checked when a program is loaded so that executors read them blindly.
// in / out: one character per operand, 'f' (1 float) or 'v' (3 floats). params: one character
// per word: 'i' a mode (the executor treats unknown values as documented), 'g' an image id,
// 't' a table in the pool (its offset; pool[offset] holds the table's float count n, the n floats
// follow). pure: reads nothing but its operands (folded when they are all constant).
struct OpSignature {
  const char* in;
  const char* out;
  const char* params;
  bool pure;
};

// Family executors: the signature of an opcode of their range (null when unknown), and running one
// instruction (validated against the signature).
const OpSignature* shaders_family_signature(uint32_t op);
void exec_shaders_family(const Instr& in, Machine& m);
const OpSignature* inputs_family_signature(uint32_t op);
void exec_inputs_family(const Instr& in, Machine& m);
const OpSignature* math_family_signature(uint32_t op);
void exec_math_family(const Instr& in, Machine& m);
const OpSignature* textures_family_signature(uint32_t op);
void exec_textures_family(const Instr& in, Machine& m);
// At load, before validation: an instruction whose table the core computes (the Sky Texture's)
// gets it appended to the pool and its 't' param pointed at it.
void prepare_textures_family(uint32_t op, uint32_t* params, std::vector<float>* pool);

// The frame a program shades in: the normal (the shading point's unless a closure brings its own)
// and, for anisotropic lobes, the tangent (zero: none).
struct ShadingFrame {
  Vec3 n;
  Vec3 tangent{0.0f};
  // The shading point's normal as the material's displacement bumped it (Cycles' SetNormal: the
  // sd->N closures and the bump shadowing term compare with); zero without one.
  Vec3 smooth{0.0f};
  // n before Cycles' ensure_valid_reflection tilted it for the viewer (ShadingContext::I): BDPT
  // tilts it again for each direction a camera path could arrive from (bdpt.h, view_frame).
  Vec3 raw{0.0f};
};

class Program {
 public:
  // Validates (every operand in range, registers written before read and once, known opcodes,
  // image ids below image_count) and folds constant instructions. Throws InvalidArgument naming
  // the instruction otherwise.
  Program(std::vector<uint32_t> code, std::vector<float> constants, int registers, size_t image_count);

  // Runs the program: lobes into bsdf (cleared first; null: emission only), returns emitted radiance.
  // frame (may be null): the normal set by a closure's Normal input, the anisotropic tangent.
  Spectrum run(const ShadingContext& ctx, const std::vector<std::unique_ptr<Image>>& images, Bsdf* bsdf,
               ShadingFrame* frame) const;
  // Runs a true-displacement program (its SetDisplacement): the world-space offset at ctx.
  Vec3 displacement(const ShadingContext& ctx, const std::vector<std::unique_ptr<Image>>& images) const;
  size_t instruction_count() const { return count_; }
  // Whether the program may emit, and a rough scalar for how bright (for picking lights by power):
  // exact for constant emission, 1 where a texture or a node decides it.
  bool emission_estimate(float* estimate) const;
  // The program has a Bump or a Wireframe node: the shading point's differentials and its triangle
  // are needed (add_differentials).
  bool needs_differentials() const { return uses_bump_ || uses_wireframe_; }
  // The program traces rays (Ambient Occlusion): the shading point needs add_tracing.
  bool traces_rays() const { return traces_rays_; }
  // The program sets the shading normal (a displacement's bump): Program::run keeps room for it.
  bool sets_normal() const { return sets_normal_; }
  // Whether the program may give a Transparent lobe (Transparent, Principled Alpha): then
  // shadow rays look at it (Cycles' transparent shadows).
  bool may_be_transparent() const;
  // Whether the program is emission closures with constant inputs only (a constant world): then
  // *emitted is what it emits everywhere.
  bool constant_emission(const std::vector<std::unique_ptr<Image>>& images, Spectrum* emitted) const;
  // The images its Environment Texture instructions read (a world's automatic map resolution).
  std::vector<uint32_t> environment_images() const;
  // The sun discs of its Sky Texture instructions that read Texture Coordinate's Generated (a
  // world's direction, unmapped): their directions and half their angular diameters.
  struct SunDisc {
    Vec3 dir;
    float half_angle;
  };
  std::vector<SunDisc> sun_discs() const;

 private:
  Spectrum execute_all(const ShadingContext& ctx, const std::vector<std::unique_ptr<Image>>& images, Bsdf* bsdf,
                       ShadingFrame* frame, Vec3* displacement) const;
  std::vector<uint32_t> code_;
  std::vector<float> constants_;
  int registers_ = 0;
  size_t count_ = 0;
  bool uses_bump_ = false, uses_wireframe_ = false, traces_rays_ = false;
  bool sets_normal_ = false, bump_eval_ = false;
};

}  // namespace lt
