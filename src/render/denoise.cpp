// The denoiser of path-traced frames (render/denoise.h): the guide's two marched pictures, and
// the edge-avoiding à-trous filter with its noise probe.
#include "exabricks/render/denoise.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/render/renderer.h"

#include "denoise_filter.h"
#include "gpu_api.h"

#include <tbb/parallel_for.h>

#include <algorithm>
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
  guide.device = renderer.device();
  guide.seconds = timer.seconds();
  return guide;
}

namespace {

/// A random sign per pixel and channel, fixed by their numbers (the probe's).
float probeSign(size_t pixel, int channel) {
  uint64_t h = (uint64_t(pixel) << 2 | uint64_t(channel)) * 0x9E3779B97F4A7C15ull;
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 29;
  return (h & 1) ? 1.f : -1.f;
}

/// One level's arrays on the host.
struct LevelArrays {
  std::vector<vec4f> color;
  std::vector<vec3f> probe;
  std::vector<float> lumProbe;
  explicit LevelArrays(size_t n) : color(n), probe(n), lumProbe(n) {}
  DenoiseLevel view() { return {color.data(), probe.data(), lumProbe.data()}; }
};

/// The levels on the CPU's threads: the same per-pixel steps as the GPU's kernels.
void filterOnCpu(const DenoiseImages& im, LevelArrays& a, const std::vector<float>& first, int levels) {
  const size_t n = a.color.size();
  LevelArrays b(n);
  std::vector<float> variance(n);
  for (int l = 0; l < levels; ++l) {
    const DenoiseLevel in = a.view(), out = b.view();
    const float* from = l == 0 ? first.data() : nullptr;
    tbb::parallel_for(0, im.height, [&](int y) {
      for (int x = 0; x < im.width; ++x)
        variance[size_t(y) * size_t(im.width) + size_t(x)] = denoiseVariance(im, in, from, x, y);
    });
    tbb::parallel_for(0, im.height, [&](int y) {
      for (int x = 0; x < im.width; ++x)
        denoiseLevelPixel(im, in, variance.data(), 1 << l, x, y, out);
    });
    std::swap(a, b);
  }
}

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
  std::vector<float> features(n * kDenoiseFeatures, 0.f), first(n, 0.f);
  std::vector<uint8_t> valid(n), unknown(n);
  LevelArrays a(n);
  const Image mean = buffer.resolve();
  const float backgroundLuminance = luminance(background);
  tbb::parallel_for(size_t(0), n, [&](size_t p) {
    addFeatures(guide.albedo.pixels[p], &features[p * kDenoiseFeatures], true);
    if (shaded) addFeatures(guide.shaded.pixels[p], &features[p * kDenoiseFeatures + 4], false);
    const uint32_t passes = buffer.pixelPasses(p);
    valid[p] = passes > 0;
    unknown[p] = passes < 2;
    a.color[p] = mean.pixels[p];
    a.probe[p] = vec3f(0.f);
    a.lumProbe[p] = 0.f;
    if (passes < 2) return; // no estimate of the noise: kept as it is
    const vec4f e = buffer.pixelError(p);
    const float shownError = luminance(e.rgb()) + backgroundLuminance * e.w;
    first[p] = shownError * shownError;
    a.lumProbe[p] = shownError * probeSign(p, 3);
    const vec3f steps = buffer.pixelNoise(p, background);
    a.probe[p] = {steps.x * probeSign(p, 0), steps.y * probeSign(p, 1), steps.z * probeSign(p, 2)};
  });
  DenoiseImages im;
  im.width = width;
  im.height = height;
  im.features = features.data();
  im.valid = valid.data();
  im.unknown = unknown.data();
  im.background = background;
  im.guideScale = 1.f / (settings.guideSigma * settings.guideSigma);
  im.colorSigma = settings.colorSigma;
  if (guide.device == Device::Cuda)
    gpu::denoiseLevels(im, a.view(), first.data(), settings.levels);
  else
    filterOnCpu(im, a, first, settings.levels);
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
