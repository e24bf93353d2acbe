// Overlapping AMR grids given in world coordinates (the layout of yt's load_amr_grids and of
// yt's grid index): each grid a box with its cells per axis and one array per field. Cells
// covered by a finer grid are dropped; what remains are the leaf cells on one lattice.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/io/patch_source.h"

#include <string>
#include <vector>

namespace exa {

struct GridPatch {
  vec3d lower, upper;                      ///< world box of the grid
  vec3l cells;                             ///< cells per axis
  std::vector<std::vector<double>> values; ///< per field, x fastest, one per cell
  /// Held by another process (no values): it takes part in the lattice (the finest spacing) and
  /// covers coarser cells, but gives no cells here.
  bool elsewhere = false;
};

/// Leaf cells of the grids. The finest cell spacing defines the lattice, whose origin is
/// `origin` (default: the lowest grid corner); every grid's spacing must be a power-of-two
/// multiple of it, equal on all axes in lattice units, and its corner must lie on the lattice.
/// Errors name `source`, the grid and the problem. With grids held elsewhere, the cells of the
/// others may be none (a process whose grids are all covered or that holds no grids).
CellSet cellsFromGrids(std::vector<GridPatch> grids, const std::vector<std::string>& fieldNames,
                       const std::string& source, const vec3d* origin = nullptr);

/// The same grids as patches on the lattice (checked as above), their values read from the grids
/// (which the source keeps), for a build from the boxes (buildModelOfPatches).
PatchSource patchesOfGrids(std::vector<GridPatch> grids, const std::vector<std::string>& fieldNames,
                           const std::string& source, const vec3d* origin = nullptr);

} // namespace exa
