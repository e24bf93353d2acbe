// libFuzzer entry for the FLASH reader over hostile but well-formed HDF5: the input picks the
// test fixture's block size, dimensionality, precision and defects, moves and relabels blocks,
// then rewrites its tables (refine level, node type, bounding box, block size, coordinates,
// variables) with values from the input. Corrupt HDF5 bytes are libhdf5's own concern
// (docs/reliability.md).
#include "fuzz_files.h"
#include "fuzz_hdf5_edit.h"

#include "../src/io/hdf5_file.h"

#include "../tests/flash_fixture.h"

#include "exabricks/core/error.h"
#include "exabricks/io/flash.h"
#include "exabricks/io/particles.h"

// The inputs are well-formed HDF5 written by libhdf5: no check of each in a child process
// (fuzz_hdf5 fuzzes damaged files through it).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  exa::h5::setChildCheck(false);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  flash_fixture::FlashFixture f;
  f.file = fuzz::folder() / "f.hdf5";
  const uint8_t flags = in.byte();
  f.float32 = flags & 1;
  f.badSize = flags & 2;
  f.nanValue = flags & 4;
  f.dropRow = flags & 8;
  f.shift = (flags & 16) ? 0.25 : 0.0;
  f.dimensionality = 1 + (flags >> 5) % 3;
  f.nxb = 1 + in.byte() % 8;
  f.nyb = 1 + in.byte() % 8;
  f.nzb = 1 + in.byte() % 8;
  f.particles = int(in.byte() % 8) - 1;
  const uint8_t moves = in.byte() % 8;
  for (uint8_t m = 0; m < moves; ++m) {
    flash_fixture::Block& b = f.blocks[in.byte() % f.blocks.size()];
    const uint8_t what = in.byte();
    const double v = double(int8_t(in.byte())) / 8;
    switch (what % 4) {
    case 0:
      b.lo[what / 4 % 3] = v;
      break;
    case 1:
      b.hi[what / 4 % 3] = v;
      break;
    case 2:
      b.level = int(v * 8) % 6;
      break;
    default:
      b.nodeType = int(v * 8) % 4;
      break;
    }
  }
  try {
    f.write();
  } catch (const std::exception&) {
    return 0; // a layout the fixture writer cannot write
  }
  const hid_t file = H5Fopen(f.file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return 0;
  static const char* const tables[] = {"refine level",     "node type",     "bounding box", "block size",
                                       "coordinates",      "dens",          "pres",         "unknown names",
                                       "tracer particles", "particle names"};
  while (!in.empty()) {
    const uint8_t op = in.byte();
    const char* table = tables[(op >> 2) % 10];
    switch (op % 4) {
    case 0: {
      std::vector<int> v(in.byte() % 24);
      for (int& x : v)
        x = int(int8_t(in.byte()));
      fuzz::setDataset(file, table, H5T_NATIVE_INT, v.data(), v.size());
      break;
    }
    case 1: {
      std::vector<double> v(in.byte());
      for (double& x : v)
        x = double(int8_t(in.byte())) / 4;
      fuzz::setDataset(file, table, H5T_NATIVE_DOUBLE, v.data(), v.size());
      break;
    }
    case 2: {
      const int v = in.value<int32_t>();
      fuzz::setAttr(file, "/", table, H5T_NATIVE_INT, &v, 1);
      break;
    }
    default:
      H5Ldelete(file, table, H5P_DEFAULT);
      break;
    }
  }
  fuzz::closeAndRead(
      file, f.file.string(),
      [](const std::string& p) {
        exa::listFlashFields(p);
        try { // the block table alone
          if (!(exa::flashCensus(p).cells() >= 0)) __builtin_trap();
        } catch (const exa::Error&) {
        }
        fuzz::boxBuildMatchesRead([&] { return exa::readFlash(p); }, [&] { return exa::flashPatches(p); });
      },
      [](const std::string& p) { return exa::readFlash(p); });
  try {
    exa::listFlashParticles(f.file.string());
    for (const exa::ParticleSpecies& s : exa::readFlashParticles(f.file.string()).species)
      for (const exa::ParticleAttribute& a : s.attributes)
        if (a.values.size() != s.count()) __builtin_trap();
  } catch (const exa::Error&) {
  }
  return 0;
}
