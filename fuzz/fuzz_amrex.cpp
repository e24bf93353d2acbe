// libFuzzer entry for the AMReX plotfile reader: the input holds the Header, a level's Cell_H
// and its FAB data file (Level_0/Cell_D_00000), cut at "--8<--" lines; the plotfile is read
// whole and by field list, its fields' ranges from the Cell_H min/max tables, its census from the
// headers, the part of it inside a box, and its build from the boxes.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/amrex.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> p = fuzz::parts(data, size, 3);
  const std::string dir = (fuzz::folder() / "plt").string();
  fuzz::write("plt/Header", p[0]);
  fuzz::write("plt/Level_0/Cell_H", p[1]);
  fuzz::write("plt/Level_0/Cell_D_00000", p[2]);
  try {
    for (const std::string& name : exa::listAmrexFields(dir))
      exa::amrexFieldRange(dir, name);
    const exa::CellSet s = exa::readAmrex(dir);
    if (!s.fields.empty() && s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    const exa::Census census = exa::amrexCensus(dir);
    if (census.cells() < 0) __builtin_trap();
    const exa::CellSet s = exa::readAmrex(dir, {}, exa::box3i(exa::vec3i(0), exa::vec3i(4)));
    if (!s.fields.empty() && s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  fuzz::boxBuildMatchesRead([&] { return exa::readAmrex(dir); }, [&] { return exa::amrexPatches(dir); });
  return 0;
}
