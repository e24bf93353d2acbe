#include "errors.h"
#include "exabricks/core/error.h"
#include "exabricks/io/enzo.h"
#include "exabricks/io/load.h"

#include "h5_writer.h"
#include "reader_checks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;

namespace {

double truth(double x, double y, double z) { return 1.0 + x * x - std::sin(3 * y) + 0.5 * z; }

struct EGrid {
  int id, level;
  double left[3], right[3];
  int file; ///< cpu number
};

/// A root grid of 8^3 cells, two level-1 grids (one refined again by a level-2 grid) and one
/// level-2 grid; 3 ghost zones per side. Grids are spread over DD0010.cpu0000 and .cpu0001.
/// Fields: Density = truth(centre), Temperature = 10 Density + level; ghosts hold -999.
struct EnzoFixture {
  fs::path dir;
  bool ghostArrays = false; ///< store GridDimension-sized arrays (WriteGhostZones = 1)
  bool float32 = false;
  int refineBy = 2;
  int rank = 3;
  bool truncate = false; ///< cut the hierarchy text inside grid 3
  bool wrongShape = false;
  std::vector<EGrid> grids{{1, 0, {0, 0, 0}, {1, 1, 1}, 0},
                           {2, 1, {0.25, 0.25, 0.25}, {0.75, 0.5, 0.5}, 1},
                           {3, 1, {0.75, 0.25, 0.25}, {1.0, 0.5, 0.5}, 0},
                           {4, 2, {0.375, 0.3125, 0.3125}, {0.5, 0.4375, 0.4375}, 1}};
  static constexpr int kGhost = 3;

  fs::path parameterFile() const { return dir / "DD0010"; }
  /// Independent truth for the grids up to Enzo level `maxLevel`: a cell of such a grid is a leaf
  /// unless one of them, one level finer, contains it. (x, y, z, level) -> Enzo level.
  std::map<std::tuple<int, int, int, int>, int> expectedLeaves(int maxLevel = 2) const {
    std::map<std::tuple<int, int, int, int>, int> expected;
    for (const EGrid& g : grids) {
      if (g.level > maxLevel) continue;
      const int w = 4 >> g.level;
      for (int k = 0; k < cells(g, 2); ++k)
        for (int j = 0; j < cells(g, 1); ++j)
          for (int i = 0; i < cells(g, 0); ++i) {
            const int x = int(std::lround(g.left[0] * 32)) + i * w, y = int(std::lround(g.left[1] * 32)) + j * w,
                      z = int(std::lround(g.left[2] * 32)) + k * w;
            bool covered = false;
            for (const EGrid& c : grids)
              covered |= c.level == g.level + 1 && c.level <= maxLevel && x >= c.left[0] * 32 && x < c.right[0] * 32 &&
                         y >= c.left[1] * 32 && y < c.right[1] * 32 && z >= c.left[2] * 32 && z < c.right[2] * 32;
            if (!covered) expected[{x, y, z, 2 - g.level}] = g.level;
          }
    }
    return expected;
  }
  static int cells(const EGrid& g, int a) { return int(std::lround((g.right[a] - g.left[a]) * 8 * (1 << g.level))); }

