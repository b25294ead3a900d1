// The light tree for next-event estimation among many lights (Conty Estevez and Kulla 2018,
// "Importance Sampling of Many Lights with Adaptive Tree Splitting"; pbrt-v4's BVHLightSampler,
// section 12.6.3): a binary BVH over the bounded lights (lamps and emissive triangles; never sun
// or world) whose nodes keep a box, an orientation cone and their total flux. A shading point
// walks down it, choosing each child in proportion to an importance that bounds what the child's
// lights can send there, so the light picked and its probability depend on where the light is
// received. pmf() retraces the same walk along the light's stored bit trail and multiplies the
// same ratios, so it is exactly the probability sample() produced (MIS needs that).
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"
#include "geometry/geometry.h"

namespace lt {

// What a light or a group of lights can emit (pbrt-v4's LightBounds): its box, the flux phi, the
// cone of normals (axis w, cos of its spread theta_o) and the emission spread theta_e about each
// normal (pi/2 for a cosine emitter, pi for a point). Two-sided: each normal also emits along -w.
struct LightBounds {
  Bounds box;
  Vec3 w{0, 0, 1};
  float phi = 0;
  float cos_o = 1, cos_e = 1;
  bool two_sided = false;
};

LightBounds light_bounds_union(const LightBounds& a, const LightBounds& b);
// An upper estimate of what the lights within b send to the point p with normal n (zero n: a point
// in a medium, no cosine), zero only where none of them can send anything (pbrt-v4's
// LightBounds::Importance).
float light_importance(const LightBounds& b, const Vec3& p, const Vec3& n);

class LightTree {
 public:
  struct Item {
    int light;  // the caller's index of the light
    LightBounds bounds;
  };
  // O(n log n), the halves of large subtrees on TBB threads: binned SAH-like splits over the
  // centroids (pbrt-v4's EvaluateCost), at most 63 levels deep so that a light's path from the
  // root fits in 64 bits. light_count: the caller's number of lights (items' indices are below).
  void build(std::vector<Item> items, size_t light_count);
  bool empty() const { return nodes_.empty(); }
  size_t node_count() const { return nodes_.size(); }

  // Walks down from the root with u; the light picked and its probability, or -1 where no light
  // of the tree can reach p.
  int sample(const Vec3& p, const Vec3& n, float u, float* pmf) const;
  // The probability sample() picks `light` at (p, n): 0 for lights outside the tree.
  float pmf(const Vec3& p, const Vec3& n, int light) const;

 private:
  struct Node {
    LightBounds bounds;
    uint32_t index = 0;  // inner: the second child (the first follows the node); leaf: the light
    bool leaf = false;
  };
  void build_node(std::vector<Item>& items, size_t begin, size_t end, uint64_t trail, int depth,
                  std::vector<Node>& out);
  size_t split(std::vector<Item>& items, size_t begin, size_t end, const LightBounds& all, const Bounds& centroids,
               int depth);
  // Probability of the first child of inner node i at (p, n); negative if neither child can reach p.
  float first_child_probability(int i, const Vec3& p, const Vec3& n) const;
  std::vector<Node> nodes_;
  std::vector<uint64_t> trail_;  // per caller's light: bit k set = the second child at depth k
};

}  // namespace lt
