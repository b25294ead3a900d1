#include "scene/lights/light_tree.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>

namespace lt {

namespace {

Bounds box_union(const Bounds& a, const Bounds& b) {
  Bounds r;
  r.lo = vmin(a.lo, b.lo);
  r.hi = vmax(a.hi, b.hi);
  return r;
}
Vec3 box_center(const Bounds& b) { return (b.lo + b.hi) * 0.5f; }
float box_area(const Bounds& b) {
  const Vec3 d = b.hi - b.lo;
  return 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
}
float safe_acos(float c) { return std::acos(clamp(c, -1.0f, 1.0f)); }

// Rotates v about the unit axis a by angle t (Rodrigues).
Vec3 rotate(const Vec3& v, const Vec3& a, float t) {
  const float c = std::cos(t), s = std::sin(t);
  return v * c + cross(a, v) * s + a * (dot(a, v) * (1 - c));
}

// cos(max(0, a - b)) and sin(max(0, a - b)) from the sines and cosines (pbrt-v4's
// cosSubClamped / sinSubClamped).
float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
  return cos_a > cos_b ? 1.0f : cos_a * cos_b + sin_a * sin_b;
}
float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
  return cos_a > cos_b ? 0.0f : sin_a * cos_b - cos_a * sin_b;
}

// pbrt-v4's EvaluateCost: flux x the orientation cone's measure M_omega x the box's surface area,
// with Kr penalising thin slabs cut across their long side.
float split_cost(const LightBounds& b, const Bounds& node, int dim) {
  const float theta_o = safe_acos(b.cos_o), theta_e = safe_acos(b.cos_e);
  const float theta_w = std::min(theta_o + theta_e, kPi);
  const float sin_o = safe_sqrt(1 - b.cos_o * b.cos_o);
  const float m_omega =
      2 * kPi * (1 - b.cos_o) +
      kPi / 2 * (2 * theta_w * sin_o - std::cos(theta_o - 2 * theta_w) - 2 * theta_o * sin_o + b.cos_o);
  const Vec3 d = node.hi - node.lo;
  const float kr = max_component(d) / d[dim];
  return b.phi * m_omega * kr * box_area(b.box);
}

int ceil_log2(size_t n) {
  int k = 0;
  while ((size_t(1) << k) < n) ++k;
  return k;
}

}  // namespace

LightBounds light_bounds_union(const LightBounds& a, const LightBounds& b) {
  if (a.phi == 0) return b;
  if (b.phi == 0) return a;
  LightBounds r;
  r.box = box_union(a.box, b.box);
  r.phi = a.phi + b.phi;
  r.cos_e = std::min(a.cos_e, b.cos_e);
  r.two_sided = a.two_sided || b.two_sided;
  // The cone holding both cones of normals (pbrt-v4's DirectionCone Union), widened by a little
  // so that rounding never leaves a normal outside it.
  const float ta = safe_acos(a.cos_o), tb = safe_acos(b.cos_o), td = safe_acos(dot(a.w, b.w));
  const float slack = 1e-4f;
  if (std::min(td + tb, kPi) <= ta) {
    r.w = a.w;
    r.cos_o = std::cos(std::min(ta + slack, kPi));
  } else if (std::min(td + ta, kPi) <= tb) {
    r.w = b.w;
    r.cos_o = std::cos(std::min(tb + slack, kPi));
  } else {
    const float to = 0.5f * (ta + td + tb);
    const Vec3 axis = cross(a.w, b.w);
    if (to >= kPi || !(length_squared(axis) > 0)) {
      r.w = a.w;
      r.cos_o = -1;
    } else {
      r.w = normalize(rotate(a.w, normalize(axis), to - ta));
      r.cos_o = std::cos(std::min(to + slack, kPi));
    }
  }
  return r;
}

