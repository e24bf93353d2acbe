// libFuzzer entry for the VTK overlapping-AMR reader: the input holds the .vthb hierarchy and one
// .vti piece (p.vti, in any encoding: ascii, base64 binary, raw appended, zlib), cut at a
// "--8<--" line.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/vtk_amr.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> p = fuzz::parts(data, size, 2);
  const std::string path = fuzz::write("data.vthb", p[0]);
  fuzz::write("p.vti", p[1]);
  try {
    exa::listVtkAmrFields(path);
    const exa::CellSet s = exa::readVtkAmr(path);
    if (!s.fields.empty() && s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try { // the coarse levels alone: the boxes' counts, then a read without the finest boxes
    exa::vtkAmrLevelCells(path);
    if (!(exa::vtkAmrCensus(path).cells() >= 0)) __builtin_trap();
    const exa::CellSet s = exa::readVtkAmr(path, {}, 1);
    for (const exa::Cell& c : s.cells)
      if (c.level < 1) __builtin_trap();
    if (!s.fields.empty() && s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  fuzz::boxBuildMatchesRead([&] { return exa::readVtkAmr(path); }, [&] { return exa::vtkAmrPatches(path); });
  return 0;
}
