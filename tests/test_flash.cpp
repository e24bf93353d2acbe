#include "errors.h"
#include "exabricks/core/error.h"
#include "exabricks/io/flash.h"
#include "exabricks/io/load.h"

#include "flash_fixture.h"
#include "merged_leaves_check.h"
#include "reader_checks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <tuple>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;

using flash_fixture::Block;
using flash_fixture::FlashFixture;
using flash_fixture::truth;

namespace {
/// The fixture written to `name` (in the tests' folder), its values and coordinates in float32 or
/// float64.
FlashFixture written(const std::string& name, bool float32) {
  FlashFixture f;
  f.file = fs::path(EXABRICKS_TEST_TMP) / "flash" / name;
  f.float32 = float32;
  f.write();
  return f;
}
} // namespace

TEST(Flash, LeafBlocksBothPrecisions) {
  for (int variant = 0; variant < 2; ++variant) {
    SCOPED_TRACE(variant);
    const FlashFixture f = written(variant ? "plt_f32_hdf5_0001" : "chk_f64_hdf5_0001", variant);
    ASSERT_TRUE(isFlashFile(f.file.string()));
    EXPECT_EQ(detectInput(f.file.string()), InputKind::Flash);
    EXPECT_EQ(listFields(f.file.string()), (std::vector<std::string>{"dens", "pres"}));
    const CellSet s = loadCells(f.file.string());
    EXPECT_EQ(s.simulation.time, 0.5); // from "real scalars"
    EXPECT_EQ(s.simulation.cycle, 42); // from "integer scalars"
    // FLASH's variables carry CGS units by name.
    EXPECT_EQ(s.fields.at(0).units, "g/cm^3");
    EXPECT_EQ(s.fields.at(1).units, "erg/cm^3");
    // Finest cells: a level-3 block is a quarter of a root block.
    const vec3d finest(0.25 / 4, 0.5 / 4, 2.0 / 4);
    EXPECT_EQ(s.world.scale, finest);
    EXPECT_EQ(s.world.origin, vec3d(-1, 0, 0));
    // Independent truth: every leaf block's cells with their lattice corner and level.
    std::map<std::tuple<int, int, int, int>, int> expected;
    for (const Block& b : f.blocks) {
      if (b.nodeType != 1) continue;
      const int w = 1 << (3 - b.level);
      for (int k = 0; k < f.nzb; ++k)
        for (int j = 0; j < f.nyb; ++j)
          for (int i = 0; i < f.nxb; ++i) {
            const int x = int(std::lround((b.lo[0] + 1) / finest.x)) + i * w;
            const int y = int(std::lround(b.lo[1] / finest.y)) + j * w;
            const int z = int(std::lround(b.lo[2] / finest.z)) + k * w;
            expected[{x, y, z, 3 - b.level}] = b.level;
          }
    }
    ASSERT_EQ(s.size(), expected.size());
    ASSERT_EQ(s.size(), (1u + 7u + 8u) * 32u);
    for (size_t i = 0; i < s.size(); ++i) {
      const Cell& c = s.cells[i];
      const auto it = expected.find({c.lower.x, c.lower.y, c.lower.z, c.level});
      ASSERT_NE(it, expected.end()) << c.lower.x << " " << c.lower.y << " " << c.lower.z << " level " << c.level;
      const vec3d centre = s.world.toWorld(vec3d(c.lower) + vec3d(0.5 * c.width()));
      const double v = truth(centre.x, centre.y, centre.z);
      EXPECT_NEAR(s.fields[0].values[i], v, 1e-6 * (1 + std::abs(v)));
      EXPECT_NEAR(s.fields[1].values[i], 3 * v + it->second, 4e-6 * (1 + std::abs(v)));
    }
    LoadOptions o;
    o.fields = {"pres"};
    EXPECT_EQ(loadCells(f.file.string(), o).fields.at(0).name, "pres");
  }
}

