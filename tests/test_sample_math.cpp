// The per-sample functions of the renderer (render/sample_math.h) on their own: opacity
// correction, shading terms, compositing, iso-surface bisection and the transfer-function table.
#include "exabricks/render/sample_math.h"
#include "exabricks/render/transfer_function.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace exa;

namespace {

/// The marcher's table of `tf` (colour and log2 transmittance per entry) in `entries`.
TfTableView tableOf(const TransferFunction& tf, std::vector<vec4f>& entries) {
  entries.resize(kTfTableSize);
  for (int i = 0; i < kTfTableSize; ++i) {
    const vec4f c = tf.atNormalized(float(i) / float(kTfTableSize - 1));
    entries[size_t(i)] = {c.x, c.y, c.z, std::log2(1.f - std::min(c.w, 0.999999f))};
  }
  TfTableView t;
  t.entries = entries.data();
  t.range = tf.valueRange;
  t.logScale = tf.logScale;
  t.fastLinear = !tf.logScale;
  t.lower = tf.valueRange.lower;
  t.scale = 1.f / (tf.valueRange.upper - tf.valueRange.lower);
  return t;
}

/// The table of `tf` mapped linearly over [-2, 6] or logarithmically over [0.01, 100] (set in
/// tf), and values to try a little beyond either range.
TfTableView mappedTable(TransferFunction& tf, bool logScale, std::vector<vec4f>& entries,
                        std::uniform_real_distribution<float>& values) {
  tf.logScale = logScale;
  tf.valueRange = logScale ? range1f{0.01f, 100.f} : range1f{-2.f, 6.f};
  values = std::uniform_real_distribution<float>(logScale ? 0.001f : -3.f, logScale ? 200.f : 7.f);
  return tableOf(tf, entries);
}

} // namespace

TEST(SampleMath, OpacityCorrectionComposesOverSteps) {
  for (float alpha : {0.01f, 0.3f, 0.9f}) {
    const float log2T = std::log2(1.f - alpha);
    // One reference width gives the table's opacity; two half steps give the same as one step.
    EXPECT_NEAR(correctedOpacity(log2T, 2.f, 0.5f), alpha, 1e-6f);
    const float half = correctedOpacity(log2T, 1.f, 0.5f);
    EXPECT_NEAR(1.f - (1.f - half) * (1.f - half), alpha, 2e-6f);
    EXPECT_EQ(correctedOpacity(log2T, 0.f, 1.f), 0.f);
  }
  // The documented bound, measured densely: 2.4e-7 relative.
  for (float x = -126.f; x <= 0.f; x += 0.37f)
    EXPECT_NEAR(exp2Negative(x), std::exp2(double(x)), 2.5e-7 * std::exp2(double(x)));
  EXPECT_EQ(exp2Negative(-200.f), 0.f);
}

TEST(SampleMath, ShadingTerms) {
  const ShadingTerms t{0.2f, 0.6f, 0.3f, 20.f};
  const vec3f red(1.f, 0.f, 0.f), light(0.f, 0.f, -1.f), half(0.f, 0.f, -1.f);
  // No gradient: lit as if facing the light, no highlight.
  const vec3f flat = shadeVolumeSample(red, vec3f(0.f), light, half, t, 1.f);
  EXPECT_FLOAT_EQ(flat.x, 0.8f);
  EXPECT_FLOAT_EQ(flat.y, 0.f);
  // Gradient along the light, either sign (two-sided): full diffuse and highlight.
  for (float sign : {1.f, -1.f}) {
    const vec3f lit = shadeVolumeSample(red, vec3f(0.f, 0.f, 5.f * sign), light, half, t, 1.f);
    EXPECT_FLOAT_EQ(lit.x, 0.2f + 0.6f + 0.3f);
    EXPECT_FLOAT_EQ(lit.y, 0.3f);
  }
  // Gradient across the light: ambient only.
  EXPECT_FLOAT_EQ(shadeVolumeSample(red, vec3f(1.f, 0.f, 0.f), light, half, t, 1.f).x, 0.2f);
  // The shaded term fades out where the gradient's change per cell is round-off.
  EXPECT_EQ(shadingWeight(1e-6f), 0.f);
  EXPECT_EQ(shadingWeight(1e-3f), 1.f);
  EXPECT_NEAR(shadingWeight(5.5e-5f), 0.5f, 1e-5f);
  const vec3f faint = shadeVolumeSample(red, vec3f(0.f, 0.f, 1.f), light, half, t, 5.5e-5f); // half the shading
  EXPECT_NEAR(faint.x, 0.8f + 0.5f * (1.1f - 0.8f), 1e-5f);
  EXPECT_FLOAT_EQ(shadeVolumeSample(red, vec3f(0.f, 0.f, 1.f), light, half, t, 1e-7f).x, 0.8f);
  // Surfaces are one-sided; occlusion dims ambient fully and diffuse by half.
  const vec3f facing = shadeSurface(red, vec3f(0.f, 0.f, 1.f), light, half, 1.f, t);
  EXPECT_FLOAT_EQ(facing.x, 1.1f);
  const vec3f occluded = shadeSurface(red, vec3f(0.f, 0.f, 1.f), light, half, 0.f, t);
  EXPECT_FLOAT_EQ(occluded.x, 0.3f + 0.3f);
  EXPECT_FLOAT_EQ(shadeSurface(red, vec3f(0.f, 0.f, -1.f), light, half, 1.f, t).x, 0.2f);
}

