#include "exabricks/amr/gradients.h"

#include <tbb/parallel_for.h>

namespace exa {

namespace {

/// Per region, the level of all its bricks, or -1 where it holds bricks of more than one level.
std::vector<int32_t> regionLevels(const FieldView& view, size_t regionCount) {
  std::vector<int32_t> out(regionCount, -1);
  tbb::parallel_for(size_t(0), regionCount, [&](size_t r) {
    const Region& region = view.regions[r];
    if (region.brickCount == 0) return;
    int32_t level = view.bricks[view.brickIds[region.brickBegin]].level;
    for (uint32_t k = 1; k < region.brickCount && level >= 0; ++k)
      if (view.bricks[view.brickIds[region.brickBegin + k]].level != level) level = -1;
    out[r] = level;
  });
  return out;
}

bool strictlyInside(const box3f& b, const vec3f& q) {
  return q.x > b.lower.x && q.x < b.upper.x && q.y > b.lower.y && q.y < b.upper.y && q.z > b.lower.z && q.z < b.upper.z;
}

/// The value of the cell of `b` centred at q.
float cellValue(const FieldView& view, const Brick& b, const vec3f& q) {
  const float inv = inverseWidth(b.level);
  const int x = int((q.x - float(b.lower.x)) * inv), y = int((q.y - float(b.lower.y)) * inv),
            z = int((q.z - float(b.lower.z)) * inv);
  return view.values[b.valueOffset + uint32_t((z * b.size.y + y) * b.size.x + x)];
}

} // namespace

std::array<std::vector<float>, 3> cellGradients(const FieldView& view, const std::vector<Brick>& bricks,
                                                size_t regionCount, size_t valueCount) {
  std::array<std::vector<float>, 3> out;
  for (std::vector<float>& g : out)
    g.assign(valueCount, 0.f);
  const std::vector<int32_t> levels = regionLevels(view, regionCount);
  tbb::parallel_for(size_t(0), bricks.size(), [&](size_t bi) {
    const Brick& b = bricks[bi];
    const float w = float(b.cellWidth());
    const box3i own = b.bounds();
    const box3f ownBox(vec3f(own.lower), vec3f(own.upper));
    // The region of the cell before: the next centre is most often strictly inside it too,
    // where the k-d tree would find the same region.
    uint32_t last = kNoRegion;
    box3f lastBox;
    uint32_t slot = b.valueOffset;
    for (int z = 0; z < b.size.z; ++z)
      for (int y = 0; y < b.size.y; ++y)
        for (int x = 0; x < b.size.x; ++x, ++slot) {
          const vec3f c = vec3f(b.lower) + (vec3f(float(x), float(y), float(z)) + vec3f(0.5f)) * w;
          // The centre's region serves the points that fall inside it (most, inside a brick);
          // the others are located through the k-d tree.
          const bool again = last != kNoRegion && strictlyInside(lastBox, c);
          const uint32_t r = again ? last : locateRegion(view, c);
          const box3f rb = again ? lastBox : r != kNoRegion ? view.regions[r].bounds() : box3f();
          last = r, lastBox = rb;
          auto inside = [&](const vec3f& q) {
            return r != kNoRegion && q.x >= rb.lower.x && q.x <= rb.upper.x && q.y >= rb.lower.y && q.y <= rb.upper.y &&
                   q.z >= rb.lower.z && q.z <= rb.upper.z;
          };
          // q is a cell centre of this brick's level. Where every brick active in q's region is
          // of that level, each hat is 1 or 0 at q (cell corners are multiples of the width, so
          // the centres of one level are whole widths apart): the reconstruction there is the
          // value of the cell centred at q, or none where no brick has that cell. Elsewhere (at
          // level jumps) it is reconstructed.
          auto at = [&](const vec3f& q, float& v) {
            const uint32_t qr = inside(q) ? r : locateRegion(view, q);
            if (qr == kNoRegion) return false;
            if (levels[qr] != b.level) return sampleRegion(view, qr, q, v);
            if (strictlyInside(ownBox, q)) return v = cellValue(view, b, q), true;
            const Region& region = view.regions[qr];
            for (uint32_t k = 0; k < region.brickCount; ++k) {
              const Brick& other = view.bricks[view.brickIds[region.brickBegin + k]];
              const box3i ob = other.bounds();
              if (strictlyInside(box3f(vec3f(ob.lower), vec3f(ob.upper)), q))
                return v = cellValue(view, other, q), true;
            }
            return false;
          };
          float v0 = 0.f;
          const bool centre = at(c, v0);
          for (int a = 0; a < 3; ++a) {
            vec3f pp = c, pm = c;
            pp[a] += w;
            pm[a] -= w;
            float vp = 0.f, vm = 0.f;
            const bool hasP = at(pp, vp), hasM = at(pm, vm);
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
