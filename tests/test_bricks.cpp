#include "datasets.h"
#include "exabricks/amr/bricks.h"
#include "exabricks/core/error.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <map>

using namespace exa;
using namespace exa::test;

namespace {

void checkBricks(const CellSet& set, const BrickBuild& b, int maxWidth) {
  // Every value slot holds exactly one input cell, at the slot's position and level.
  ASSERT_EQ(b.cellOfSlot.size(), set.cells.size());
  std::vector<int> seen(set.cells.size(), 0);
  uint64_t next = 0;
  for (const Brick& brick : b.bricks) {
    EXPECT_EQ(brick.valueOffset, next) << "bricks tile the value array in order";
    next += brick.cellCount();
    EXPECT_GE(reduceMin(brick.size), 1);
    EXPECT_LE(reduceMax(brick.size), maxWidth);
    for (int z = 0; z < brick.size.z; ++z)
      for (int y = 0; y < brick.size.y; ++y)
        for (int x = 0; x < brick.size.x; ++x) {
          const size_t slot = brick.valueOffset + x + size_t(brick.size.x) * (y + size_t(brick.size.y) * z);
          const uint32_t cell = b.cellOfSlot[slot];
          ASSERT_LT(cell, set.cells.size());
          seen[cell]++;
          EXPECT_EQ(set.cells[cell].level, brick.level) << "bricks hold one level";
          EXPECT_EQ(set.cells[cell].lower, brick.lower + vec3i(x, y, z) * brick.cellWidth())
              << "brick is full and cells sit at their slots";
        }
  }
  EXPECT_EQ(next, set.cells.size());
  for (size_t i = 0; i < seen.size(); ++i)
    ASSERT_EQ(seen[i], 1) << "cell " << i;
  // Bricks are pairwise disjoint: sweep along x over bricks sorted by their lower x.
  std::vector<box3i> boxes;
  for (const Brick& brick : b.bricks)
    boxes.push_back(brick.bounds());
  std::sort(boxes.begin(), boxes.end(), [](const box3i& l, const box3i& r) { return l.lower.x < r.lower.x; });
  for (size_t i = 0; i < boxes.size(); ++i)
    for (size_t j = i + 1; j < boxes.size() && boxes[j].lower.x < boxes[i].upper.x; ++j) {
      const box3i overlap(max(boxes[i].lower, boxes[j].lower), min(boxes[i].upper, boxes[j].upper));
      if (!overlap.empty()) FAIL() << "two bricks overlap";
    }
  // Values reorder with the slots.
  const std::vector<float> ordered = toBrickOrder(set.fields[0].values, b.cellOfSlot);
  for (size_t s = 0; s < ordered.size(); ++s)
    ASSERT_EQ(ordered[s], set.fields[0].values[b.cellOfSlot[s]]);
}

} // namespace

TEST(Bricks, InvariantsOnAllDatasets) {
  for (const auto& d : smallDatasets()) {
    SCOPED_TRACE(d.name);
    for (int width : {32, 4, 1}) {
      const BrickBuild b = buildBricks(d.cells.cells, {width});
      checkBricks(d.cells, b, width);
    }
  }
}

TEST(Bricks, FullBoxIsOneBrick) {
  CellSet s;
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x)
        s.cells.push_back({vec3i(x, y, z) * 2 + vec3i(-8, 6, 2), 1});
  const BrickBuild b = buildBricks(s.cells);
  ASSERT_EQ(b.bricks.size(), 1u);
  EXPECT_EQ(b.bricks[0].size, vec3i(5, 3, 4));
  EXPECT_EQ(b.bricks[0].lower, vec3i(-8, 6, 2));
  // A width limit of 2 splits it into at least ceil(5/2) * ceil(3/2) * 2 bricks.
  EXPECT_GE(buildBricks(s.cells, {2}).bricks.size(), 12u);
}

TEST(Bricks, BlocksStayWholeAndFarApartCellsSplitQuickly) {
  // Four same-level blocks of 4 x 4 x 4 cells in a row along x, each 16 units wide: the splits
  // follow their faces (none is aligned to 32 or 64), so a limit of 8 cells per axis keeps two
  // blocks per brick and never cuts one.
  CellSet s;
  for (int block = 0; block < 4; ++block)
    for (int z = 0; z < 4; ++z)
      for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
          s.cells.push_back({vec3i(8 + 16 * block + 4 * x, 4 * y, 4 * z), 2});
  // A coarser layer beside them makes the node mixed, so the first split is a choice.
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 9; ++x)
        s.cells.push_back({vec3i(8 * x, 16 + 8 * y, 8 * z), 3});
  const BrickBuild b = buildBricks(s.cells, {8});
  int fine = 0;
  for (const Brick& brick : b.bricks)
    if (brick.level == 2) {
      ++fine;
      EXPECT_EQ((brick.lower.x - 8) % 16, 0) << "a block was cut";
      EXPECT_EQ(brick.size.x % 4, 0) << "a block was cut";
    }
  EXPECT_EQ(fine, 2);
  // Two cells 2^31 - 16 apart build without counters over the gap between them.
  CellSet far;
  far.cells = {{vec3i(-(1 << 30), 0, 0), 0}, {vec3i((1 << 30) - 16, 5, -7), 1}};
  EXPECT_EQ(buildBricks(far.cells).bricks.size(), 2u);
  // Brick widths stay within what model files hold and samplers index exactly.
  EXPECT_THROW(buildBricks(far.cells, {0}), Error);
  EXPECT_THROW(buildBricks(far.cells, {kMaxBrickWidth + 1}), Error);
  EXPECT_EQ(buildBricks(far.cells, {kMaxBrickWidth}).bricks.size(), 2u);
}