TEST(SampleMath, FrontToBackCompositingEqualsBackToFrontOver) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<std::pair<vec3f, float>> layers(6);
    for (auto& l : layers)
      l = {vec3f(u(rng), u(rng), u(rng)), u(rng)};
    vec4f front;
    for (const auto& [c, a] : layers)
      compositeBehind(front, c, a);
    vec4f back; // "over", from the far end
    for (auto it = layers.rbegin(); it != layers.rend(); ++it) {
      const auto& [c, a] = *it;
      back = {c.x * a + back.x * (1.f - a), c.y * a + back.y * (1.f - a), c.z * a + back.z * (1.f - a),
              a + back.w * (1.f - a)};
    }
    EXPECT_NEAR(front.x, back.x, 1e-5f);
    EXPECT_NEAR(front.w, back.w, 1e-5f);
  }
  // Order matters: the front colour dominates.
  vec4f a, b;
  compositeBehind(a, vec3f(1.f, 0.f, 0.f), 0.8f);
  compositeBehind(a, vec3f(0.f, 0.f, 1.f), 0.8f);
  compositeBehind(b, vec3f(0.f, 0.f, 1.f), 0.8f);
  compositeBehind(b, vec3f(1.f, 0.f, 0.f), 0.8f);
  EXPECT_GT(a.x, a.z);
  EXPECT_GT(b.z, b.x);
  EXPECT_FLOAT_EQ(a.w, b.w);
  compositeOpaqueBehind(a, vec3f(0.f, 1.f, 0.f));
  EXPECT_EQ(a.w, 1.f);
  EXPECT_NEAR(a.y, 0.04f, 1e-6f);
}

TEST(SampleMath, IsoBisectionFindsAnalyticRoots) {
  // A cubic with one root in [0, 2] at t = cbrt(3) ~ 1.44225 for level 3.
  auto cubic = [](float t, float& v) {
    v = t * t * t;
    return true;
  };
  const float root = refineCrossing(cubic, 0.f, 2.f, 0.f, 8.f, 3.f, false, 1e-4f);
  EXPECT_NEAR(root, std::cbrt(3.f), 2e-4f);
  // Falling through the level (lo above it).
  auto falling = [](float t, float& v) {
    v = std::cos(t);
    return true;
  };
  EXPECT_NEAR(refineCrossing(falling, 0.f, 3.f, 1.f, std::cos(3.f), 0.f, true, 1e-5f), 1.5707963f, 1e-5f);
  // A linear function is exact after the secant step, whatever the tolerance.
  auto linear = [](float t, float& v) {
    v = 2.f * t - 1.f;
    return true;
  };
  EXPECT_NEAR(refineCrossing(linear, 0.f, 1.f, -1.f, 1.f, 0.f, false, 0.5f), 0.5f, 1e-6f);
  // No value in the middle: the search keeps the near part.
  auto hole = [](float t, float& v) {
    v = t;
    return t < 0.4f;
  };
  EXPECT_LE(refineCrossing(hole, 0.f, 1.f, 0.f, 1.f, 0.9f, false, 1e-4f), 0.5f);
}

