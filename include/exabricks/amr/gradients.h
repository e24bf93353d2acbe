// Gradient fields for smooth shading: per cell, the gradient of the basis reconstruction at the
// cell's centre by central differences one cell width each way. Reconstructed with the basis
// like a field's values, they give a gradient that is continuous where the reconstruction's
// exact gradient jumps (at cell centres and support faces), so lighting by it does not draw the
// cells.
#pragma once

#include "exabricks/amr/basis.h"
#include "exabricks/amr/bricks.h"

#include <array>
#include <vector>

namespace exa {

/// The x, y and z components, per lattice unit, in brick order (as the field's values), of
/// (f(c + w e) - f(c - w e)) / 2w at every cell's centre c (w its width, f the reconstruction of
/// `view`); one-sided where one point has no value, 0 where neither has.
std::array<std::vector<float>, 3> cellGradients(const FieldView& view, const std::vector<Brick>& bricks,
                                                size_t regionCount, size_t valueCount);

/// Gradient fields built brick by brick, as scenes need them (a renderer's smooth shading).
struct GradientFields {
  std::array<std::vector<float>, 3> values; ///< as cellGradients gives, 0 in the bricks not built
  std::vector<uint8_t> built;               ///< per brick: 1 where its cells' are built
  size_t missing = 0;                       ///< bricks not built
  uint64_t version = 0;                     ///< counts the builds: a copy is current while it is unchanged
};

/// The same, for the bricks that `which` lists (indices into `bricks`) only, written into `out`
/// (each of the field's value count) at their cells' slots; the other cells are left as they are.
void fillCellGradients(const FieldView& view, const std::vector<Brick>& bricks, size_t regionCount,
                       const std::vector<uint32_t>& which, std::array<std::vector<float>, 3>& out);

} // namespace exa
