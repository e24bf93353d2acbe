// A bounding-volume hierarchy of plain arrays over any primitives: built on the host from the
// primitives' boxes and centres (binned surface-area costs, the subtrees in parallel), traversed
// by host and device code alike with the primitives' own intersection test. The triangle and
// sphere hierarchies (triangle_bvh.h, sphere_bvh.h) are this over their primitives.
#pragma once

#include "exabricks/core/math.h"

#include <cstdint>
#include <vector>

namespace exa {

/// A node: leaves (count > 0) hold primitives [first, first + count); inner nodes have their two
/// children at first and first + 1.
struct BvhNode {
  box3f bounds;
  uint32_t first = 0, count = 0;
};

/// Builds the nodes over primitives with these boxes and centres (at most 2^31), with leaves of
/// about `leafSize`; `order` receives the primitives' order in the leaves (leaf ranges index it).
void buildBvh(const std::vector<box3f>& boxes, const std::vector<vec3f>& centres, uint32_t leafSize,
              std::vector<BvhNode>& nodes, std::vector<uint32_t>& order);

/// Visits the leaves the ray org + t dir, t in [tmin, far], enters, nearest-first by the order of
/// the children; `leaf(first, count, far)` tests the leaf's primitives, may shorten `far` (a
/// nearer hit) and returns true to stop (an occlusion test's first hit).
template <typename Leaf>
EXA_HOST_DEVICE inline void traverseBvh(const BvhNode* nodes, const vec3f& org, const vec3f& dir, float tmin,
                                        float& far, Leaf&& leaf) {
  const vec3f inv(dir.x != 0.f ? 1.f / dir.x : 1e30f, dir.y != 0.f ? 1.f / dir.y : 1e30f,
                  dir.z != 0.f ? 1.f / dir.z : 1e30f);
  auto enters = [&](const box3f& b) {
    float t0 = tmin, t1 = far;
    for (int a = 0; a < 3; ++a) {
      const float ta = (b.lower[a] - org[a]) * inv[a], tb = (b.upper[a] - org[a]) * inv[a];
      t0 = t0 > (ta < tb ? ta : tb) ? t0 : (ta < tb ? ta : tb);
      t1 = t1 < (ta > tb ? ta : tb) ? t1 : (ta > tb ? ta : tb);
    }
    return t0 <= t1;
  };
  uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const BvhNode& n = nodes[stack[--top]];
    if (!enters(n.bounds)) continue;
    if (n.count == 0) {
      if (top < 63) {
        stack[top++] = n.first + 1;
        stack[top++] = n.first;
      }
      continue;
    }
    if (leaf(n.first, n.count, far)) return;
  }
}

} // namespace exa
