"""Overlapping AMR written by VTK itself (vtkXMLUniformGridAMRWriter: zlib-compressed, base64
appended data, as VTK writes by default) read by exabricks and by VTK's own reader. Needs VTK
in /usr/bin/python3 (Debian's python3-paraview provides it); skipped without."""
import numpy as np
import pytest

import exabricks as eb

vtk = pytest.importorskip("vtk", reason="VTK's Python module is not installed (Debian: python3-paraview)")
from vtk.util import numpy_support  # noqa: E402


def linear(c):
    return 1.0 + c[:, 0] + 2.0 * c[:, 1] + 3.0 * c[:, 2]


def block(origin, h, n):
    g = vtk.vtkUniformGrid()
    g.SetOrigin(*origin)
    g.SetSpacing(h, h, h)
    g.SetDimensions(n + 1, n + 1, n + 1)
    idx = np.indices((n, n, n)).reshape(3, -1).T[:, ::-1]  # x fastest
    a = numpy_support.numpy_to_vtk(linear(np.asarray(origin) + (idx + 0.5) * h), deep=True)
    a.SetName("density")
    g.GetCellData().AddArray(a)
    return g


def write_two_levels(path):
    """An 8^3 level of cells 1 wide and, over [2, 6]^3, an 8^3 level of cells 0.5 wide."""
    amr = vtk.vtkOverlappingAMR()
    amr.Initialize(2, [1, 1])
    amr.SetOrigin([0.0, 0.0, 0.0])
    amr.SetSpacing(0, [1.0, 1.0, 1.0])
    amr.SetSpacing(1, [0.5, 0.5, 0.5])
    amr.SetRefinementRatio(0, 2)
    amr.SetAMRBox(0, 0, vtk.vtkAMRBox([0, 0, 0], [7, 7, 7]))
    amr.SetDataSet(0, 0, block((0.0, 0.0, 0.0), 1.0, 8))
    amr.SetAMRBox(1, 0, vtk.vtkAMRBox([4, 4, 4], [11, 11, 11]))
    amr.SetDataSet(1, 0, block((2.0, 2.0, 2.0), 0.5, 8))
    vtk.vtkAMRUtilities.BlankCells(amr)
    w = vtk.vtkXMLUniformGridAMRWriter()
    w.SetFileName(str(path))
    w.SetInputData(amr)
    assert w.Write() == 1


def visible_cells(path):
    """Centres and values of the cells VTK's reader leaves visible (not covered by a finer one)."""
    r = vtk.vtkXMLUniformGridAMRReader()
    r.SetFileName(str(path))
    r.SetMaximumLevelsToReadByDefault(0)
    r.Update()
    amr = r.GetOutput()
    centres, values = [], []
    for level in range(amr.GetNumberOfLevels()):
        for i in range(amr.GetNumberOfDataSets(level)):
            g = amr.GetDataSet(level, i)
            v = numpy_support.vtk_to_numpy(g.GetCellData().GetArray("density"))
            for c in range(g.GetNumberOfCells()):
                if g.IsCellVisible(c):
                    b = g.GetCell(c).GetBounds()
                    centres.append(((b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2))
                    values.append(v[c])
    return np.array(centres), np.array(values)


def test_vtk_written_amr_reads_as_vtk_reads_it(tmp_path):
    path = tmp_path / "two.vthb"
    write_two_levels(path)
    piece = next(tmp_path.glob("two/*.vti")).read_text(errors="replace")
    assert 'encoding="base64"' in piece and "vtkZLibDataCompressor" in piece  # VTK's defaults
    centres, values = visible_cells(path)
    ds = eb.load(path)
    assert ds.cells == len(values) == 512 - 64 + 512
    info = ds.info()
    field = next(f for f in info["fields"] if f["name"] == "density")
    assert (field["range"]["min"], field["range"]["max"]) == (values.min(), values.max())
    # Away from the level boundary every cell's hat meets only cells of its own level, so the
    # reconstruction of the linear field at a cell centre is the cell's value.
    inner = np.all((centres > 2.7) & (centres < 5.3), axis=1) | np.all(centres < 0.6, axis=1)
    assert inner.sum() > 100
    got, _ = ds.sample(centres[inner], "density")
    np.testing.assert_allclose(got, values[inner], rtol=1e-6)
