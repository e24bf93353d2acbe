// A check shared by the readers that count their cells from metadata: a build in parts (each part
// read through its box) reconstructs what the whole build does.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/io/load.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

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

} // namespace exa::test
