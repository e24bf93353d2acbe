#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/io/amrex.h"
#include "exabricks/io/amrex_write.h"
#include "exabricks/io/load.h"

#include "reader_checks.h"

#include <gtest/gtest.h>

#include <limits>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <random>
#include <sstream>

using namespace exa;
namespace fs = std::filesystem;

namespace {

/// The shared sample data: $EXABRICKS_DATA or ../shared/data beside the source tree.
fs::path sharedData() {
  if (const char* env = std::getenv("EXABRICKS_DATA")) return env;
  return fs::path(EXABRICKS_SOURCE_DIR).parent_path() / "shared" / "data";
}

#define REQUIRE_DATA(sub)                                                                                              \
  const fs::path data = sharedData() / (sub);                                                                          \
  if (!fs::exists(data))                                                                                               \
  GTEST_SKIP() << "sample data not found at " << data.string() << " (set EXABRICKS_DATA to the shared data folder)"

std::map<int, uint64_t> cellsPerLevel(const CellSet& s) {
  std::map<int, uint64_t> m;
  for (const Cell& c : s.cells)
    m[c.level]++;
  return m;
}

/// Writes a small plotfile: level 0 is one 4^3 box; level 1 (ratio 4) refines the coarse
/// cells [1,2]x[1,1]x[1,1] as one 8x4x4 box. Values are v = 100 * level + linear index.
struct Fixture {
  bool bigEndian = false;
  bool float32 = false;
  int ghost = 0;
  int dim = 3;
  int ratio = 4;
  int64_t nanAt = -1; ///< this level-0 cell's first field is NaN
  fs::path dir;

  static float value(int level, int64_t i) { return float(100 * level) + float(i); }

  void write() const {
    fs::remove_all(dir);
    fs::create_directories(dir / "Level_0");
    fs::create_directories(dir / "Level_1");
    std::ofstream h(dir / "Header");
    h << "HyperCLaw-V1.1\n2\nrho\ntemp\n" << dim << "\n0.5\n1\n-1 0 2\n3 4 6\n" << ratio << "\n";
    h << "((0,0,0) (3,3,3) (0,0,0)) ((0,0,0) (" << 4 * ratio - 1 << "," << 4 * ratio - 1 << "," << 4 * ratio - 1
      << ") (0,0,0))\n0 0\n1 1 1\n"
      << 1.0 / ratio << " " << 1.0 / ratio << " " << 1.0 / ratio << "\n0\n0\n";
    h << "0 1 0.5\n0\n-1 3\n0 4\n2 6\nLevel_0/Cell\n1 1 0.5\n0\n0 1\n1 2\n3 4\nLevel_1/Cell\n";
    writeLevel(0, {0, 0, 0}, {3, 3, 3});
    writeLevel(1, {ratio, ratio, ratio}, {3 * ratio - 1, 2 * ratio - 1, 2 * ratio - 1});
  }

