// The denoiser of path-traced frames: on buffers of known noise it lowers the noise and keeps the
// mean, stops at the guide's edges and at edges of the light the guide lacks, and its probe
// predicts the noise the denoised picture keeps; on a path-traced frame it reaches a noise
// target with fewer passes and keeps the low frequencies of a converged render; the view and
// the whole-frame function show the same picture.
#include "exabricks/amr/basis_batch.h"
#include "exabricks/amr/model.h"
#include "exabricks/core/color.h"
#include "exabricks/render/denoise.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/progressive.h"

#include "lit_ball.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include <cmath>
#include <functional>
#include <random>

using namespace exa;
using exa::test::LitBall;
using exa::test::rmsSteps;

namespace {

constexpr int kSize = 64;

/// A buffer whose passes are `truth(x, y)` (opaque grey) plus Gaussian noise of `sigma`.
FrameBuffer noisyBuffer(const std::function<float(int, int)>& truth, float sigma, uint32_t passes, unsigned seed,
                        int size = kSize) {
  FrameBuffer buffer(size, size);
  const FrameBuffer::Sums s = buffer.sums();
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, sigma);
  for (uint32_t k = 0; k < passes; ++k)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const size_t p = size_t(y) * size_t(size) + size_t(x);
        const float v = truth(x, y) + noise(rng);
        for (int c = 0; c < 4; ++c) {
          const float value = c == 3 ? 1.f : v;
          s.colors[4 * p + size_t(c)] += value;
          s.squares[4 * p + size_t(c)] += value * value;
        }
      }
  for (size_t t = 0; t < s.tiles; ++t)
    s.tilePasses[t] = passes;
  return buffer;
}

/// Adds `passes` such passes to the tiles listed (every tile where none is).
void addPasses(FrameBuffer& buffer, const std::function<float(int, int)>& truth, float sigma, uint32_t passes,
               unsigned seed, const std::vector<int>& tiles) {
  const FrameBuffer::Sums s = buffer.sums();
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, sigma);
  for (int t = 0; t < buffer.tileCount(); ++t) {
    if (!tiles.empty() && std::find(tiles.begin(), tiles.end(), t) == tiles.end()) continue;
    for (uint32_t k = 0; k < passes; ++k)
      buffer.forTilePixels(t, [&](int x, int y, size_t p) {
        const float v = truth(x, y) + noise(rng);
        for (int c = 0; c < 4; ++c) {
          const float value = c == 3 ? 1.f : v;
          s.colors[4 * p + size_t(c)] += value;
          s.squares[4 * p + size_t(c)] += value * value;
        }
      });
    s.tilePasses[size_t(t)] += passes;
  }
}

/// A guide whose albedo picture is `albedo(x, y)` (opaque grey), without a shaded picture.
DenoiseGuide guideOf(const std::function<float(int, int)>& albedo, int size = kSize) {
  DenoiseGuide g;
  g.albedo = Image(size, size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const float v = albedo(x, y);
      g.albedo.at(x, y) = {v, v, v, 1.f};
    }
  return g;
}

/// RMS of an image's red channel against `truth`.
double rmsError(const Image& image, const std::function<float(int, int)>& truth) {
  double sum = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const double d = image.at(x, y).x - truth(x, y);
      sum += d * d;
    }
  return std::sqrt(sum / double(kSize * kSize));
}

/// The mean absolute difference of two images' 5×5 box means, in 8-bit sRGB steps.
double lowFrequencyDifference(const Image& a, const Image& b) {
  double sum = 0;
  int count = 0;
  for (int y = 2; y + 2 < a.height; ++y)
    for (int x = 2; x + 2 < a.width; ++x) {
      vec3f ma(0.f), mb(0.f);
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          ma = ma + linearToSrgb(a.at(x + dx, y + dy).rgb()) * (1.f / 25.f);
          mb = mb + linearToSrgb(b.at(x + dx, y + dy).rgb()) * (1.f / 25.f);
        }
      const vec3f d = ma - mb;
      sum += (std::fabs(d.x) + std::fabs(d.y) + std::fabs(d.z)) / 3.0 * 255.0;
      ++count;
    }
  return sum / count;
}

} // namespace

TEST(Denoise, FlatNoiseFallsAndItsMeanStays) {
  const auto flat = [](int, int) { return 0.4f; };
  const FrameBuffer buffer = noisyBuffer(flat, 0.2f, 16, 1);
  const Image noisy = buffer.resolve(), denoised = denoise(buffer, guideOf(flat), vec3f(0.f));
  const double before = rmsError(noisy, flat), after = rmsError(denoised, flat);
  EXPECT_NEAR(before, 0.05, 0.005); // 0.2 / sqrt(16)
  EXPECT_LT(after, before / 4) << before << " -> " << after;
  double mean = 0;
  for (const vec4f& p : denoised.pixels)
    mean += p.x / double(denoised.pixels.size());
  EXPECT_NEAR(mean, 0.4, 0.003);
}

