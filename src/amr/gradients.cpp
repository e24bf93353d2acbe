#include "exabricks/amr/gradients.h"

#include <tbb/parallel_for.h>

namespace exa {

std::array<std::vector<float>, 3> cellGradients(const FieldView& view, const std::vector<Brick>& bricks,
                                                size_t valueCount) {
  std::array<std::vector<float>, 3> out;
  for (std::vector<float>& g : out)
    g.assign(valueCount, 0.f);
  tbb::parallel_for(size_t(0), bricks.size(), [&](size_t bi) {
    const Brick& b = bricks[bi];
    const float w = float(b.cellWidth());
    uint32_t slot = b.valueOffset;
    for (int z = 0; z < b.size.z; ++z)
      for (int y = 0; y < b.size.y; ++y)
        for (int x = 0; x < b.size.x; ++x, ++slot) {
          const vec3f c = vec3f(b.lower) + (vec3f(float(x), float(y), float(z)) + vec3f(0.5f)) * w;
          // The centre's region serves the points that fall inside it (most, inside a brick);
          // the others are located through the k-d tree.
          const uint32_t r = locateRegion(view, c);
          const box3f rb = r != kNoRegion ? view.regions[r].bounds() : box3f();
          // Where the region holds this brick alone, the reconstruction at a cell's centre is
          // that cell's value (its hat is 1 there, its neighbours' 0).
          const bool alone = r != kNoRegion && view.regions[r].brickCount == 1 &&
                             view.brickIds[view.regions[r].brickBegin] == uint32_t(bi);
          auto inside = [&](const vec3f& q) {
            return r != kNoRegion && q.x >= rb.lower.x && q.x <= rb.upper.x && q.y >= rb.lower.y && q.y <= rb.upper.y &&
                   q.z >= rb.lower.z && q.z <= rb.upper.z;
          };
          auto at = [&](const vec3f& q, float& v) {
            return inside(q) ? sampleRegion(view, r, q, v) : sampleField(view, q, v);
          };
          const vec3i cell(x, y, z);
          auto neighbour = [&](int a, int step, const vec3f& q, float& v) {
            vec3i n = cell;
            n[a] += step;
            if (alone && inside(q) && n[a] >= 0 && n[a] < b.size[a]) {
              v = view.values[b.valueOffset + uint32_t((n.z * b.size.y + n.y) * b.size.x + n.x)];
              return true;
            }
            return at(q, v);
          };
          float v0 = 0.f;
          const bool centre = alone ? (v0 = view.values[slot], true) : at(c, v0);
          for (int a = 0; a < 3; ++a) {
            vec3f pp = c, pm = c;
            pp[a] += w;
            pm[a] -= w;
            float vp = 0.f, vm = 0.f;
            const bool hasP = neighbour(a, 1, pp, vp), hasM = neighbour(a, -1, pm, vm);
            float g = 0.f;
            if (hasP && hasM)
              g = (vp - vm) / (2.f * w);
            else if (hasP && centre)
              g = (vp - v0) / w;
            else if (hasM && centre)
              g = (v0 - vm) / w;
            out[size_t(a)][slot] = g;
          }
        }
  });
  return out;
}

} // namespace exa
