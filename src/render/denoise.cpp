// The denoiser of path-traced frames (render/denoise.h): the guide's two marched pictures, and
// the edge-avoiding à-trous filter with its noise probe.
#include "exabricks/render/denoise.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/render/renderer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace exa {

DenoiseGuide renderDenoiseGuide(Renderer& renderer, const Frame& frame) {
  Timer timer;
  const Scene original = renderer.scene();
  Scene marched = original;
  marched.integration.integrator = Integrator::March;
  marched.ao.rays = 0; // occlusion rays would add noise to a picture that has none
  Frame one = frame;
  one.samplesPerPixel = 1;
  one.noiseTarget = 0.f;
  one.frameIndex = 0;
  FrameBuffer buffer(frame.width, frame.height);
  DenoiseGuide guide;
  auto pass = [&](Shading shading, Image& out) {
    marched.shading = shading;
    renderer.setScene(marched);
    buffer.clear();
    renderer.renderPass(one, buffer);
    buffer.resolve(out);
  };
  // Normals matter where surfaces are: in a medium the shaded picture changed neither the
  // denoised noise nor its bias (measured), and costs a marched frame.
  const bool surfaces = !original.iso.values.empty() || !original.meshes.empty() || original.particles.show;
  try {
    pass(Shading::None, guide.albedo);
    try {
      if (surfaces) pass(Shading::Analytic, guide.shaded);
    } catch (const Error& e) { // a device without analytic shading: the albedo guides alone
      logInfo(strCat("denoising without the shaded guide: ", e.what()));
      guide.shaded = Image();
    }
  } catch (...) {
    renderer.setScene(original);
    throw;
  }
  renderer.setScene(original);
  guide.seconds = timer.seconds();
  return guide;
}

namespace {

constexpr float kB3[5] = {1.f / 16.f, 1.f / 4.f, 3.f / 8.f, 1.f / 4.f, 1.f / 16.f};
constexpr int kFeatures = 7;

float luminance(const vec3f& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/// A random sign per pixel and channel, fixed by their numbers (the probe's).
float probeSign(size_t pixel, int channel) {
  uint64_t h = (uint64_t(pixel) << 2 | uint64_t(channel)) * 0x9E3779B97F4A7C15ull;
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 29;
  return (h & 1) ? 1.f : -1.f;
}

/// What one level filters: the colour (premultiplied RGBA) and two probes of its noise, carried
/// with the same weights: per channel in 1/255 steps of the 8-bit sRGB picture, and its luminance
/// over the background (linear), whose square estimates the variance the colour term compares.
struct Level {
  std::vector<vec4f> color;
  std::vector<vec3f> probe;
  std::vector<float> lumProbe;
  void resize(size_t n) {
    color.resize(n);
    probe.resize(n);
    lumProbe.resize(n);
  }
};

struct Filter {
  int width, height;
  const DenoiseSettings& settings;
  vec3f background;
  std::vector<std::array<float, kFeatures>> features;
  std::vector<uint8_t> valid;   ///< the pixel's tile holds passes
  std::vector<uint8_t> unknown; ///< fewer than two passes: no estimate of the noise (no colour term)

  float shownLuminance(const vec4f& c) const { return luminance(c.rgb() + background * (1.f - c.w)); }

  /// The variance of each pixel's luminance that the colour term compares: the passes' own
  /// estimate (a 3×3 binomial blur of it: one pixel's is noisy) before the first level, then the
  /// luminance probe's square averaged over 5×5 pixels. The probe carries the correlation the
  /// levels leave between neighbours, which a variance filtered with the squared weights misses;
  /// missed, the colour term would take the blotches of the remaining noise for edges.
  void variances(const Level& in, const std::vector<float>* first, std::vector<float>& out) const {
    const int r = first ? 1 : 2;
    tbb::parallel_for(0, height, [&](int y) {
      for (int x = 0; x < width; ++x) {
        const size_t p = size_t(y) * size_t(width) + size_t(x);
        if (unknown[p]) {
          out[p] = 1e30f; // finite: its weights squared may be zero
          continue;
        }
        float sum = 0.f, weights = 0.f;
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx) {
            const int qx = x + dx, qy = y + dy;
            if (qx < 0 || qy < 0 || qx >= width || qy >= height) continue;
            const size_t q = size_t(qy) * size_t(width) + size_t(qx);
            if (!valid[q] || unknown[q]) continue;
            const float w = first ? (dx == 0 ? 2.f : 1.f) * (dy == 0 ? 2.f : 1.f) : 1.f;
            sum += w * (first ? (*first)[q] : in.lumProbe[q] * in.lumProbe[q]);
            weights += w;
          }
        out[p] = weights > 0.f ? sum / weights : 0.f;
      }
    });
  }

  /// One à-trous level at `step` pixels.
  void level(const Level& in, const std::vector<float>& variance, int step, Level& out) const {
    const float guideScale = 1.f / (settings.guideSigma * settings.guideSigma);
    tbb::parallel_for(0, height, [&](int y) {
      for (int x = 0; x < width; ++x) {
        const size_t p = size_t(y) * size_t(width) + size_t(x);
        if (!valid[p]) {
          out.color[p] = in.color[p];
          out.probe[p] = in.probe[p];
          out.lumProbe[p] = in.lumProbe[p];
          continue;
        }
        const float lp = shownLuminance(in.color[p]);
        const float colorScale = 1.f / (settings.colorSigma * std::sqrt(variance[p]) + 1e-6f);
        const std::array<float, kFeatures>& fp = features[p];
        vec4f color;
        vec3f probe(0.f);
        float weights = 0.f, lumProbe = 0.f;
        for (int j = 0; j < 5; ++j) {
          const int qy = y + (j - 2) * step;
          if (qy < 0 || qy >= height) continue;
          for (int i = 0; i < 5; ++i) {
            const int qx = x + (i - 2) * step;
            if (qx < 0 || qx >= width) continue;
            const size_t q = size_t(qy) * size_t(width) + size_t(qx);
            if (!valid[q]) continue;
            float distance = 0.f;
            for (int k = 0; k < kFeatures; ++k) {
              const float d = fp[size_t(k)] - features[q][size_t(k)];
              distance += d * d;
            }
            const float colorTerm = std::fabs(lp - shownLuminance(in.color[q])) * colorScale;
            const float w = kB3[i] * kB3[j] * std::exp(-distance * guideScale - colorTerm);
            color += in.color[q] * w;
            probe = probe + in.probe[q] * w;
            lumProbe += w * in.lumProbe[q];
            weights += w;
          }
        }
        const float inv = 1.f / weights; // the pixel itself weighs kB3[2]² > 0
        out.color[p] = color * inv;
        out.probe[p] = probe * inv;
        out.lumProbe[p] = lumProbe * inv;
      }
    });
  }
};

/// Features of one guide pixel: square roots of its premultiplied colour, so that dark colours
/// differ as much as the eye sees.
void addFeatures(const vec4f& c, float* out, bool withAlpha) {
  out[0] = std::sqrt(std::max(0.f, c.x));
  out[1] = std::sqrt(std::max(0.f, c.y));
  out[2] = std::sqrt(std::max(0.f, c.z));
  if (withAlpha) out[3] = std::sqrt(std::clamp(c.w, 0.f, 1.f));
}

} // namespace

