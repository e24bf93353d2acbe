#include "exabricks/amr/macrocells.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace exa {

MacrocellGrid macrocellsOver(const box3f& bounds, int perAxis, int minWidth, size_t maxCells) {
  MacrocellGrid g;
  const vec3f extent = bounds.upper - bounds.lower;
  const float longest = std::max({extent.x, extent.y, extent.z, 0.f});
  g.lower = bounds.lower;
  const auto cellsAlong = [&](int a, float size) {
    return std::max(1, int(std::ceil(std::max(0.f, extent[a]) / size)));
  };
  g.cellSize = std::max(float(std::max(1, minWidth)), std::ceil(longest / float(std::max(1, perAxis))));
  // Wider where the count would pass maxCells: from the width that volume alone would ask for.
  const double volume =
      double(std::max(extent.x, 1.f)) * double(std::max(extent.y, 1.f)) * double(std::max(extent.z, 1.f));
  g.cellSize = std::max(g.cellSize, std::floor(float(std::cbrt(volume / double(std::max<size_t>(1, maxCells))))));
  while (double(cellsAlong(0, g.cellSize)) * cellsAlong(1, g.cellSize) * cellsAlong(2, g.cellSize) > double(maxCells))
    g.cellSize = std::max(g.cellSize + 1.f, std::ceil(g.cellSize * 1.0625f)); // grows whatever its size
  for (int a = 0; a < 3; ++a)
    g.dims[a] = cellsAlong(a, g.cellSize);
  return g;
}

std::vector<range1f> macrocellValueRanges(const MacrocellGrid& g, const std::vector<Brick>& bricks,
                                          const float* values) {
  const size_t layerSize = size_t(g.dims.x) * size_t(g.dims.y);
  std::vector<range1f> ranges(g.count());
  // Each layer of macrocells (along z) is filled by one task from the bricks whose supports reach
  // it: no two tasks write the same macrocell. Cell i's support along an axis is
  // (lower + (i - 0.5) w, lower + (i + 1.5) w).
  std::vector<std::vector<uint32_t>> bricksOfLayer(size_t(g.dims.z));
  for (size_t b = 0; b < bricks.size(); ++b) {
    const Brick& brick = bricks[b];
    const double w = brick.cellWidth();
    int first, last;
    g.span(2, brick.lower.z - 0.5 * w, brick.lower.z + (brick.size.z + 0.5) * w, true, first, last);
    for (int z = first; z <= last; ++z)
      bricksOfLayer[size_t(z)].push_back(uint32_t(b));
  }
  tbb::parallel_for(0, g.dims.z, [&](int mz) {
    const double slab0 = double(g.lower.z) + double(mz) * g.cellSize, slab1 = slab0 + g.cellSize;
    range1f* layer = ranges.data() + layerSize * size_t(mz);
    for (uint32_t b : bricksOfLayer[size_t(mz)]) {
      const Brick& brick = bricks[b];
      const double w = brick.cellWidth();
      // The cells whose support meets the slab: lower + (z + 1.5) w > slab0, lower + (z - 0.5) w < slab1.
      const int z0 = std::max(0, int(std::floor((slab0 - brick.lower.z) / w - 1.5)) + 1);
      const int z1 = std::min(brick.size.z - 1, int(std::ceil((slab1 - brick.lower.z) / w + 0.5)) - 1);
      for (int z = z0; z <= z1; ++z)
        for (int y = 0; y < brick.size.y; ++y) {
          int y0, y1;
          g.span(1, brick.lower.y + (y - 0.5) * w, brick.lower.y + (y + 1.5) * w, true, y0, y1);
          const float* row = values + brick.valueOffset + size_t(brick.size.x) * (y + size_t(brick.size.y) * z);
          for (int x = 0; x < brick.size.x; ++x) {
            int x0, x1;
            g.span(0, brick.lower.x + (x - 0.5) * w, brick.lower.x + (x + 1.5) * w, true, x0, x1);
            for (int my = y0; my <= y1; ++my)
              for (int mx = x0; mx <= x1; ++mx)
                layer[size_t(mx) + size_t(g.dims.x) * size_t(my)].extend(row[x]);
          }
        }
    }
  });
  return ranges;
}

HatPlanes hatPlanesOf(const std::vector<Brick>& bricks) {
  std::set<std::pair<int, int>> seen[3];
  for (const Brick& b : bricks) {
    const int w = b.cellWidth();
    for (int a = 0; a < 3; ++a)
      seen[a].insert({w, ((b.lower[a] % w) + w) % w});
  }
  HatPlanes planes;
  for (int a = 0; a < 3; ++a)
    planes.axis[a].assign(seen[a].begin(), seen[a].end());
  return planes;
}

