#include "amr_cells.h"

#include "exabricks/core/error.h"
#include "exabricks/io/grids.h"
#include "exabricks/io/patch_source.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkOverlappingAMR.h>
#include <vtkUniformGrid.h>

namespace exa::paraview {

namespace {

// Calls visit(level, id, grid, patch) for every block this process holds, its box in `patch`.
template <typename Visit> void forBlocks(vtkOverlappingAMR* amr, Visit&& visit) {
  if (!amr) fail("ExaBricks: the input is not overlapping AMR data");
  for (unsigned level = 0; level < amr->GetNumberOfLevels(); ++level)
    for (unsigned id = 0; id < amr->GetNumberOfDataSets(level); ++id) {
      vtkUniformGrid* grid = amr->GetDataSet(level, id);
      if (!grid) continue; // held by another process
      int dims[3];
      double origin[3], spacing[3];
      grid->GetDimensions(dims);
      grid->GetOrigin(origin);
      grid->GetSpacing(spacing);
      GridPatch p;
      for (int a = 0; a < 3; ++a) {
        if (dims[a] < 2)
          fail("ExaBricks renders 3D AMR data; block ", id, " of level ", level, " has ", dims[a],
               " points along axis ", a);
        p.cells[a] = dims[a] - 1;
        p.lower[a] = origin[a];
        p.upper[a] = origin[a] + spacing[a] * double(dims[a] - 1);
      }
      visit(level, id, grid, p);
    }
}

} // namespace

std::vector<GridPatch> amrBlockBoxes(vtkOverlappingAMR* amr) {
  std::vector<GridPatch> boxes;
  forBlocks(amr, [&](unsigned, unsigned, vtkUniformGrid*, GridPatch& p) {
    p.elsewhere = true;
    boxes.push_back(std::move(p));
  });
  return boxes;
}

namespace {

/// The blocks this process holds with the values of `name`, and the boxes of `elsewhere`.
std::vector<GridPatch> amrGrids(vtkOverlappingAMR* amr, const std::string& name,
                                const std::vector<GridPatch>& elsewhere) {
  std::vector<GridPatch> grids;
  forBlocks(amr, [&](unsigned level, unsigned id, vtkUniformGrid* grid, GridPatch& p) {
    vtkDataArray* values = grid->GetCellData()->GetArray(name.c_str());
    if (!values)
      fail("ExaBricks renders cell arrays; block ", id, " of level ", level, " has no cell array '", name, "'");
    if (values->GetNumberOfComponents() != 1)
      fail("ExaBricks renders one-component arrays; '", name, "' has ", values->GetNumberOfComponents());
    const vtkIdType n = grid->GetNumberOfCells();
    if (values->GetNumberOfTuples() != n)
      fail("block ", id, " of level ", level, ": '", name, "' has ", values->GetNumberOfTuples(), " values for ", n,
           " cells");
    std::vector<double> v(static_cast<size_t>(n));
    for (vtkIdType i = 0; i < n; ++i)
      v[static_cast<size_t>(i)] = values->GetComponent(i, 0);
    p.values.push_back(std::move(v));
    grids.push_back(std::move(p));
  });
  if (grids.empty() && elsewhere.empty()) fail("ExaBricks: the AMR data holds no blocks here");
  grids.insert(grids.end(), elsewhere.begin(), elsewhere.end());
  return grids;
}

vec3d originOf(vtkOverlappingAMR* amr) {
  const double* o = amr->GetOrigin();
  return vec3d(o[0], o[1], o[2]);
}

} // namespace

CellSet amrLeafCells(vtkOverlappingAMR* amr, const std::string& name, const std::vector<GridPatch>& elsewhere) {
  std::vector<GridPatch> grids = amrGrids(amr, name, elsewhere);
  const vec3d origin = originOf(amr);
  return cellsFromGrids(std::move(grids), {name}, "ParaView AMR data", &origin);
}

Model amrModel(vtkOverlappingAMR* amr, const std::string& name) {
  std::vector<GridPatch> grids = amrGrids(amr, name, {});
  const vec3d origin = originOf(amr);
  Model m = buildModelOfPatches(patchesOfGrids(std::move(grids), {name}, "ParaView AMR data", &origin));
  if (m.bricks.empty()) fail("ExaBricks: the AMR data holds no cells");
  return m;
}

} // namespace exa::paraview
