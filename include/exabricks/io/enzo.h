// Enzo packed-HDF5 outputs: the DDnnnn parameter file, the DDnnnn.hierarchy text and the
// DDnnnn.cpuNNNN HDF5 data files named by each grid's BaryonFileName (its basename, looked up
// beside the hierarchy). Ghost zones are dropped (arrays may hold active zones only or the full
// GridDimension), overlapping grids are reduced to leaf cells, float32 and float64 fields are
// read. Refinement must be by powers of two; only 3-D outputs are read.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/patch_source.h"

#include <string>
#include <vector>

namespace exa {

/// True when `path` is an Enzo parameter file with a PATH.hierarchy beside it, or the
/// hierarchy file itself.
bool isEnzoOutput(const std::string& path);

/// Names of the grid fields (the 3-D datasets of the first grid with fields).
std::vector<std::string> listEnzoFields(const std::string& path);

/// Reads the leaf cells with the requested fields (all when empty). The world transform maps
/// the finest grid cell size onto code units, with DomainLeftEdge as origin. Grids whose cells are
/// narrower than 2^finestLevel finest cells are not read, and the cells under them are leaves
/// (the lattice stays the whole step's).
/// With a box (finest lattice), the grids that do not overlap it are not read.
CellSet readEnzo(const std::string& path, const std::vector<std::string>& fields = {}, int finestLevel = 0,
                 const box3i& box = {});

/// Where the leaf cells lie, from the hierarchy file alone (per grid, its cells less those finer
/// grids cover).
Census enzoCensus(const std::string& path);

/// Cells in each level's grids (index: exabricks level), from the hierarchy file alone.
std::vector<double> enzoLevelCells(const std::string& path);

/// The boxes from the file's metadata and a reader of each box's values (structure without
/// values), for the fields asked for (all when empty) and the levels of cells 2^finestLevel
/// finest cells wide and wider; the read above is this, box by box.
PatchSource enzoPatches(const std::string& path, const std::vector<std::string>& fields = {}, int finestLevel = 0);

} // namespace exa
