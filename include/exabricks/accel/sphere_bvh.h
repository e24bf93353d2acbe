// Spheres (particles) behind a bounding-volume hierarchy of plain arrays, traversed by host and
// device code alike: every back end of the renderer intersects particles with this one code (a
// float ray, the nearest hit within [tmin, tmax], the normal facing the ray's origin).
#pragma once

#include "exabricks/accel/bvh.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace exa {

struct BvhSphere {
  vec3f centre{0.f};
  float radius = 0.f;
};

struct SphereBvhView {
  const BvhNode* nodes = nullptr; ///< null: no spheres
  const BvhSphere* spheres = nullptr;
};

class SphereBvh {
public:
  /// Replaces the spheres (world space, radius > 0). `order` receives, per sphere of the
  /// hierarchy (the index a hit reports), the index of the sphere given.
  void build(const std::vector<BvhSphere>& spheres, std::vector<uint32_t>& order);
  bool empty() const { return nodes_.empty(); }
  size_t size() const { return spheres_.size(); }
  SphereBvhView view() const { return {nodes_.empty() ? nullptr : nodes_.data(), spheres_.data()}; }
  const std::vector<BvhNode>& nodes() const { return nodes_; }
  const std::vector<BvhSphere>& spheres() const { return spheres_; }

private:
  std::vector<BvhNode> nodes_;
  std::vector<BvhSphere> spheres_;
};

struct SphereHit {
  float t = 0.f;
  uint32_t sphere = 0; ///< index in the hierarchy's order
  vec3f normal{0.f};   ///< unit, facing the ray's origin
};

/// The distance along org + t dir (dir unit) to the sphere's surface at or beyond tmin (its far
/// side from inside), or a negative value. The closest approach is found first, so that spheres
/// small against their distance from the origin keep their precision.
EXA_HOST_DEVICE inline float intersectSphere(const BvhSphere& s, const vec3f& org, const vec3f& dir, float tmin) {
  const vec3f oc = s.centre - org;
  const float tc = dot(oc, dir);
  const vec3f off = oc - dir * tc;
  const float d2 = dot(off, off), r2 = s.radius * s.radius;
  if (!(d2 <= r2)) return -1.f;
  const float h = sqrtf(r2 - d2);
  if (tc - h >= tmin) return tc - h;
  if (tc + h >= tmin) return tc + h;
  return -1.f;
}

/// The nearest sphere with t in [tmin, tmax] (`any`: the first one found, for occlusion).
EXA_HOST_DEVICE inline bool intersectSpheres(const SphereBvhView& bvh, const vec3f& org, const vec3f& dir, float tmin,
                                             float tmax, bool any, SphereHit& hit) {
  if (!bvh.nodes || !(tmax >= tmin)) return false;
  bool found = false;
  float far = tmax;
  traverseBvh(bvh.nodes, org, dir, tmin, far, [&](uint32_t first, uint32_t count, float& best) {
    for (uint32_t i = first; i < first + count; ++i) {
      const float t = intersectSphere(bvh.spheres[i], org, dir, tmin);
      if (!(t >= tmin && t <= best)) continue;
      best = t;
      found = true;
      hit.t = t;
      hit.sphere = i;
      if (any) return true;
    }
    return false;
  });
  if (found) {
    const BvhSphere& s = bvh.spheres[hit.sphere];
    vec3f n = (org + dir * hit.t - s.centre) * (1.f / s.radius);
    const float len = sqrtf(dot(n, n));
    n = len > 0.f ? n * (1.f / len) : -dir;
    if (dot(n, dir) > 0.f) n = -n;
    hit.normal = n;
  }
  return found;
}

} // namespace exa
