#include "errors.h"
#include "exabricks/core/error.h"
#include "exabricks/io/chombo.h"
#include "exabricks/io/load.h"

#include "chombo_fixture.h"
#include "reader_checks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <tuple>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;
using chombo_fixture::ChomboFixture;
using chombo_fixture::truth;

TEST(Chombo, LeafCellsAndValuesBothPrecisionsWithGhostCells) {
  for (int variant = 0; variant < 4; ++variant) {
    SCOPED_TRACE(variant);
    ChomboFixture f;
    f.file = fs::path(EXABRICKS_TEST_TMP) / "chombo" / ("plt" + std::to_string(variant) + ".3d.hdf5");
    f.float32 = variant & 1;
    f.ghost = (variant & 2) ? 2 : 0;
    f.write();
    ASSERT_TRUE(isChomboFile(f.file.string()));
    EXPECT_EQ(detectInput(f.file.string()), InputKind::Chombo);
    EXPECT_EQ(listFields(f.file.string()), (std::vector<std::string>{"density", "energy"}));
    const CellSet s = loadCells(f.file.string());
    const auto expected = f.expectedLeaves();
    ASSERT_EQ(s.size(), expected.size());
    ASSERT_EQ(s.fields.size(), 2u);
    EXPECT_EQ(s.world.scale, vec3d(1.0 / 8));
    EXPECT_EQ(s.world.origin, vec3d(0.0));
    const double tol = 1e-6; // fields are stored as float32
    for (size_t i = 0; i < s.size(); ++i) {
      const Cell& c = s.cells[i];
      const auto it = expected.find({c.lower.x, c.lower.y, c.lower.z, c.level});
      ASSERT_NE(it, expected.end()) << "unexpected cell " << c.lower.x << " " << c.lower.y << " " << c.lower.z
                                    << " level " << c.level;
      const vec3d centre = s.world.toWorld(vec3d(c.lower) + vec3d(0.5 * c.width()));
      const double v = truth(centre.x, centre.y, centre.z);
      EXPECT_NEAR(s.fields[0].values[i], v, tol * (1 + std::abs(v)));
      EXPECT_NEAR(s.fields[1].values[i], 2 * v + it->second, 4 * tol * (1 + std::abs(v)));
    }
  }
}

TEST(Chombo, FieldSelectionAndRatioTwoEverywhere) {
  ChomboFixture f;
  f.file = fs::path(EXABRICKS_TEST_TMP) / "chombo" / "ratio2.3d.hdf5";
  f.ratio1 = 2;
  f.levels[2] = {{{8, 8, 8}, {11, 11, 11}}}; // level-1 cells [4,5]^3 refined by 2
  f.write();
  LoadOptions o;
  o.fields = {"energy"};
  const CellSet s = loadCells(f.file.string(), o);
  ASSERT_EQ(s.fields.size(), 1u);
  EXPECT_EQ(s.fields[0].name, "energy");
  EXPECT_EQ(s.size(), f.expectedLeaves().size());
  EXPECT_EQ(s.world.scale, vec3d(0.25));
  o.fields = {"nope"};
  try {
    loadCells(f.file.string(), o);
    FAIL() << "unknown field accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown field 'nope'"), std::string::npos) << e.what();
  }
}

TEST(Chombo, CoarseLevelsAloneFromTheBoxTables) {
  // The box tables give each level's cells; a read of the coarse levels leaves out the finer
  // ones, and the cells under them are leaves with their own level's stored values.
  ChomboFixture f;
  f.file = fs::path(EXABRICKS_TEST_TMP) / "chombo" / "coarse.3d.hdf5";
  f.write();
  const std::string path = f.file.string();
  std::vector<double> expectedCells(size_t(kMaxLevel) + 1, 0.0);
  expectedCells[0] = 8 * 8 * 8 + 4 * 4 * 4, expectedCells[2] = 4 * 4 * 4, expectedCells[3] = 2 * 4 * 8 * 8;
  EXPECT_EQ(chomboLevelCells(path), expectedCells);
  const std::vector<CoarseFirst> choices = coarseFirstChoices(path);
  ASSERT_EQ(choices.size(), 3u);
  EXPECT_EQ(choices[1].level, 3);
  EXPECT_EQ(choices[2].level, 2);
  EXPECT_EQ(choices[2].coarseCells, 512 + 64);
  const int levelsRead[4] = {3, 2, 2, 1}; // for finestLevel 0..3
  for (int finest = 0; finest <= 3; ++finest) {
    SCOPED_TRACE(finest);
    LoadOptions o;
    o.finestLevel = finest;
    const CellSet s = loadCells(path, o);
    EXPECT_EQ(s.world.scale, vec3d(1.0 / 8)); // the whole file's lattice
    expectCoarseLeaves(
        s, f.expectedLeaves(levelsRead[finest]), finest, 64.0,
        [](const vec3d& p, int level) { return 2 * truth(p.x, p.y, p.z) + level; }, 4e-6 * 20);
  }
}