float light_importance(const LightBounds& b, const Vec3& p, const Vec3& n) {
  if (!(b.phi > 0)) return 0;
  const Vec3 pc = box_center(b.box);
  const float dist2 = length_squared(p - pc);
  const float radius2 = 0.25f * length_squared(b.box.hi - b.box.lo);
  // pbrt-v4 clamps the distance with the box's half diagonal so that points near or inside a
  // large node do not blow up.
  const float d2 = std::max(dist2, std::sqrt(radius2));
  if (!(d2 > 0)) return 0;                  // a point light at p sends nothing to p
  if (dist2 <= radius2) return b.phi / d2;  // inside the node's bounding sphere: every direction
  const Vec3 wi = (p - pc) / std::sqrt(dist2);
  float cos_w = dot(b.w, wi);
  if (b.two_sided) cos_w = std::abs(cos_w);
  const float sin_w = safe_sqrt(1 - cos_w * cos_w);
  // theta_b: the half angle the node's bounding sphere subtends at p.
  const float cos_b = safe_sqrt(1 - radius2 / dist2), sin_b = safe_sqrt(radius2 / dist2);
  // theta' = max(0, theta_w - theta_o - theta_b): the smallest angle between a normal of the
  // cone and a direction from the node to p; nothing is emitted beyond theta_e.
  const float sin_o = safe_sqrt(1 - b.cos_o * b.cos_o);
  const float cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, b.cos_o);
  const float sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, b.cos_o);
  const float cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
  if (cos_p <= b.cos_e) return 0;
  float importance = b.phi * cos_p / d2;
  if (n.x != 0 || n.y != 0 || n.z != 0) {
    // The receiver's cosine, bounded the same way (either side: transmission receives too).
    const float cos_i = std::abs(dot(wi, n)) / length(n);
    const float sin_i = safe_sqrt(1 - cos_i * cos_i);
    importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
  }
  return std::max(importance, 0.0f);
}

void LightTree::build(std::vector<Item> items, size_t light_count) {
  nodes_.clear();
  trail_.assign(light_count, 0);
  if (items.empty()) return;
  nodes_.reserve(2 * items.size() - 1);
  build_node(items, 0, items.size(), 0, 0, nodes_);
}

// Appends the subtree of items[begin, end) to out in depth-first order (a node's first child
// follows it; inner nodes' indices are positions in out). Large subtrees build their two halves
// on TBB threads, each into its own vector, then move them in.
void LightTree::build_node(std::vector<Item>& items, size_t begin, size_t end, uint64_t trail, int depth,
                           std::vector<Node>& out) {
  const size_t index = out.size();
  out.emplace_back();
  if (end - begin == 1) {
    Node& leaf = out[index];
    leaf.bounds = items[begin].bounds;
    leaf.index = uint32_t(items[begin].light);
    leaf.leaf = true;
    trail_[items[begin].light] = trail;
    return;
  }
  LightBounds all;
  Bounds centroids;
  for (size_t i = begin; i < end; ++i) {
    all = light_bounds_union(all, items[i].bounds);
    centroids.extend(box_center(items[i].bounds.box));
  }
  const size_t mid = split(items, begin, end, all, centroids, depth);
  const uint64_t second_trail = trail | (uint64_t(1) << depth);
  size_t second;
  if (end - begin < 8192) {
    build_node(items, begin, mid, trail, depth + 1, out);
    second = out.size();
    build_node(items, mid, end, second_trail, depth + 1, out);
  } else {
    std::vector<Node> first_nodes, second_nodes;
    tbb::parallel_invoke([&] { build_node(items, begin, mid, trail, depth + 1, first_nodes); },
                         [&] { build_node(items, mid, end, second_trail, depth + 1, second_nodes); });
    second = out.size() + first_nodes.size();
    for (std::vector<Node>* part : {&first_nodes, &second_nodes}) {
      const uint32_t base = uint32_t(out.size());
      for (Node n : *part) {
        if (!n.leaf) n.index += base;
        out.push_back(n);
      }
    }
  }
  Node& node = out[index];
  node.bounds = all;
  node.index = uint32_t(second);
  node.leaf = false;
}

