// libFuzzer entry for the Enzo reader: the input holds the parameter file and the hierarchy,
// cut at a "--8<--" line. The data file DD0001.cpu0000 is a fixed valid HDF5 file written once
// (grids 1 to 3 with Density of 4^3, 8^3 and 4x8x8 values, particles in grids 1 and 2), so the
// hierarchy's claims (fields, NumberOfParticles) are
// checked against real datasets; corrupt HDF5 bytes are libhdf5's own parser's concern.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/enzo.h"
#include "exabricks/io/particles.h"

#include <hdf5.h>

namespace {

void writeDataFile(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t shapes[3][3] = {{4, 4, 4}, {8, 8, 8}, {8, 8, 4}};
  for (int g = 0; g < 3; ++g) {
    const std::string group = "/Grid0000000" + std::to_string(g + 1);
    H5Gclose(H5Gcreate2(f, group.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    const std::vector<double> values(shapes[g][0] * shapes[g][1] * shapes[g][2], 1.5 + g);
    const hid_t space = H5Screate_simple(3, shapes[g], nullptr);
    const hid_t d =
        H5Dcreate2(f, (group + "/Density").c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
    H5Dclose(d);
    H5Sclose(space);
    // Grids 1 and 2 hold 3 and 2 particles (positions, mass; grid 1 also types), grid 3 none.
    const hsize_t n = g == 0 ? 3 : g == 1 ? 2 : 0;
    if (n == 0) continue;
    const hid_t line = H5Screate_simple(1, &n, nullptr);
    const double p[3] = {0.1, 0.5, 0.9};
    for (const char* name : {"particle_position_x", "particle_position_y", "particle_position_z", "particle_mass"}) {
      const hid_t a =
          H5Dcreate2(f, (group + "/" + name).c_str(), H5T_IEEE_F64LE, line, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
      H5Dwrite(a, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, p);
      H5Dclose(a);
    }
    if (g == 0) {
      const int types[3] = {1, 2, 1};
      const hid_t t =
          H5Dcreate2(f, (group + "/particle_type").c_str(), H5T_STD_I32LE, line, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
      H5Dwrite(t, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, types);
      H5Dclose(t);
    }
    H5Sclose(line);
  }
  H5Fclose(f);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool ready = [] {
    writeDataFile((fuzz::folder() / "DD0001.cpu0000").string());
    return true;
  }();
  (void)ready;
  const std::vector<std::string> p = fuzz::parts(data, size, 2);
  const std::string path = fuzz::write("DD0001", p[0]);
  fuzz::write("DD0001.hierarchy", p[1]);
  try {
    exa::listEnzoFields(path);
    const exa::CellSet s = exa::readEnzo(path);
    if (!s.fields.empty() && s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  try {
    // The coarse levels alone: the hierarchy's counts, then a read without the finest grids.
    double cells = 0;
    for (double c : exa::enzoLevelCells(path))
      cells += c;
    if (!(cells >= 0) || !(exa::enzoCensus(path).cells() >= 0)) __builtin_trap();
    const exa::CellSet s = exa::readEnzo(path, {}, 1);
    for (const exa::Cell& c : s.cells)
      if (c.level < 1) __builtin_trap();
  } catch (const exa::Error&) {
  }
  fuzz::boxBuildMatchesRead([&] { return exa::readEnzo(path); }, [&] { return exa::enzoPatches(path); });
  try {
    exa::listEnzoParticles(path);
    for (const exa::ParticleSpecies& s : exa::readEnzoParticles(path).species)
      for (const exa::ParticleAttribute& a : s.attributes)
        if (a.values.size() != s.count()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  return 0;
}
