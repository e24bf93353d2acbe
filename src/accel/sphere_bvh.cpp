#include "exabricks/accel/sphere_bvh.h"

#include <tbb/parallel_for.h>

namespace exa {

void SphereBvh::build(const std::vector<BvhSphere>& spheres, std::vector<uint32_t>& order) {
  std::vector<box3f> boxes(spheres.size());
  std::vector<vec3f> centres(spheres.size());
  tbb::parallel_for(size_t(0), spheres.size(), [&](size_t i) {
    const BvhSphere& s = spheres[i];
    boxes[i] = box3f(s.centre - vec3f(s.radius), s.centre + vec3f(s.radius));
    centres[i] = s.centre;
  });
  buildBvh(boxes, centres, 4, nodes_, order);
  spheres_.resize(spheres.size());
  tbb::parallel_for(size_t(0), order.size(), [&](size_t i) { spheres_[i] = spheres[order[i]]; });
}

} // namespace exa
