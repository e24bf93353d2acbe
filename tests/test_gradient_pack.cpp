// Smooth shading's packed gradient fields: a cell's gradient in 32 bits (gradient_pack.h) keeps
// its components within 1/255 of its largest above its brick's base, the packed fields equal the
// float fields to that bound, and the vectorised reconstruction of a value with its packed
// gradient equals the scalar reference.
#include "datasets.h"

#include "exabricks/amr/basis_batch.h"
#include "exabricks/amr/gradient_pack.h"
#include "exabricks/amr/gradients.h"
#include "exabricks/amr/model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace exa {
namespace {

float largest(const vec3f& g) { return std::max(std::abs(g.x), std::max(std::abs(g.y), std::abs(g.z))); }

/// The model's first field's packed gradient fields, built in every brick.
GradientFields packedEverywhere(const Model& m) {
  GradientFields fields;
  fields.reset(m.fieldValues[0].data(), m.fieldValues[0].size(), m.bricks.size());
  std::vector<uint32_t> all(m.bricks.size());
  for (size_t b = 0; b < all.size(); ++b)
    all[b] = uint32_t(b);
  fillPackedGradients(m.view(0), m.bricks, m.regions.regions.size(), all, fields);
  return fields;
}

TEST(GradientPack, KeepsEightBitsOfTheLargestComponentOverEveryMagnitude) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::uniform_int_distribution<int> octave(-90, 120);
  for (int trial = 0; trial < 100000; ++trial) {
    vec3f g(u(rng), u(rng), u(rng));
    g = g * std::ldexp(1.f, octave(rng));
    if (trial % 5 == 0) g[trial % 3] = 0.f;
    const int base = gradientBase(packedGradientExponent(g));
    const vec3f back = unpackGradient(packGradient(g, base), gradientScaleBias(base));
    const float m = largest(g);
    // Within half a unit of the cell's exponent (and the word's conversion to a float).
    const float halfUnit = std::ldexp(0.5f, packedGradientExponent(g)) * (1.f + 0x1p-14f);
    for (int a = 0; a < 3; ++a) {
      ASSERT_LE(std::abs(back[a] - g[a]), m / 255.f) << "trial " << trial << " axis " << a;
      ASSERT_LE(std::abs(back[a] - g[a]), halfUnit) << "trial " << trial << " axis " << a;
    }
    ASSERT_LE(std::abs(largest(back) - m), m / 255.f);
  }
}

TEST(GradientPack, ExponentIsTheLargestComponentsRoundedToEightBitsDownToSubnormals) {
  // Independent of the packer's bit reading: the exponent E with the largest component rounding
  // to [128, 255] 2^E, found by the library's ldexp, for every binade of float.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(1.f, 2.f);
  for (int e = -149; e <= 127; ++e)
    for (int trial = 0; trial < 40; ++trial) {
      const float m = trial == 0 ? std::ldexp(1.f, e) : std::ldexp(trial == 1 ? 2.f - 0x1p-23f : u(rng), e);
      if (!(m > 0.f) || !std::isfinite(m)) continue;
      // The smallest E that keeps the rounded component within 255 units (its 8 bits).
      int expected = 200;
      while (std::nearbyint(std::ldexp(double(m), -(expected - 1))) <= 255.)
        --expected;
      ASSERT_GE(std::nearbyint(std::ldexp(double(m), -expected)), 128.) << m;
      ASSERT_EQ(packedGradientExponent(vec3f(0.25f * m, -m, 0.f)), expected) << m;
      EXPECT_EQ(exactPowerOfTwo(e), std::ldexp(1.0, e));
    }
}

TEST(GradientPack, ZeroNonFiniteAndRoundingToTheNextExponent) {
  const int base = gradientBase(0);
  EXPECT_EQ(unpackGradient(packGradient(vec3f(0.f), base), gradientScaleBias(base)), vec3f(0.f));
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const vec3f odd(inf, 2.f, nan);
  const int oddBase = gradientBase(packedGradientExponent(odd));
  const vec3f oddBack = unpackGradient(packGradient(odd, oddBase), gradientScaleBias(oddBase));
  const vec3f oddWant(0.f, 2.f, 0.f);
  for (int a = 0; a < 3; ++a) // units of 2^-6
    EXPECT_LE(std::abs(oddBack[a] - oddWant[a]), 0x1p-7f) << a;
  // 255.75 rounds to 256, which needs the next exponent (units of 2): the sign kept, every
  // component within half a unit.
  const vec3f edge(-255.75f, 1.f, 0.5f);
  const int edgeBase = gradientBase(packedGradientExponent(edge));
  EXPECT_EQ(packedGradientExponent(edge), 1);
  const vec3f back = unpackGradient(packGradient(edge, edgeBase), gradientScaleBias(edgeBase));
  for (int a = 0; a < 3; ++a)
    EXPECT_LE(std::abs(back[a] - edge[a]), 1.f) << a;
  // Far below the base: every component within half a unit of the base, so zero or near it.
  const int high = gradientBase(packedGradientExponent(vec3f(1e20f, 0.f, 0.f)));
  const vec3f tiny = unpackGradient(packGradient(vec3f(1.f, -1.f, 0.5f), high), gradientScaleBias(high));
  EXPECT_EQ(tiny, vec3f(0.f));
  // A cell 2^20 times smaller than its brick's largest keeps its eight bits.
  const vec3f small(3.3e-6f, -1.1e-6f, 0.f);
  const int shared = gradientBase(packedGradientExponent(vec3f(3.3f, 0.f, 0.f)));
  const vec3f kept = unpackGradient(packGradient(small, shared), gradientScaleBias(shared));
  for (int a = 0; a < 3; ++a)
    EXPECT_LE(std::abs(kept[a] - small[a]), largest(small) / 255.f) << a;
}

