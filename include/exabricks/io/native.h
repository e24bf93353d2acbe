// The native exchange format: NAME.cells (int32 x, y, z, level records, little-endian) with one
// float32 value per cell in NAME.scalars (field "scalar") and NAME.FIELD.scalars; and the
// ".grids" text fixture format (one box per line: x y z nx ny nz level value, or eight trilinear
// corner values).
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"
#include "exabricks/core/files.h"

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace exa {

/// Reads NAME.cells and its fields. `fields` selects fields by name (all when empty). Validates
/// everything but overlaps; errors name the file, the record and the problem. With a box, only
/// the cells overlapping it are kept, read in pieces, with room reserved for `expectedCells` (an
/// estimate; more are kept where more overlap).
/// `keepNonFinite`: NaN and infinite values are returned as read (the caller makes their cells
/// holes); else the first is refused, naming its file, record and field.
CellSet readNative(const std::string& cellsPath, const std::vector<std::string>& fields = {}, const box3i& box = {},
                   bool keepNonFinite = false, size_t expectedCells = 0);
/// The cell records of NAME.cells alone, validated (readNative without the values).
std::vector<Cell> readNativeCells(const std::string& cellsPath);
/// The fields readNative reads for `fields`: those, else every field beside the cells (an error
/// names the file when there is none); each checked to exist and to hold one value per cell.
std::vector<std::string> nativeFieldsToRead(const std::string& cellsPath, const std::vector<std::string>& fields,
                                            uint64_t cellCount);
/// One field's values in cell order, as readNative reads them.
std::vector<float> readNativeField(const std::string& cellsPath, const std::string& field, uint64_t cellCount,
                                   bool keepNonFinite = false);
/// Where the cells of NAME.cells lie, read in pieces (values are not read).
Census nativeCensus(const std::string& cellsPath);

/// Reads NAME.cells and the values of `fields` (nativeFieldsToRead's names) in pieces of
/// 65,536 records, each validated, and hands each piece to `use(cells, values, n)`, one value
/// array per field: memory for one piece. A value that is not finite is refused, naming its
/// file, record and field, unless `keepNonFinite`.
void streamNative(const std::string& cellsPath, const std::vector<std::string>& fields, bool keepNonFinite,
                  const std::function<void(const Cell*, const std::vector<const float*>&, size_t)>& use);

/// Names of the fields stored beside a .cells file.
std::vector<std::string> listNativeFields(const std::string& cellsPath);

/// Writes NAME.cells and one NAME[.FIELD].scalars per field (field "scalar" is NAME.scalars).
/// Every file is written to a temporary name first; they are renamed into place together.
void writeNative(const CellSet& cells, const std::string& cellsPath);

/// Most cells a .grids fixture may describe (2^26): each line expands to a box of cells.
constexpr uint64_t kMaxGridsCells = uint64_t(1) << 26;

/// Reads a .grids text fixture (field "scalar").
CellSet readGrids(const std::string& path);

/// Writes NAME.cells and its field files in pieces, in order; finish() publishes them together
/// (nothing appears when it is not called) and removes a NAME.particles it did not write.
class NativeWriter {
public:
  NativeWriter(const std::string& cellsPath, const std::vector<std::string>& fieldNames);
  /// Appends cells with one value per cell of every field, fields in the constructor's order.
  void append(const CellSet& piece);
  /// A further file published with the dataset (its particles).
  void addFile(const std::string& path, const std::vector<char>& bytes);
  void finish();
  uint64_t cellCount() const { return cells_; }

private:
  std::string cellsPath_;
  std::vector<std::string> fieldNames_;
  AtomicFiles files_;
  uint64_t cells_ = 0;
  bool wroteParticles_ = false;
};

} // namespace exa