TEST(SampleMath, TransferFunctionTableAndSkippingTest) {
  TransferFunction tf = defaultTransferFunction("plasma");
  tf.opacityScale = 1.f;
  tf.opacity = {{0.f, 0.f}, {0.5f, 0.f}, {0.5f, 0.4f}, {1.f, 0.8f}};
  for (bool logScale : {false, true}) {
    std::vector<vec4f> entries;
    std::uniform_real_distribution<float> u;
    const TfTableView t = mappedTable(tf, logScale, entries, u);
    std::mt19937 rng(9);
    for (int i = 0; i < 500; ++i) {
      const float v = u(rng);
      EXPECT_NEAR(tfNormalized(t, v), tf.normalize(v), 1e-6f);
      const vec4f want = tf.lookup(v), got = tfLookup(t, v);
      EXPECT_NEAR(got.x, want.x, 2e-3f);
      EXPECT_NEAR(1.f - std::exp2(got.w), want.w, 2e-3f);
      // Space skipping never hides a visible value.
      float a = u(rng), b = u(rng);
      if (a > b) std::swap(a, b);
      bool anyVisible = false;
      for (int k = 0; k <= 64; ++k)
        anyVisible = anyVisible || tfLookup(t, a + (b - a) * float(k) / 64.f).w < 0.f;
      if (anyVisible) {
        EXPECT_TRUE(tfMayBeVisible(t, range1f{a, b}));
      }
    }
  }
  EXPECT_EQ(normalizeValue(range1f{1.f, 1.f}, false, 1.f), 0.5f);
  EXPECT_EQ(normalizeValue(range1f(), false, 3.f), 0.5f);
  EXPECT_EQ(normalizeValue(range1f{0.f, 100.f}, true, 1e-4f), 0.f); // cut six decades below 100
  EXPECT_EQ(normalizeValue(range1f{0.f, 1.f}, false, std::nanf("")), 0.f);
}

TEST(SampleMath, TableMaxExtinctionIsTheLargestOverTheEntriesAndEnds) {
  TransferFunction tf = defaultTransferFunction("plasma");
  tf.opacityScale = 1.f;
  tf.opacity = {{0.f, 0.9f}, {0.1f, 0.f}, {0.3f, 0.5f}, {0.31f, 0.05f}, {0.7f, 0.2f}, {1.f, 0.6f}};
  for (bool logScale : {false, true}) {
    std::vector<vec4f> entries;
    std::uniform_real_distribution<float> u;
    const TfTableView t = mappedTable(tf, logScale, entries, u);
    const float perLog2 = 0.7f;
    const TableMaxExtinction maxExtinction(t, perLog2);
    std::mt19937 rng(3);
    for (int i = 0; i < 2000; ++i) {
      float a = u(rng), b = i % 5 == 0 ? a : u(rng);
      if (a > b) std::swap(a, b);
      // Brute force: the ends (interpolated) and every entry between them.
      const float n0 = tfNormalized(t, a), n1 = tfNormalized(t, b);
      float w = std::min(tfTableAt(t, n0).w, tfTableAt(t, n1).w);
      for (int e = 0; e < kTfTableSize; ++e) {
        if (float(e) >= n0 * float(kTfTableSize - 1) && float(e) <= n1 * float(kTfTableSize - 1))
          w = std::min(w, entries[size_t(e)].w);
      }
      ASSERT_EQ(maxExtinction(range1f{a, b}), -w * perLog2) << a << " " << b;
      for (int k = 0; k <= 16; ++k)
        ASSERT_LE(-tfLookup(t, a + (b - a) * float(k) / 16.f).w * perLog2, maxExtinction(range1f{a, b}) * 1.000001f);
    }
    EXPECT_EQ(maxExtinction(range1f()), 0.f);
  }
}

