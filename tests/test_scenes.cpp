#include "exabricks/amr/bricks.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <set>

using namespace exa;

TEST(Scenes, DeterministicAndValid) {
  for (const SceneInfo& info : sceneList()) {
    SCOPED_TRACE(info.name);
    const CellSet a = generateScene({info.name, 5000, 4, 4});
    CellSet b;
    {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
      b = generateScene({info.name, 5000, 4, 4});
    }
    EXPECT_EQ(a.cells, b.cells);
    ASSERT_EQ(a.fields.size(), b.fields.size());
    for (size_t f = 0; f < a.fields.size(); ++f)
      EXPECT_EQ(a.fields[f].values, b.fields[f].values);
    EXPECT_NO_THROW(validateCells(a, info.name));
    EXPECT_NO_THROW(buildBricks(a.cells)); // no overlaps
    const CellSet other = generateScene({info.name, 5000, 5, 4});
    EXPECT_TRUE(a.cells != other.cells || a.fields[0].values != other.fields[0].values) << "seed matters";
  }
}

TEST(Scenes, SizeFollowsTheRequest) {
  for (uint64_t n : {50ull, 20000ull, 300000ull}) {
    const CellSet s = generateScene({"blobs", n, 1, 4});
    const double slack = n < 1000 ? 10.0 : 2.0; // a handful of cells cannot follow every level
    EXPECT_GT(double(s.size()), double(n) / slack) << n;
    EXPECT_LT(double(s.size()), double(n) * slack) << n;
  }
  EXPECT_GE(generateScene({"ramp", 1, 1, 1}).size(), 1u);
}

TEST(Scenes, ShellsHaveHolesAndLevelJumpsOfMoreThanOne) {
  const CellSet s = generateScene({"shells", 300000, 1, 4});
  std::set<int> levels;
  for (const Cell& c : s.cells)
    levels.insert(c.level);
  EXPECT_TRUE(levels.count(0) && levels.count(3));
  EXPECT_FALSE(levels.count(2)) << "finest cells sit directly beside coarsest";
  // Holes: fewer cells' volume than the bounding box.
  const box3l b = s.bounds();
  double volume = 0;
  for (const Cell& c : s.cells)
    volume += std::pow(double(c.width()), 3);
  const vec3l e = b.size();
  EXPECT_LT(volume, 0.8 * double(e.x) * double(e.y) * double(e.z));
}

TEST(Scenes, BadOptionsAreRejected) {
  EXPECT_THROW(generateScene({"nope", 100, 1, 4}), Error);
  EXPECT_THROW(generateScene({"blobs", 0, 1, 4}), Error);
  EXPECT_THROW(generateScene({"blobs", 100, 1, 0}), Error);
}

TEST(Scenes, PiecesConcatenateToTheWholeScene) {
  for (const SceneInfo& info : sceneList()) {
    SCOPED_TRACE(info.name);
    const CellSet whole = generateScene({info.name, 20000, 2, 4});
    for (int slabs : {1, 3}) {
      CellSet joined;
      int pieces = 0;
      const uint64_t n = generateScenePieces({info.name, 20000, 2, 4}, slabs, [&](CellSet& piece) {
        ++pieces;
        joined.cells.insert(joined.cells.end(), piece.cells.begin(), piece.cells.end());
        joined.fields.resize(piece.fields.size());
        for (size_t f = 0; f < piece.fields.size(); ++f) {
          joined.fields[f].name = piece.fields[f].name;
          joined.fields[f].values.insert(joined.fields[f].values.end(), piece.fields[f].values.begin(),
                                         piece.fields[f].values.end());
        }
      });
      EXPECT_GT(pieces, 1);
      EXPECT_EQ(n, whole.cells.size());
      EXPECT_EQ(joined.cells, whole.cells);
      ASSERT_EQ(joined.fields.size(), whole.fields.size());
      for (size_t f = 0; f < whole.fields.size(); ++f) {
        EXPECT_EQ(joined.fields[f].name, whole.fields[f].name);
        EXPECT_EQ(joined.fields[f].values, whole.fields[f].values);
      }
    }
  }
}

TEST(Scenes, CosmicSpansDecadesWithCoarseVoidsAndFineHaloes) {
  const CellSet s = generateScene({"cosmic", 30000, 1, 4});
  ASSERT_EQ(s.fields.size(), 1u);
  EXPECT_EQ(s.fields[0].name, "density");
  float lo = 1e30f, hi = 0.f;
  double coarseMean = 0, fineMean = 0;
  size_t coarse = 0, fine = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const float v = s.fields[0].values[i];
    ASSERT_GT(v, 0.f);
    lo = std::min(lo, v), hi = std::max(hi, v);
    if (s.cells[i].level == 3) coarseMean += std::log10(v), ++coarse;
    if (s.cells[i].level == 0) fineMean += std::log10(v), ++fine;
  }
  EXPECT_GT(std::log10(hi / lo), 4.0) << "a cosmology-like density spans decades";
  ASSERT_GT(coarse, 0u);
  ASSERT_GT(fine, 0u);
  // Refinement follows overdensity: the finest cells are denser, by more than a decade on average.
  EXPECT_GT(fineMean / double(fine) - coarseMean / double(coarse), 1.0);
}
