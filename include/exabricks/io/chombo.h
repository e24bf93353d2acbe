// Chombo HDF5 plot files (level_N groups with boxes, data:datatype=0 and data:offsets=0):
// overlapping levels reduced to leaf cells, refinement ratios that are powers of two, float32
// or float64 data, ghost cells (outputGhost) stripped. Only 3-D files are read.
#pragma once

#include "exabricks/amr/cells.h"

#include <string>
#include <vector>

namespace exa {

/// True when `path` is an HDF5 file with Chombo's layout (a level_0 group and num_levels).
bool isChomboFile(const std::string& path);

/// Names of the file's components.
std::vector<std::string> listChomboFields(const std::string& path);

/// Reads the leaf cells with the requested fields (all when empty). The world transform maps
/// the finest level's index space onto index × dx (Chombo stores no origin).
CellSet readChombo(const std::string& path, const std::vector<std::string>& fields = {});

} // namespace exa
