// Triangle meshes in world space behind one bounding-volume hierarchy (Embree): the nearest hit
// along a ray and whether anything lies on a stretch of it. Embree stays behind this interface.
#pragma once

#include "exabricks/core/math.h"
#include "exabricks/core/mesh.h"

#include <memory>
#include <vector>

namespace exa {

/// A ray's nearest mesh hit.
struct MeshHit {
  int mesh = 0;        ///< index of the mesh in the list given to build()
  double distance = 0; ///< along the unit direction
  vec3f normal{0.f};   ///< unit geometric normal, facing the ray origin
};

class MeshBvh {
public:
  MeshBvh();
  ~MeshBvh();
  MeshBvh(const MeshBvh&) = delete;
  MeshBvh& operator=(const MeshBvh&) = delete;

  /// Replaces the meshes (none: empty). Throws exa::Error naming the mesh when Embree cannot hold it.
  void build(const std::vector<const TriangleMesh*>& meshes);
  void clear();
  bool empty() const;

  /// Nearest hit along org + s dir (dir unit) with s in [sMin, sMax]; false when none.
  bool intersect(const vec3d& org, const vec3d& dir, double sMin, double sMax, MeshHit& hit) const;
  /// Whether any triangle lies at s in [sMin, sMax] (false when sMax <= sMin).
  bool occluded(const vec3d& org, const vec3d& dir, double sMin, double sMax) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace exa
