// VTK overlapping AMR: a .vthb file (vtkOverlappingAMR: one Block per level with its spacing,
// one DataSet per box with amr_box and a .vti file) and its ImageData pieces. Cell-data arrays
// in ascii, base64 binary or raw appended form, UInt32 or UInt64 headers, either byte order,
// uncompressed or zlib-compressed (vtkZLibDataCompressor). Leaf cells are found from the finer
// levels' amr_box entries; refinement must be by powers of two; only 3-D data is read.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/patch_source.h"

#include <string>
#include <vector>

namespace exa {

/// True when `path` is a file whose XML names a vtkOverlappingAMR VTKFile.
bool isVtkAmrFile(const std::string& path);

/// Names of the scalar cell-data arrays of the first piece (vtkGhostType excluded).
std::vector<std::string> listVtkAmrFields(const std::string& path);

/// Reads the leaf cells with the requested fields (all when empty). The world transform is
/// the file's origin with the finest level's spacing. Boxes whose cells are narrower than
/// 2^finestLevel finest cells are not read, and the cells under them are leaves.
/// With a box (finest lattice), the pieces of boxes that do not overlap it are not read.
CellSet readVtkAmr(const std::string& path, const std::vector<std::string>& fields = {}, int finestLevel = 0,
                   const box3i& box = {});

/// Where the leaf cells lie, from the .vthb file alone (per box, its cells less those the next
/// finer level covers).
Census vtkAmrCensus(const std::string& path);

/// Cells in each level's boxes (index: exabricks level), from the .vthb file alone.
std::vector<double> vtkAmrLevelCells(const std::string& path);

/// The boxes from the file's metadata and a reader of each box's values (structure without
/// values), for the fields asked for (all when empty) and the levels of cells 2^finestLevel
/// finest cells wide and wider; the read above is this, box by box.
PatchSource vtkAmrPatches(const std::string& path, const std::vector<std::string>& fields = {}, int finestLevel = 0);

} // namespace exa
