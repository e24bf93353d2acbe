#include "exabricks/io/grids.h"

#include "exabricks/core/error.h"

#include "patches.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace exa {

namespace {

/// Every grid's box and values against its cell counts; the finest spacing per axis and the
/// lowest corner.
void checkGrids(const std::vector<GridPatch>& grids, const std::vector<std::string>& fieldNames,
                const std::string& source, vec3d& finest, vec3d& lowest) {
  finest = lowest = vec3d(std::numeric_limits<double>::infinity());
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
}

} // namespace

PatchSource patchesOfGrids(std::vector<GridPatch> gridsIn, const std::vector<std::string>& fieldNames,
                           const std::string& source, const vec3d* originIn) {
  auto held = std::make_shared<std::vector<GridPatch>>(std::move(gridsIn));
  const std::vector<GridPatch>& grids = *held;
  if (grids.empty()) fail(source, ": no grids");
  vec3d finest, lowest;
  checkGrids(grids, fieldNames, source, finest, lowest);
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
  PatchSource out;
  out.input = source;
  out.fieldNames = fieldNames;
  out.fieldUnits.assign(fieldNames.size(), "");
  out.patches = std::move(patches);
  for (const GridPatch& g : grids)
    out.elsewhere.push_back(g.elsewhere ? 1 : 0);
  out.name = [source](size_t g) { return strCat(source, ": grid ", g); };
  out.read = [held, fieldNames, source](size_t g, std::vector<std::vector<float>>& values) {
    const GridPatch& grid = (*held)[g];
    values.assign(fieldNames.size(), {});
    for (size_t f = 0; f < fieldNames.size(); ++f) {
      values[f].reserve(grid.values[f].size());
      for (size_t i = 0; i < grid.values[f].size(); ++i)
        values[f].push_back(io::toFloat32(grid.values[f][i], [&] {
          return strCat(source, ": grid ", g, ": field '", fieldNames[f], "' value ", i);
        }));
    }
  };
  out.concurrentReads = true;
  out.world.origin = origin;
  out.world.scale = finest;
  return out;
}

CellSet cellsFromGrids(std::vector<GridPatch> grids, const std::vector<std::string>& fieldNames,
                       const std::string& source, const vec3d* origin) {
  const bool anyElsewhere = std::any_of(grids.begin(), grids.end(), [](const GridPatch& g) { return g.elsewhere; });
  CellSet set = io::readPatchCells(patchesOfGrids(std::move(grids), fieldNames, source, origin), box3i());
  if (anyElsewhere && set.cells.empty()) return set; // the cells are all held elsewhere
  validateCells(set, source);
  return set;
}

} // namespace exa