TEST(Bricks, DeterministicForAnyThreadCount) {
  const CellSet s = generateScene({"blobs", 20000, 3, 4});
  BrickBuild one, many;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = buildBricks(s.cells);
  }
  many = buildBricks(s.cells);
  ASSERT_EQ(one.bricks.size(), many.bricks.size());
  EXPECT_EQ(one.cellOfSlot, many.cellOfSlot);
  for (size_t i = 0; i < one.bricks.size(); ++i) {
    EXPECT_EQ(one.bricks[i].lower, many.bricks[i].lower);
    EXPECT_EQ(one.bricks[i].size, many.bricks[i].size);
  }
}

TEST(Bricks, OverlapsAndDuplicatesAreReported) {
  auto message = [](std::vector<Cell> cells) {
    try {
      buildBricks(cells);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // A coarse cell covering a fine one.
  {
    const std::string m = message({{vec3i(0, 0, 0), 0}, {vec3i(4, 4, 4), 2}, {vec3i(5, 6, 7), 0}});
    EXPECT_NE(m.find("overlap"), std::string::npos) << m;
    EXPECT_NE(m.find("cells 1"), std::string::npos) << m;
    EXPECT_NE(m.find(" 2 "), std::string::npos) << m;
  }
  {
    const std::string m = message({{vec3i(0, 0, 0), 1}, {vec3i(2, 0, 0), 1}, {vec3i(0, 0, 0), 1}});
    EXPECT_NE(m.find("duplicates"), std::string::npos) << m;
    EXPECT_NE(m.find("cells 0 and 2"), std::string::npos) << m;
  }
  {
    // Duplicates whose count equals the box volume must not pass as a full brick.
    const std::string m = message({{vec3i(0, 0, 0), 0}, {vec3i(0, 0, 0), 0}, {vec3i(2, 0, 0), 0}});
    EXPECT_NE(m.find("duplicates"), std::string::npos) << m;
  }
  {
    // Overlap deep inside a large valid dataset.
    CellSet s = generateScene({"blobs", 5000, 1, 3});
    s.cells.push_back(s.cells[1234]);
    const std::string m = message(s.cells);
    EXPECT_NE(m.find("duplicates"), std::string::npos) << m;
    EXPECT_NE(m.find("1234"), std::string::npos) << m;
  }
}

TEST(Bricks, ReorderingInPlaceEqualsIndexedBuild) {
  for (const auto& d : smallDatasets()) {
    SCOPED_TRACE(d.name);
    for (int width : {32, 3}) {
      const BrickBuild indexed = buildBricks(d.cells.cells, {width});
      std::vector<Cell> cells = d.cells.cells;
      std::vector<std::vector<float>> values;
      std::vector<std::vector<float>*> arrays;
      for (const Field& f : d.cells.fields)
        values.push_back(f.values);
      for (auto& v : values)
        arrays.push_back(&v);
      const std::vector<Brick> bricks = buildBricksReordering(cells, arrays, {width});
      ASSERT_EQ(bricks.size(), indexed.bricks.size());
      for (size_t i = 0; i < bricks.size(); ++i) {
        EXPECT_EQ(bricks[i].lower, indexed.bricks[i].lower);
        EXPECT_EQ(bricks[i].level, indexed.bricks[i].level);
        EXPECT_EQ(bricks[i].size, indexed.bricks[i].size);
        EXPECT_EQ(bricks[i].valueOffset, indexed.bricks[i].valueOffset);
      }
      for (size_t f = 0; f < values.size(); ++f)
        EXPECT_EQ(values[f], toBrickOrder(d.cells.fields[f].values, indexed.cellOfSlot)) << "field " << f;
    }
  }
}

TEST(Bricks, ReorderingConflictsAreLocatedInTheInput) {
  // Each case: the in-place build throws CellConflict; located in the input it reads exactly as
  // the indexed build's message.
  auto check = [](const std::vector<Cell>& input) {
    std::string indexed = "no error";
    try {
      buildBricks(input);
    } catch (const Error& e) {
      indexed = e.what();
    }
    std::vector<Cell> cells = input;
    std::vector<float> values(cells.size(), 1.0f);
    try {
      buildBricksReordering(cells, {&values});
      ADD_FAILURE() << "no conflict reported";
    } catch (const CellConflict& c) {
      EXPECT_EQ(locateConflict(c, input), indexed);
    }
  };
  check({{vec3i(0, 0, 0), 0}, {vec3i(4, 4, 4), 2}, {vec3i(5, 6, 7), 0}});
  check({{vec3i(0, 0, 0), 1}, {vec3i(2, 0, 0), 1}, {vec3i(0, 0, 0), 1}});
  check({{vec3i(0, 0, 0), 0}, {vec3i(0, 0, 0), 0}, {vec3i(2, 0, 0), 0}});
  CellSet s = generateScene({"blobs", 5000, 1, 3});
  s.cells.push_back(s.cells[1234]);
  check(s.cells);
  s.cells.back() = Cell{s.cells[77].lower, s.cells[77].level + 1};
  s.cells.back().lower = s.cells.back().lower / 2 * 2;
  check(s.cells);
}
