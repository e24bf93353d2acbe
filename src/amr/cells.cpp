#include "exabricks/amr/cells.h"

#include "exabricks/core/error.h"

#include <cmath>

namespace exa {

int CellSet::fieldIndex(const std::string& name) const {
  for (size_t i = 0; i < fields.size(); ++i)
    if (fields[i].name == name) return int(i);
  return -1;
}

box3l CellSet::bounds() const {
  box3l b;
  for (const Cell& c : cells) {
    b.extend(vec3l(c.lower));
    b.extend(vec3l(c.lower) + vec3l(int64_t(c.width())));
  }
  return b;
}

std::string cellProblem(const Cell& c) {
  if (c.level < 0) return strCat("negative level ", c.level);
  if (c.level > kMaxLevel) return strCat("absurd level ", c.level, " (at most ", kMaxLevel, ")");
  const int64_t w = int64_t(1) << c.level;
  for (int a = 0; a < 3; ++a) {
    const int64_t v = c.lower[a];
    if (v < -kLatticeLimit || v + w > kLatticeLimit)
      return strCat("coordinate ", v, " outside the supported lattice range [-2^29, 2^29]");
    if (v % w != 0)
      return strCat("corner (", c.lower.x, ",", c.lower.y, ",", c.lower.z, ") is not aligned to the level-", c.level,
                    " cell width ", w);
  }
  return {};
}

void validateCellRecords(const std::vector<Cell>& cells, const std::string& source) {
  if (cells.empty()) fail(source, ": no cells (empty input)");
  for (size_t i = 0; i < cells.size(); ++i) {
    const std::string problem = cellProblem(cells[i]);
    if (!problem.empty()) fail(source, ": record ", i, ": ", problem);
  }
}

void validateFieldValues(const Field& f, size_t cellCount, const std::string& source) {
  if (f.values.size() != cellCount)
    fail(source, ": field '", f.name, "' has ", f.values.size(), " values for ", cellCount, " cells");
  for (size_t i = 0; i < f.values.size(); ++i)
    if (!std::isfinite(f.values[i]))
      fail(source, ": record ", i, ": value ", f.values[i], " of field '", f.name, "' is not finite");
}

void validateCells(const CellSet& set, const std::string& source) {
  validateCellRecords(set.cells, source);
  if (set.fields.empty()) fail(source, ": no fields");
  for (const Field& f : set.fields)
    validateFieldValues(f, set.cells.size(), source);
  for (int a = 0; a < 3; ++a)
    if (!(set.world.scale[a] > 0.0) || !std::isfinite(set.world.scale[a]) || !std::isfinite(set.world.origin[a]))
      fail(source, ": invalid world transform (scale must be positive and finite)");
}

} // namespace exa