TEST(Flash, CensusFromTheBlockTableAndABuildFromTheBlocksEqualTheCells) {
  for (int variant = 0; variant < 2; ++variant) {
    SCOPED_TRACE(variant);
    const std::string path = written(variant ? "parts_f32_hdf5_0001" : "parts_f64_hdf5_0001", variant).file.string();
    const Census census = flashCensus(path);
    EXPECT_EQ(census.cells(), double((1 + 7 + 8) * 32));
    EXPECT_EQ(census.coarsestLevel, 2); // the root block's cells are 4 finest cells wide
    // Whole, through a box, and in parts (each the cells whose support reaches it).
    expectBoxBuildEqualsCells(path, 2, (1 + 7 + 8) * 32);
    const Model m = loadModel(path);
    EXPECT_EQ(m.simulation.time, 0.5);
    EXPECT_EQ(m.simulation.cycle, 42);
    EXPECT_EQ(m.fieldUnits.at(0), "g/cm^3");
  }
  // A value float32 cannot hold is named by its block, variable and cell on this path too.
  FlashFixture bad;
  bad.file = fs::path(EXABRICKS_TEST_TMP) / "flash" / "parts_nan_hdf5_0001";
  bad.nanValue = true;
  bad.write();
  try {
    loadModel(bad.file.string());
    ADD_FAILURE() << "a NaN was read";
  } catch (const Error& e) {
    expectIn(e.what(), {"parts_nan_hdf5_0001", "block 17", "dens", "NaN"});
  }
}

TEST(Flash, EveryLeafMergedIntoCubesFromTheBlocks) {
  // A first picture of a FLASH file (whose parent blocks need not hold values): every leaf cell
  // merged into cubes, block by block, against sums over the cells loadCells reads.
  const std::string path = written("merged_hdf5_0001", false).file.string();
  const CellSet cells = loadCells(path);
  EXPECT_FALSE(loadMergedLeaves(path, {}, double(cells.size())));
  for (const double most : {100.0, 20.0}) {
    const std::optional<MergedLeaves> m = loadMergedLeaves(path, {}, most);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->cells, double(cells.size()));
    EXPECT_EQ(m->model.world, cells.world);
    expectCubeMeans(*m, cells);
  }
}

TEST(Flash, BadFilesAreRejectedClearly) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "flash-bad";
  auto errorFor = [&](const std::string& name, auto change) {
    FlashFixture f;
    f.file = dir / name;
    change(f);
    f.write();
    return loadError(f.file.string());
  };
  expectIn(errorFor("flat",
                    [](FlashFixture& f) {
                      f.dimensionality = 2;
                      f.nzb = 1;
                    }),
           {"flat", "integer scalars", "2-D"});
  expectIn(errorFor("flat2", [](FlashFixture& f) { f.nzb = 1; }), {"flat2", "nzb is 1", "2-D"});
  expectIn(errorFor("shifted", [](FlashFixture& f) { f.shift = 0.01; }),
           {"shifted", "block 3", "not on the finest lattice"});
  expectIn(errorFor("third", [](FlashFixture& f) { f.badSize = true; }), {"third", "block 4", "not a power of two"});
  expectIn(errorFor("nan", [](FlashFixture& f) { f.nanValue = true; }), {"nan", "block 17", "dens", "NaN"});
  expectIn(errorFor("rows", [](FlashFixture& f) { f.dropRow = true; }), {"rows", "dens", "dimensions do not match"});
  FlashFixture f;
  f.file = dir / "cut";
  f.write();
  fs::resize_file(f.file, fs::file_size(f.file) * 2 / 3);
  expectIn(loadError(f.file.string()), {"cut", "HDF5"});
}

TEST(Flash, HugeFixedLengthStringsAreRefusedBeforeReading) {
  // "unknown names" as two strings of 100000 bytes each: refused by the declared string size.
  FlashFixture f;
  f.file = fs::path(EXABRICKS_TEST_TMP) / "flash-strings" / "strings.hdf5";
  f.write();
  const hid_t file = H5Fopen(f.file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  H5Ldelete(file, "unknown names", H5P_DEFAULT);
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, 100000);
  const hsize_t dims[2] = {2, 1};
  const hid_t space = H5Screate_simple(2, dims, nullptr);
  const hid_t d = H5Dcreate2(file, "unknown names", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const std::string text(200000, 'd');
  H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, text.data());
  H5Dclose(d);
  H5Sclose(space);
  H5Tclose(type);
  H5Fclose(file);
  expectIn(loadError(f.file.string()), {"strings.hdf5", "unknown names", "strings of 100000 bytes", "at most 65536"});
}
