#include "shading/program.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <string>

#include "core/error.h"
#include "shading/bsdf.h"
#include "shading/inputs.h"
#include "shading/shaders.h"
#include "shading/sky.h"
#include "shading/textures.h"

namespace lt {

namespace {

const OpSignature* signature_of(uint32_t op) {
  if (op >= kFamilyCurveInputsBegin && op < kFamilyCurveInputsEnd) return inputs_family_signature(op);
  if (op < kFamilyInputsBegin) return shaders_family_signature(op);
  if (op < kFamilyMathBegin) return inputs_family_signature(op);
  if (op < kFamilyTexturesBegin) return math_family_signature(op);
  if (op < kOpEnd) return textures_family_signature(op);
  return nullptr;
}

void execute(const Instr& in, Machine& m) {
  if (in.op >= kFamilyCurveInputsBegin && in.op < kFamilyCurveInputsEnd)
    exec_inputs_family(in, m);
  else if (in.op < kFamilyInputsBegin)
    exec_shaders_family(in, m);
  else if (in.op < kFamilyMathBegin)
    exec_inputs_family(in, m);
  else if (in.op < kFamilyTexturesBegin)
    exec_math_family(in, m);
  else
    exec_textures_family(in, m);
}

Instr decode(const uint32_t* w) {
  Instr in;
  in.op = w[0];
  in.n_in = int(w[1] & 0xff);
  in.n_out = int((w[1] >> 8) & 0xff);
  in.n_param = int((w[1] >> 16) & 0xff);
  in.in = w + 2;
  in.out = in.in + in.n_in;
  in.param = in.out + in.n_out;
  return in;
}

size_t words_of(const Instr& in) { return 2 + size_t(in.n_in + in.n_out + in.n_param); }

uint32_t size_of(char c) { return c == 'v' ? 3u : 1u; }

}  // namespace

Program::Program(std::vector<uint32_t> code, std::vector<float> constants, int registers, size_t image_count) {
  if (code.size() > size_t(kMaxProgramWords))
    throw InvalidArgument("shader program of " + std::to_string(code.size()) + " words is longer than " +
                          std::to_string(kMaxProgramWords));
  if (registers < 0 || registers > kMaxRegisters)
    throw InvalidArgument("shader program needs " + std::to_string(registers) + " registers; at most " +
                          std::to_string(kMaxRegisters) + " are allowed");
  if (constants.size() > kIndexMask) throw InvalidArgument("shader program has too many constants");
  for (size_t i = 0; i < constants.size(); ++i)
    if (!std::isfinite(constants[i]))
      throw InvalidArgument("shader program constant " + std::to_string(i) + " is not finite");

  // Each register written once, read only as the whole output that wrote it (its start and size):
  // then folding rewrites a read by one pool offset.
  std::vector<uint8_t> written(size_t(registers), 0);  // 0: not yet; else the output's size at its start
  std::vector<int32_t> folded(size_t(registers), -1);  // pool offset of a folded output
  std::vector<uint32_t> out_code;
  out_code.reserve(code.size());
  std::vector<float> scratch(size_t(registers), 0.0f);

  size_t pos = 0, index = 0;
  while (pos < code.size()) {
    const std::string where =
        "shader program instruction " + std::to_string(index) + " (word " + std::to_string(pos) + ")";
    if (code.size() - pos < 2) throw InvalidArgument(where + " is cut short");
    Instr in = decode(code.data() + pos);
    if (words_of(in) > code.size() - pos) throw InvalidArgument(where + " is cut short");
    const OpSignature* sig = signature_of(in.op);
    if (!sig) throw InvalidArgument(where + " has an unknown opcode " + std::to_string(in.op));
    if (size_t(in.n_in) != std::strlen(sig->in) || size_t(in.n_out) != std::strlen(sig->out) ||
        size_t(in.n_param) != std::strlen(sig->params))
      throw InvalidArgument(where + " (opcode " + std::to_string(in.op) + ") has the wrong operand count");
    std::vector<uint32_t> words(code.begin() + long(pos), code.begin() + long(pos + words_of(in)));
    uint32_t* ins = words.data() + 2;
    if (in.op >= kFamilyTexturesBegin && in.op < kOpEnd)
      prepare_textures_family(in.op, ins + in.n_in + in.n_out, &constants);
    bool all_constant = true;
    for (int k = 0; k < in.n_in; ++k) {
      uint32_t w = ins[k];
      const uint32_t size = operand_size(w), at = operand_index(w);
      if (size != size_of(sig->in[k]) || (w & 0x70000000u))
        throw InvalidArgument(where + " input " + std::to_string(k) + " has the wrong size");
      if (w & kConstBit) {
        if (size_t(at) + size > constants.size())
          throw InvalidArgument(where + " input " + std::to_string(k) + " reads past the constants");
        continue;
      }
      if (at >= size_t(registers) || written[at] != size)
        throw InvalidArgument(where + " input " + std::to_string(k) + " reads register " + std::to_string(at) +
                              " before an instruction writes it");
      if (folded[at] >= 0)
        ins[k] = kConstBit | (size << 24) | uint32_t(folded[at]);
      else
        all_constant = false;
    }
    uint32_t* outs = ins + in.n_in;
    for (int k = 0; k < in.n_out; ++k) {
      uint32_t w = outs[k];
      const uint32_t size = operand_size(w), at = operand_index(w);
      if ((w & kConstBit) || size != size_of(sig->out[k]) || size_t(at) + size > size_t(registers))
        throw InvalidArgument(where + " output " + std::to_string(k) + " is not a register range");
      for (uint32_t j = 0; j < size; ++j)
        if (written[at + j]) throw InvalidArgument(where + " writes register " + std::to_string(at + j) + " twice");
      written[at] = uint8_t(size);
      for (uint32_t j = 1; j < size; ++j) written[at + j] = 0xff;  // inside a vector: not readable alone
    }
    const uint32_t* params = outs + in.n_out;
    for (int k = 0; k < in.n_param; ++k) {
      const char kind = sig->params[k];
      if (kind == 'g' && params[k] >= image_count)
        throw InvalidArgument(where + " refers to image " + std::to_string(params[k]) + " which does not exist");
      if (kind == 't') {
        const size_t at = params[k];
        if (at >= constants.size() ||
            !(constants[at] >= 0.0f && double(constants[at]) <= double(constants.size() - at - 1)))
          throw InvalidArgument(where + " refers to a table past the constants");
      }
    }
    if (sig->pure && all_constant && in.n_out > 0) {
      // Fold: run once and move the outputs into the pool.
      Machine m;
      m.r = scratch.data();
      m.k = constants.data();
      execute(decode(words.data()), m);
      for (int k = 0; k < in.n_out; ++k) {
        const uint32_t at = operand_index(outs[k]);
        folded[at] = int32_t(constants.size());
        for (uint32_t j = 0; j < operand_size(outs[k]); ++j)
          constants.push_back(std::isfinite(scratch[at + j]) ? scratch[at + j] : 0.0f);
      }
    } else {
      out_code.insert(out_code.end(), words.begin(), words.end());
      ++count_;
      uses_bump_ |= in.op == kOpBump;
      uses_wireframe_ |= in.op == kOpWireframe;
      traces_rays_ |= in.op == kOpAmbientOcclusion || in.op == kOpBevel;
      sets_normal_ |= in.op == kOpSetNormal;
      bump_eval_ |= in.op == kOpBumpEval;
    }
    pos += words_of(in);
    ++index;
  }
  code_ = std::move(out_code);
  constants_ = std::move(constants);
  registers_ = registers;
}

Spectrum Program::run(const ShadingContext& ctx, const std::vector<std::unique_ptr<Image>>& images, Bsdf* bsdf,
                      ShadingFrame* frame) const {
  return execute_all(ctx, images, bsdf, frame, nullptr);
}

Vec3 Program::displacement(const ShadingContext& ctx, const std::vector<std::unique_ptr<Image>>& images) const {
  Vec3 d(0.0f);
  execute_all(ctx, images, nullptr, nullptr, &d);
  return d;
}

Spectrum Program::execute_all(const ShadingContext& ctx, const std::vector<std::unique_ptr<Image>>& images, Bsdf* bsdf,
                              ShadingFrame* frame, Vec3* displacement) const {
  float regs[kMaxRegisters];  // left uninitialised: validation guarantees every read follows a write
  Machine m;
  m.r = regs;
  m.k = constants_.data();
  m.ctx = &ctx;
  m.images = &images;
  m.bsdf = bsdf;
  m.displacement = displacement;
  // Rooms for contexts only some programs use (Machine::displaced, moved, undisplaced).
  Room<std::array<ShadingContext, 2>> bump_room;
  if (uses_bump_) {
    ShadingContext* moved = bump_room.make()->data();
    for (int k = 0; k < 2; ++k) {
      moved[k] = ctx;
      const ShadingContext::Offset& d = ctx.offset[k];
      moved[k].P += d.P;
      moved[k].object_P += d.object_P;
      moved[k].generated += d.generated;
      moved[k].uv = {ctx.uv.x + d.uv.x, ctx.uv.y + d.uv.y};
      moved[k].bary = {ctx.bary.x + d.bary.x, ctx.bary.y + d.bary.y};
      // The point's own object normal and tangent: the move shifts the position and its
      // coordinates, not the normal's frame (a moved Generated would turn the tangent).
      moved[k].set_normal_values(ctx.object_normal(), ctx.surface_tangent());
      m.bumped[k] = &moved[k];
    }
    m.moved = moved;
  }
  Room<ShadingContext> displaced;  // made by a SetNormal only
  if (sets_normal_) m.displaced = &displaced;
  Room<std::array<ShadingContext, 3>> undisplaced;
  if (bump_eval_) m.undisplaced = undisplaced.make()->data();
  m.emitted = Spectrum(0.0f);
  if (bsdf) bsdf->clear();
  const uint32_t* w = code_.data();
  const uint32_t* end = w + code_.size();
  while (w < end) {
    Instr in = decode(w);
    execute(in, m);
    w += words_of(in);
  }
  if (frame) {
    frame->raw = frame->n;
    if (m.ctx != &ctx) {
      frame->smooth = m.ctx->N;
      if (!m.has_shading_normal) frame->n = m.ctx->N;
      frame->raw = m.displaced_raw;
    }
    if (m.has_shading_normal) {
      frame->n = m.shading_normal;
      frame->raw = m.shading_normal_raw;
    } else if (bsdf && bsdf->count() > 0 && !same_vector(frame->n, m.ctx->Ng)) {
      // Cycles' closure nodes pass an unlinked Normal (sd->N) through ensure_valid_reflection too:
      // a smooth-shaded silhouette's normal tilts so that its mirror direction leaves the surface
      // (Ng itself reflects every direction above it and stays).
      const Vec3 valid = ensure_valid_reflection(m.ctx->Ng, m.ctx->I, frame->n);
      if (is_finite(valid)) frame->n = valid;
    }
    frame->tangent = m.shading_tangent;
  }
  return m.emitted;
}

bool Program::may_be_transparent() const {
  auto zero = [&](uint32_t w) {
    if (!(w & kConstBit)) return false;
    for (uint32_t j = 0; j < operand_size(w); ++j)
      if (constants_[operand_index(w) + j] != 0) return false;
    return true;
  };
  for (const uint32_t* w = code_.data(); w < code_.data() + code_.size();) {
    Instr in = decode(w);
    w += words_of(in);
    if (in.op == kOpTransparent && !zero(in.in[0]) && !zero(in.in[1])) return true;
    if (in.op == kOpPrincipled && !zero(in.in[0]) &&
        (!(in.in[23] & kConstBit) || constants_[operand_index(in.in[23])] < 1))
      return true;
  }
  return false;
}

bool Program::constant_emission(const std::vector<std::unique_ptr<Image>>& images, Spectrum* emitted) const {
  for (const uint32_t* w = code_.data(); w < code_.data() + code_.size();) {
    Instr in = decode(w);
    w += words_of(in);
    if (in.op != kOpEmission) return false;
    for (int k = 0; k < in.n_in; ++k)
      if (!(in.in[k] & kConstBit)) return false;
  }
  *emitted = run(ShadingContext(), images, nullptr, nullptr);
  return true;
}

std::vector<uint32_t> Program::environment_images() const {
  std::vector<uint32_t> ids;
  for (const uint32_t* w = code_.data(); w < code_.data() + code_.size();) {
    Instr in = decode(w);
    w += words_of(in);
    if (in.op == kOpEnvironment) ids.push_back(in.param[0]);
  }
  return ids;
}

std::vector<Program::SunDisc> Program::sun_discs() const {
  std::vector<SunDisc> discs;
  std::vector<uint32_t> generated;  // Texture Coordinate's Generated outputs: a world's direction
  for (const uint32_t* w = code_.data(); w < code_.data() + code_.size();) {
    Instr in = decode(w);
    w += words_of(in);
    if (in.op == kOpTexCoord) generated.push_back(in.out[0]);
    SunDisc d;
    // Only a sky that sees the direction unmapped has its disc where sun_disc says.
    if (in.op == kOpTexSky && std::find(generated.begin(), generated.end(), in.in[0]) != generated.end() &&
        sky::sun_disc(in.param[0], constants_.data() + in.param[1 + sky::kSettings] + 1, &d.dir, &d.half_angle))
      discs.push_back(d);
  }
  return discs;
}

bool Program::emission_estimate(float* estimate) const {
  bool emits = false;
  float best = 0;
  for (const uint32_t* w = code_.data(); w < code_.data() + code_.size();) {
    Instr in = decode(w);
    w += words_of(in);
    if (in.op != kOpEmission && in.op != kOpPrincipled) continue;
    const uint32_t weight = in.in[0], color = in.in[in.op == kOpEmission ? 1 : 21],
                   strength = in.in[in.op == kOpEmission ? 2 : 22];
    float e = 1;
    if ((weight & color & strength) & kConstBit) {
      const float* wk = constants_.data() + operand_index(weight);
      const float* ck = constants_.data() + operand_index(color);
      float c = 0, wm = 0;
      for (int j = 0; j < 3; ++j) {
        c = std::max(c, std::abs(ck[j]));
        wm = std::max(wm, wk[j]);
      }
      // Negative strength is negative light (as Cycles renders it): the estimate is its magnitude.
      e = wm * c * std::abs(constants_[operand_index(strength)]);
    }
    if (std::isfinite(e) && e > 0) {
      emits = true;
      best = std::max(best, e);
    }
  }
  *estimate = best;
  return emits;
}

}  // namespace lt
