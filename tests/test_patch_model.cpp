// Structure without values: models built from patches (buildModelOfPatches) against the cells the
// same patches give (cellsFromGrids and the cells' own brick build), on random nested hierarchies,
// whole and under each rule of which cells to keep; and the errors of patches whose leaves overlap.
#include "exabricks/amr/partition.h"
#include "exabricks/core/error.h"
#include "exabricks/io/grids.h"
#include "exabricks/io/load.h"
#include "exabricks/io/patch_source.h"

#include "reader_checks.h"

#include <gtest/gtest.h>

#include <array>
#include <map>
#include <random>

using namespace exa;

namespace {

/// A box of `cells` cells of width `width` at `lower` (finest lattice units).
struct Box {
  vec3l lower, cells;
  int64_t width;
  vec3l upper() const { return lower + cells * width; }
};

bool overlap(const Box& a, const Box& b) {
  for (int k = 0; k < 3; ++k)
    if (!(a.lower[k] < b.upper()[k] && b.lower[k] < a.upper()[k])) return false;
  return true;
}

/// A random properly nested hierarchy on a 32^3 lattice: two grids of width 4, disjoint grids of
/// width 2 on whole cells of width 4, and grids of width 1 each inside one grid of width 2.
std::vector<Box> randomHierarchy(std::mt19937& rng) {
  std::vector<Box> boxes{{vec3l(0), vec3l(4, 8, 8), 4}, {vec3l(16, 0, 0), vec3l(4, 8, 8), 4}};
  auto pick = [&](int64_t lo, int64_t hi) { return std::uniform_int_distribution<int64_t>(lo, hi)(rng); };
  std::vector<Box> medium;
  for (int t = 0; t < 8; ++t) {
    Box b{vec3l(0), vec3l(0), 2};
    for (int k = 0; k < 3; ++k) {
      b.lower[k] = 4 * pick(0, 6);
      b.cells[k] = 2 * pick(1, std::min<int64_t>(4, (32 - b.lower[k]) / 4));
    }
    if (std::none_of(medium.begin(), medium.end(), [&](const Box& m) { return overlap(m, b); })) medium.push_back(b);
  }
  boxes.insert(boxes.end(), medium.begin(), medium.end());
  std::vector<Box> fine;
  for (int t = 0; t < 8 && !medium.empty(); ++t) {
    const Box& m = medium[size_t(pick(0, int64_t(medium.size()) - 1))];
    Box b{vec3l(0), vec3l(0), 1};
    for (int k = 0; k < 3; ++k) {
      const int64_t slots = m.cells[k]; // cells of width 2 along the axis
      const int64_t first = pick(0, slots - 1);
      b.lower[k] = m.lower[k] + 2 * first;
      b.cells[k] = 2 * pick(1, slots - first);
    }
    if (std::none_of(fine.begin(), fine.end(), [&](const Box& f) { return overlap(f, b); })) fine.push_back(b);
  }
  boxes.insert(boxes.end(), fine.begin(), fine.end());
  return boxes;
}

/// The boxes as grids in world units (0.5 per finest cell, origin -3) with two random fields.
std::vector<GridPatch> gridsOf(const std::vector<Box>& boxes, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<GridPatch> grids;
  for (const Box& b : boxes) {
    GridPatch g;
    g.lower = vec3d(b.lower) * 0.5 - vec3d(3.0);
    g.upper = vec3d(b.upper()) * 0.5 - vec3d(3.0);
    g.cells = b.cells;
    g.values.resize(2);
    for (auto& v : g.values)
      for (int64_t i = 0; i < b.cells.x * b.cells.y * b.cells.z; ++i)
        v.push_back(u(rng));
    grids.push_back(std::move(g));
  }
  return grids;
}

const std::vector<std::string> kNames{"a", "b"};
const vec3d kOrigin(-3.0);

Model fromBoxes(const std::vector<GridPatch>& grids, const PatchKeep& keep = {}, int maxBrickWidth = 32) {
  BuildOptions o;
  o.bricks.maxBrickWidth = maxBrickWidth;
  return buildModelOfPatches(patchesOfGrids(grids, kNames, "grids", &kOrigin), keep, o);
}

std::string errorOf(const std::vector<GridPatch>& grids) {
  try {
    fromBoxes(grids);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

} // namespace

TEST(PatchModel, RandomHierarchiesHoldTheCellsOfTheirReadWholeAndUnderEveryRule) {
  std::mt19937 rng{11};
  for (int trial = 0; trial < 25; ++trial) {
    const std::vector<GridPatch> grids = gridsOf(randomHierarchy(rng), rng);
    const int width = trial % 3 == 0 ? 3 : 32; // bricks cut finer than the boxes, or not
    const Model whole = fromBoxes(grids, {}, width);
    for (const Brick& b : whole.bricks)
      EXPECT_TRUE(b.size.x <= width && b.size.y <= width && b.size.z <= width);
    test::expectSameCells(whole, cellsFromGrids(grids, kNames, "grids", &kOrigin));
    EXPECT_EQ(whole.world.scale, vec3d(0.5));
    // A box (the cells that overlap it) and a part's reach (the cells whose support reaches it).
    auto pick = [&] { return std::uniform_int_distribution<int64_t>(-4, 36)(rng); };
    box3l box(vec3l(pick(), pick(), pick()), vec3l(0));
    box.upper = box.lower + vec3l(1 + pick() % 12 + 4);
    const box3i ibox(vec3i(box.lower), vec3i(box.upper));
    for (const PatchKeep::Rule rule : {PatchKeep::Rule::Overlapping, PatchKeep::Rule::Reaching}) {
      CellSet cells = cellsFromGrids(grids, kNames, "grids", &kOrigin);
      if (rule == PatchKeep::Rule::Overlapping)
        cropCells(cells, ibox);
      else
        keepSupportOf(cells, box);
      const Model kept = fromBoxes(grids, {rule, box}, width);
      if (cells.cells.empty()) {
        EXPECT_TRUE(kept.bricks.empty());
        continue;
      }
      test::expectSameCells(kept, std::move(cells));
    }
  }
}

TEST(PatchModel, GridsHeldElsewhereCoverButGiveNoCells) {
  std::mt19937 rng{5};
  const std::vector<Box> boxes{
      {vec3l(0), vec3l(4, 8, 8), 4}, {vec3l(16, 0, 0), vec3l(4, 8, 8), 4}, {vec3l(4), vec3l(4), 2}};
  std::vector<GridPatch> grids = gridsOf(boxes, rng);
  grids[2].elsewhere = true;
  grids[2].values.clear();
  const Model m = fromBoxes(grids);
  EXPECT_EQ(m.cellCount(), 2u * 4 * 8 * 8 - 8); // the width-2 grid covers 2^3 cells of width 4
  for (const Brick& b : m.bricks)               // the lattice is the finest grid's, held elsewhere or not
    EXPECT_EQ(b.level, 1);
  test::expectSameCells(m, cellsFromGrids(grids, kNames, "grids", &kOrigin));
}

TEST(PatchModel, LeavesThatOverlapAreRefusedNamingBothBoxes) {
  std::mt19937 rng{7};
  // Two boxes of one width that overlap.
  std::string e =
      errorOf(gridsOf({{vec3l(0), vec3l(8), 4}, {vec3l(8, 8, 8), vec3l(4), 2}, {vec3l(12, 8, 8), vec3l(4), 2}}, rng));
  EXPECT_NE(e.find("grids: grid 1 and grids: grid 2 hold cells that overlap"), std::string::npos) << e;
  // A box of width 1 on cells of width 4 with no box of width 2 between: not nested.
  std::vector<Box> skipping{{vec3l(0), vec3l(8), 4}, {vec3l(0), vec3l(2), 2}, {vec3l(16), vec3l(4), 1}};
  e = errorOf(gridsOf(skipping, rng));
  EXPECT_NE(e.find("grids: grid 0 and grids: grid 2 hold cells that overlap"), std::string::npos) << e;
  // A finer box that cuts a coarser cell.
  e = errorOf(gridsOf({{vec3l(0), vec3l(8), 4}, {vec3l(2), vec3l(2), 2}}, rng));
  EXPECT_NE(e.find("covers only part of a cell"), std::string::npos) << e;
}

TEST(PatchModel, ValuesThatAreNotFloat32AreRefusedNamingTheGridAndTheValue) {
  std::mt19937 rng{9};
  std::vector<GridPatch> grids = gridsOf({{vec3l(0), vec3l(4), 4}}, rng);
  grids[0].values[1][5] = std::nan("");
  const std::string e = errorOf(grids);
  EXPECT_NE(e.find("grids: grid 0: field 'b' value 5 is NaN"), std::string::npos) << e;
}

TEST(PatchModel, MergedCellsHoldTheMeanOfTheCellsTheyMerge) {
  // One level of three boxes, two of them aligned to blocks of 4 cells and one to blocks of 2:
  // merged by 2, each merged cell (two lattice units wide, at a corner on the blocks' lattice)
  // holds the mean of the 8 cells it covers, field by field.
  std::mt19937 rng{11};
  const std::vector<Box> boxes{
      {vec3l(0), vec3l(8, 4, 4), 1}, {vec3l(8, 0, 0), vec3l(4, 4, 8), 1}, {vec3l(0, 6, 0), vec3l(2, 2, 2), 1}};
  const std::vector<GridPatch> grids = gridsOf(boxes, rng);
  const PatchSource source = patchesOfGrids(grids, kNames, "grids", &kOrigin);
  EXPECT_EQ(alignedMerge(source.patches, 8), 2);
  EXPECT_EQ(alignedMerge({source.patches[0], source.patches[1]}, 8), 4);
  const Model whole = buildModelOfPatches(source);
  std::map<std::array<int64_t, 3>, std::vector<double>> sums; // per merged corner: the fields' sums
  for (const std::vector<double>& c : test::cellsOf(whole)) {
    std::vector<double>& s = sums[{int64_t(c[0]) / 2 * 2, int64_t(c[1]) / 2 * 2, int64_t(c[2]) / 2 * 2}];
    s.resize(c.size() - 4, 0.0);
    for (size_t f = 4; f < c.size(); ++f)
      s[f - 4] += c[f];
  }
  const Model merged = buildModelOfPatches(mergedPatches(source, 2));
  EXPECT_EQ(merged.fieldNames, whole.fieldNames);
  EXPECT_EQ(merged.world.scale, whole.world.scale);
  const std::vector<std::vector<double>> cells = test::cellsOf(merged);
  ASSERT_EQ(cells.size(), sums.size());
  ASSERT_EQ(whole.cellCount(), 8 * sums.size());
  for (const std::vector<double>& c : cells) {
    EXPECT_EQ(c[3], 1.0); // cells two lattice units wide
    const std::vector<double>& s = sums.at({int64_t(c[0]), int64_t(c[1]), int64_t(c[2])});
    for (size_t f = 4; f < c.size(); ++f)
      EXPECT_NEAR(c[f], s[f - 4] / 8, 1e-6);
  }
  // A merge the boxes are not aligned to is refused.
  EXPECT_THROW(mergedPatches(source, 4), Error);
}
