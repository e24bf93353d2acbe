// libFuzzer entry for the Chombo reader over hostile but well-formed HDF5: the input picks the
// layout of the test fixture (levels, ratios, ghost width, space dimension, box corners) and
// then rewrites attributes and datasets of the written file with values from the input
// (level and component counts, ratios, cell sizes, box tables, offsets). Bytes that make a
// corrupt HDF5 file exercise libhdf5's own parser, outside this project (docs/reliability.md).
#include "fuzz_files.h"
#include "fuzz_hdf5_edit.h"

#include "../src/io/hdf5_file.h"

#include "../tests/chombo_fixture.h"

#include "exabricks/core/error.h"
#include "exabricks/io/chombo.h"

// The inputs are well-formed HDF5 written by libhdf5: no check of each in a child process
// (fuzz_hdf5 fuzzes damaged files through it).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  exa::h5::setChildCheck(false);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  chombo_fixture::ChomboFixture f;
  f.file = fuzz::folder() / "c.hdf5";
  const uint8_t flags = in.byte();
  f.float32 = flags & 1;
  f.nanValue = flags & 2;
  f.shortData = flags & 4;
  f.badDx = flags & 8;
  f.ghost = (flags >> 4) & 3;
  f.ratio1 = 1 + in.byte() % 8;
  f.numLevels = in.byte() % 5;
  f.spaceDim = 1 + in.byte() % 3;
  // Box corners within a small range keep the written data small.
  const uint8_t moves = in.byte() % 8;
  for (uint8_t m = 0; m < moves; ++m) {
    const uint8_t which = in.byte();
    auto& level = f.levels[which % 3];
    if (level.empty()) continue;
    chombo_fixture::Box& b = level[(which >> 2) % level.size()];
    const int axis = (which >> 4) % 3;
    const int v = int(int8_t(in.byte())) % 20;
    (which & 0x80 ? b.hi : b.lo)[axis] = v;
  }
  try {
    f.write();
  } catch (const std::exception&) {
    return 0; // a layout the fixture writer cannot write
  }
  const hid_t file = H5Fopen(f.file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return 0;
  while (!in.empty()) {
    const uint8_t op = in.byte();
    const std::string level = "/level_" + std::to_string((op >> 4) % 3);
    switch (op % 8) {
    case 0: {
      const int v = in.value<int32_t>();
      fuzz::setAttr(file, "/", "num_levels", H5T_NATIVE_INT, &v, 1);
      break;
    }
    case 1: {
      const int v = in.value<int32_t>();
      fuzz::setAttr(file, "/", "num_components", H5T_NATIVE_INT, &v, 1);
      break;
    }
    case 2: {
      const int v = in.value<int32_t>();
      fuzz::setAttr(file, level, "ref_ratio", H5T_NATIVE_INT, &v, 1);
      break;
    }
    case 3: {
      const double v = in.value<double>();
      fuzz::setAttr(file, level, "dx", H5T_NATIVE_DOUBLE, &v, 1);
      break;
    }
    case 4: {
      std::vector<long long> v(in.byte() % 6);
      for (long long& x : v)
        x = in.value<int32_t>();
      fuzz::setDataset(file, level + "/data:offsets=0", H5T_NATIVE_LLONG, v.data(), v.size());
      break;
    }
    case 5: {
      std::vector<int> v((in.byte() % 4) * 6);
      for (int& x : v)
        x = int(int8_t(in.byte()));
      fuzz::setDataset(file, level + "/boxes", H5T_NATIVE_INT, v.data(), v.size());
      break;
    }
    case 6: {
      std::vector<double> v(in.byte());
      for (double& x : v)
        x = double(int8_t(in.byte()));
      fuzz::setDataset(file, level + "/data:datatype=0", H5T_NATIVE_DOUBLE, v.data(), v.size());
      break;
    }
    default:
      H5Ldelete(file, (level + (op & 0x80 ? "/boxes" : "/data_attributes")).c_str(), H5P_DEFAULT);
      break;
    }
  }
  fuzz::closeAndRead(
      file, f.file.string(),
      [](const std::string& p) {
        exa::listChomboFields(p);
        try { // the coarse levels alone: the box tables' counts, then a read without the finest level
          exa::chomboLevelCells(p);
          if (!(exa::chomboCensus(p).cells() >= 0)) __builtin_trap();
          const exa::CellSet s = exa::readChombo(p, {}, 1);
          for (const exa::Cell& c : s.cells)
            if (c.level < 1) __builtin_trap();
          if (!s.fields.empty() && s.fields[0].values.size() != s.cells.size()) __builtin_trap();
        } catch (const exa::Error&) {
        }
        fuzz::boxBuildMatchesRead([&] { return exa::readChombo(p); }, [&] { return exa::chomboPatches(p); });
      },
      [](const std::string& p) { return exa::readChombo(p); });
  return 0;
}
