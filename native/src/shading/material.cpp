#include "shading/material.h"

#include <functional>
#include <string>

#include "core/error.h"

namespace lt {

namespace {

Vec3 color_of(const Input& in, const std::vector<std::unique_ptr<Image>>& images, Vec2 uv) {
  return in.image >= 0 ? images[in.image]->lookup(uv) : in.value;
}
float value_of(const Input& in, const std::vector<std::unique_ptr<Image>>& images, Vec2 uv) {
  return in.image >= 0 ? images[in.image]->lookup_value(uv) : in.value.x;
}
float unit(float x) { return std::isfinite(x) ? clamp(x, 0.0f, 1.0f) : 0.0f; }
Vec3 non_negative(Vec3 c) {
  for (int k = 0; k < 3; ++k) c[k] = std::isfinite(c[k]) ? std::max(0.0f, c[k]) : 0.0f;
  return c;
}
// Glass and Principled IOR as Cycles 3.4 takes it (fmaxf(ior, 1e-5f)): below 1 is an optically
// thinner inside (an air bubble in water, IOR 0.75, reflects totally beyond asin(0.75) = 48.6
// degrees from its normal); 0 or less becomes 1e-5, a near-perfect mirror.
float glass_ior(float ior) { return std::max(ior, 1e-5f); }

constexpr int kMaxDepth = 64;
constexpr float kClosureCutoff = 1e-5f;  // Cycles' CLOSURE_WEIGHT_CUTOFF

}  // namespace

Material::Material(std::vector<ShaderNode> nodes, int root, size_t image_count)
    : nodes_(std::move(nodes)), root_(root) {
  const int n = int(nodes_.size());
  if (n == 0) throw InvalidArgument("material has no nodes");
  if (root < 0 || root >= n) throw InvalidArgument("material root " + std::to_string(root) + " is out of range");
  for (int i = 0; i < n; ++i) {
    const ShaderNode& s = nodes_[i];
    if (int(s.type) < 0 || s.type >= NodeType::Count)
      throw InvalidArgument("material node " + std::to_string(i) + " has an unknown type " +
                            std::to_string(int(s.type)));
    for (const Input* in :
         {&s.color, &s.roughness, &s.fac, &s.metallic, &s.specular, &s.transmission, &s.emission, &s.strength})
      if (in->image >= int(image_count))
        throw InvalidArgument("material node " + std::to_string(i) + " refers to image " + std::to_string(in->image) +
                              " which does not exist");
    int kids = s.type == NodeType::Mix || s.type == NodeType::Add ? 2 : 0;
    for (int c = 0; c < kids; ++c)
      if (s.child[c] < 0 || s.child[c] >= n)
        throw InvalidArgument("material node " + std::to_string(i) + " has child " + std::to_string(s.child[c]) +
                              " out of range");
  }
  // Reject cycles and trees deeper than the evaluator walks (depth-first with colours).
  std::vector<int> state(n, 0);
  std::vector<std::pair<int, int>> stack{{root, 0}};
  bool emissive = false;
  float estimate = 0;
  while (!stack.empty()) {
    auto [i, depth] = stack.back();
    stack.pop_back();
    if (i < 0) {
      state[-i - 1] = 2;
      continue;
    }
    if (state[i] == 1) throw InvalidArgument("material node graph has a cycle through node " + std::to_string(i));
    if (depth > kMaxDepth) throw InvalidArgument("material node tree is deeper than " + std::to_string(kMaxDepth));
    if (state[i] == 2) continue;
    state[i] = 1;
    stack.push_back({-i - 1, depth});
    const ShaderNode& s = nodes_[i];
    if (s.type == NodeType::Mix || s.type == NodeType::Add) {
      stack.push_back({s.child[0], depth + 1});
      stack.push_back({s.child[1], depth + 1});
    }
    if (s.type == NodeType::Emission || s.type == NodeType::Principled) {
      Input c = s.type == NodeType::Emission ? s.color : s.emission;
      float strength = s.strength.image >= 0 ? 1.0f : s.strength.value.x;
      // Negative strength is negative light (as Cycles renders it): the estimate is its magnitude.
      float e = (c.image >= 0 ? 1.0f : max_component(non_negative(c.value))) * std::abs(strength);
      if (std::isfinite(e) && e > 0) {
        emissive = true;
        estimate = std::max(estimate, e);
      }
    }
  }
  // The evaluator walks the graph as a tree: a node shared by several inputs is visited once per
  // path to it. The depth-first check above sees a shared node only at the first depth it reaches
  // it, so measure the longest path (the evaluator's stack holds kMaxDepth levels) and the expanded
  // size (sharing can make the walk exponentially long; a tree of n nodes expands to n) here.
  constexpr double kMaxExpanded = 4096;
  std::vector<std::pair<double, int>> memo(n, {-1.0, 0});                           // expanded size, longest path below
  std::function<std::pair<double, int>(int, int)> expand = [&](int i, int depth) {  // acyclic here
    if (memo[i].first < 0) {
      if (depth > kMaxDepth) throw InvalidArgument("material node tree is deeper than " + std::to_string(kMaxDepth));
      const ShaderNode& s = nodes_[i];
      std::pair<double, int> r{1, 0};
      if (s.type == NodeType::Mix || s.type == NodeType::Add) {
        auto a = expand(s.child[0], depth + 1), b = expand(s.child[1], depth + 1);
        r = {std::min(1 + a.first + b.first, 2 * kMaxExpanded), 1 + std::max(a.second, b.second)};
      }
      memo[i] = r;
    }
    if (depth + memo[i].second > kMaxDepth)
      throw InvalidArgument("material node tree is deeper than " + std::to_string(kMaxDepth));
    return memo[i];
  };
  if (expand(root, 0).first > kMaxExpanded)
    throw InvalidArgument("material node graph expands to more than " + std::to_string(int(kMaxExpanded)) +
                          " nodes when shared nodes are repeated for each input they feed");
  emissive_ = emissive;
  emission_estimate_ = estimate;
}

Material Material::default_surface() {
  Material m;
  ShaderNode d;
  d.type = NodeType::Diffuse;
  d.color.value = Vec3(0.8f);
  m.nodes_ = {d};
  return m;
}

template <bool kLobes>
Spectrum Material::walk(const std::vector<std::unique_ptr<Image>>& images, Vec2 uv, bool backface, Bsdf* bsdf) const {
  // Plain floats: a Vec3 member would zero-fill the whole stack on every evaluation.
  struct Item {
    int node;
    float w[3];
    Vec3 weight() const { return {w[0], w[1], w[2]}; }
  };
  Item stack[kMaxDepth + 2];
  int top = 0;
  auto push = [&](int node, const Vec3& weight) { stack[top++] = {node, {weight.x, weight.y, weight.z}}; };
  push(root_, Vec3(1.0f));
  Spectrum emitted(0.0f);
  while (top > 0) {
    const Item& top_item = stack[--top];
    const int node = top_item.node;
    const Vec3 weight = top_item.weight();
    if (is_black(weight)) continue;
    const ShaderNode& s = nodes_[node];
    switch (s.type) {
      case NodeType::Mix: {
        float f = unit(value_of(s.fac, images, uv));
        push(s.child[0], weight * (1 - f));
        push(s.child[1], weight * f);
        break;
      }
      case NodeType::Add:
        push(s.child[0], weight);
        push(s.child[1], weight);
        break;
      case NodeType::Emission:
        emitted += weight * non_negative(color_of(s.color, images, uv)) * value_of(s.strength, images, uv);
        break;
      case NodeType::Principled:
        if (s.emission.image >= 0 || !is_black(s.emission.value))
          emitted += weight * non_negative(color_of(s.emission, images, uv)) * value_of(s.strength, images, uv);
        if constexpr (kLobes) {
          // Cycles 3.x Principled v1, reduced to its main lobes (README: departures): Burley's
          // diffuse with retro-reflection (no sheen, subsurface or clearcoat), a GGX specular layer as
          // Cycles' (its Fresnel blends cspec0 = mix(0.08 specular, base, metallic), saturated, to 1
          // along the dielectric Fresnel of the IOR Specular stands for), and a GGX glass lobe.
          Vec3 base = non_negative(color_of(s.color, images, uv));
          float metallic = unit(value_of(s.metallic, images, uv));
          float transmission = unit(value_of(s.transmission, images, uv)) * (1 - metallic);
          float r = unit(value_of(s.roughness, images, uv));
          // 12.5 is where 0.08 specular reaches 1 (an infinite IOR); NaN becomes 0.
          float spec = std::min(std::max(0.0f, value_of(s.specular, images, uv)), 12.5f);
          Lobe d;
          d.type = LobeType::PrincipledDiffuse;
          d.roughness = r;
          d.weight = weight * base * ((1 - metallic) * (1 - transmission));
          bsdf->add(d);
          // Cycles leaves the layer out when Specular and Metallic are both below its closure cutoff.
          if (spec > kClosureCutoff || metallic > kClosureCutoff) {
            Lobe g;
            g.type = LobeType::SpecularGGX;
            g.weight = weight * (1 - transmission);
            g.alpha = r * r;
            g.f0 = lerp(metallic, Vec3(0.08f * spec), base);  // fresnel_principled saturates it
            g.eta = principled_specular_ior(spec);
            bsdf->add(g);
          }
          if (transmission > 0) {
            Lobe t;
            t.type = LobeType::Dielectric;
            t.weight = weight * base * transmission;
            t.alpha = r * r;
            const float ior = glass_ior(s.ior);
            t.eta = backface ? 1 / ior : ior;
            bsdf->add(t);
          }
        }
        break;
      default:
        if constexpr (kLobes) {
          Lobe l;
          l.weight = weight * non_negative(color_of(s.color, images, uv));
          float r = unit(value_of(s.roughness, images, uv));
          switch (s.type) {
            case NodeType::Diffuse:
              l.type = LobeType::Diffuse;
              l.roughness = r;
              break;
            case NodeType::Glossy:
              l.type = LobeType::GlossyGGX;
              l.alpha = r * r;
              break;
            case NodeType::Glass: {
              l.type = LobeType::Dielectric;
              l.alpha = r * r;
              const float ior = glass_ior(s.ior);
              l.eta = backface ? 1 / ior : ior;
              break;
            }
            case NodeType::Transparent:
              l.type = LobeType::Transparent;
              break;
            default:
              break;
          }
          bsdf->add(l);
        }
        break;
    }
  }
  return emitted;
}

Spectrum Material::evaluate(const std::vector<std::unique_ptr<Image>>& images, Vec2 uv, bool backface,
                            Bsdf* bsdf) const {
  bsdf->clear();
  return walk<true>(images, uv, backface, bsdf);
}

Spectrum Material::emission(const std::vector<std::unique_ptr<Image>>& images, Vec2 uv) const {
  if (!emissive_) return Spectrum(0.0f);
  return walk<false>(images, uv, false, nullptr);
}

}  // namespace lt
