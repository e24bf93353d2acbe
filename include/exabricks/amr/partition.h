// Splitting a dataset among processes for data-parallel rendering: where the cells lie (a
// census of counted boxes), a k-d partition of the finest lattice balanced by cell count, the
// halo a part needs (every cell whose basis support reaches into it, so that samples inside the
// part equal the whole dataset's), and the order in which a camera sees the parts.
#pragma once

#include "exabricks/amr/bricks.h"
#include "exabricks/amr/cells.h"

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

namespace exa {

/// A face of a part on the outside of the data lies this far out: the part reaches to infinity
/// there (rays in the margin of the outermost supports still belong to it).
constexpr int64_t kUnboundedLattice = int64_t(1) << 40;

/// A lattice box holding `cells` cells, assumed spread evenly over it.
struct CensusBox {
  box3l box;
  double cells = 0;
};

/// Where a dataset's cells lie, without their values.
struct Census {
  std::vector<CensusBox> boxes;
  int coarsestLevel = 0; ///< the widest cell, 2^coarsestLevel: how far a halo reaches
  /// The leaf cells' exact lattice bounds and their count per level (index = level), where the
  /// census knows them (every census made here does; empty otherwise). The boxes' union may be
  /// larger: a cell census counts in blocks.
  box3l cellBounds;
  std::vector<double> levelCells;
  box3l bounds() const;
  double cells() const;
};

/// Counts cells into blocks of at most 8^3 cells of one level (the census of a cell list that is
/// read in pieces).
class CellCensus {
public:
  void add(const Cell& cell);
  void add(const Cell* cells, size_t count) {
    for (size_t i = 0; i < count; ++i)
      add(cells[i]);
  }
  Census finish() const;

private:
  struct Key {
    int64_t x, y, z;
    int32_t level;
    friend bool operator==(const Key&, const Key&) = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const;
  };
  std::unordered_map<Key, uint64_t, KeyHash> blocks_;
  int coarsest_ = 0;
  box3l cellBounds_;
};

/// The census of built bricks.
Census censusOfBricks(const std::vector<Brick>& bricks);

/// Whether the basis supports of same-level cells of width 2^level that fill the lattice box
/// `cells` (one cell, or a brick) reach into the lattice box [lower, upper): each support is
/// the cell's centre +- its width (open), so together they are `cells` grown by half a width.
inline bool supportReaches(const box3i& cells, int level, const box3l& box) {
  const int64_t w = int64_t(1) << level;
  for (int a = 0; a < 3; ++a) // doubled units: (2 lower - w, 2 upper + w)
    if (!(2 * int64_t(cells.lower[a]) - w < 2 * box.upper[a] && 2 * int64_t(cells.upper[a]) + w > 2 * box.lower[a]))
      return false;
  return true;
}

/// Whether a cell's centre lies in [lower, upper) along axis a.
inline bool centreInsideAlong(int a, int32_t lower, int level, const box3l& box) {
  const int64_t c2 = 2 * int64_t(lower) + (int64_t(1) << level);
  return c2 >= 2 * box.lower[a] && c2 < 2 * box.upper[a];
}

/// Whether a cell's centre lies in [lower, upper): each cell belongs to exactly one part.
inline bool centreInside(const vec3i& lower, int level, const box3l& box) {
  for (int a = 0; a < 3; ++a)
    if (!centreInsideAlong(a, lower[a], level, box)) return false;
  return true;
}

/// Calls visit(slot) for every cell of the brick whose centre lies in `box` (the cells a part
/// owns), with the cell's slot in the brick (x fastest).
template <typename Visit> void forCellsCentredIn(const Brick& b, const box3l& box, Visit&& visit) {
  const int w = b.cellWidth();
  uint32_t slot = 0;
  for (int z = 0; z < b.size.z; ++z)
    for (int y = 0; y < b.size.y; ++y)
      for (int x = 0; x < b.size.x; ++x, ++slot)
        if (centreInside(b.lower + vec3i(x, y, z) * w, b.level, box)) visit(slot);
}

/// How many cells of the brick have their centre in `box` (those forCellsCentredIn visits).
inline uint64_t cellsCentredIn(const Brick& b, const box3l& box) {
  uint64_t n = 1;
  for (int a = 0; a < 3; ++a) {
    uint64_t along = 0;
    for (int i = 0; i < b.size[a]; ++i)
      along += centreInsideAlong(a, b.lower[a] + i * b.cellWidth(), b.level, box) ? 1 : 0;
    n *= along;
  }
  return n;
}

/// The part grown by two coarsest cell widths: smooth shading's gradient at a cell whose support
/// reaches the part differences the reconstruction one cell width beyond the cell's centre, so a
/// part's renderer holds the cells whose support reaches this box.
box3l shadingReach(const box3l& part, int coarsestLevel);

/// The box a reader must return cells of for a part: every cell whose support reaches into the
/// part overlaps it (the part grown by the coarsest width, clamped to the lattice range).
box3i haloReadBox(const box3l& part, int coarsestLevel);

/// Keeps the cells whose support reaches into `part`, with their values.
void keepSupportOf(CellSet& set, const box3l& part);

/// A k-d partition of the finest lattice into parts of about equal cell counts.
class KdPartition {
public:
  struct Node {
    int axis = -1;     ///< -1: a leaf
    int64_t split = 0; ///< lattice plane: the low child holds x[axis] < split
    int child[2] = {-1, -1};
    int part = -1; ///< leaves: the part
  };

  /// Splits the census's bounds into `parts` parts: each split halves the parts (the larger half
  /// high) along the longest axis of the data in the box, at the lattice plane that gives each
  /// side its share of the cells. Faces outside the data are unbounded. With a grain, every plane
  /// is a multiple of it: a grain of the coarsest cell width cuts no cell.
  static KdPartition balance(const Census& census, int parts, int64_t grain = 1);
  /// The whole lattice as one part.
  static KdPartition whole();

  int parts() const { return int(boxes_.size()); }
  /// A part's lattice box, upper exclusive; faces on the outside are +-kUnboundedLattice.
  const box3l& box(int part) const { return boxes_[size_t(part)]; }
  /// The part whose box holds a lattice point (down the tree: every finite point has one); -1 for
  /// a point that is not finite.
  int partAt(const vec3d& lattice) const;
  /// Parts front to back as seen from a point (perspective), lattice coordinates.
  std::vector<int> orderFrom(const vec3d& eye) const;
  /// Parts front to back along a direction (orthographic), lattice directions.
  std::vector<int> orderAlong(const vec3d& direction) const;

  /// Calls visit(p) for every part p whose box, grown by `margin` on every side, may overlap
  /// `box` (those and maybe more: the caller tests).
  void forEachPartNear(const box3l& box, int64_t margin, const std::function<void(int)>& visit) const;

  /// A flat form of the partition for sending between processes, and back (checked).
  std::vector<int64_t> encode() const;
  static KdPartition decode(const std::vector<int64_t>& data);

private:
  template <typename NearLow> std::vector<int> order(NearLow&& nearLow) const;
  std::vector<Node> nodes_;
  std::vector<box3l> boxes_;
};

/// The census cells each part reads: those of the census boxes, whole, that overlap the part's
/// halo read box (haloReadBox of its shadingReach), as a reader reads the patches (AMReX boxes,
/// blocks of NAME.cells records) that reach a part entirely before it crops them.
std::vector<double> cellsReadByParts(const Census& census, const KdPartition& partition);

} // namespace exa