  void write() const {
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(parameterFile()) << "InitialTime = 0.5\nCosmologyCurrentRedshift = 3.25\nTopGridRank = " << rank
                                   << "\nTopGridDimensions = 8 8 8\nRefineBy = " << refineBy
                                   << "\nDomainLeftEdge = 0 0 0\nDomainRightEdge = 1 1 1\nWriteGhostZones = "
                                   << ghostArrays << "\n";
    std::ostringstream h;
    h.precision(17);
    for (const EGrid& g : grids) {
      const int n[3] = {cells(g, 0), cells(g, 1), cells(g, 2)};
      h << "\nGrid = " << g.id << "\nTask = " << g.file << "\nGridRank = " << rank
        << "\nGridDimension = " << n[0] + 2 * kGhost << " " << n[1] + 2 * kGhost << " " << n[2] + 2 * kGhost
        << "\nGridStartIndex = 3 3 3\nGridEndIndex = " << n[0] + 2 << " " << n[1] + 2 << " " << n[2] + 2
        << "\nGridLeftEdge = " << g.left[0] << " " << g.left[1] << " " << g.left[2]
        << "\nGridRightEdge = " << g.right[0] << " " << g.right[1] << " " << g.right[2]
        << "\nTime = 0.5\nNumberOfBaryonFields = 2\nFieldType = 0 4\nBaryonFileName = "
           "/scratch/run42/DD0010/DD0010.cpu000"
        << g.file << "\nCourantSafetyNumber = 0.3\nPointer: Grid[" << g.id << "]->NextGridThisLevel = 0\n";
    }
    std::string text = h.str();
    if (truncate) text.resize(text.find("GridLeftEdge", text.find("Grid = 3")));
    std::ofstream(dir / "DD0010.hierarchy") << text;
    for (int cpu = 0; cpu < 2; ++cpu) {
      h5w::Writer w((dir / ("DD0010.cpu000" + std::to_string(cpu))).string());
      for (const EGrid& g : grids) {
        if (g.file != cpu) continue;
        char group[32];
        std::snprintf(group, sizeof group, "/Grid%08d", g.id);
        w.group(group);
        const int n[3] = {cells(g, 0), cells(g, 1), cells(g, 2)};
        const int gh = ghostArrays ? kGhost : 0;
        const double dx = 1.0 / (8 << g.level);
        for (int field = 0; field < 2; ++field) {
          std::vector<double> v;
          for (int k = -gh; k < n[2] + gh; ++k)
            for (int j = -gh; j < n[1] + gh; ++j)
              for (int i = -gh; i < n[0] + gh; ++i) {
                const bool inside = i >= 0 && j >= 0 && k >= 0 && i < n[0] && j < n[1] && k < n[2];
                const double t =
                    truth(g.left[0] + (i + 0.5) * dx, g.left[1] + (j + 0.5) * dx, g.left[2] + (k + 0.5) * dx);
                v.push_back(!inside ? -999.0 : field == 0 ? t : 10 * t + g.level);
              }
          std::vector<hsize_t> dims{hsize_t(n[2] + 2 * gh), hsize_t(n[1] + 2 * gh), hsize_t(n[0] + 2 * gh)};
          if (wrongShape && g.id == 3) dims[0] -= 1, v.resize(v.size() - size_t(dims[1] * dims[2]));
          w.doubles(std::string(group) + (field == 0 ? "/Density" : "/Temperature"), dims, v, float32);
        }
        // A particle dataset (1-D) is not a grid field.
        w.doubles(std::string(group) + "/particle_mass", {3}, {1, 2, 3});
      }
    }
  }
};

} // namespace

TEST(Enzo, LeafCellsGhostZonesSeveralFilesBothPrecisions) {
  for (int variant = 0; variant < 4; ++variant) {
    SCOPED_TRACE(variant);
    EnzoFixture f;
    f.dir = fs::path(EXABRICKS_TEST_TMP) / ("enzo" + std::to_string(variant)) / "DD0010";
    f.ghostArrays = variant & 1;
    f.float32 = variant & 2;
    f.write();
    const std::string path = f.parameterFile().string();
    ASSERT_TRUE(isEnzoOutput(path));
    EXPECT_EQ(detectInput(path), InputKind::Enzo);
    EXPECT_EQ(detectInput(path + ".hierarchy"), InputKind::Enzo);
    EXPECT_EQ(listFields(path), (std::vector<std::string>{"Density", "Temperature"}));
    const CellSet s = loadCells(path);
    EXPECT_EQ(s.fields.at(0).units, "code units");
    EXPECT_EQ(s.fields.at(1).units, "K");
    EXPECT_EQ(s.world.scale, vec3d(1.0 / 32));
    EXPECT_EQ(s.world.origin, vec3d(0.0));
    EXPECT_EQ(s.simulation.time, 0.5);
    EXPECT_EQ(s.simulation.timeUnits, "code units");
    EXPECT_EQ(s.simulation.redshift, 3.25);
    const auto expected = f.expectedLeaves();
    ASSERT_EQ(s.size(), expected.size());
    for (size_t i = 0; i < s.size(); ++i) {
      const Cell& c = s.cells[i];
      const auto it = expected.find({c.lower.x, c.lower.y, c.lower.z, c.level});
      ASSERT_NE(it, expected.end()) << c.lower.x << " " << c.lower.y << " " << c.lower.z << " level " << c.level;
      const vec3d centre = s.world.toWorld(vec3d(c.lower) + vec3d(0.5 * c.width()));
      const double v = truth(centre.x, centre.y, centre.z);
      EXPECT_NEAR(s.fields[0].values[i], v, 1e-6 * (1 + std::abs(v)));
      EXPECT_NEAR(s.fields[1].values[i], 10 * v + it->second, 1e-5 * (1 + std::abs(v)));
    }
  }
}

