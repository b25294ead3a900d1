#include "shading/shaders.h"

#include "shading/bsdf.h"

namespace lt {

namespace {

float unit(float x) { return std::isfinite(x) ? clamp(x, 0.0f, 1.0f) : 0.0f; }
Vec3 finite(Vec3 c) {
  for (int k = 0; k < 3; ++k) c[k] = std::isfinite(c[k]) ? c[k] : 0.0f;
  return c;
}
Vec3 non_negative(Vec3 c) {
  for (int k = 0; k < 3; ++k) c[k] = std::isfinite(c[k]) ? std::max(0.0f, c[k]) : 0.0f;
  return c;
}
// Glass and Principled IOR as Cycles 3.4 takes it (fmaxf(ior, 1e-5f)): below 1 is an optically
// thinner inside (an air bubble in water, IOR 0.75, reflects totally beyond asin(0.75) = 48.6
// degrees from its normal); 0 or less becomes 1e-5, a near-perfect mirror.
float glass_ior(float ior) { return std::max(ior, 1e-5f); }
constexpr float kClosureCutoff = 1e-5f;  // Cycles' CLOSURE_WEIGHT_CUTOFF

// Cycles' ensure_valid_reflection (kernel/closure/bsdf_util.h), applied by its closure nodes to
// their normal: tilts N towards Ng just enough that the mirror reflection of I stays above the
// surface (normal maps seen at grazing angles otherwise shade from below).
Vec3 ensure_valid_reflection(const Vec3& Ng, const Vec3& I, const Vec3& N) {
  const float threshold = std::min(0.9f * dot(Ng, I), 0.01f);
  if (dot(Ng, 2 * dot(N, I) * N - I) >= threshold) return N;
  // Frame: Ng as Z, N in the X-Z plane; solve for N'.z so that the reflection's z is the threshold.
  const Vec3 X = normalize(N - dot(N, Ng) * Ng);
  const float ix = dot(I, X), iz = dot(I, Ng);
  const float a = ix * ix + iz * iz;
  const float b = std::sqrt(std::max(ix * ix * (a - threshold * threshold), 0.0f));
  const float c = iz * threshold + a;
  const float fac = 0.5f / a;
  const float z1 = fac * (b + c), z2 = fac * (c - b);
  bool ok1 = z1 > 1e-5f && z1 <= 1 + 1e-5f, ok2 = z2 > 1e-5f && z2 <= 1 + 1e-5f;
  auto root = [](float x) { return std::sqrt(std::max(x, 0.0f)); };
  float nx, nz;
  if (ok1 && ok2) {
    const float x1 = root(1 - z1), y1 = root(z1), x2 = root(1 - z2), y2 = root(z2);
    const float r1 = 2 * (x1 * ix + y1 * iz) * y1 - iz, r2 = 2 * (x2 * ix + y2 * iz) * y2 - iz;
    ok1 = r1 >= 1e-5f;
    ok2 = r2 >= 1e-5f;
    // Both valid: the shallower reflection (closest to N); else the one reflecting upwards.
    const bool first = ok1 && ok2 ? r1 < r2 : r1 > r2;
    nx = first ? x1 : x2;
    nz = first ? y1 : y2;
  } else if (ok1 || ok2) {
    const float z = ok1 ? z1 : z2;
    nx = root(1 - z);
    nz = root(z);
  } else {
    return Ng;
  }
  return nx * X + nz * Ng;
}

// One shading normal per point: the first closure that brings its own (Normal linked) sets it.
void take_normal(Machine& m, const Vec3& n, const Vec3& weight) {
  if (m.has_shading_normal || is_black(weight) || !(dot(n, n) > 0) || !is_finite(n)) return;
  Vec3 N = normalize(n);
  if (m.ctx) {
    const Vec3 valid = ensure_valid_reflection(m.ctx->Ng, m.ctx->I, N);
    N = is_finite(valid) ? valid : N;
  }
  m.shading_normal = N;
  m.has_shading_normal = true;
}

bool backfacing(const Machine& m) { return m.ctx && m.ctx->backfacing; }

void principled(const Instr& in, Machine& m, Vec3 weight) {
  // Cycles 3.4 svm_node_closure_bsdf (PRINCIPLED): alpha below 1 makes the rest of the closure
  // partly transparent.
  const float alpha = unit(m.f(in.in[23]));
  if (alpha < 1) {
    Lobe t;
    t.type = LobeType::Transparent;
    t.weight = weight * (1 - alpha);
    m.bsdf->add(t);
    weight *= alpha;
  }
  take_normal(m, m.v(in.in[1]), weight);
  // Cycles 3.x Principled v1, reduced to its main lobes (README: departures): Burley's diffuse with
  // retro-reflection, a GGX specular layer as Cycles' (its Fresnel blends cspec0 = mix(0.08
  // specular, base, metallic), saturated, to 1 along the dielectric Fresnel of the IOR Specular
  // stands for), and a GGX glass lobe.
  const Vec3 base = non_negative(m.v(in.in[2]));
  const float metallic = unit(m.f(in.in[8]));
  const float transmission = unit(m.f(in.in[19])) * (1 - metallic);
  const float r = unit(m.f(in.in[11]));
  // 12.5 is where 0.08 specular reaches 1 (an infinite IOR); NaN becomes 0.
  const float spec = std::min(std::max(0.0f, m.f(in.in[9])), 12.5f);
  Lobe d;
  d.type = LobeType::PrincipledDiffuse;
  d.roughness = r;
  d.weight = weight * base * ((1 - metallic) * (1 - transmission));
  m.bsdf->add(d);
  // Cycles leaves the layer out when Specular and Metallic are both below its closure cutoff.
  if (spec > kClosureCutoff || metallic > kClosureCutoff) {
    Lobe g;
    g.type = LobeType::SpecularGGX;
    g.weight = weight * (1 - transmission);
    g.alpha = r * r;
    g.f0 = lerp(metallic, Vec3(0.08f * spec), base);  // fresnel_principled saturates it
    g.eta = principled_specular_ior(spec);
    m.bsdf->add(g);
  }
  if (transmission > 0) {
    Lobe t;
    t.type = LobeType::Dielectric;
    t.weight = weight * base * transmission;
    t.alpha = r * r;
    const float ior = glass_ior(m.f(in.in[18]));
    t.eta = backfacing(m) ? 1 / ior : ior;
    m.bsdf->add(t);
  }
}

const OpSignature kSignatures[] = {
    {"vvf", "", "", false},                           // emission
    {"vvvf", "", "", false},                          // diffuse
    {"vvvf", "", "i", false},                         // glossy
    {"vvvff", "", "i", false},                        // glass
    {"vv", "", "", false},                            // transparent
    {"vvvfvvfffffffffffffffvffvv", "", "ii", false},  // principled
    {"vf", "vv", "", true},                           // mix weights
    {"v", "", "", false},                             // holdout
};

}  // namespace

const OpSignature* shaders_family_signature(uint32_t op) {
  if (op < kOpEmission || op > kOpHoldout) return nullptr;
  return &kSignatures[op - kOpEmission];
}

void exec_shaders_family(const Instr& in, Machine& m) {
  if (in.op == kOpMixWeights) {
    const Vec3 w = m.v(in.in[0]);
    const float f = unit(m.f(in.in[1]));
    m.set(in.out[0], w * (1 - f));
    m.set(in.out[1], w * f);
    return;
  }
  const Vec3 weight = m.v(in.in[0]);
  if (is_black(weight)) return;
  if (in.op == kOpEmission) {
    // Emission keeps its sign, as Cycles' (a negative colour or strength is negative light).
    m.emitted += weight * finite(m.v(in.in[1])) * m.f(in.in[2]);
    return;
  }
  if (in.op == kOpPrincipled) {
    // Emission first: light sampling runs without lobes.
    const Vec3 e = finite(m.v(in.in[21]));
    if (!is_black(e)) m.emitted += weight * e * m.f(in.in[22]);
    if (m.bsdf) principled(in, m, weight);
    return;
  }
  if (!m.bsdf) return;
  Lobe l;
  switch (in.op) {
    case kOpDiffuse:
      take_normal(m, m.v(in.in[1]), weight);
      l.type = LobeType::Diffuse;
      l.weight = weight * non_negative(m.v(in.in[2]));
      l.roughness = unit(m.f(in.in[3]));
      break;
    case kOpGlossy: {
      take_normal(m, m.v(in.in[1]), weight);
      const float r = in.param[0] == kDistSharp ? 0.0f : unit(m.f(in.in[3]));
      l.type = LobeType::GlossyGGX;
      l.weight = weight * non_negative(m.v(in.in[2]));
      l.alpha = r * r;
      break;
    }
    case kOpGlass: {
      take_normal(m, m.v(in.in[1]), weight);
      const float r = in.param[0] == kDistSharp ? 0.0f : unit(m.f(in.in[3]));
      l.type = LobeType::Dielectric;
      l.weight = weight * non_negative(m.v(in.in[2]));
      l.alpha = r * r;
      const float ior = glass_ior(m.f(in.in[4]));
      l.eta = backfacing(m) ? 1 / ior : ior;
      break;
    }
    case kOpTransparent:
      l.type = LobeType::Transparent;
      l.weight = weight * non_negative(m.v(in.in[1]));
      break;
    case kOpHoldout:
      l.type = LobeType::Transparent;
      l.weight = weight;
      break;
    default:
      return;
  }
  m.bsdf->add(l);
}

}  // namespace lt
