// AMReX plotfiles (HyperCLaw-V1.1 directories with Header, Level_N/Cell_H and Cell_D_* files):
// overlapping levels reduced to leaf cells, refinement ratios that are powers of two, float64
// or float32 data in either byte order (VisMF version 1 "FAB" records).
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/patch_source.h"

#include <optional>
#include <string>
#include <vector>

namespace exa {

/// True when `path` is a directory whose Header starts with "HyperCLaw".
bool isAmrexPlotfile(const std::string& path);

/// Names of the plotfile's variables.
std::vector<std::string> listAmrexFields(const std::string& path);

/// The range of a field from the plotfile's metadata alone (the per-FAB minima and maxima of the
/// Cell_H files, which cover every box including the ones finer levels cover); none when a level
/// has no such table or the field is unknown.
std::optional<range1f> amrexFieldRange(const std::string& path, const std::string& field);

/// Reads the leaf cells of a plotfile with the requested fields (all when empty). The world
/// transform maps the finest level's index space onto the physical domain. With a box (finest
/// lattice units), the data of boxes that do not overlap it is not read. With `finestLevel` > 0
/// (an exabricks level: cells 2^finestLevel finest cells wide), the boxes of finer levels are not
/// read and the coarser cells under them are leaves (a plotfile stores every level's values).
CellSet readAmrex(const std::string& path, const std::vector<std::string>& fields = {}, const box3i& box = {},
                  int finestLevel = 0);

/// The plotfile's boxes from its headers and a reader of each box's values (its FAB), for the
/// fields asked for (all when empty) and the levels of cells 2^finestLevel finest cells wide and
/// wider; every box is bounded by the bytes of its data file first.
PatchSource amrexPatches(const std::string& path, const std::vector<std::string>& fields = {}, int finestLevel = 0);

/// Cells in each level's boxes (index: exabricks level), from the headers alone.
std::vector<double> amrexLevelCells(const std::string& path);

/// Where the plotfile's leaf cells lie, from its headers alone (no cell data is read).
Census amrexCensus(const std::string& path);

/// The physical domain of a plotfile (the Header's prob_lo and prob_hi).
struct AmrexDomain {
  vec3d lower, upper;
};
AmrexDomain amrexDomain(const std::string& path);

} // namespace exa
