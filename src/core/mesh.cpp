#include "exabricks/core/mesh.h"

namespace exa {

box3f TriangleMesh::bounds() const {
  box3f b;
  for (const vec3f& v : vertices)
    b.extend(v);
  return b;
}

} // namespace exa