TEST(Enzo, CoarseLevelsAloneFromTheHierarchy) {
  // The hierarchy alone gives each level's cells; a read of the coarse levels leaves out the finer
  // grids, and the cells under them are leaves with the values their own grid stores.
  EnzoFixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "enzo-coarse" / "DD0010";
  f.write();
  const std::string path = f.parameterFile().string();
  std::vector<double> expectedCells(size_t(kMaxLevel) + 1, 0.0);
  expectedCells[0] = 64, expectedCells[1] = 128 + 64, expectedCells[2] = 512;
  EXPECT_EQ(enzoLevelCells(path), expectedCells);
  const std::vector<CoarseFirst> choices = coarseFirstChoices(path);
  ASSERT_EQ(choices.size(), 3u);
  EXPECT_EQ(choices[1].level, 2);
  EXPECT_EQ(choices[1].coarseCells, 512);
  EXPECT_EQ(choices[2].level, 1);
  EXPECT_EQ(choices[2].coarseCells, 512 + 192);
  for (int finest = 0; finest <= 2; ++finest) {
    SCOPED_TRACE(finest);
    LoadOptions options;
    options.finestLevel = finest;
    const CellSet s = loadCells(path, options);
    EXPECT_EQ(s.world.scale, vec3d(1.0 / 32)); // the whole step's lattice
    expectCoarseLeaves(
        s, f.expectedLeaves(2 - finest), finest, 32.0,
        [](const vec3d& p, int level) { return 10 * truth(p.x, p.y, p.z) + level; }, 1e-5 * 20);
  }
}

TEST(Enzo, CensusFromTheHierarchyAndABuildFromTheGridsEqualTheCells) {
  // The census counts each grid's leaves from the hierarchy alone; a build in parts (each part
  // read through its box) reconstructs what the whole build does everywhere.
  EnzoFixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "enzo-parts" / "DD0010";
  f.write();
  const std::string path = f.parameterFile().string();
  const CellSet all = loadCells(path);
  const Census census = enzoCensus(path);
  EXPECT_EQ(census.cells(), double(all.size()));
  EXPECT_EQ(census.coarsestLevel, 2);
  expectBoxBuildEqualsCells(path, 2, all.size());
}

TEST(Enzo, BadOutputsAreRejectedClearly) {
  const fs::path base = fs::path(EXABRICKS_TEST_TMP) / "enzo-bad";
  auto errorFor = [&](const std::string& name, auto change) {
    EnzoFixture f;
    f.dir = base / name;
    change(f);
    f.write();
    return loadError(f.parameterFile().string());
  };
  {
    EnzoFixture f;
    f.dir = base / "missing";
    f.write();
    fs::remove(f.dir / "DD0010.cpu0001");
    expectIn(loadError(f.parameterFile().string()), {"DD0010.cpu0001", "missing data file"});
  }
  expectIn(errorFor("flat", [](EnzoFixture& f) { f.rank = 2; }), {"DD0010", "TopGridRank is 2", "3-D"});
  expectIn(errorFor("ratio3", [](EnzoFixture& f) { f.refineBy = 3; }), {"DD0010", "RefineBy 3", "power of two"});
  expectIn(errorFor("cut", [](EnzoFixture& f) { f.truncate = true; }),
           {"DD0010.hierarchy", "grid 3", "missing GridLeftEdge", "truncated"});
  expectIn(errorFor("shape", [](EnzoFixture& f) { f.wrongShape = true; }),
           {"DD0010.cpu0000", "Grid00000003/Density", "grid 3", "shape"});
  {
    EnzoFixture f;
    f.dir = base / "nogroup";
    f.grids[2].file = 1; // the hierarchy still says cpu0001, but write grid 3 nowhere
    f.write();
    std::string text;
    {
      std::ifstream in(f.dir / "DD0010.hierarchy");
      std::stringstream ss;
      ss << in.rdbuf();
      text = ss.str();
    }
    const size_t at = text.find("Grid = 3");
    const size_t name = text.find("DD0010.cpu0001", at);
    text.replace(name, 14, "DD0010.cpu0000");
    std::ofstream(f.dir / "DD0010.hierarchy") << text;
    expectIn(loadError(f.parameterFile().string()), {"DD0010.cpu0000", "Grid00000003", "missing group"});
  }
}

TEST(Enzo, CutHierarchiesGiveErrorsNotCrashes) {
  EnzoFixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "enzo-corrupt";
  f.write();
  std::string original;
  {
    std::ifstream in(f.dir / "DD0010.hierarchy");
    std::stringstream ss;
    ss << in.rdbuf();
    original = ss.str();
  }
  for (size_t at = 0; at < original.size(); at += 29) {
    for (int mode = 0; mode < 2; ++mode) {
      std::string text = original;
      if (mode == 0)
        text.resize(at);
      else
        text[at] = "9 -x\n="[at % 6];
      std::ofstream(f.dir / "DD0010.hierarchy") << text;
      try {
        loadCells(f.parameterFile().string());
      } catch (const Error&) {
      } catch (const std::exception& e) {
        ADD_FAILURE() << "mode " << mode << " at " << at << ": " << e.what();
      }
    }
  }
}
