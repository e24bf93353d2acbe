// FLASH (PARAMESH) HDF5 checkpoint and plot files: the leaf blocks (node type 1) of any block
// size, float32 or float64 variables and coordinates, several variables. Each block's level
// comes from its cell size relative to the finest leaf block's; corners are checked to lie
// exactly on the finest lattice. Only 3-D files are read.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/patch_source.h"

#include <string>
#include <vector>

namespace exa {

/// True when `path` is an HDF5 file with FLASH's layout ("node type" and "bounding box").
bool isFlashFile(const std::string& path);

/// Names of the variables stored in the file ("unknown names" that have a dataset).
std::vector<std::string> listFlashFields(const std::string& path);

/// Reads the leaf blocks' cells with the requested variables (all when empty). The world
/// transform places the finest cell size at the lowest leaf-block corner.
CellSet readFlash(const std::string& path, const std::vector<std::string>& fields = {});

/// The leaf blocks from the block table alone (structure without values): where their cells lie,
/// and as patches whose values are read block by block. Only every level together: the parent
/// blocks need not hold values, so `finestLevel` must be 0.
Census flashCensus(const std::string& path);
PatchSource flashPatches(const std::string& path, const std::vector<std::string>& fields = {}, int finestLevel = 0);

} // namespace exa
