// libFuzzer entry for the Enzo reader: the input holds the parameter file and the hierarchy,
// cut at a "--8<--" line. The data file DD0001.cpu0000 is a fixed valid HDF5 file written once
// (grids 1 to 3 with Density of 4^3, 8^3 and 4x8x8 values), so the hierarchy's claims are
// checked against real datasets; corrupt HDF5 bytes are libhdf5's own parser's concern.
#include "fuzz_files.h"

#include "exabricks/core/error.h"
#include "exabricks/io/enzo.h"

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
  return 0;
}
