// libFuzzer entry for the native readers: the input holds d.cells, d.scalars and a .grids text,
// cut at "--8<--" lines; the dataset (whole, its census, the part inside a box, read in pieces,
// and the model built in parts of 16 cells) and the fixture are read.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/native.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> p = fuzz::parts(data, size, 3);
  const std::string cells = fuzz::write("d.cells", p[0]);
  fuzz::write("d.scalars", p[1]);
  const std::string grids = fuzz::write("g.grids", p[2]);
  try {
    const exa::CellSet s = exa::readNative(cells);
    if (s.fields.size() != 1 || s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    const exa::Census census = exa::nativeCensus(cells);
    if (census.cells() < 1) __builtin_trap();
    const exa::CellSet s = exa::readNative(cells, {}, exa::box3i(exa::vec3i(-2), exa::vec3i(3)));
    if (s.fields.size() != 1 || s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    // Built in parts: each part read through a box; whatever is built holds every cell once.
    exa::LoadOptions o;
    o.partCells = 16;
    const exa::Model m = exa::loadModel(cells, o);
    if (m.fieldValues.size() != 1 || m.fieldValues[0].size() != m.cellCount()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    const exa::CellSet s = exa::readGrids(grids);
    if (s.fields.size() != 1 || s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  return 0;
}
