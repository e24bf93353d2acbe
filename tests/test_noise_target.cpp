// Passes to a noise target: the noise a frame buffer estimates per tile against its definition
// (the standard error of the mean, through the sRGB curve), and a path-traced frame that stops
// each tile at the target: every tile equals the same tile of a render with its pass count, the
// tiles that stopped early meet the target, and two seeds differ by about the target.
#include "exabricks/amr/model.h"
#include "exabricks/core/color.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/progressive.h"

#include "lit_ball.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

using namespace exa;
using exa::test::LitBall;
using exa::test::rmsSteps;

namespace {

/// One tile (16 x 16) whose pixels all took `passes` passes, alternating between grey levels
/// `a` and `b` (opaque).
FrameBuffer alternating(float a, float b, uint32_t passes) {
  FrameBuffer buffer(kRenderTile, kRenderTile);
  const FrameBuffer::Sums s = buffer.sums();
  for (uint32_t k = 0; k < passes; ++k) {
    const float v = k % 2 ? b : a;
    for (size_t p = 0; p < s.pixels; ++p)
      for (int c = 0; c < 4; ++c) {
        const float x = c == 3 ? 1.f : v;
        s.colors[4 * p + size_t(c)] += x;
        s.squares[4 * p + size_t(c)] += x * x;
      }
  }
  s.tilePasses[0] = passes;
  return buffer;
}

} // namespace

TEST(NoiseTarget, ATilesNoiseIsTheStandardErrorThroughTheSrgbCurve) {
  // Alternating a and b over n passes: the mean's standard error is |b - a| / 2 / sqrt(n - 1).
  const float a = 0.2f, b = 0.3f;
  for (uint32_t n : {4u, 16u, 64u}) {
    const FrameBuffer buffer = alternating(a, b, n);
    const float mean = (a + b) / 2, error = (b - a) / 2 / std::sqrt(float(n - 1));
    const float want = (linearToSrgb(mean + error) - linearToSrgb(mean - error)) / 2 * 255.f;
    EXPECT_NEAR(buffer.tileNoise(0, vec3f(0.f)), want, 1e-3f * want) << n;
  }
  EXPECT_FLOAT_EQ(alternating(0.4f, 0.4f, 8).tileNoise(0, vec3f(0.f)), 0.f);
  EXPECT_EQ(alternating(0.2f, 0.3f, 1).tileNoise(0, vec3f(0.f)), std::numeric_limits<float>::infinity());
  EXPECT_DOUBLE_EQ(alternating(0.2f, 0.3f, 12).meanPasses(), 12.0);
}