TEST(GradientPack, PackedFieldsAreTheFloatFieldsToEightBits) {
  for (const test::NamedCells& d : test::smallDatasets()) {
    const Model m = buildModel(CellSet(d.cells));
    const FieldView view = m.view(0);
    const size_t cells = m.fieldValues[0].size();
    const std::array<std::vector<float>, 3> g = cellGradients(view, m.bricks, m.regions.regions.size(), cells);
    const GradientFields packed = packedEverywhere(m);
    for (size_t b = 0; b < m.bricks.size(); ++b) {
      float brickLargest = 0.f;
      for (uint32_t i = 0; i < m.bricks[b].cellCount(); ++i) {
        const size_t s = m.bricks[b].valueOffset + i;
        brickLargest = std::max(brickLargest, largest(vec3f(g[0][s], g[1][s], g[2][s])));
      }
      for (uint32_t i = 0; i < m.bricks[b].cellCount(); ++i) {
        const size_t s = m.bricks[b].valueOffset + i;
        const vec3f f(g[0][s], g[1][s], g[2][s]), back = packed.at(s, b);
        // Eight bits of the cell's own largest component, or half a unit of the brick's base.
        const float bound = std::max(largest(f) / 255.f, std::ldexp(brickLargest, -39));
        for (int a = 0; a < 3; ++a)
          ASSERT_LE(std::abs(back[a] - f[a]), bound) << d.name << " brick " << b << " cell " << i;
      }
    }
  }
}

TEST(GradientPack, ValueAndPackedGradientInOnePassEqualTheScalarReference) {
  for (const std::string& target : batchTargets()) {
    ASSERT_TRUE(useBatchTarget(target)) << target;
    SCOPED_TRACE("instruction set " + target);
    for (const test::NamedCells& d : test::smallDatasets()) {
      const Model m = buildModel(CellSet(d.cells));
      const FieldView view = m.view(0);
      const GradientFields fields = packedEverywhere(m);
      const PackedGradientView packed{fields.cells.data(), fields.scaleBias.data()};
      std::mt19937 rng(9);
      std::uniform_real_distribution<float> u(0.f, 1.f);
      std::uniform_int_distribution<int> pickRegion(0, int(m.regions.regions.size()) - 1);
      for (int trial = 0; trial < 200; ++trial) {
        const Region& region = m.regions.regions[size_t(pickRegion(rng))];
        float regionLargest = 0.f;
        for (uint32_t k = 0; k < region.brickCount; ++k) {
          const uint32_t brick = m.regions.brickIds[region.brickBegin + k];
          for (uint32_t c = 0; c < m.bricks[brick].cellCount(); ++c)
            regionLargest = std::max(regionLargest, largest(fields.at(m.bricks[brick].valueOffset + c, brick)));
        }
        const box3f b = region.bounds();
        const vec3f grow = (b.upper - b.lower) * 0.5f; // some samples where no cell has weight
        SampleBatch batch;
        batch.count = 1 + trial % kSampleBatch;
        for (int i = 0; i < batch.count; ++i) {
          batch.x[i] = b.lower.x - grow.x + u(rng) * (b.upper.x - b.lower.x + 2.f * grow.x);
          batch.y[i] = b.lower.y - grow.y + u(rng) * (b.upper.y - b.lower.y + 2.f * grow.y);
          batch.z[i] = b.lower.z - grow.z + u(rng) * (b.upper.z - b.lower.z + 2.f * grow.z);
        }
        const bool withValue = trial % 2 == 0;
        alignas(64) float got[4][kSampleBatch] = {}, ref[4][kSampleBatch] = {};
        alignas(64) int32_t valid[kSampleBatch], refValid[kSampleBatch];
        float* const out[4] = {got[0], got[1], got[2], got[3]};
        float* const expected[4] = {ref[0], ref[1], ref[2], ref[3]};
        const uint32_t* ids = m.regions.brickIds.data() + region.brickBegin;
        sampleShadedBatch(view, packed, withValue, ids, region.brickCount, batch, out, valid);
        sampleShadedBatchScalar(view, packed, withValue, ids, region.brickCount, batch, expected, refValid);
        SampleBatch alone = batch;
        sampleBricksBatch(view, ids, region.brickCount, alone, false);
        for (int i = 0; i < batch.count; ++i) {
          ASSERT_EQ(valid[i] != 0, alone.valid[i] != 0) << d.name << " sample " << i;
          ASSERT_EQ(refValid[i] != 0, alone.valid[i] != 0) << d.name << " sample " << i;
          if (withValue) {
            ASSERT_EQ(got[0][i], alone.valid[i] ? alone.value[i] : 0.f) << d.name << " sample " << i;
          }
          // The vectorised sums go without the reference value: round-off of the largest
          // gradient that the region's bricks hold.
          const float scale = 1.f + regionLargest;
          for (int a = 1; a < 4; ++a)
            ASSERT_NEAR(got[a][i], ref[a][i], 4e-6f * scale) << d.name << " sample " << i << " axis " << a;
        }
      }
    }
  }
  EXPECT_TRUE(useBatchTarget(""));
}

} // namespace
} // namespace exa
