// Chombo HDF5 plot files (level_N groups with boxes, data:datatype=0 and data:offsets=0):
// overlapping levels reduced to leaf cells, refinement ratios that are powers of two, float32
// or float64 data, ghost cells (outputGhost) stripped. Only 3-D files are read.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/patch_source.h"

#include <string>
#include <vector>

namespace exa {

/// True when `path` is an HDF5 file with Chombo's layout (a level_0 group and num_levels).
bool isChomboFile(const std::string& path);

/// Names of the file's components.
std::vector<std::string> listChomboFields(const std::string& path);

/// Reads the leaf cells with the requested fields (all when empty). The world transform maps
/// the finest level's index space onto index × dx (Chombo stores no origin). Levels whose cells
/// are narrower than 2^finestLevel finest cells are not read, and the cells under them are leaves
/// (the lattice stays the whole file's).
/// With a box (finest lattice), the boxes that do not overlap it are not read.
CellSet readChombo(const std::string& path, const std::vector<std::string>& fields = {}, int finestLevel = 0,
                   const box3i& box = {});

/// Where the leaf cells lie, from the box tables alone (per box, its cells less those the next
/// finer level covers).
Census chomboCensus(const std::string& path);

/// Cells in each level's boxes (index: exabricks level), from the box tables alone.
std::vector<double> chomboLevelCells(const std::string& path);

/// The boxes from the file's metadata and a reader of each box's values (structure without
/// values), for the fields asked for (all when empty) and the levels of cells 2^finestLevel
/// finest cells wide and wider; the read above is this, box by box.
PatchSource chomboPatches(const std::string& path, const std::vector<std::string>& fields = {}, int finestLevel = 0);

} // namespace exa