TEST(Denoise, StopsAtTheGuidesEdges) {
  // Left 0.1, right 0.7; the guide has the same edge.
  const auto step = [](int x, int) { return x < kSize / 2 ? 0.1f : 0.7f; };
  const FrameBuffer buffer = noisyBuffer(step, 0.3f, 16, 2);
  const Image denoised = denoise(buffer, guideOf(step), vec3f(0.f));
  for (int x : {kSize / 2 - 1, kSize / 2}) {
    double column = 0;
    for (int y = 0; y < kSize; ++y)
      column += denoised.at(x, y).x / double(kSize);
    EXPECT_NEAR(column, step(x, 0), 0.02) << "column " << x;
  }
}

TEST(Denoise, StopsAtEdgesOfTheLightThatTheGuideLacks) {
  // A shadow's edge: the guide is flat, the light steps by far more than its noise.
  const auto light = [](int x, int) { return x < kSize / 2 ? 0.1f : 0.7f; };
  const FrameBuffer buffer = noisyBuffer(light, 0.05f, 16, 3);
  const Image denoised = denoise(buffer, guideOf([](int, int) { return 0.5f; }), vec3f(0.f));
  for (int x : {kSize / 2 - 2, kSize / 2 - 1, kSize / 2, kSize / 2 + 1}) {
    double column = 0;
    for (int y = 0; y < kSize; ++y)
      column += denoised.at(x, y).x / double(kSize);
    EXPECT_NEAR(column, light(x, 0), 0.03) << "column " << x;
  }
}

/// A buffer of `truth` with noise and another with other noise, each denoised: the noise each
/// keeps (half the RMS difference squared, as two seeds measure it) against the probe's estimate
/// from the first. Both in 8-bit steps.
struct ProbeCheck {
  double predicted = 0, measured = 0, raw = 0;
  explicit ProbeCheck(const std::function<float(int, int)>& truth) {
    const DenoiseGuide guide = guideOf(truth);
    const FrameBuffer a = noisyBuffer(truth, 0.25f, 16, 4), b = noisyBuffer(truth, 0.25f, 16, 5);
    std::vector<float> tiles;
    const Image da = denoise(a, guide, vec3f(0.f), &tiles), db = denoise(b, guide, vec3f(0.f));
    for (float t : tiles)
      predicted += double(t) * t / double(tiles.size());
    predicted = std::sqrt(predicted);
    measured = rmsSteps(da, db) / std::sqrt(2.0);
    for (int t = 0; t < a.tileCount(); ++t)
      raw += double(a.tileNoise(t, vec3f(0.f))) / a.tileCount();
  }
};

TEST(Denoise, ItsProbePredictsTheNoiseTheDenoisedPictureKeeps) {
  const ProbeCheck flat([](int, int) { return 0.4f; });
  EXPECT_NEAR(flat.predicted, flat.measured, 0.3 * flat.measured) << flat.predicted << " " << flat.measured;
  EXPECT_LT(flat.measured, flat.raw / 10);
  // On a steep gradient of light the colour term's weights follow the noise (a pixel's own noise
  // draws it towards the neighbours it resembles), so the picture keeps more than the weights
  // carry: measured up to about twice the prediction.
  const ProbeCheck ramp([](int x, int y) { return 0.2f + 0.5f * float(x + y) / float(2 * kSize); });
  EXPECT_GT(ramp.measured, 0.8 * ramp.predicted);
  EXPECT_LT(ramp.measured, 2.5 * ramp.predicted) << ramp.predicted << " " << ramp.measured;
  EXPECT_LT(ramp.measured, ramp.raw / 5);
}

TEST(Denoise, TheGuideIsTheMarchedFrameAndLeavesTheScene) {
  LitBall ball;
  Renderer renderer(ball.model);
  renderer.setScene(ball.scene);
  auto json = [&] {
    SceneDocument doc;
    doc.scene = renderer.scene();
    return exactSceneJson(doc);
  };
  const std::string before = json();
  const DenoiseGuide guide = renderDenoiseGuide(renderer, ball.frame);
  EXPECT_EQ(json(), before);
  EXPECT_TRUE(guide.shaded.pixels.empty()); // a medium without surfaces: the albedo guides alone
  Scene marched = ball.scene;
  marched.integration.integrator = Integrator::March;
  marched.shading = Shading::None;
  Renderer march(ball.model);
  march.setScene(marched);
  Frame one = ball.frame;
  one.samplesPerPixel = 1;
  const Image want = march.render(one);
  ASSERT_EQ(guide.albedo.pixels.size(), want.pixels.size());
  for (size_t p = 0; p < want.pixels.size(); ++p)
    ASSERT_EQ(guide.albedo.pixels[p], want.pixels[p]) << p;
  // With a surface, the shaded picture too.
  Scene withIso = ball.scene;
  withIso.iso.values = {0.5f};
  renderer.setScene(withIso);
  EXPECT_EQ(renderDenoiseGuide(renderer, ball.frame).shaded.pixels.size(), want.pixels.size());
}