TEST(NoiseTarget, EachTileStopsAtTheTargetAndEqualsARenderOfItsPasses) {
  LitBall ball;
  Renderer renderer(ball.model);
  renderer.setScene(ball.scene);
  Frame frame = ball.frame;
  frame.samplesPerPixel = 512;
  frame.noiseTarget = 2.f;
  FrameBuffer adaptive(frame.width, frame.height);
  // The progress total: the tile passes planned, growing round by round to those taken.
  std::vector<uint64_t> planned;
  std::atomic<uint64_t> tilePasses{0};
  PassControl control;
  control.planned = [&](uint64_t n) { planned.push_back(n); };
  control.progress = [&](uint64_t, uint64_t) { ++tilePasses; };
  ASSERT_TRUE(renderer.renderSampled(frame, adaptive, control));
  ASSERT_GE(planned.size(), 2u);
  EXPECT_EQ(planned.front(), uint64_t(adaptive.tileCount()) * kNoiseFirstPasses);
  EXPECT_TRUE(std::is_sorted(planned.begin(), planned.end()));
  EXPECT_EQ(planned.back(), tilePasses.load());
  uint32_t fewest = 100000, most = 0;
  for (int t = 0; t < adaptive.tileCount(); ++t) {
    const uint32_t n = adaptive.tilePasses(t);
    fewest = std::min(fewest, n);
    most = std::max(most, n);
    EXPECT_GE(n, uint32_t(kNoiseFirstPasses));
    if (n < 512) {
      EXPECT_LE(adaptive.tileNoise(t, ball.scene.background), 2.f) << "tile " << t;
    }
  }
  EXPECT_LT(fewest, most); // the empty corners stop first
  EXPECT_GT(most, uint32_t(kNoiseFirstPasses));
  EXPECT_LT(adaptive.meanPasses(), 512.0);

  // Tile by tile, the n-pass render's tile.
  const Image image = adaptive.resolve();
  for (uint32_t n : {fewest, most}) {
    Frame fixed = frame;
    fixed.noiseTarget = 0.f;
    fixed.samplesPerPixel = int(n);
    const Image reference = renderer.render(fixed);
    int compared = 0;
    for (int t = 0; t < adaptive.tileCount(); ++t) {
      if (adaptive.tilePasses(t) != n) continue;
      const int tx = t % adaptive.tilesX(), ty = t / adaptive.tilesX();
      for (int y = ty * kRenderTile; y < (ty + 1) * kRenderTile; ++y)
        for (int x = tx * kRenderTile; x < (tx + 1) * kRenderTile; ++x) {
          const size_t p = size_t(y) * size_t(frame.width) + size_t(x);
          ASSERT_EQ(image.pixels[p], reference.pixels[p]) << "pixel " << x << "," << y << " of " << n << " passes";
        }
      ++compared;
    }
    EXPECT_GT(compared, 0);
  }

  // Another seed: the two differ by about sqrt(2) times the noise each holds.
  frame.seed = 7;
  const Image other = renderer.render(frame);
  const double noise = rmsSteps(image, other) / std::sqrt(2.0);
  std::printf("passes %u..%u, mean %.1f; noise of two seeds %.2f/255\n", fewest, most, adaptive.meanPasses(), noise);
  EXPECT_LE(noise, 2.0 * 1.25);
  EXPECT_GT(noise, 0.2);
}

TEST(NoiseTarget, WithoutATargetOrWhenMarchingEveryTileTakesTheCount) {
  LitBall ball;
  Renderer renderer(ball.model);
  Frame frame = ball.frame;
  frame.samplesPerPixel = 24;
  for (Integrator integrator : {Integrator::PathTrace, Integrator::March})
    for (float target : {0.f, 100.f}) {
      Scene s = ball.scene;
      s.integration.integrator = integrator;
      renderer.setScene(s);
      frame.noiseTarget = integrator == Integrator::March ? target : 0.f;
      FrameBuffer buffer(frame.width, frame.height);
      ASSERT_TRUE(renderer.renderSampled(frame, buffer));
      for (int t = 0; t < buffer.tileCount(); ++t)
        EXPECT_EQ(buffer.tilePasses(t), 24u);
    }
}

TEST(NoiseTarget, AProgressiveViewRefinesToTheTargetAndEqualsTheFrame) {
  // Pass by pass, the rounds of tiles that want more, until every tile holds its passes: the same
  // image as the frame rendered at once.
  LitBall ball;
  Renderer renderer(ball.model);
  ProgressiveView view(renderer, "cpu");
  SceneDocument doc;
  doc.scene = ball.scene;
  doc.frame = ball.frame;
  doc.frame.samplesPerPixel = 256;
  doc.frame.noiseTarget = 3.f;
  doc.hasCamera = true;
  view.show(doc);
  const PassControl control;
  int refinements = 0;
  while (!view.complete() && refinements < 100000) {
    ASSERT_TRUE(view.refine(control));
    ++refinements;
  }
  ASSERT_TRUE(view.complete());
  EXPECT_FALSE(view.refine(control));
  renderer.setScene(ball.scene);
  EXPECT_EQ(view.buffer().resolve().pixels, renderer.render(doc.frame).pixels);
  EXPECT_LT(view.buffer().meanPasses(), 256.0);
}
