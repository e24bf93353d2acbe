// libFuzzer entry for the native readers: the input holds d.cells, d.scalars, a .grids text and
// d.particles, cut at "--8<--" lines; the dataset (whole, its census, the part inside a box, read
// in pieces, the model built in parts of 16 cells and every cell merged into cubes), the fixture and the particles
// (listed, then read whole and one species) are read.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/native.h"
#include "exabricks/io/particles.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> p = fuzz::parts(data, size, 4);
  const std::string cells = fuzz::write("d.cells", p[0]);
  fuzz::write("d.scalars", p[1]);
  const std::string grids = fuzz::write("g.grids", p[2]);
  fuzz::write("d.particles", p[3]);
  try {
    const exa::CellSet s = exa::readNative(cells);
    if (s.fields.size() != 1 || s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    const exa::Census census = exa::nativeCensus(cells);
    if (census.cells() < 1) __builtin_trap();
    const exa::CellSet s = exa::readNative(cells, {}, exa::box3i(exa::vec3i(-2), exa::vec3i(3)), false, 2);
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
    // Every cell merged into cubes for a first picture (read a million records at a time): no more
    // cubes than cells, each the mean of finite values.
    const std::optional<exa::MergedLeaves> m = exa::loadMergedLeaves(cells, {}, 2);
    if (m && (m->model.cellCount() > m->cells || m->model.fieldValues.size() != 1)) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    const exa::CellSet s = exa::readGrids(grids);
    if (s.fields.size() != 1 || s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    const std::vector<exa::ParticleSpeciesInfo> listed = exa::listNativeParticles(cells);
    const exa::ParticleSet all = exa::readNativeParticles(cells);
    if (all.species.size() != listed.size()) __builtin_trap();
    for (const exa::ParticleSpecies& s : all.species)
      for (const exa::ParticleAttribute& a : s.attributes)
        if (a.values.size() != s.count()) __builtin_trap();
    if (!listed.empty()) exa::readNativeParticles(cells, listed.back().name);
  } catch (const exa::Error&) {
  }
  return 0;
}
