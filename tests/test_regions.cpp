#include "datasets.h"
#include "exabricks/amr/model.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <random>

using namespace exa;
using namespace exa::test;

namespace {

/// Support of a brick in half lattice units, open box.
box3l supportOf(const Brick& b) {
  const int64_t w = b.cellWidth();
  return {vec3l(b.lower) * int64_t(2) - vec3l(w), (vec3l(b.lower) + vec3l(b.size) * w) * int64_t(2) + vec3l(w)};
}

bool overlapsOpen(const box3l& a, const box3l& b) {
  for (int ax = 0; ax < 3; ++ax)
    if (!(a.lower[ax] < b.upper[ax] && b.lower[ax] < a.upper[ax])) return false;
  return true;
}

box3l halfBox(const Region& r) { return {vec3l(r.halfBounds.lower), vec3l(r.halfBounds.upper)}; }

void checkRegions(const CellSet& cells, const Model& m) {
  const auto& regions = m.regions.regions;
  ASSERT_FALSE(regions.empty());
  // Pairwise disjoint interiors.
  for (size_t i = 0; i < regions.size(); ++i) {
    const box3l a = halfBox(regions[i]);
    ASSERT_FALSE(a.empty()) << "region " << i << " has no volume";
    for (size_t j = i + 1; j < regions.size(); ++j)
      ASSERT_FALSE(overlapsOpen(a, halfBox(regions[j]))) << "regions " << i << " and " << j;
  }
  // Each region's brick list is exactly the set of bricks whose support overlaps it; its
  // finest width and value ranges match a brute-force pass over the cells.
  for (size_t i = 0; i < regions.size(); ++i) {
    const Region& r = regions[i];
    const box3l rb = halfBox(r);
    std::vector<uint32_t> expected;
    int finest = 1000;
    for (uint32_t b = 0; b < m.bricks.size(); ++b)
      if (overlapsOpen(supportOf(m.bricks[b]), rb)) {
        expected.push_back(b);
        finest = std::min(finest, m.bricks[b].level);
      }
    const std::vector<uint32_t> got(m.regions.brickIds.begin() + r.brickBegin,
                                    m.regions.brickIds.begin() + r.brickBegin + r.brickCount);
    ASSERT_EQ(got, expected) << "region " << i;
    EXPECT_EQ(r.finestLevel, finest);
    for (size_t f = 0; f < cells.fields.size(); ++f) {
      range1f truth;
      for (size_t c = 0; c < cells.cells.size(); ++c) {
        const Cell& cell = cells.cells[c];
        const int64_t w = cell.width();
        const box3l support(vec3l(cell.lower) * int64_t(2) - vec3l(w), vec3l(cell.lower) * int64_t(2) + vec3l(3 * w));
        if (overlapsOpen(support, rb)) truth.extend(cells.fields[f].values[c]);
      }
      ASSERT_EQ(m.regions.valueRanges[f][i], truth) << "region " << i << " field " << f;
    }
  }
}

/// Volume of the union of brick supports, by coordinate compression (half units, cubed).
double supportUnionVolume(const std::vector<Brick>& bricks) {
  std::vector<int64_t> coords[3];
  for (const Brick& b : bricks) {
    const box3l s = supportOf(b);
    for (int a = 0; a < 3; ++a) {
      coords[a].push_back(s.lower[a]);
      coords[a].push_back(s.upper[a]);
    }
  }
  for (auto& c : coords) {
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
  }
  double volume = 0;
  for (size_t z = 0; z + 1 < coords[2].size(); ++z)
    for (size_t y = 0; y + 1 < coords[1].size(); ++y)
      for (size_t x = 0; x + 1 < coords[0].size(); ++x) {
        const vec3l lo(coords[0][x], coords[1][y], coords[2][z]);
        const vec3l hi(coords[0][x + 1], coords[1][y + 1], coords[2][z + 1]);
        for (const Brick& b : bricks)
          if (overlapsOpen(supportOf(b), box3l(lo, hi))) {
            const vec3l s = hi - lo;
            volume += double(s.x) * double(s.y) * double(s.z);
            break;
          }
      }
  return volume;
}

} // namespace

