// Macrocells: a coarse uniform grid of cubic cells over a box of the lattice, and per macrocell
// the range of a field's values over every cell whose basis support meets it, which bounds the
// reconstruction anywhere in the macrocell (a weighted mean of those cells' values); or, where
// asked, the reconstruction's range there, exact where it has a value at every corner of the
// pieces the hats' planes cut. The path tracer's majorant grid is built on it.
// Its size is bounded whatever the box's volume.
#pragma once

#include "exabricks/amr/basis.h"
#include "exabricks/amr/bricks.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace exa {

struct MacrocellGrid {
  vec3f lower{0.f};   ///< lattice
  float cellSize = 1; ///< lattice units per macrocell edge
  vec3i dims{0};      ///< macrocells per axis, x fastest in arrays over the grid

  size_t count() const { return size_t(dims.x) * size_t(dims.y) * size_t(dims.z); }
  EXA_HOST_DEVICE size_t index(const vec3i& c) const {
    return size_t(c.x) + size_t(dims.x) * (size_t(c.y) + size_t(dims.y) * size_t(c.z));
  }
  /// The macrocell at `index` in arrays over the grid.
  vec3i cellAt(size_t i) const {
    return {int(i % size_t(dims.x)), int(i / size_t(dims.x) % size_t(dims.y)),
            int(i / (size_t(dims.x) * size_t(dims.y)))};
  }
  /// Closed lattice box of macrocell c.
  box3f bounds(const vec3i& c) const {
    const vec3f lo = lower + vec3f(c) * cellSize;
    return {lo, lo + vec3f(cellSize)};
  }
  /// The macrocell along `axis` that lattice coordinate x lies in, clamped into the grid.
  EXA_HOST_DEVICE int cellAlong(int axis, float x) const {
    const int c = int(floorf((x - lower[axis]) / cellSize));
    return c < 0 ? 0 : (c > dims[axis] - 1 ? dims[axis] - 1 : c);
  }
  /// The macrocells along `axis` that the lattice interval from a to b overlaps, clamped into the
  /// grid: first..last, none where last < first. With `touching`, also one that b only touches
  /// (b on its lower face).
  void span(int axis, double a, double b, bool touching, int& first, int& last) const {
    const double o = double(lower[axis]), size = double(cellSize);
    first = int(std::max(0.0, std::floor((a - o) / size)));
    const double end = touching ? std::floor((b - o) / size) : std::ceil((b - o) / size) - 1.0;
    last = int(std::min(double(dims[axis] - 1), end));
  }
};

/// Cubic macrocells covering `bounds` (lattice): at most `perAxis` along its longest axis and
/// `maxCells` in all, at least `minWidth` lattice units wide (an integer width).
MacrocellGrid macrocellsOver(const box3f& bounds, int perAxis = 256, int minWidth = 1,
                             size_t maxCells = 128 * 128 * 128);

/// For every macrocell, the range of `values` (brick-ordered, one per cell of `bricks`) over the
/// cells whose support (open, centre ± cell width) meets the macrocell or touches its faces;
/// empty where none does.
std::vector<range1f> macrocellValueRanges(const MacrocellGrid& grid, const std::vector<Brick>& bricks,
                                          const float* values);

/// Where the reconstruction's weights change slope along each axis: the planes through the cell
/// centres of every level, given per axis as the distinct (cell width, offset) of the bricks,
/// centres lying at offset + (i + 0.5) width.
struct HatPlanes {
  std::vector<std::pair<int, int>> axis[3];
};
HatPlanes hatPlanesOf(const std::vector<Brick>& bricks);

/// The range of the reconstruction over macrocell c (clipped to the view's bounds). Between the
/// planes every hat weight is multilinear, so the value, a ratio of two such sums, is monotone
/// along each axis within each piece and takes its extremes at the pieces' corners: where every
/// corner has a value, the range is exactly theirs (`exact` true), grown by a float rounding
/// margin. A piece with a corner where no cell has weight (the edge of every support, where the
/// limit depends on the direction of approach) adds the values of the cells whose hats are
/// positive in it instead (each hat is positive in all of a piece or none). False, with nothing
/// evaluated, where the corners number more than maxPoints or no cell has weight in c.
bool macrocellRange(const MacrocellGrid& grid, const vec3i& c, const FieldView& view, const HatPlanes& planes,
                    size_t maxPoints, range1f& out, bool* exact = nullptr);
/// The number of corners macrocellRange evaluates for macrocell c.
size_t macrocellRangePoints(const MacrocellGrid& grid, const vec3i& c, const FieldView& view, const HatPlanes& planes);

} // namespace exa
