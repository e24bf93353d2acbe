// Gradient fields for smooth shading: per cell, the gradient of the basis reconstruction at the
// cell's centre by central differences one cell width each way. Reconstructed with the basis
// like a field's values, they give a gradient that is continuous where the reconstruction's
// exact gradient jumps (at cell centres and support faces), so lighting by it does not draw the
// cells.
#pragma once

#include "exabricks/amr/basis.h"
#include "exabricks/amr/bricks.h"
#include "exabricks/amr/gradient_pack.h"

#include <array>
#include <vector>

namespace exa {

/// The x, y and z components, per lattice unit, in brick order (as the field's values), of
/// (f(c + w e) - f(c - w e)) / 2w at every cell's centre c (w its width, f the reconstruction of
/// `view`); one-sided where one point has no value, 0 where neither has.
std::array<std::vector<float>, 3> cellGradients(const FieldView& view, const std::vector<Brick>& bricks,
                                                size_t regionCount, size_t valueCount);

/// Gradient fields built brick by brick, as scenes need them (a renderer's smooth shading), each
/// cell's gradient packed into 32 bits (gradient_pack.h): a third of three float fields. Each
/// cell's packed gradient follows its value, so that the two corners of a row (value and gradient
/// of a cell and of its neighbour along x) are four adjacent words that one load fetches.
struct GradientFields {
  std::vector<uint32_t> cells;    ///< per cell, in brick order, two words: the value's bits, then
                                  ///< the packed gradient (0, a zero gradient, where not built)
  std::vector<int32_t> scaleBias; ///< per brick: gradientScaleBias of its base exponent
  std::vector<uint8_t> built;     ///< per brick: 1 where its cells' are built
  size_t missing = 0;             ///< bricks not built
  uint64_t version = 0;           ///< counts the builds: a copy is current while it is unchanged

  /// Fields for a field of `count` values (in brick order) in `bricks` bricks: each cell's value
  /// copied, no gradient built.
  void reset(const float* values, size_t count, size_t bricks);
  /// Cells held (two words each).
  size_t cellCount() const { return cells.size() / 2; }
  /// The gradient of cell `slot` of brick `brick` as the renderers reconstruct it (decoded).
  vec3f at(size_t slot, size_t brick) const { return unpackGradient(cells[2 * slot + 1], scaleBias[brick]); }
};

/// cellGradients for the bricks that `which` lists (indices into `bricks`) only, packed into
/// `out` (sized by reset) at their cells' slots; the other cells are left as they are. Each
/// brick's base exponent comes from its own cells' largest component, so that every cell keeps 8
/// significant bits unless it is more than 2^31 times smaller than the brick's largest.
void fillPackedGradients(const FieldView& view, const std::vector<Brick>& bricks, size_t regionCount,
                         const std::vector<uint32_t>& which, GradientFields& out);

} // namespace exa
