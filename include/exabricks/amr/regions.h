// Active brick regions (paper §3.2): a partition of the union of all brick supports into boxes,
// each listing exactly the bricks whose basis-function support overlaps it. The k-d tree that
// produced the partition is kept: it locates the region of a point and gives a front-to-back
// traversal order. Where the supports of same-level bricks overlap in thin slabs, the paper's
// partition (one region per set of bricks) gives rays many short segments; there neighbouring
// regions of one finest level are merged into one when that costs a ray less (a brick then need
// not cover all of its region, only overlap it).
#pragma once

#include "exabricks/amr/bricks.h"

#include <cstdint>
#include <vector>

namespace exa {

struct Region {
  box3i halfBounds;    ///< closed box in half lattice units (exact: faces are support faces)
  uint32_t brickBegin; ///< first entry in RegionSet::brickIds
  uint32_t brickCount; ///< number of bricks active here
  int32_t finestLevel; ///< finest level among the active bricks

  /// Closed box in lattice units.
  EXA_HOST_DEVICE box3f bounds() const { return {vec3f(halfBounds.lower) * 0.5f, vec3f(halfBounds.upper) * 0.5f}; }
  /// Smallest cell width of the active bricks, lattice units.
  EXA_HOST_DEVICE float finestWidth() const { return float(int32_t(1) << finestLevel); }
};

/// k-d tree node over regions. Inner nodes split `axis` at `pos` (lattice units); points with
/// coordinate < pos go to child `index`, the others to child `index + 1`. Leaves (axis 3) hold
/// a region index in `index`, or kNoRegion for space that no support covers.
struct RegionKdNode {
  float pos;
  uint32_t axis;
  uint32_t index;
};
constexpr uint32_t kNoRegion = UINT32_MAX;
constexpr uint32_t kLeafAxis = 3;

struct RegionSet {
  std::vector<Region> regions;
  std::vector<uint32_t> brickIds;  ///< per region, ascending brick indices
  std::vector<RegionKdNode> nodes; ///< node 0 is the root (absent when there are no regions)
  box3f bounds;                    ///< lattice box of the root node
  /// Per field, per region: range of the values of every cell whose support overlaps it.
  std::vector<std::vector<range1f>> valueRanges;

  size_t memoryBytes() const;
};

struct RegionBuildOptions {
  /// What one more segment costs a ray, in units of one brick's reconstruction at one sample:
  /// a subtree of regions of one finest level becomes one region listing all their bricks where
  /// that is cheaper for rays on average. 0 keeps the paper's partition.
  double segmentCost = 64.0;
};

/// Builds the regions over the bricks. Deterministic for any thread count.
RegionSet buildRegions(const std::vector<Brick>& bricks, const RegionBuildOptions& options = {});

/// Computes the per-region value range of one field given in brick order.
std::vector<range1f> computeValueRanges(const RegionSet& regions, const std::vector<Brick>& bricks,
                                        const float* brickValues);

} // namespace exa