TEST(Regions, InvariantsOnAllDatasets) {
  for (const auto& d : smallDatasets()) {
    SCOPED_TRACE(d.name);
    CellSet copy = d.cells;
    const Model m = buildModel(std::move(copy));
    checkRegions(d.cells, m);
  }
}

TEST(Regions, UnionOfRegionsIsUnionOfSupports) {
  for (const auto& d : smallDatasets()) {
    if (d.cells.size() > 1000) continue; // the compressed grid grows with the cube of bricks
    SCOPED_TRACE(d.name);
    CellSet copy = d.cells;
    const Model m = buildModel(std::move(copy));
    double regionVolume = 0;
    for (const Region& r : m.regions.regions) {
      const vec3l s = halfBox(r).size();
      regionVolume += double(s.x) * double(s.y) * double(s.z);
    }
    EXPECT_DOUBLE_EQ(regionVolume, supportUnionVolume(m.bricks));
  }
}

TEST(Regions, KdTreeLocatesTheRegionHoldingAPoint) {
  for (const auto& d : smallDatasets()) {
    SCOPED_TRACE(d.name);
    CellSet copy = d.cells;
    const Model m = buildModel(std::move(copy));
    const FieldView view = m.view(0);
    std::mt19937 rng(42);
    const box3f b = m.regions.bounds;
    for (int i = 0; i < 3000; ++i) {
      vec3d p;
      for (int a = 0; a < 3; ++a)
        p[a] = std::uniform_real_distribution<double>(b.lower[a] - 1, b.upper[a] + 1)(rng);
      const uint32_t r = locateRegion(view, p);
      // Brute force: the regions whose closed box holds p.
      bool inAny = false;
      for (size_t k = 0; k < m.regions.regions.size(); ++k) {
        const box3f rb = m.regions.regions[k].bounds();
        bool in = true;
        for (int a = 0; a < 3; ++a)
          in = in && p[a] >= rb.lower[a] && p[a] <= rb.upper[a];
        inAny = inAny || in;
      }
      if (r == kNoRegion) {
        EXPECT_FALSE(inAny) << "point in a region was not located";
      } else {
        const box3f rb = m.regions.regions[r].bounds();
        for (int a = 0; a < 3; ++a) {
          EXPECT_GE(p[a], rb.lower[a]);
          EXPECT_LE(p[a], rb.upper[a]);
        }
      }
    }
  }
}

TEST(Regions, DeterministicForAnyThreadCount) {
  CellSet a = generateScene({"shells", 30000, 9, 4});
  CellSet b = a;
  Model one;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = buildModel(std::move(a));
  }
  const Model many = buildModel(std::move(b));
  ASSERT_EQ(one.regions.regions.size(), many.regions.regions.size());
  EXPECT_EQ(one.regions.brickIds, many.regions.brickIds);
  for (size_t i = 0; i < one.regions.regions.size(); ++i)
    EXPECT_EQ(one.regions.regions[i].halfBounds, many.regions.regions[i].halfBounds);
  ASSERT_EQ(one.regions.nodes.size(), many.regions.nodes.size());
  for (size_t i = 0; i < one.regions.nodes.size(); ++i) {
    EXPECT_EQ(one.regions.nodes[i].index, many.regions.nodes[i].index);
    EXPECT_EQ(one.regions.nodes[i].pos, many.regions.nodes[i].pos);
  }
}

namespace {

/// Whether the open support of `brick` contains the closed half-unit box `b` entirely.
bool supportCovers(const Brick& brick, const box3l& b) {
  const box3l s = supportOf(brick);
  for (int a = 0; a < 3; ++a)
    if (!(s.lower[a] <= b.lower[a] && b.upper[a] <= s.upper[a])) return false;
  return true;
}

Model buildWithSegmentCost(const CellSet& cells, double segmentCost) {
  CellSet copy = cells;
  BuildOptions o;
  o.bricks.maxBrickWidth = 4; // many same-level bricks, so many thin overlap slabs
  o.regions.segmentCost = segmentCost;
  return buildModel(std::move(copy), o);
}

} // namespace