TEST(SampleMath, RegionStrideOnlyWhereTheLookIsUniform) {
  TransferFunction tf = defaultTransferFunction("viridis");
  tf.opacityScale = 0.05f;
  tf.opacity = {{0.f, 0.f}, {0.4f, 0.f}, {0.6f, 1.f}, {1.f, 1.f}};
  const float perLog2 = 0.7f;
  for (bool logScale : {false, true}) {
    std::vector<vec4f> entries;
    std::uniform_real_distribution<float> u;
    const TfTableView t = mappedTable(tf, logScale, entries, u);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> narrow(0.f, 1e-3f);
    int strided = 0, whole = 0;
    for (int i = 0; i < 3000; ++i) {
      // Wide ranges, and ranges a thousandth of the map wide or less (where most are uniform).
      float a = u(rng), b = i % 2 ? u(rng) : a * (1.f + (logScale ? 0.05f : 0.f)) + narrow(rng) * (logScale ? a : 8.f);
      if (a > b) std::swap(a, b);
      const float diagonal = i % 3 == 0 ? 0.5f : 8.f;
      // Brute force: the table's colour and depth over the range, densely.
      vec4f lo(1e30f, 1e30f, 1e30f, 1e30f), hi(-1e30f, -1e30f, -1e30f, -1e30f);
      for (int k = 0; k <= 4096; ++k) {
        const vec4f e = tfLookup(t, a + (b - a) * float(k) / 4096.f);
        lo = vec4f(std::min(lo.x, e.x), std::min(lo.y, e.y), std::min(lo.z, e.z), std::min(lo.w, e.w));
        hi = vec4f(std::max(hi.x, e.x), std::max(hi.y, e.y), std::max(hi.z, e.z), std::max(hi.w, e.w));
      }
      const float colour = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
      const float depth = (hi.w - lo.w) * perLog2 * diagonal;
      const float stride = regionStride({&t}, {range1f{a, b}}, diagonal, perLog2);
      if (stride > 1.f) {
        ++strided;
        ASSERT_LE(colour, kUniformVariation * 1.0001f) << a << " " << b;
        ASSERT_LE(depth, kUniformVariation * 1.0001f) << a << " " << b;
        ASSERT_EQ(stride, kUniformStride);
      } else {
        ++whole;
        // Not uniform: the dense samples (or the entries between them) vary by more.
        ASSERT_EQ(stride, 1.f);
        ASSERT_TRUE(colour > kUniformVariation * 0.95f || depth > kUniformVariation * 0.95f) << a << " " << b;
      }
    }
    EXPECT_GT(strided, 100);
    EXPECT_GT(whole, 100);
  }
  // Every layer must be uniform; a layer without values in the region does not count.
  tf.logScale = false;
  tf.valueRange = range1f{0.f, 1.f};
  std::vector<vec4f> entries;
  const TfTableView t = tableOf(tf, entries);
  EXPECT_EQ(regionStride({&t, &t}, {range1f{0.1f, 0.1001f}, range1f{0.1f, 0.9f}}, 1.f, perLog2), 1.f);
  EXPECT_EQ(regionStride({&t, &t}, {range1f{0.1f, 0.1001f}, range1f()}, 1.f, perLog2), kUniformStride);
  // Shaded samples stride only through nearly transparent regions: the layers' summed optical
  // depth across the region at most kUniformShadedDepth.
  const float faint = -kUniformShadedDepth / (t.entries[kTfTableSize - 1].w * perLog2); // diagonal at the bound
  ASSERT_GT(faint, 0.f);
  EXPECT_EQ(regionStride({&t}, {range1f{1.f, 1.f}}, 0.9f * faint, perLog2, true), kUniformStride);
  EXPECT_EQ(regionStride({&t}, {range1f{1.f, 1.f}}, 1.1f * faint, perLog2, true), 1.f);
  EXPECT_EQ(regionStride({&t}, {range1f{1.f, 1.f}}, 1.1f * faint, perLog2, false), kUniformStride);
  EXPECT_EQ(regionStride({&t, &t}, {range1f{1.f, 1.f}, range1f{1.f, 1.f}}, 0.6f * faint, perLog2, true), 1.f);
  // A constant look over any range.
  std::vector<vec4f> flatEntries(kTfTableSize, vec4f(0.2f, 0.3f, 0.4f, -0.1f));
  TfTableView f = t;
  f.entries = flatEntries.data();
  EXPECT_EQ(regionStride({&f}, {range1f{-1e6f, 1e6f}}, 1e3f, perLog2), kUniformStride);
}
