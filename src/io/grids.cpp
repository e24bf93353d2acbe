#include "exabricks/io/grids.h"

#include "exabricks/core/error.h"

#include "patches.h"

#include <cmath>

namespace exa {

CellSet cellsFromGrids(const std::vector<GridPatch>& grids, const std::vector<std::string>& fieldNames,
                       const std::string& source, const vec3d* originIn) {
  if (grids.empty()) fail(source, ": no grids");
  // The finest spacing per axis and the lowest corner.
  vec3d finest(std::numeric_limits<double>::infinity()), lowest(std::numeric_limits<double>::infinity());
  for (size_t g = 0; g < grids.size(); ++g) {
    const GridPatch& p = grids[g];
    for (int a = 0; a < 3; ++a) {
      if (p.cells[a] < 1 || p.cells[a] > (int64_t(1) << 30))
        fail(source, ": grid ", g, ": ", p.cells[a], " cells along axis ", a);
      if (a == 2) io::checkPatchCells(p.cells, strCat(source, ": grid ", g));
      const double d = (p.upper[a] - p.lower[a]) / double(p.cells[a]);
      if (!(d > 0.0) || !std::isfinite(d) || !std::isfinite(p.lower[a]))
        fail(source, ": grid ", g, ": its box [", p.lower[a], ", ", p.upper[a], "] along axis ", a,
             " is empty or not finite");
      finest[a] = std::min(finest[a], d);
      lowest[a] = std::min(lowest[a], p.lower[a]);
    }
    if (p.elsewhere) continue;
    if (p.values.size() != fieldNames.size())
      fail(source, ": grid ", g, " holds ", p.values.size(), " fields, expected ", fieldNames.size());
    for (size_t f = 0; f < p.values.size(); ++f)
      if (int64_t(p.values[f].size()) != p.cells.x * p.cells.y * p.cells.z)
        fail(source, ": grid ", g, ": field '", fieldNames[f], "' has ", p.values[f].size(), " values for ",
             p.cells.x * p.cells.y * p.cells.z, " cells");
  }
  const vec3d origin = originIn ? *originIn : lowest;
  // Grids on the lattice of the finest spacing.
  std::vector<io::Patch> patches;
  auto nearInteger = [](double x, int64_t& out) {
    const double r = std::round(x);
    if (std::abs(x - r) > 1e-6 * std::max(1.0, std::abs(x)) || std::abs(r) > 4.0e18) return false;
    out = int64_t(r);
    return true;
  };
  for (size_t g = 0; g < grids.size(); ++g) {
    const GridPatch& p = grids[g];
    io::Patch patch;
    patch.cells = p.cells;
    int64_t width = 0;
    for (int a = 0; a < 3; ++a) {
      int64_t w = 0, lo = 0;
      const double d = (p.upper[a] - p.lower[a]) / double(p.cells[a]);
      if (!nearInteger(d / finest[a], w) || (width && w != width) || io::log2Exact(w) < 0)
        fail(source, ": grid ", g, ": cell size ", d, " along axis ", a, " is not a power-of-two multiple of the",
             " finest cell size ", finest[a], " (the same on every axis)");
      width = w;
      if (!nearInteger((p.lower[a] - origin[a]) / finest[a], lo) || lo % w != 0)
        fail(source, ": grid ", g, ": its corner ", p.lower[a], " along axis ", a,
             " does not lie on the lattice of its cell size");
      patch.lower[a] = lo;
    }
    patch.width = width;
    patches.push_back(patch);
  }
  const io::Coverage coverage(patches, [](size_t g) { return strCat("grid ", g); });
  CellSet set;
  for (const std::string& name : fieldNames)
    set.fields.push_back({name, {}});
  bool anyElsewhere = false;
  for (size_t g = 0; g < grids.size(); ++g) {
    anyElsewhere = anyElsewhere || grids[g].elsewhere;
    if (grids[g].elsewhere) continue;
    std::vector<std::vector<float>> values(fieldNames.size());
    for (size_t f = 0; f < fieldNames.size(); ++f) {
      values[f].reserve(grids[g].values[f].size());
      for (size_t i = 0; i < grids[g].values[f].size(); ++i)
        values[f].push_back(io::toFloat32(grids[g].values[f][i], [&] {
          return strCat(source, ": grid ", g, ": field '", fieldNames[f], "' value ", i);
        }));
    }
    io::appendLeafCells(set, patches[g], coverage.covered(g), values, strCat(source, ": grid ", g));
  }
  set.world.origin = origin;
  set.world.scale = finest;
  if (anyElsewhere && set.cells.empty()) return set; // the cells are all held elsewhere
  validateCells(set, source);
  return set;
}

} // namespace exa