TEST(Denoise, AFrameMeetsItsTargetWithFewerPassesAndKeepsItsLight) {
  LitBall ball;
  Renderer renderer(ball.model);
  renderer.setScene(ball.scene);
  Frame frame = ball.frame;
  frame.samplesPerPixel = 512;
  frame.noiseTarget = 2.f;
  frame.denoise = true;
  RenderStats first, plain;
  const Image a = renderPicture(renderer, frame, &first);
  frame.seed = 1;
  const Image b = renderPicture(renderer, frame);
  EXPECT_LT(rmsSteps(a, b) / std::sqrt(2.0), 2.5);
  frame.denoise = false;
  frame.seed = 0;
  renderer.render(frame, &plain);
  EXPECT_LT(first.rays * 3, plain.rays) << "denoised " << first.rays << " rays, undenoised " << plain.rays;
  // Its low frequencies are those of a converged render.
  Frame converged = ball.frame;
  converged.samplesPerPixel = 1024;
  converged.seed = 7;
  EXPECT_LT(lowFrequencyDifference(a, renderer.render(converged)), 1.0);
}

TEST(Denoise, AFilterAfterAFewTilesTookPassesEqualsTheWholeFilter) {
  // Rounds to a noise target filter the frame after each round's passes: given what the last
  // filter made, the next one filters only around the tiles that took passes, and its picture and
  // tile noise are the whole filter's, to the bit.
  const int size = 320; // 20 × 20 tiles: the filter reaches 4 tiles, its input 8 more
  const auto truth = [](int x, int y) { return ((x / 37 + y / 29) % 2) ? 0.7f : 0.25f; };
  FrameBuffer buffer = noisyBuffer(truth, 0.2f, 4, 1, size);
  const DenoiseGuide guide = guideOf(truth, size);
  const vec3f background(0.1f, 0.2f, 0.3f);
  DenoiseMemo memo;
  const Image before = denoise(buffer, guide, background, nullptr, {}, &memo);
  EXPECT_EQ(memo.filteredTiles, size_t(buffer.tileCount()));
  for (const std::vector<int>& tiles : {std::vector<int>{0}, std::vector<int>{21, 398}, std::vector<int>{}}) {
    addPasses(buffer, truth, 0.2f, 3, unsigned(7 + tiles.size()), tiles);
    std::vector<float> noise, wholeNoise;
    const Image again = denoise(buffer, guide, background, &noise, {}, &memo);
    const Image whole = denoise(buffer, guide, background, &wholeNoise);
    if (!tiles.empty()) {
      EXPECT_LT(memo.filteredTiles, size_t(buffer.tileCount()) / 2);
    }
    ASSERT_EQ(again.pixels.size(), whole.pixels.size());
    EXPECT_EQ(0, std::memcmp(again.pixels.data(), whole.pixels.data(), whole.pixels.size() * sizeof(vec4f)));
    EXPECT_EQ(noise, wholeNoise);
    EXPECT_NE(0, std::memcmp(again.pixels.data(), before.pixels.data(), whole.pixels.size() * sizeof(vec4f)));
  }
  // Nothing new: the same picture, nothing filtered.
  std::vector<float> noise;
  const Image same = denoise(buffer, guide, background, &noise, {}, &memo);
  EXPECT_EQ(memo.filteredTiles, 0u);
  EXPECT_EQ(same.pixels.size(), memo.picture.pixels.size());
}