  void writeLevel(int level, vec3i lo, vec3i hi) const {
    const fs::path l = dir / ("Level_" + std::to_string(level));
    std::ostringstream box;
    box << "((" << lo.x << "," << lo.y << "," << lo.z << ") (" << hi.x << "," << hi.y << "," << hi.z << ") (0,0,0))";
    std::ofstream ch(l / "Cell_H");
    ch << "1\n0\n2\n" << ghost << "\n(1 0\n" << box.str() << "\n)\n1\nFabOnDisk: Cell_D_00000 0\n";
    std::ofstream d(l / "Cell_D_00000", std::ios::binary);
    const vec3i g(ghost);
    const vec3i glo = lo - g, ghi = hi + g;
    const int bytes = float32 ? 4 : 8;
    d << "FAB ((8, (" << (float32 ? "32 8 23 0 1 9 0 127" : "64 11 52 0 1 12 0 1023") << ")),(" << bytes << ", (";
    for (int i = 0; i < bytes; ++i)
      d << (bigEndian ? i + 1 : bytes - i) << (i + 1 < bytes ? " " : "");
    d << ")))((" << glo.x << "," << glo.y << "," << glo.z << ") (" << ghi.x << "," << ghi.y << "," << ghi.z
      << ") (0,0,0)) 2\n";
    const vec3i n = ghi - glo + vec3i(1);
    for (int comp = 0; comp < 2; ++comp)
      for (int z = 0; z < n.z; ++z)
        for (int y = 0; y < n.y; ++y)
          for (int x = 0; x < n.x; ++x) {
            const bool inside =
                x >= ghost && y >= ghost && z >= ghost && x < n.x - ghost && y < n.y - ghost && z < n.z - ghost;
            const vec3i v = hi - lo + vec3i(1);
            const int64_t i = (int64_t(z - ghost) * v.y + (y - ghost)) * v.x + (x - ghost);
            double value = inside ? value1(level, i) + 1000.0 * comp : -7.0;
            if (inside && level == 0 && comp == 0 && i == nanAt) value = std::numeric_limits<double>::quiet_NaN();
            unsigned char b[8];
            if (float32) {
              const float f = float(value);
              std::memcpy(b, &f, 4);
            } else {
              std::memcpy(b, &value, 8);
            }
            if (bigEndian)
              for (int k = 0; k < bytes / 2; ++k)
                std::swap(b[k], b[bytes - 1 - k]);
            d.write(reinterpret_cast<const char*>(b), bytes);
          }
  }
  static double value1(int level, int64_t i) { return double(value(level, i)); }
};

std::string errorOf(const std::string& path) {
  try {
    loadModel(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

} // namespace

TEST(Amrex, SharedAdvectionSampleLeafCounts) {
  REQUIRE_DATA("amrex/advection_3d/plt_small");
  EXPECT_TRUE(isAmrexPlotfile(data.string()));
  EXPECT_EQ(listAmrexFields(data.string()), std::vector<std::string>{"phi"});
  const CellSet s = readAmrex(data.string());
  // Leaf counts given with the sample (AMReX levels 0..3 are exabricks levels 3..0).
  EXPECT_EQ(s.size(), 1036288u);
  const auto levels = cellsPerLevel(s);
  EXPECT_EQ(levels.at(3), 22528u);
  EXPECT_EQ(levels.at(2), 40960u);
  EXPECT_EQ(levels.at(1), 235520u);
  EXPECT_EQ(levels.at(0), 737280u);
  // phi lies in [0.99015, 1.99454] over all stored cells; the peak sits on the finest level.
  range1f r;
  for (float v : s.fields[0].values)
    r.extend(v);
  EXPECT_GE(r.lower, 0.99014f); // the published range is rounded to five digits
  EXPECT_LE(r.upper, 1.99455f);
  EXPECT_GT(r.upper, 1.99f);
  // The simulation's time and step, from the Header.
  EXPECT_TRUE(s.simulation.hasTime());
  EXPECT_TRUE(s.simulation.hasCycle());
  // Domain [0,1]^3 with 256 finest cells per axis.
  EXPECT_DOUBLE_EQ(s.world.scale.x, 1.0 / 256);
  EXPECT_DOUBLE_EQ(s.world.origin.x, 0.0);
}

TEST(Amrex, SharedPeleSamplePartialRefinement) {
  REQUIRE_DATA("amrex/pele_eb_3d/plt_eb_3d");
  const CellSet s = readAmrex(data.string(), {"density"});
  // Level 0: 64x32x16 cells; level 1 (64x64x32 fine cells) covers 16384 of them.
  EXPECT_EQ(s.size(), 64u * 32 * 16 - 16384 + 64 * 64 * 32);
  ASSERT_EQ(s.fields.size(), 1u);
  EXPECT_EQ(s.fields[0].name, "density");
}

TEST(Amrex, SharedPeleLmSampleValuesAtCellCentres) {
  REQUIRE_DATA("amrex/pelelm_3lev_3d/example_plt_3d");
  CellSet s = readAmrex(data.string(), {"temp"});
  EXPECT_EQ(s.size(), 32768u); // every leaf on the finest level
  const CellSet copy = s;
  const Model m = buildModel(std::move(s));
  // With one level everywhere, the basis method returns the stored value at a cell centre.
  std::mt19937 rng(1);
  for (int k = 0; k < 2000; ++k) {
    const size_t i = rng() % copy.size();
    const Cell& c = copy.cells[i];
    const vec3d centre = vec3d(c.lower) + vec3d(0.5 * c.width());
    double v;
    ASSERT_TRUE(sampleField(m.view(0), centre, v));
    EXPECT_NEAR(v, copy.fields[0].values[i], 1e-9 * std::abs(v));
  }
}

TEST(Amrex, NaNIsRefusedByNameOrKeptAsAHole) {
  Fixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-nan";
  f.nanAt = 5; // a coarse cell that no finer box covers
  f.write();
  EXPECT_NE(errorOf(f.dir.string()).find("Cell_D_00000"), std::string::npos) << errorOf(f.dir.string());
  LoadOptions o;
  o.nonFinite = NonFinite::Holes;
  const Model m = loadModel(f.dir.string(), o);
  EXPECT_EQ(m.cellCount(), 64u - 2 + 2 * 64 - 1); // the cell is a hole in both fields
  for (const auto& values : m.fieldValues)
    for (float v : values)
      EXPECT_TRUE(std::isfinite(v));
}

TEST(Amrex, FixtureBothPrecisionsByteOrdersAndGhostCells) {
  for (int variant = 0; variant < 4; ++variant) {
    Fixture f;
    f.dir = fs::path(EXABRICKS_TEST_TMP) / ("amrex-" + std::to_string(variant));
    f.bigEndian = variant & 1;
    f.float32 = variant & 2;
    f.ghost = variant == 3 ? 2 : 0;
    f.write();
    SCOPED_TRACE(variant);
    const CellSet s = readAmrex(f.dir.string());
    // 64 coarse cells, 2 of them refined by 4^3 each.
    ASSERT_EQ(s.size(), 64u - 2 + 2 * 64);
    ASSERT_EQ(s.fields.size(), 2u);
    EXPECT_EQ(s.world.scale, vec3d(0.25));
    EXPECT_EQ(s.world.origin, vec3d(-1, 0, 2));
    const auto levels = cellsPerLevel(s);
    EXPECT_EQ(levels.at(2), 62u); // ratio 4: the coarse cells are 4 finest cells wide
    EXPECT_EQ(levels.at(0), 128u);
    for (size_t i = 0; i < s.size(); ++i) {
      const Cell& c = s.cells[i];
      int64_t index;
      if (c.level == 2) {
        const vec3i q = c.lower / 4;
        index = (int64_t(q.z) * 4 + q.y) * 4 + q.x;
        EXPECT_FALSE(q.y == 1 && q.z == 1 && (q.x == 1 || q.x == 2)) << "covered cell kept";
        EXPECT_EQ(s.fields[0].values[i], Fixture::value(0, index));
      } else {
        const vec3i q = c.lower - vec3i(4);
        index = (int64_t(q.z) * 4 + q.y) * 8 + q.x;
        EXPECT_EQ(s.fields[0].values[i], Fixture::value(1, index));
      }
      EXPECT_EQ(s.fields[1].values[i], s.fields[0].values[i] + 1000.f);
    }
  }
}

TEST(Amrex, ABoxReadsOnlyTheCellsThatOverlapIt) {
  Fixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-box";
  f.write();
  const CellSet all = readAmrex(f.dir.string());
  for (const box3i& box : {box3i(vec3i(0), vec3i(4)), box3i(vec3i(5, 5, 5), vec3i(6, 6, 6)),
                           box3i(vec3i(-100), vec3i(100)), box3i(vec3i(100), vec3i(101))}) {
    CellSet cropped = all;
    cropCells(cropped, box);
    const CellSet part = readAmrex(f.dir.string(), {}, box);
    // The reader skips whole boxes; what it returns holds every overlapping cell.
    CellSet partCropped = part;
    cropCells(partCropped, box);
    EXPECT_EQ(partCropped.cells, cropped.cells);
    EXPECT_EQ(partCropped.fields[1].values, cropped.fields[1].values);
    // Through the registry the result is cropped exactly; no cell at all is an error.
    LoadOptions o;
    o.box = box;
    if (cropped.cells.empty())
      EXPECT_THROW(loadCells(f.dir.string(), o), Error);
    else
      EXPECT_EQ(loadCells(f.dir.string(), o).cells, cropped.cells);
  }
  // The box (0,0,0)-(4,4,4) lies in the coarse level only: the fine box's data is not read.
  const CellSet coarseOnly = readAmrex(f.dir.string(), {}, box3i(vec3i(0), vec3i(4)));
  for (const Cell& c : coarseOnly.cells)
    EXPECT_EQ(c.level, 2);
}

TEST(Amrex, TheCensusCountsTheLeafCellsFromTheHeadersAlone) {
  Fixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-census";
  f.write();
  const CellSet all = readAmrex(f.dir.string());
  const Census census = amrexCensus(f.dir.string());
  EXPECT_DOUBLE_EQ(census.cells(), double(all.size()));
  int coarsest = 0;
  for (const Cell& c : all.cells)
    coarsest = std::max(coarsest, c.level);
  EXPECT_EQ(census.coarsestLevel, coarsest);
  // Every leaf cell lies in a census box of its level's count.
  for (const Cell& c : all.cells) {
    bool in = false;
    for (const CensusBox& b : census.boxes)
      in = in || (c.lower.x >= b.box.lower.x && c.lower.x < b.box.upper.x && c.lower.y >= b.box.lower.y &&
                  c.lower.y < b.box.upper.y && c.lower.z >= b.box.lower.z && c.lower.z < b.box.upper.z);
    EXPECT_TRUE(in);
  }
}

TEST(Amrex, SharedSampleCensusMatchesTheLeafCount) {
  REQUIRE_DATA("amrex/advection_3d/plt_small");
  const Census census = loadCensus(data.string());
  EXPECT_DOUBLE_EQ(census.cells(), 1036288.0);
  EXPECT_EQ(census.coarsestLevel, 3);
}

TEST(Amrex, SharedSampleBuiltFromItsBoxesEqualsItsCells) {
  REQUIRE_DATA("amrex/advection_3d/plt_small");
  test::expectBoxBuildEqualsCells(data.string(), 3, 1036288u);
}

TEST(Amrex, TheRegistryNamesEveryFormatOnce) {
  std::vector<InputKind> kinds;
  for (const FormatReader& r : formatReaders()) {
    EXPECT_TRUE(std::find(kinds.begin(), kinds.end(), r.kind) == kinds.end()) << r.name;
    kinds.push_back(r.kind);
  }
  EXPECT_EQ(kinds.size(), 8u);
  Fixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-registry";
  f.write();
  const FormatReader* r = findReader(f.dir.string());
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->kind, InputKind::Amrex);
  EXPECT_EQ(r->listFields(f.dir.string()), listAmrexFields(f.dir.string()));
}

TEST(Amrex, BadPlotfilesAreRejectedClearly) {
  Fixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-bad";
  f.write();
  ASSERT_EQ(errorOf(f.dir.string()), "no error");

  fs::resize_file(f.dir / "Level_1" / "Cell_D_00000", 300);
  std::string m = errorOf(f.dir.string());
  EXPECT_NE(m.find("Cell_D_00000"), std::string::npos) << m;
  EXPECT_NE(m.find("truncated"), std::string::npos) << m;

  f.write();
  fs::remove(f.dir / "Level_1" / "Cell_D_00000");
  m = errorOf(f.dir.string());
  EXPECT_NE(m.find("cannot open"), std::string::npos) << m;

  f.write();
  fs::remove(f.dir / "Level_0" / "Cell_H");
  m = errorOf(f.dir.string());
  EXPECT_NE(m.find("Cell_H"), std::string::npos) << m;

  Fixture flat = f;
  flat.dim = 2;
  flat.write();
  m = errorOf(flat.dir.string());
  EXPECT_NE(m.find("2-D"), std::string::npos) << m;
  EXPECT_NE(m.find("Header"), std::string::npos) << m;

  Fixture three = f;
  three.ratio = 3;
  three.write();
  m = errorOf(three.dir.string());
  EXPECT_NE(m.find("power of two"), std::string::npos) << m;

  f.write();
  { std::ofstream(f.dir / "Header") << "HyperCLaw-V1.1\n2\nrho\n"; }
  m = errorOf(f.dir.string());
  EXPECT_NE(m.find("Header"), std::string::npos) << m;
  EXPECT_NE(m.find("end of file"), std::string::npos) << m;
  // An unknown header version is refused by name, not read as if it were V1.1.
  {
    Fixture v;
    v.dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-version";
    v.write();
    std::ifstream in(v.dir / "Header");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    text.replace(0, text.find('\n'), "HyperCLaw-V9.9");
    std::ofstream(v.dir / "Header") << text;
    const std::string e = errorOf(v.dir.string());
    EXPECT_NE(e.find("HyperCLaw-V9.9"), std::string::npos) << e;
    EXPECT_NE(e.find("not supported"), std::string::npos) << e;
  }
}

TEST(Amrex, FieldRangesFromMetadataHoldTheData) {
  for (const char* sub :
       {"amrex/advection_3d/plt_small", "amrex/advection_3d/plt_drop", "amrex/pelelm_3lev_3d/example_plt_3d"}) {
    const fs::path dir = sharedData() / sub;
    if (!fs::exists(dir)) continue;
    for (const std::string& name : listAmrexFields(dir.string())) {
      const std::optional<range1f> meta = fieldRangeFromMetadata(dir.string(), name);
      ASSERT_TRUE(meta.has_value()) << sub << " " << name;
      const CellSet cells = readAmrex(dir.string(), {name});
      range1f data;
      for (float v : cells.fields[0].values)
        data.extend(v);
      // The tables cover the boxes finer levels cover too (averages of the finer values), so the
      // range holds the leaves' range and, for these files, equals it to float precision.
      const float tol = 1e-6f * std::max(std::abs(data.lower), std::abs(data.upper)) + 1e-30f;
      EXPECT_LE(meta->lower, data.lower + tol) << sub << " " << name;
      EXPECT_GE(meta->upper, data.upper - tol) << sub << " " << name;
      EXPECT_NEAR(meta->lower, data.lower, 1e-3 * (data.upper - data.lower) + tol) << sub << " " << name;
      EXPECT_NEAR(meta->upper, data.upper, 1e-3 * (data.upper - data.lower) + tol) << sub << " " << name;
    }
  }
  EXPECT_FALSE(
      fieldRangeFromMetadata(sharedData().string() + "/amrex/advection_3d/plt_drop", "no-such-field").has_value());
}

TEST(AmrexWrite, GeneratedScenesReadBackLeafForLeafWithCoveredCellsTheMeanOfTheirChildren) {
  // Every scene without holes (level jumps, two block sizes) written piece by piece, in both precisions:
  // its leaves read back exactly (float64; float32 stores the same floats), and a coarse read
  // gives each covered cell the mean of the leaves under it.
  for (const char* name : {"blobs", "ramp", "cosmic"})
    for (const bool float32 : {false, true}) {
      SceneOptions so;
      so.name = name;
      so.targetCells = 30000;
      so.levels = 4;
      so.seed = 3;
      const SceneOptions resolved = resolveSceneSize(so);
      const CellSet truth = generateScene(resolved);
      const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / (std::string("written_") + name);
      std::unique_ptr<AmrexPlotfileWriter> writer;
      generateScenePieces(resolved, AmrexPlotfileWriter::kSlabCells, [&](CellSet& piece) {
        if (!writer) {
          std::vector<std::string> names;
          for (const Field& f : piece.fields)
            names.push_back(f.name);
          writer = std::make_unique<AmrexPlotfileWriter>(dir.string(), names, resolved.levels,
                                                         int64_t(sceneLatticeWidth(resolved)), float32);
        }
        writer->append(piece);
      });
      EXPECT_GT(writer->finish(), 1u);
      const CellSet back = loadCells(dir.string());
      ASSERT_EQ(back.size(), truth.size()) << name;
      std::map<std::tuple<int, int, int, int>, std::vector<float>> want;
      for (size_t i = 0; i < truth.size(); ++i) {
        const Cell& c = truth.cells[i];
        std::vector<float>& v = want[{c.lower.x, c.lower.y, c.lower.z, c.level}];
        for (const Field& f : truth.fields)
          v.push_back(f.values[i]);
      }
      for (size_t i = 0; i < back.size(); ++i) {
        const Cell& c = back.cells[i];
        const auto it = want.find({c.lower.x, c.lower.y, c.lower.z, c.level});
        ASSERT_NE(it, want.end()) << name;
        for (size_t f = 0; f < back.fields.size(); ++f)
          ASSERT_EQ(back.fields[f].values[i], it->second[f]) << name;
      }
      // Level 1 and coarser alone: a cell that covers finer leaves holds their mean (weighted by
      // volume: each child the mean of its own).
      LoadOptions coarse;
      coarse.finestLevel = 1;
      const CellSet top = loadCells(dir.string(), coarse);
      std::map<std::tuple<int, int, int>, std::pair<double, int>> children; // level-1 cell -> sum, count
      for (size_t i = 0; i < truth.size(); ++i)
        if (truth.cells[i].level == 0) {
          auto& s = children[{truth.cells[i].lower.x & ~1, truth.cells[i].lower.y & ~1, truth.cells[i].lower.z & ~1}];
          s.first += truth.fields[0].values[i];
          s.second += 1;
        }
      int checked = 0;
      for (size_t i = 0; i < top.size(); ++i) {
        const Cell& c = top.cells[i];
        if (c.level != 1) continue;
        const auto it = children.find({c.lower.x, c.lower.y, c.lower.z});
        if (it == children.end() || it->second.second != 8) continue;
        EXPECT_NEAR(top.fields[0].values[i], it->second.first / 8, 1e-5 * (1 + std::abs(it->second.first)));
        ++checked;
      }
      EXPECT_GT(checked, 0) << name;
    }
}

TEST(AmrexWrite, HolesAreRefusedLeavingNothingBehind) {
  // Holes (space without cells under a refined cell) have no place in a plotfile.
  SceneOptions so;
  so.name = "shells";
  so.targetCells = 30000;
  const SceneOptions resolved = resolveSceneSize(so);
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "written_shells";
  try {
    AmrexPlotfileWriter writer(dir.string(), {"scalar", "radius"}, resolved.levels,
                               int64_t(sceneLatticeWidth(resolved)), false);
    generateScenePieces(resolved, AmrexPlotfileWriter::kSlabCells, [&](CellSet& piece) { writer.append(piece); });
    writer.finish();
    ADD_FAILURE() << "holes were written";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("data with holes"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir));
  EXPECT_FALSE(fs::exists(dir.string() + ".partial"));
}