namespace {

void checkMergedRegions(const CellSet& cells) {
  const Model exact = buildWithSegmentCost(cells, 0.0);
  for (const Region& r : exact.regions.regions)
    for (uint32_t k = 0; k < r.brickCount; ++k)
      ASSERT_TRUE(supportCovers(exact.bricks[exact.regions.brickIds[r.brickBegin + k]], halfBox(r)));
  for (double cost : {RegionBuildOptions().segmentCost, 1e12}) {
    SCOPED_TRACE(cost);
    const Model merged = buildWithSegmentCost(cells, cost);
    checkRegions(cells, merged);
    ASSERT_EQ(merged.bricks.size(), exact.bricks.size());
    EXPECT_LT(merged.regions.regions.size(), exact.regions.regions.size() * 3 / 4);
    const FieldView ev = exact.view(0), mv = merged.view(0);
    for (const Region& r : exact.regions.regions) {
      const box3f b = r.bounds();
      const uint32_t m = locateRegion(mv, (b.lower + b.upper) * 0.5f);
      ASSERT_NE(m, kNoRegion);
      const Region& into = merged.regions.regions[m];
      const box3l mb = halfBox(into), eb = halfBox(r);
      for (int a = 0; a < 3; ++a)
        ASSERT_TRUE(mb.lower[a] <= eb.lower[a] && eb.upper[a] <= mb.upper[a]);
      EXPECT_EQ(into.finestLevel, r.finestLevel);
      const auto* ids = merged.regions.brickIds.data() + into.brickBegin;
      for (uint32_t k = 0; k < r.brickCount; ++k)
        EXPECT_TRUE(std::binary_search(ids, ids + into.brickCount, exact.regions.brickIds[r.brickBegin + k]));
    }
    // Random points, and points on the half-unit lattice (support faces, cell centres).
    std::mt19937 rng(7);
    const box3f bb = exact.regions.bounds;
    for (int i = 0; i < 20000; ++i) {
      vec3f p;
      for (int a = 0; a < 3; ++a) {
        p[a] = std::uniform_real_distribution<float>(bb.lower[a], bb.upper[a])(rng);
        if (i % 2) p[a] = std::round(p[a] * 2.f) * 0.5f;
      }
      float ve = 0.f, vm = 0.f;
      vec3f ge(0.f), gm(0.f);
      const bool fe = sampleField(ev, p, ve, &ge), fm = sampleField(mv, p, vm, &gm);
      ASSERT_EQ(fe, fm) << p.x << " " << p.y << " " << p.z;
      if (!fe) continue;
      ASSERT_EQ(ve, vm) << p.x << " " << p.y << " " << p.z;
      ASSERT_TRUE(ge == gm) << p.x << " " << p.y << " " << p.z;
    }
  }
}

} // namespace

// With a segment cost of 0 every region is one set of bricks, each covering all of it (the
// paper's partition). With a cost, regions of one finest level merge: every exact region lies in
// one merged region of its level that lists its bricks, and reconstruction is bit for bit the
// same, since bricks that do not reach a point add nothing to its sums.
TEST(Regions, MergedRegionsUniteRegionsOfOneLevelAndReconstructTheSame) {
  // Cells of width 2 fill [0, 16)^3 but for a hole [4, 12)^3 of cells of width 1 (eight bricks
  // of 4^3): no empty space between the levels' supports.
  std::vector<std::pair<Cell, float>> blocks;
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        const bool hole = x >= 4 && x < 12 && y >= 4 && y < 12 && z >= 4 && z < 12;
        if (hole)
          blocks.push_back({{vec3i(x, y, z), 0}, float(x * x + y - z)});
        else if (x % 2 == 0 && y % 2 == 0 && z % 2 == 0)
          blocks.push_back({{vec3i(x, y, z), 1}, float(y * z - x)});
      }
  const std::vector<NamedCells> sets = {{"shells", generateScene({"shells", 30000, 9, 4})},
                                        {"two levels", makeCells(blocks)}};
  for (const NamedCells& set : sets) {
    SCOPED_TRACE(set.name);
    checkMergedRegions(set.cells);
  }
}