TEST(Chombo, CensusFromTheBoxTablesAndABuildFromTheBoxesEqualTheCells) {
  ChomboFixture f;
  f.file = fs::path(EXABRICKS_TEST_TMP) / "chombo" / "parts.3d.hdf5";
  f.write();
  const std::string path = f.file.string();
  const Census census = chomboCensus(path);
  EXPECT_EQ(census.cells(), double(f.expectedLeaves().size()));
  EXPECT_EQ(census.coarsestLevel, 3);
  expectBoxBuildEqualsCells(path, 2, f.expectedLeaves().size());
}

TEST(Chombo, BadFilesAreRejectedClearly) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "chombo-bad";
  auto errorFor = [&](const std::string& name, auto change) {
    ChomboFixture f;
    f.file = dir / (name + ".3d.hdf5");
    change(f);
    f.write();
    return loadError(f.file.string());
  };
  auto expectIn = [](const std::string& m, std::initializer_list<const char*> parts) {
    for (const char* p : parts)
      EXPECT_NE(m.find(p), std::string::npos) << "'" << p << "' not in: " << m;
  };
  expectIn(errorFor("ratio3", [](ChomboFixture& f) { f.ratio1 = 3; }),
           {"ratio3.3d.hdf5", "level_1", "refinement ratio 3", "power of two"});
  expectIn(errorFor("flat", [](ChomboFixture& f) { f.spaceDim = 2; }), {"flat.3d.hdf5", "SpaceDim is 2", "3-D"});
  expectIn(errorFor("nan", [](ChomboFixture& f) { f.nanValue = true; }),
           {"nan.3d.hdf5", "level 2 box 0", "density", "NaN"});
  expectIn(errorFor("short", [](ChomboFixture& f) { f.shortData = true; }),
           {"short.3d.hdf5", "level_1/data:datatype=0", "values"});
  expectIn(errorFor("levels", [](ChomboFixture& f) { f.numLevels = 4; }),
           {"levels.3d.hdf5", "level_3", "missing group"});
  expectIn(errorFor("dx", [](ChomboFixture& f) { f.badDx = true; }), {"dx.3d.hdf5", "level_2", "inconsistent headers"});
  // A truncated file keeps its signature but cannot be opened.
  ChomboFixture f;
  f.file = dir / "cut.3d.hdf5";
  f.write();
  fs::resize_file(f.file, fs::file_size(f.file) / 2);
  expectIn(loadError(f.file.string()), {"cut.3d.hdf5"});
}

TEST(Chombo, UnwrittenDatasetsAreRefusedBeforeReading) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "chombo-sizes";
  ChomboFixture f;
  f.file = dir / "unwritten.3d.hdf5";
  f.write();
  {
    // level_2's data declared 2^30 values long, chunked and never written.
    const hid_t file = H5Fopen(f.file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    H5Ldelete(file, "/level_2/data:datatype=0", H5P_DEFAULT);
    const hsize_t n = hsize_t(1) << 30, chunk = 4096;
    const hid_t space = H5Screate_simple(1, &n, nullptr);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 1, &chunk);
    H5Dclose(H5Dcreate2(file, "/level_2/data:datatype=0", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT));
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Fclose(file);
  }
  const std::string m = loadError(f.file.string());
  EXPECT_TRUE(m.find("bytes are present") != std::string::npos || m.find("values") != std::string::npos) << m;
  expectIn(m, {"unwritten.3d.hdf5", "level_2"});
}
