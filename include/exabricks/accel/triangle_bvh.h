// Triangle meshes behind a bounding-volume hierarchy of plain arrays: built on the host, traversed
// by host and device code alike (the renderer's device back ends; the CPU renderer's meshes go
// through Embree, mesh_bvh.h, with the same conventions: a float ray, the nearest hit within
// [tmin, tmax], the geometric normal facing the ray's origin).
#pragma once

#include "exabricks/core/math.h"
#include "exabricks/core/mesh.h"

#include <cstdint>
#include <vector>

namespace exa {

/// A node: leaves (count > 0) hold triangles [first, first + count); inner nodes have their two
/// children at first and first + 1.
struct BvhNode {
  box3f bounds;
  uint32_t first = 0, count = 0;
};

/// A triangle as its first vertex and two edges, with the mesh it belongs to.
struct BvhTriangle {
  vec3f v0, e1, e2;
  int mesh = 0;
};

struct TriangleBvhView {
  const BvhNode* nodes = nullptr; ///< null: no triangles
  const BvhTriangle* triangles = nullptr;
};

class TriangleBvh {
public:
  /// Replaces the meshes (world space; mesh i's triangles get mesh index i).
  void build(const std::vector<const TriangleMesh*>& meshes);
  bool empty() const { return nodes_.empty(); }
  const std::vector<BvhNode>& nodes() const { return nodes_; }
  const std::vector<BvhTriangle>& triangles() const { return triangles_; }
  TriangleBvhView view() const { return {nodes_.empty() ? nullptr : nodes_.data(), triangles_.data()}; }

private:
  std::vector<BvhNode> nodes_;
  std::vector<BvhTriangle> triangles_;
};

/// A hit of a ray with the triangles.
struct TriangleHit {
  float t = 0.f;
  int mesh = 0;
  vec3f normal{0.f}; ///< unit geometric normal, facing the ray's origin
};

/// Möller-Trumbore: the distance along org + t dir to the triangle, or a negative value.
EXA_HOST_DEVICE inline float intersectTriangle(const BvhTriangle& tri, const vec3f& org, const vec3f& dir) {
  const vec3f p = cross(dir, tri.e2);
  const float det = dot(tri.e1, p);
  if (det == 0.f || det != det) return -1.f;
  const float inv = 1.f / det;
  const vec3f s = org - tri.v0;
  const float u = dot(s, p) * inv;
  if (u < 0.f || u > 1.f) return -1.f;
  const vec3f q = cross(s, tri.e1);
  const float w = dot(dir, q) * inv;
  if (w < 0.f || u + w > 1.f) return -1.f;
  return dot(tri.e2, q) * inv;
}

/// The nearest hit with t in [tmin, tmax] (`any`: the first one found, for occlusion); false
/// where there is none.
EXA_HOST_DEVICE inline bool intersectTriangles(const TriangleBvhView& bvh, const vec3f& org, const vec3f& dir,
                                               float tmin, float tmax, bool any, TriangleHit& hit) {
  if (!bvh.nodes || !(tmax >= tmin)) return false;
  const vec3f inv(dir.x != 0.f ? 1.f / dir.x : 1e30f, dir.y != 0.f ? 1.f / dir.y : 1e30f,
                  dir.z != 0.f ? 1.f / dir.z : 1e30f);
  auto enters = [&](const box3f& b, float far) {
    float t0 = tmin, t1 = far;
    for (int a = 0; a < 3; ++a) {
      const float ta = (b.lower[a] - org[a]) * inv[a], tb = (b.upper[a] - org[a]) * inv[a];
      t0 = std::max(t0, std::min(ta, tb));
      t1 = std::min(t1, std::max(ta, tb));
    }
    return t0 <= t1;
  };
  uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  bool found = false;
  float best = tmax;
  while (top > 0) {
    const BvhNode& n = bvh.nodes[stack[--top]];
    if (!enters(n.bounds, best)) continue;
    if (n.count == 0) {
      if (top < 63) {
        stack[top++] = n.first + 1;
        stack[top++] = n.first;
      }
      continue;
    }
    for (uint32_t i = n.first; i < n.first + n.count; ++i) {
      const BvhTriangle& tri = bvh.triangles[i];
      const float t = intersectTriangle(tri, org, dir);
      if (!(t >= tmin && t <= best)) continue;
      best = t;
      found = true;
      hit.t = t;
      hit.mesh = tri.mesh;
      vec3f nrm = normalize(cross(tri.e1, tri.e2));
      if (dot(nrm, dir) > 0.f) nrm = -nrm;
      hit.normal = nrm;
      if (any) return true;
    }
  }
  return found;
}

} // namespace exa
