// Leaf cells of a vtkOverlappingAMR: every block this process holds as a grid patch with one cell
// array, the cells covered by a finer block dropped by exabricks' grid builder (io/grids.h).
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/model.h"
#include "exabricks/io/grids.h"

#include <string>
#include <vector>

class vtkOverlappingAMR;

namespace exa::paraview {

/// The leaf cells of the blocks of `amr` with the values of its cell array `name` (one
/// component). Throws exa::Error naming the level, the block and the problem: an array that is
/// missing or has several components, blocks that are not 3D, spacings that are not power-of-two
/// multiples of the finest. `elsewhere`: the blocks other processes hold (boxes only), which set
/// the lattice and cover coarser cells here; with them, this process may give no cells.
CellSet amrLeafCells(vtkOverlappingAMR* amr, const std::string& name, const std::vector<GridPatch>& elsewhere = {});

/// The model of all the blocks of `amr` (one process), built from the blocks as boxes
/// (buildModelOfPatches): the same bricks as a plotfile's own read, when the blocks are its boxes.
Model amrModel(vtkOverlappingAMR* amr, const std::string& name);

/// The boxes of the blocks this process holds (no values), marked as held elsewhere: what the
/// other processes need of them.
std::vector<GridPatch> amrBlockBoxes(vtkOverlappingAMR* amr);

} // namespace exa::paraview
