// Input data: AMR leaf cells on the finest-level integer lattice, their named fields and the
// world transform. This is "what was loaded"; bricks and regions are built from it.
#pragma once

#include "exabricks/core/math.h"

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace exa {

/// Largest level accepted (cell width 2^28 finest units); coordinates must stay within
/// [-kLatticeLimit, kLatticeLimit] so that every extent fits in 32 bits.
constexpr int kMaxLevel = 28;
constexpr int64_t kLatticeLimit = int64_t(1) << 29;

/// One AMR cell: lower corner in finest-level lattice units and level (width 2^level, level 0
/// finest). Same layout as a record of the native .cells file.
struct Cell {
  vec3i lower;
  int32_t level = 0;
  int32_t width() const { return int32_t(1) << level; }
  box3i bounds() const { return {lower, lower + vec3i(width())}; }
  friend bool operator==(const Cell& a, const Cell& b) = default;
};
static_assert(sizeof(Cell) == 16, "Cell must match the 16-byte native record");

/// Whether a cell overlaps the lattice box [lower, upper).
inline bool cellOverlaps(const Cell& c, const box3i& box) {
  const int64_t w = int64_t(1) << c.level;
  for (int a = 0; a < 3; ++a)
    if (!(int64_t(c.lower[a]) + w > box.lower[a] && c.lower[a] < box.upper[a])) return false;
  return true;
}

/// A named scalar field with one value per cell, in cell order.
struct Field {
  std::string name;
  std::vector<float> values;
  std::string units; ///< as the file or its format states them; empty where unknown
};

/// A set of leaf cells with fields and world placement.
/// When the data was written, as the simulation counts: its time and step (cycle), where the
/// file says.
struct SimulationState {
  double time = std::numeric_limits<double>::quiet_NaN();     ///< NaN: unknown
  int64_t cycle = -1;                                         ///< -1: unknown
  double redshift = std::numeric_limits<double>::quiet_NaN(); ///< cosmology runs; NaN: unknown or none
  std::string timeUnits; ///< as the format states them ("code units"); empty where unknown
  bool hasTime() const { return time == time; }
  bool hasCycle() const { return cycle >= 0; }
  bool hasRedshift() const { return redshift == redshift; }
};

struct CellSet {
  std::vector<Cell> cells;
  std::vector<Field> fields;
  WorldTransform world;
  SimulationState simulation;

  size_t size() const { return cells.size(); }
  /// Index of the field with this name, or -1.
  int fieldIndex(const std::string& name) const;
  /// Lattice bounds of all cells (empty box when there are none).
  box3l bounds() const;
};

/// Keeps the cells for which `keep(cell)` holds, with their values, in order.
template <typename Keep> void keepCells(CellSet& set, Keep&& keep) {
  size_t kept = 0;
  for (size_t i = 0; i < set.cells.size(); ++i) {
    if (!keep(set.cells[i])) continue;
    set.cells[kept] = set.cells[i];
    for (Field& f : set.fields)
      f.values[kept] = f.values[i];
    ++kept;
  }
  set.cells.resize(kept);
  for (Field& f : set.fields)
    f.values.resize(kept);
}

/// Validates cells and fields independently of where they came from: levels in range, corners
/// aligned to the cell width, coordinates within the lattice limit, one value per cell and
/// field, no NaN or infinite values, at least one cell and one field. Overlaps are detected by
/// the brick builder. `source` names the data in messages; failures throw exa::Error.
void validateCells(const CellSet& cells, const std::string& source);

/// Validates one cell; returns an empty string when it is fine, else the problem.
std::string cellProblem(const Cell& cell);

/// The cell checks of validateCells; messages read "SOURCE: record N: problem".
void validateCellRecords(const std::vector<Cell>& cells, const std::string& source);

/// The field checks of validateCells; messages read "SOURCE: record N: problem".
void validateFieldValues(const Field& field, size_t cellCount, const std::string& source);

} // namespace exa
