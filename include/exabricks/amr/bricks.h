// Bricks (paper §3.1): non-overlapping boxes of same-level cells built by a k-d tree over the
// input cells. Scalars are stored per brick, x fastest, in brick order.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/core/error.h"

#include <cstdint>
#include <vector>

namespace exa {

struct Brick {
  vec3i lower;          ///< lower corner, finest-level lattice units
  int32_t level = 0;    ///< cell width is 2^level lattice units
  vec3i size;           ///< cells per axis
  uint32_t valueOffset; ///< first value of this brick in every field's brick-ordered array

  int32_t cellWidth() const { return int32_t(1) << level; }
  uint32_t cellCount() const { return uint32_t(size.x) * uint32_t(size.y) * uint32_t(size.z); }
  /// Lattice box covered by the cells, upper exclusive.
  box3i bounds() const { return {lower, lower + size * cellWidth()}; }
};
static_assert(sizeof(Brick) == 32);

/// The most cells along one axis of any brick, built or read (samplers convert indices below
/// 2^23 exactly through floats).
constexpr int kMaxBrickWidth = 1 << 20;

struct BrickBuildOptions {
  int maxBrickWidth = 32; ///< at most this many cells per axis in one brick (up to kMaxBrickWidth)
};

struct BrickBuild {
  std::vector<Brick> bricks;
  /// For every brick-ordered value slot, the index of the input cell stored there.
  std::vector<uint32_t> cellOfSlot;
};

/// Builds bricks over the cells (which must have passed validateCells). Deterministic for any
/// thread count. Throws exa::Error naming the cells when two cells overlap or are duplicates.
BrickBuild buildBricks(const std::vector<Cell>& cells, const BrickBuildOptions& options = {});
/// The same, permuting `cells` in place (their order afterwards is unspecified): the build then
/// needs 4 bytes per cell beyond the cells (cellOfSlot) instead of a copy.
BrickBuild buildBricksInPlace(std::vector<Cell>& cells, const BrickBuildOptions& options = {});

/// Two input cells that cannot both be leaves: duplicates, or one overlapping the other. Thrown by
/// buildBricksReordering, whose cells no longer know their input indices: the message names
/// their positions, and locateConflict names their indices given the input cells.
class CellConflict : public Error {
public:
  CellConflict(const Cell& first, const Cell& second, bool duplicate);
  Cell first, second;
  bool duplicate;
};

/// The message buildBricks would give for the conflict: the two cells with their indices in
/// `cells` (the input as it was before the build).
std::string locateConflict(const CellConflict& conflict, const std::vector<Cell>& cells);

/// Builds bricks permuting `cells` and every array in `values` (one value per cell each) in
/// place: afterwards the values are in brick order and the cells' order is unspecified. Needs no
/// memory per cell beyond its arguments. Throws CellConflict when two cells overlap.
std::vector<Brick> buildBricksReordering(std::vector<Cell>& cells, const std::vector<std::vector<float>*>& values,
                                         const BrickBuildOptions& options = {});

/// Reorders values given per input cell into brick order.
std::vector<float> toBrickOrder(const std::vector<float>& cellValues, const std::vector<uint32_t>& cellOfSlot);

} // namespace exa
