#include "exabricks/core/error.h"
#include "exabricks/io/chombo.h"
#include "exabricks/io/load.h"

#include "h5_writer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <tuple>

using namespace exa;
namespace fs = std::filesystem;

namespace {

/// A known function of the world position (cell centres).
double truth(double x, double y, double z) { return std::sin(x) + 0.5 * y - 0.1 * z * z; }

struct Box {
  int lo[3], hi[3]; // inclusive, in the level's index space
  bool contains(int i, int j, int k) const {
    return i >= lo[0] && i <= hi[0] && j >= lo[1] && j <= hi[1] && k >= lo[2] && k <= hi[2];
  }
};

/// Three levels: an 8^3 domain in two boxes, level 1 (ratio 2) refines [2,3]^3 of level 0,
/// level 2 (ratio 4) refines [4,5]^3 of level 1. Components: density = truth(centre) and
/// energy = 2 * density + level. Ghost cells hold -999 so that reading them shows.
struct ChomboFixture {
  fs::path file;
  bool float32 = false;
  int ghost = 0;
  int ratio1 = 4;
  int spaceDim = 3;
  int numLevels = 3;
  bool nanValue = false;
  bool shortData = false;
  std::vector<std::vector<Box>> levels{{{{0, 0, 0}, {3, 7, 7}}, {{4, 0, 0}, {7, 7, 7}}},
                                       {{{4, 4, 4}, {7, 7, 7}}},
                                       {{{16, 16, 16}, {23, 23, 23}}, {{24, 16, 16}, {27, 19, 19}}}};
  std::vector<int> ratios() const { return {2, ratio1, 2}; }
  double dx(int l) const {
    double d = 1.0;
    for (int i = 0; i < l; ++i) d /= ratios()[size_t(i)];
    return d;
  }

  void write() const {
    fs::create_directories(file.parent_path());
    h5w::Writer w(file.string());
    w.attrInts("/", "num_levels", {numLevels});
    w.attrInts("/", "num_components", {2});
    w.attrString("/", "component_0", "density");
    w.attrString("/", "component_1", "energy");
    w.group("/Chombo_global");
    w.attrInts("/Chombo_global", "SpaceDim", {spaceDim});
    for (int l = 0; l < 3; ++l) {
      const std::string g = "/level_" + std::to_string(l);
      w.group(g);
      w.attrDoubles(g, "dx", {dx(l)});
      w.attrInts(g, "ref_ratio", {ratios()[size_t(l)]});
      w.group(g + "/data_attributes");
      w.attrIntCompound(g + "/data_attributes", "outputGhost", {"intvecti", "intvectj", "intvectk"}, {ghost, ghost, ghost});
      std::vector<int> boxes;
      std::vector<long long> offsets{0};
      std::vector<double> data;
      for (const Box& b : levels[size_t(l)]) {
        boxes.insert(boxes.end(), {b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]});
        for (int c = 0; c < 2; ++c)
          for (int k = b.lo[2] - ghost; k <= b.hi[2] + ghost; ++k)
            for (int j = b.lo[1] - ghost; j <= b.hi[1] + ghost; ++j)
              for (int i = b.lo[0] - ghost; i <= b.hi[0] + ghost; ++i) {
                const bool inside = b.contains(i, j, k);
                const double v = truth((i + 0.5) * dx(l), (j + 0.5) * dx(l), (k + 0.5) * dx(l));
                data.push_back(!inside ? -999.0 : c == 0 ? v : 2 * v + l);
              }
        offsets.push_back((long long)data.size());
      }
      if (nanValue && l == 2) data[5] = std::nan("");
      if (shortData && l == 1) data.resize(data.size() - 10);
      w.intCompound(g + "/boxes", {"lo_i", "lo_j", "lo_k", "hi_i", "hi_j", "hi_k"}, boxes);
      w.int64s(g + "/data:offsets=0", {offsets.size()}, offsets);
      w.doubles(g + "/data:datatype=0", {data.size()}, data, float32);
    }
  }

  /// Expected leaf cells: (x, y, z, level) on the finest lattice -> level index.
  std::map<std::tuple<int, int, int, int>, int> expectedLeaves() const {
    std::map<std::tuple<int, int, int, int>, int> out;
    const int widths[3] = {2 * ratio1, ratio1, 1};
    const int exaLevels[3] = {ratio1 == 4 ? 3 : 2, ratio1 == 4 ? 2 : 1, 0};
    for (int l = 0; l < 3; ++l)
      for (const Box& b : levels[size_t(l)])
        for (int k = b.lo[2]; k <= b.hi[2]; ++k)
          for (int j = b.lo[1]; j <= b.hi[1]; ++j)
            for (int i = b.lo[0]; i <= b.hi[0]; ++i) {
              bool covered = false;
              if (l < 2) {
                const int r = ratios()[size_t(l)];
                for (const Box& f : levels[size_t(l) + 1])
                  covered |= f.contains(i * r, j * r, k * r);
              }
              if (!covered) out[{i * widths[l], j * widths[l], k * widths[l], exaLevels[l]}] = l;
            }
    return out;
  }
};

std::string loadError(const std::string& path) {
  try {
    loadCells(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

} // namespace

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
      ASSERT_NE(it, expected.end()) << "unexpected cell " << c.lower.x << " " << c.lower.y << " " << c.lower.z << " level " << c.level;
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
    for (const char* p : parts) EXPECT_NE(m.find(p), std::string::npos) << "'" << p << "' not in: " << m;
  };
  expectIn(errorFor("ratio3", [](ChomboFixture& f) { f.ratio1 = 3; }),
           {"ratio3.3d.hdf5", "level_1", "refinement ratio 3", "power of two"});
  expectIn(errorFor("flat", [](ChomboFixture& f) { f.spaceDim = 2; }), {"flat.3d.hdf5", "SpaceDim is 2", "3-D"});
  expectIn(errorFor("nan", [](ChomboFixture& f) { f.nanValue = true; }), {"nan.3d.hdf5", "level 2 box 0", "density", "NaN"});
  expectIn(errorFor("short", [](ChomboFixture& f) { f.shortData = true; }), {"short.3d.hdf5", "level_1/data:datatype=0", "values"});
  expectIn(errorFor("levels", [](ChomboFixture& f) { f.numLevels = 4; }), {"levels.3d.hdf5", "level_3", "missing group"});
  // A truncated file keeps its signature but cannot be opened.
  ChomboFixture f;
  f.file = dir / "cut.3d.hdf5";
  f.write();
  fs::resize_file(f.file, fs::file_size(f.file) / 2);
  expectIn(loadError(f.file.string()), {"cut.3d.hdf5"});
}
