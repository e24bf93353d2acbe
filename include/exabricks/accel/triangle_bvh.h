// Triangle meshes behind a bounding-volume hierarchy of plain arrays: built on the host, traversed
// by host and device code alike (the renderer's device back ends; the CPU renderer's meshes go
// through Embree, mesh_bvh.h, with the same conventions: a float ray, the nearest hit within
// [tmin, tmax], the geometric normal facing the ray's origin).
#pragma once

#include "exabricks/accel/bvh.h"
#include "exabricks/core/math.h"
#include "exabricks/core/mesh.h"

#include <cstdint>
#include <vector>

namespace exa {

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
  bool found = false;
  float far = tmax;
  traverseBvh(bvh.nodes, org, dir, tmin, far, [&](uint32_t first, uint32_t count, float& best) {
    for (uint32_t i = first; i < first + count; ++i) {
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
    return false;
  });
  return found;
}

} // namespace exa