Image denoise(const FrameBuffer& buffer, const DenoiseGuide& guide, const vec3f& background,
              std::vector<float>* tileNoise, const DenoiseSettings& settings) {
  const int width = buffer.width(), height = buffer.height();
  const bool shaded = !guide.shaded.pixels.empty();
  for (const Image* g : {&guide.albedo, &guide.shaded})
    if ((g == &guide.albedo || shaded) && (g->width != width || g->height != height))
      fail("denoise: the guide is ", g->width, "x", g->height, ", the frame ", width, "x", height);
  const size_t n = size_t(width) * size_t(height);
  Filter filter{width, height, settings, background, {}, {}, {}};
  filter.features.resize(n);
  filter.valid.resize(n);
  filter.unknown.resize(n);
  Level a, b;
  a.resize(n);
  b.resize(n);
  std::vector<float> first(n), variance(n);
  const Image mean = buffer.resolve();
  tbb::parallel_for(size_t(0), n, [&](size_t p) {
    addFeatures(guide.albedo.pixels[p], filter.features[p].data(), true);
    if (shaded) addFeatures(guide.shaded.pixels[p], filter.features[p].data() + 4, false);
    const uint32_t passes = buffer.pixelPasses(p);
    filter.valid[p] = passes > 0;
    filter.unknown[p] = passes < 2;
    a.color[p] = mean.pixels[p];
    a.probe[p] = vec3f(0.f);
    a.lumProbe[p] = 0.f;
    if (passes < 2) return; // no estimate of the noise: kept as it is
    const vec4f e = buffer.pixelError(p);
    const float shownError = luminance(e.rgb()) + luminance(background) * e.w;
    first[p] = shownError * shownError;
    a.lumProbe[p] = shownError * probeSign(p, 3);
    const vec3f steps = buffer.pixelNoise(p, background);
    a.probe[p] = {steps.x * probeSign(p, 0), steps.y * probeSign(p, 1), steps.z * probeSign(p, 2)};
  });
  for (int l = 0; l < settings.levels; ++l) {
    filter.variances(a, l == 0 ? &first : nullptr, variance);
    filter.level(a, variance, 1 << l, b);
    std::swap(a, b);
  }
  if (tileNoise) {
    tileNoise->assign(size_t(buffer.tileCount()), 0.f);
    tbb::parallel_for(0, buffer.tileCount(), [&](int tile) {
      (*tileNoise)[size_t(tile)] = buffer.tileRms(tile, [&](size_t p) { return a.probe[p]; });
    });
  }
  Image out(width, height);
  out.pixels = std::move(a.color);
  return out;
}

Image renderPicture(Renderer& renderer, const Frame& frame, RenderStats* stats) {
  if (!denoises(renderer.scene(), frame)) return renderer.render(frame, stats);
  Timer timer;
  const DenoiseGuide guide = renderDenoiseGuide(renderer, frame);
  Image image; // rounds to a noise target end with the picture of their last measure
  const TileNoiseEstimate estimate = denoisedNoise(guide, renderer.scene().background, &image);
  FrameBuffer buffer(frame.width, frame.height);
  renderer.renderSampled(frame, buffer, {}, &estimate);
  if (!NoiseRounds::applies(renderer.scene(), frame)) image = denoise(buffer, guide, renderer.scene().background);
  if (stats) {
    *stats = buffer.stats();
    stats->seconds = timer.seconds();
  }
  return image;
}

TileNoiseEstimate denoisedNoise(const DenoiseGuide& guide, const vec3f& background, Image* picture,
                                const DenoiseSettings& settings) {
  TileNoiseEstimate estimate;
  estimate.measure = [&guide, background, picture, settings](const FrameBuffer& buffer, std::vector<float>& tileNoise) {
    Image denoised = denoise(buffer, guide, background, &tileNoise, settings);
    if (picture) *picture = std::move(denoised);
  };
  return estimate;
}

} // namespace exa