TEST(Denoise, TheVectorisedRowsEqualThePerPixelSteps) {
  // The CPU filters rows of pixels as vectors; the GPU's kernels run the per-pixel steps. With
  // every instruction set, on a frame whose width is no multiple of a vector or a tile, with a
  // shaded guide, a tile without passes and one of a single pass (no noise estimate), both give
  // the same picture and tile noise to float round-off.
  const int size = 83;
  const auto truth = [](int x, int y) { return ((x / 13 + y / 11) % 2) ? 0.7f : 0.25f; };
  FrameBuffer buffer = noisyBuffer(truth, 0.2f, 4, 3, size);
  const FrameBuffer::Sums s = buffer.sums();
  s.tilePasses[2] = 0;
  s.tilePasses[7] = 1;
  DenoiseGuide guide = guideOf(truth, size);
  guide.shaded = guideOf([](int x, int y) { return 0.1f + 0.8f * float((x * 7 + y * 3) % 17) / 17.f; }, size).albedo;
  const vec3f background(0.1f, 0.2f, 0.3f);
  DenoiseSettings perPixel;
  perPixel.perPixel = true;
  std::vector<float> wantNoise;
  const Image want = denoise(buffer, guide, background, &wantNoise, perPixel);
  int targets = 0;
  for (const std::string& target : batchTargets()) {
    ASSERT_TRUE(useBatchTarget(target)) << target;
    SCOPED_TRACE("instruction set " + target);
    ++targets;
    std::vector<float> noise;
    const Image got = denoise(buffer, guide, background, &noise);
    ASSERT_EQ(got.pixels.size(), want.pixels.size());
    double largest = 0;
    for (size_t p = 0; p < want.pixels.size(); ++p) {
      const vec4f d = got.pixels[p] - want.pixels[p];
      for (float c : {d.x, d.y, d.z, d.w})
        largest = std::max(largest, double(std::fabs(c)));
    }
    EXPECT_LT(largest, 1e-5);
    ASSERT_EQ(noise.size(), wantNoise.size());
    for (size_t t = 0; t < noise.size(); ++t)
      if (std::isinf(wantNoise[t]))
        EXPECT_EQ(noise[t], wantNoise[t]) << "tile " << t; // fewer than two passes
      else
        EXPECT_NEAR(noise[t], wantNoise[t], 1e-4f * std::max(1.f, wantNoise[t])) << "tile " << t;
  }
  EXPECT_TRUE(std::isinf(wantNoise[2]) && std::isinf(wantNoise[7]));
  EXPECT_TRUE(useBatchTarget(""));
  EXPECT_GT(targets, 0);
  // The tile without passes stays transparent black; the filter changed the others.
  buffer.forTilePixels(2, [&](int, int, size_t p) { EXPECT_EQ(want.pixels[p], vec4f(0.f, 0.f, 0.f, 0.f)); });
  EXPECT_NE(want.pixels, buffer.resolve().pixels);
}

TEST(Denoise, AViewShowsTheFramesDenoisedPicture) {
  LitBall ball;
  Renderer renderer(ball.model);
  ProgressiveView view(renderer, "cpu");
  SceneDocument doc;
  doc.scene = ball.scene;
  doc.frame = ball.frame;
  doc.frame.samplesPerPixel = 256;
  doc.frame.noiseTarget = 2.f;
  doc.frame.denoise = true;
  view.show(doc);
  while (!view.complete())
    ASSERT_TRUE(view.refine({}));
  EXPECT_TRUE(view.showsDenoised());
  Image shown;
  view.resolve(shown);
  Renderer other(ball.model);
  other.setScene(ball.scene);
  const Image want = renderPicture(other, doc.frame);
  ASSERT_EQ(shown.pixels.size(), want.pixels.size());
  for (size_t p = 0; p < want.pixels.size(); ++p)
    ASSERT_EQ(shown.pixels[p], want.pixels[p]) << p;
}

TEST(FrameBufferTiles, NearOrderVisitsEveryPixelOfItsTileOnce) {
  // Sizes with partial tiles on the right and at the bottom: the Morton order of each tile
  // visits exactly the pixels the row order does, adjacent pairs first.
  for (const std::pair<int, int>& size : {std::pair{37, 21}, std::pair{16, 16}, std::pair{1, 5}}) {
    const int w = size.first, h = size.second;
    FrameBuffer buffer(w, h);
    std::vector<int> seen(size_t(w) * size_t(h), 0);
    for (int t = 0; t < buffer.tileCount(); ++t) {
      std::vector<size_t> rows, near;
      buffer.forTilePixels(t, [&](int, int, size_t p) { rows.push_back(p); });
      std::vector<std::pair<int, int>> order;
      buffer.forTilePixelsNear(t, [&](int x, int y, size_t p) {
        EXPECT_EQ(p, size_t(y) * size_t(w) + size_t(x));
        near.push_back(p);
        order.emplace_back(x, y);
        ++seen[p];
      });
      if (buffer.width() >= 2 && order.size() >= 2 && t == 0) {
        EXPECT_EQ(order[1], std::make_pair(1, 0)); // (0, 0), (1, 0), (0, 1), (1, 1), ...
        if (order.size() >= 3 && h >= 2) EXPECT_EQ(order[2], std::make_pair(0, 1));
      }
      std::sort(near.begin(), near.end());
      EXPECT_EQ(near, rows) << w << "x" << h << " tile " << t;
    }
    for (int n : seen)
      EXPECT_EQ(n, 1);
  }
}
