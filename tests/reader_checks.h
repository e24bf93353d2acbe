// Checks shared by the readers of patch-based formats that work from their box lists: a read of
// the coarse levels alone against brute force, and a build from the boxes (whole, through a box
// and by parts with their halos) against the cells a read returns.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/load.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <tuple>

namespace exa::test {

/// A model's leaf cells with their values, sorted: (x, y, z, level, values of every field).
inline std::vector<std::vector<double>> cellsOf(const Model& m) {
  std::vector<std::vector<double>> out;
  for (const Brick& b : m.bricks)
    for (int z = 0; z < b.size.z; ++z)
      for (int y = 0; y < b.size.y; ++y)
        for (int x = 0; x < b.size.x; ++x) {
          const vec3i at = b.lower + vec3i(x, y, z) * b.cellWidth();
          std::vector<double> c{double(at.x), double(at.y), double(at.z), double(b.level)};
          const size_t slot = b.valueOffset + size_t((z * b.size.y + y) * b.size.x + x);
          for (const ValueArray& v : m.fieldValues)
            c.push_back(v[slot]);
          out.push_back(std::move(c));
        }
  std::sort(out.begin(), out.end());
  return out;
}

/// The same cells and values as building the cells a read returns (the cells' own build).
inline void expectSameCells(const Model& fromBoxes, CellSet&& cells) {
  const Model fromCells = buildModel(std::move(cells));
  EXPECT_EQ(fromBoxes.fieldNames, fromCells.fieldNames);
  EXPECT_EQ(fromBoxes.world.origin, fromCells.world.origin);
  EXPECT_EQ(fromBoxes.world.scale, fromCells.world.scale);
  EXPECT_TRUE(cellsOf(fromBoxes) == cellsOf(fromCells));
}

/// `path` built from its boxes (structure without values) holds exactly the `cells` leaves, with
/// the values, of the cells a read returns, whole and through a box; and each of more than
/// `minParts` parts of a k-d partition of its census (loadModelPart: the cells whose support
/// reaches the part and its halo) holds exactly the cells the cells' own rule keeps and, at random
/// points inside the part, the same values and gradients as the whole.
inline void expectBoxBuildEqualsCells(const std::string& path, int minParts, size_t cells) {
  const Model whole = loadModel(path);
  ASSERT_EQ(whole.cellCount(), cells);
  EXPECT_EQ(whole.stats.parts, 1);
  expectSameCells(whole, loadCells(path));
  const box3i cb = whole.cellBounds();
  {
    LoadOptions inBox;
    inBox.box = box3i(cb.lower, cb.lower + (cb.upper - cb.lower) / 2);
    expectSameCells(loadModel(path, inBox), loadCells(path, inBox));
  }
  const Census census = loadCensus(path);
  const KdPartition partition = KdPartition::balance(census, minParts + 1, int64_t(1) << census.coarsestLevel);
  ASSERT_GT(partition.parts(), minParts);
  std::mt19937 rng{3};
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int p = 0; p < partition.parts(); ++p) {
    const box3l part = partition.box(p);
    const std::optional<Model> m = loadModelPart(path, {}, part, census.coarsestLevel);
    ASSERT_TRUE(m) << "part " << p;
    CellSet kept = loadCells(path, {});
    keepSupportOf(kept, shadingReach(part, census.coarsestLevel));
    expectSameCells(*m, std::move(kept));
    for (int i = 0; i < 2000; ++i) {
      vec3d q;
      for (int k = 0; k < 3; ++k)
        q[k] = double(std::max<int64_t>(part.lower[k], cb.lower[k])) +
               u(rng) * double(std::min<int64_t>(part.upper[k], cb.upper[k]) -
                               std::max<int64_t>(part.lower[k], cb.lower[k]));
      double v0 = 0, v1 = 0;
      vec3d g0, g1;
      const bool h0 = whole.sampleWorld(0, whole.world.toWorld(q), v0, g0);
      const bool h1 = m->sampleWorld(0, m->world.toWorld(q), v1, g1);
      ASSERT_EQ(h0, h1);
      if (!h0) continue;
      EXPECT_NEAR(v0, v1, 1e-5 * (1.0 + std::abs(v0)));
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(g0[k], g1[k], 1e-4 * (1.0 + std::abs(g0[k])));
    }
  }
}

/// The cells `s` read with LoadOptions::finestLevel `finest` are exactly `expected` ((x, y, z,
/// level) -> the format's level), none finer than 2^finest, together the whole domain of `side`^3
/// finest cells, and field 1 holds `value`(cell centre in world units, the format's level).
inline void expectCoarseLeaves(const CellSet& s, const std::map<std::tuple<int, int, int, int>, int>& expected,
                               int finest, double side, const std::function<double(const vec3d&, int)>& value,
                               double tolerance) {
  ASSERT_EQ(s.size(), expected.size());
  double volume = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const Cell& c = s.cells[i];
    EXPECT_GE(c.level, finest);
    volume += std::pow(double(c.width()), 3);
    const auto it = expected.find({c.lower.x, c.lower.y, c.lower.z, c.level});
    ASSERT_NE(it, expected.end()) << c.lower.x << " " << c.lower.y << " " << c.lower.z << " level " << c.level;
    const vec3d centre = s.world.toWorld(vec3d(c.lower) + vec3d(0.5 * c.width()));
    EXPECT_NEAR(s.fields[1].values[i], value(centre, it->second), tolerance);
  }
  EXPECT_EQ(volume, side * side * side); // the whole domain, whichever levels
}

} // namespace exa::test