namespace {

/// Per axis, the coordinates of the corners of the pieces of macrocell c (clipped to the view's
/// bounds) between the hat planes: its faces and every plane strictly between them. False where
/// the clipped macrocell is empty.
bool pieceCorners(const MacrocellGrid& g, const vec3i& c, const FieldView& view, const HatPlanes& planes,
                  std::vector<double> (&corners)[3]) {
  const box3f cell = g.bounds(c);
  for (int a = 0; a < 3; ++a) {
    const double lo = std::max(double(cell.lower[a]), double(view.bounds.lower[a]));
    const double hi = std::min(double(cell.upper[a]), double(view.bounds.upper[a]));
    if (!(lo <= hi)) return false;
    std::vector<double>& at = corners[a];
    at.assign({lo, hi});
    for (const auto& [w, offset] : planes.axis[a])
      for (double x = offset + (std::floor((lo - offset) / w - 0.5) + 1.5) * w; x < hi; x += w)
        if (x > lo) at.push_back(x);
    std::sort(at.begin(), at.end());
    at.erase(std::unique(at.begin(), at.end()), at.end());
  }
  return true;
}

} // namespace

size_t macrocellRangePoints(const MacrocellGrid& grid, const vec3i& c, const FieldView& view, const HatPlanes& planes) {
  std::vector<double> corners[3];
  if (!pieceCorners(grid, c, view, planes, corners)) return 0;
  return corners[0].size() * corners[1].size() * corners[2].size();
}

bool macrocellRange(const MacrocellGrid& grid, const vec3i& c, const FieldView& view, const HatPlanes& planes,
                    size_t maxPoints, range1f& out, bool* exact) {
  std::vector<double> corners[3];
  if (!pieceCorners(grid, c, view, planes, corners)) return false;
  const size_t nx = corners[0].size(), ny = corners[1].size(), nz = corners[2].size();
  if (nx * ny * nz > maxPoints) return false;
  // The reconstruction at every corner (and which have no value).
  std::vector<uint8_t> valued(nx * ny * nz);
  double lo = INFINITY, hi = -INFINITY;
  for (size_t k = 0, z = 0; z < nz; ++z)
    for (size_t y = 0; y < ny; ++y)
      for (size_t x = 0; x < nx; ++x, ++k) {
        double v;
        valued[k] = sampleField(view, vec3d(corners[0][x], corners[1][y], corners[2][z]), v);
        if (valued[k]) lo = std::min(lo, v), hi = std::max(hi, v);
      }
  const bool everywhere = std::find(valued.begin(), valued.end(), uint8_t(0)) == valued.end();
  // A piece's middle along an axis of n corners (the corner where the clipped macrocell is flat).
  const auto mid = [&](int a, size_t i, size_t n) {
    return n > 1 ? 0.5 * (corners[a][i] + corners[a][i + 1]) : corners[a][0];
  };
  if (!everywhere) // the pieces with a corner without a value: the values weighed inside them
    for (size_t z = 0; z + 1 < std::max<size_t>(nz, 2); ++z)
      for (size_t y = 0; y + 1 < std::max<size_t>(ny, 2); ++y)
        for (size_t x = 0; x + 1 < std::max<size_t>(nx, 2); ++x) {
          bool all = true;
          for (size_t d = 0; d < 8; ++d) {
            const size_t cx = std::min(x + (d & 1), nx - 1), cy = std::min(y + (d >> 1 & 1), ny - 1);
            const size_t cz = std::min(z + (d >> 2), nz - 1);
            all = all && valued[cx + nx * (cy + ny * cz)];
          }
          if (all) continue;
          const range1f weighed = weighedValueRange(view, vec3d(mid(0, x, nx), mid(1, y, ny), mid(2, z, nz)));
          if (!weighed.empty()) lo = std::min(lo, double(weighed.lower)), hi = std::max(hi, double(weighed.upper));
        }
  if (!(lo <= hi)) return false;
  // The renderer reconstructs in float: a margin of a few of its roundings.
  const double margin = 1e-5 * std::max({std::abs(lo), std::abs(hi), hi - lo});
  out = {float(lo - margin), float(hi + margin)};
  if (exact) *exact = everywhere;
  return true;
}

} // namespace exa
