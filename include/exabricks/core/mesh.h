// Triangle meshes in world space (surfaces shown with the volume). Files are read by documents/mesh.h.
#pragma once

#include "exabricks/core/math.h"

#include <vector>

namespace exa {

struct TriangleMesh {
  std::vector<vec3f> vertices;  ///< world space
  std::vector<vec3i> triangles; ///< 0-based vertex indices, each within `vertices`
  /// Bounds of all vertices (empty box when there are none).
  box3f bounds() const;
};

} // namespace exa
