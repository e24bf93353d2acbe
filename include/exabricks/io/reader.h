// The readers of simulation outputs behind one interface: each format registers how to
// recognise an input (probe), list its fields and read selected fields, optionally only the
// cells inside a box. io/load.h picks the reader for a path.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/patch_source.h"
#include "exabricks/io/raw.h"

#include <optional>
#include <string>
#include <vector>

namespace exa {

enum class InputKind { Default, Model, Native, Grids, Amrex, Chombo, Flash, Enzo, VtkAmr, Raw };

/// What a read asks for.
struct ReadRequest {
  std::vector<std::string> fields; ///< in this order; all when empty
  /// Finest-lattice box; when not empty, only cells that overlap it are returned (readers that
  /// can skip the data of whole patches outside it do so).
  box3i box;
  /// About how many cells the box holds, at most, where the caller knows (a census's count): a
  /// reader that keeps cells one by one reserves room for them. 0: unknown.
  size_t expectedCells = 0;
  RawOptions raw; ///< dimensions, type and merging of raw volumes
  /// NaN and infinite values are returned as read (the loader makes their cells holes); readers
  /// that do not take it refuse them.
  bool keepNonFinite = false;
  /// Readers of patch-based files that store every level's values (FormatReader::levelCells):
  /// levels finer than this (cells narrower than 2^finestLevel) are not read and the coarser
  /// cells under them are leaves. 0: every level.
  int finestLevel = 0;
};

struct FormatReader {
  InputKind kind;
  const char* name;                       ///< "AMReX plotfile", ...
  bool (*probe)(const std::string& path); ///< by content first, by name last
  std::vector<std::string> (*listFields)(const std::string& path);
  CellSet (*read)(const std::string& path, const ReadRequest& request);
  /// A field's value range from metadata alone, where the format records one (else null, or
  /// none returned: the data must be read).
  std::optional<range1f> (*fieldRange)(const std::string& path, const std::string& field) = nullptr;
  /// Where the cells lie without reading their values, where the format allows (else null: the
  /// cells are read to count them).
  Census (*census)(const std::string& path) = nullptr;
  /// Cells in each level's patches (index: exabricks level) from metadata alone, where the format
  /// stores every level's values so that coarse levels can be read alone (ReadRequest::finestLevel);
  /// else null.
  std::vector<double> (*levelCells)(const std::string& path) = nullptr;
  /// The input's patches from metadata and a reader of each patch's values (structure without
  /// values: io/patch_source.h), for the fields asked for (all when empty) and the levels of
  /// cells 2^finestLevel finest cells wide and wider; else null.
  PatchSource (*patches)(const std::string& path, const std::vector<std::string>& fields, int finestLevel) = nullptr;
};

/// The registered readers, in the order in which inputs are probed.
const std::vector<FormatReader>& formatReaders();

/// The reader that recognises `path`, or null.
const FormatReader* findReader(const std::string& path);

/// Keeps the cells that overlap `box` (finest lattice units), with their values.
void cropCells(CellSet& set, const box3i& box);

} // namespace exa
