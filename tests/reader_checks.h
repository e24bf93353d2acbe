// Checks shared by the readers of patch-based formats that work from their box lists: a read of
// the coarse levels alone against brute force, and a build in parts (each part read through its
// box) against the whole build.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/io/load.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <tuple>

namespace exa::test {

/// Builds `path` whole and in parts of about `partCells` cells: more than `minParts` parts, every
/// one of the `cells` leaves, and at random points the same values and gradients as the whole.
inline void expectPartsEqualWhole(const std::string& path, uint64_t partCells, int minParts, size_t cells) {
  LoadOptions whole, inParts;
  whole.partCells = 0;
  inParts.partCells = partCells;
  const Model a = loadModel(path, whole), b = loadModel(path, inParts);
  EXPECT_EQ(a.stats.parts, 1);
  EXPECT_GT(b.stats.parts, minParts);
  ASSERT_EQ(b.cellCount(), cells);
  EXPECT_DOUBLE_EQ(b.world.scale.x, a.world.scale.x);
  EXPECT_EQ(b.simulation.cycle, a.simulation.cycle);
  const box3i cb = a.cellBounds();
  std::mt19937 rng{3};
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 5000; ++i) {
    vec3d q;
    for (int k = 0; k < 3; ++k)
      q[k] = double(cb.lower[k]) + u(rng) * double(cb.upper[k] - cb.lower[k]);
    double v0 = 0, v1 = 0;
    vec3d g0, g1;
    const bool h0 = a.sampleWorld(0, a.world.toWorld(q), v0, g0);
    const bool h1 = b.sampleWorld(0, b.world.toWorld(q), v1, g1);
    ASSERT_EQ(h0, h1);
    if (!h0) continue;
    EXPECT_NEAR(v0, v1, 1e-5 * (1.0 + std::abs(v0)));
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(g0[k], g1[k], 1e-4 * (1.0 + std::abs(g0[k])));
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
