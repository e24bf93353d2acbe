#include "exabricks/accel/triangle_bvh.h"

namespace exa {

void TriangleBvh::build(const std::vector<const TriangleMesh*>& meshes) {
  nodes_.clear();
  triangles_.clear();
  std::vector<box3f> boxes;
  std::vector<vec3f> centres;
  for (size_t m = 0; m < meshes.size(); ++m) {
    const TriangleMesh& mesh = *meshes[m];
    for (const vec3i& t : mesh.triangles) {
      const vec3f a = mesh.vertices[size_t(t.x)], b = mesh.vertices[size_t(t.y)], c = mesh.vertices[size_t(t.z)];
      triangles_.push_back({a, b - a, c - a, int(m)});
      box3f box(a, a);
      box.extend(box3f(b, b));
      box.extend(box3f(c, c));
      boxes.push_back(box);
      centres.push_back((a + b + c) * (1.f / 3.f));
    }
  }
  std::vector<uint32_t> order;
  buildBvh(boxes, centres, 4, nodes_, order);
  std::vector<BvhTriangle> sorted(triangles_.size());
  for (size_t i = 0; i < order.size(); ++i)
    sorted[i] = triangles_[order[i]];
  triangles_ = std::move(sorted);
}

} // namespace exa