// Where to cut items[begin, end) (reordering them): binned split search over the centroids
// (pbrt-v4's buildBVH, 12 buckets per axis), else halves along the widest axis.
size_t LightTree::split(std::vector<Item>& items, size_t begin, size_t end, const LightBounds& all,
                        const Bounds& centroids, int depth) {
  constexpr int kBuckets = 12;
  float best_cost = INFINITY;
  int best_dim = -1, best_bucket = -1;
  const size_t count = end - begin;
  // Within 63 levels whatever the splits found: below this depth, halve by count.
  const bool must_halve = depth + ceil_log2(count) >= 63;
  auto bucket_of = [&](const Item& it, int dim) {
    const float lo = centroids.lo[dim], hi = centroids.hi[dim];
    int b = int(kBuckets * ((box_center(it.bounds.box)[dim] - lo) / (hi - lo)));
    return clamp(b, 0, kBuckets - 1);
  };
  for (int dim = 0; dim < 3 && !must_halve; ++dim) {
    if (!(centroids.hi[dim] > centroids.lo[dim])) continue;
    LightBounds bucket[kBuckets];
    for (size_t i = begin; i < end; ++i) {
      const int b = bucket_of(items[i], dim);
      bucket[b] = light_bounds_union(bucket[b], items[i].bounds);
    }
    // Prefix and suffix unions: O(buckets) per axis.
    LightBounds below[kBuckets], above[kBuckets];
    below[0] = bucket[0];
    for (int b = 1; b < kBuckets; ++b) below[b] = light_bounds_union(below[b - 1], bucket[b]);
    above[kBuckets - 1] = bucket[kBuckets - 1];
    for (int b = kBuckets - 2; b >= 0; --b) above[b] = light_bounds_union(above[b + 1], bucket[b]);
    for (int b = 0; b < kBuckets - 1; ++b) {
      if (below[b].phi == 0 || above[b + 1].phi == 0) continue;
      const float cost = split_cost(below[b], all.box, dim) + split_cost(above[b + 1], all.box, dim);
      if (cost < best_cost) {
        best_cost = cost;
        best_dim = dim;
        best_bucket = b;
      }
    }
  }
  if (best_dim >= 0) {
    auto it = std::partition(items.begin() + begin, items.begin() + end,
                             [&](const Item& item) { return bucket_of(item, best_dim) <= best_bucket; });
    const size_t mid = size_t(it - items.begin());
    if (mid != begin && mid != end) return mid;
  }
  // No useful split: halve along the widest axis of the centroids.
  const size_t mid = begin + count / 2;
  const Vec3 ext = centroids.hi - centroids.lo;
  const int dim = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
  std::nth_element(items.begin() + begin, items.begin() + mid, items.begin() + end, [&](const Item& a, const Item& b) {
    return box_center(a.bounds.box)[dim] < box_center(b.bounds.box)[dim];
  });
  return mid;
}

// One function for both walks, so that sample() and pmf() multiply bit-identical factors.
float LightTree::first_child_probability(int i, const Vec3& p, const Vec3& n) const {
  const float c0 = light_importance(nodes_[i + 1].bounds, p, n);
  const float c1 = light_importance(nodes_[nodes_[i].index].bounds, p, n);
  const float sum = c0 + c1;
  if (!(sum > 0) || !std::isfinite(sum)) return -1;
  return c0 / sum;
}

int LightTree::sample(const Vec3& p, const Vec3& n, float u, float* pmf) const {
  *pmf = 0;
  if (nodes_.empty()) return -1;
  // A single light is the pick wherever it is (pbrt-v4 first asks whether it can reach p: 4 % of a
  // Cornell box render for nothing, since its samples then light nothing; pmf() agrees).
  float prob = 1;
  int i = 0;
  while (!nodes_[i].leaf) {
    const float p0 = first_child_probability(i, p, n);
    if (p0 < 0) return -1;
    if (u < p0) {
      u = std::min(u / p0, kOneMinusEpsilon);
      prob *= p0;
      i = i + 1;
    } else {
      u = std::min((u - p0) / (1 - p0), kOneMinusEpsilon);
      prob *= 1 - p0;
      i = int(nodes_[i].index);
    }
  }
  *pmf = prob;
  return int(nodes_[i].index);
}

float LightTree::pmf(const Vec3& p, const Vec3& n, int light) const {
  if (nodes_.empty() || light < 0 || size_t(light) >= trail_.size()) return 0;
  uint64_t trail = trail_[light];
  float prob = 1;
  int i = 0;
  while (!nodes_[i].leaf) {
    const float p0 = first_child_probability(i, p, n);
    if (p0 < 0) return 0;
    if (trail & 1) {
      prob *= 1 - p0;
      i = int(nodes_[i].index);
    } else {
      prob *= p0;
      i = i + 1;
    }
    trail >>= 1;
  }
  return nodes_[i].index == uint32_t(light) ? prob : 0.0f;
}

}  // namespace lt
