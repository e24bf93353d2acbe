// Leaf cells of a vtkOverlappingAMR: every block this process holds as a grid patch with one cell
// array, the cells covered by a finer block dropped by exabricks' grid builder (io/grids.h).
#pragma once

#include "exabricks/amr/cells.h"

#include <string>

class vtkOverlappingAMR;

namespace exa::paraview {

/// The leaf cells of the blocks of `amr` with the values of its cell array `name` (one
/// component). Throws exa::Error naming the level, the block and the problem: an array that is
/// missing or has several components, blocks that are not 3D, spacings that are not power-of-two
/// multiples of the finest.
CellSet amrLeafCells(vtkOverlappingAMR* amr, const std::string& name);

} // namespace exa::paraview
