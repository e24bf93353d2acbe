// The denoiser of path-traced frames (render/denoise.h): the guide's two marched pictures, and
// the edge-avoiding à-trous filter with its noise probe.
#include "exabricks/render/denoise.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/render/renderer.h"

#include "denoise_batch.h"
#include "denoise_filter.h"
#include "gpu_api.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

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

/// Where each level is filtered, in tiles of the frame buffer: all of them, or (after some tiles
/// took passes) those whose outputs the later levels read, around the tiles whose output changes.
struct TileRegions {
  std::vector<std::vector<int>> level; ///< per level, the tiles whose outputs it makes
  std::vector<int> input;              ///< the tiles of the first level's input it reads
};

/// The tiles within `reach` pixels (Chebyshev) of the tiles `from` marks.
std::vector<uint8_t> dilated(const std::vector<uint8_t>& from, int tilesX, int tilesY, int reach) {
  const int d = (reach + kRenderTile - 1) / kRenderTile;
  std::vector<uint8_t> rows(from.size(), 0), out(from.size(), 0);
  for (int y = 0; y < tilesY; ++y)
    for (int x = 0; x < tilesX; ++x)
      if (from[size_t(y * tilesX + x)])
        for (int k = std::max(0, x - d); k <= std::min(tilesX - 1, x + d); ++k)
          rows[size_t(y * tilesX + k)] = 1;
  for (int y = 0; y < tilesY; ++y)
    for (int x = 0; x < tilesX; ++x)
      if (rows[size_t(y * tilesX + x)])
        for (int k = std::max(0, y - d); k <= std::min(tilesY - 1, y + d); ++k)
          out[size_t(k * tilesX + x)] = 1;
  return out;
}

std::vector<int> marked(const std::vector<uint8_t>& mask) {
  std::vector<int> tiles;
  for (size_t t = 0; t < mask.size(); ++t)
    if (mask[t]) tiles.push_back(int(t));
  return tiles;
}

/// The regions that make the outputs of the tiles within the filter's reach of `changed` (level
/// l's step reaches 2^(l+1) pixels; its variance 2 at most): the last level's outputs there, each
/// level before it over those grown by the later levels' reach. None where they would cover most
/// of the frame (the whole filter is as fast).
std::optional<TileRegions> regionsAround(const std::vector<uint8_t>& changed, int tilesX, int tilesY, int levels,
                                         std::vector<uint8_t>& outputs) {
  int reach = 0;
  for (int l = 0; l < levels; ++l)
    reach += 2 << l;
  outputs = dilated(changed, tilesX, tilesY, reach);
  TileRegions r{std::vector<std::vector<int>>(size_t(levels)), {}};
  int later = 0; // the reach of the levels after l
  for (int l = levels - 1; l >= 0; --l) {
    r.level[size_t(l)] = marked(dilated(outputs, tilesX, tilesY, later));
    later += 2 << l;
  }
  r.input = marked(dilated(outputs, tilesX, tilesY, later));
  if (r.input.size() * 3 > changed.size() * 2) return std::nullopt;
  return r;
}

/// Calls f(y, x0, x1) for the pixels x0 .. x1 - 1 of each row of the tiles listed (all where
/// `tiles` is null), on the CPU's threads.
template <typename F> void forTileRows(const DenoiseImages& im, const std::vector<int>* tiles, F&& f) {
  if (!tiles) {
    tbb::parallel_for(0, im.height, [&](int y) { f(y, 0, im.width); });
    return;
  }
  const int tilesX = (im.width + kRenderTile - 1) / kRenderTile;
  tbb::parallel_for(size_t(0), tiles->size(), [&](size_t k) {
    const int tx = (*tiles)[k] % tilesX, ty = (*tiles)[k] / tilesX;
    for (int y = ty * kRenderTile; y < std::min(im.height, (ty + 1) * kRenderTile); ++y)
      f(y, tx * kRenderTile, std::min(im.width, (tx + 1) * kRenderTile));
  });
}

/// Calls f(x, y, pixel) for every pixel of the tiles listed (all where `tiles` is null), on the
/// CPU's threads.
template <typename F> void forTiles(const DenoiseImages& im, const std::vector<int>* tiles, F&& f) {
  forTileRows(im, tiles, [&](int y, int x0, int x1) {
    for (int x = x0; x < x1; ++x)
      f(x, y, size_t(y) * size_t(im.width) + size_t(x));
  });
}

/// The tiles level l makes (`made`) and those of its input it reads (`read`) where the filter
/// runs over `regions`; null (every tile) without them.
void levelTiles(const TileRegions* regions, int l, const std::vector<int>*& made, const std::vector<int>*& read) {
  made = regions ? &regions->level[size_t(l)] : nullptr;
  read = !regions ? nullptr : l == 0 ? &regions->input : &regions->level[size_t(l - 1)];
}

/// Planes of one float per pixel on the host, each with `padding` floats of room before and after
/// (zero, and never written: the taps that read it weigh zero).
struct Planes {
  size_t stride = 0;
  int padding = 0;
  std::vector<float> storage;
  /// `count` planes of n pixels: kept where they were that already, else new and zero.
  void reset(int count, size_t n, int padding_) {
    const size_t newStride = n + 2 * size_t(padding_);
    if (newStride == stride && padding_ == padding && storage.size() == size_t(count) * newStride) return;
    stride = newStride, padding = padding_;
    storage.assign(size_t(count) * stride, 0.f);
  }
  float* operator[](int k) { return storage.data() + size_t(k) * stride + size_t(padding); }
};

/// A level's colour and probes as planes.
struct LevelPlanes {
  Planes planes;
  DenoisePlanes view;
  void reset(size_t n, int padding) {
    planes.reset(8, n, padding);
    for (int c = 0; c < 4; ++c)
      view.color[c] = planes[c];
    for (int c = 0; c < 3; ++c)
      view.probe[c] = planes[4 + c];
    view.lumProbe = planes[7];
  }
};

} // namespace

/// The vectorised filter's planes: two levels' and those every level reads.
struct DenoiseScratch {
  LevelPlanes a, b;
  Planes fixed;
};

namespace {

/// The levels on the CPU's threads, each pixel's shown luminance found once per level (the GPU's
/// kernels find it at each of the 25 taps); only over `regions` where given. Rows of pixels go
/// through the vectorised form of the per-pixel steps (denoise_batch.h) where there is one and
/// `perPixel` is false, else pixel by pixel.
void filterOnCpu(const DenoiseImages& im, LevelArrays& a, const std::vector<float>& first, int levels,
                 const TileRegions* regions, bool perPixel, DenoiseScratch& scratch) {
  const size_t n = a.color.size();
  const std::vector<int>*made, *read;
  const DenoiseRowFunction rowFunction = perPixel ? nullptr : denoiseRowFunction();
  if (!rowFunction) {
    LevelArrays b(n);
    std::vector<float> variance(n), shown(n);
    for (int l = 0; l < levels; ++l) {
      DenoiseLevel in = a.view();
      const DenoiseLevel out = b.view();
      const float* from = l == 0 ? first.data() : nullptr;
      levelTiles(regions, l, made, read);
      forTiles(im, read, [&](int, int, size_t p) { shown[p] = denoiseShownLuminance(im, in.color[p]); });
      forTiles(im, made, [&](int x, int y, size_t p) { variance[p] = denoiseVariance(im, in, from, x, y); });
      in.shown = shown.data();
      forTiles(im, made, [&](int x, int y, size_t) { denoiseLevelPixel(im, in, variance.data(), 1 << l, x, y, out); });
      std::swap(a, b);
    }
    return;
  }
  const DenoiseVarianceRowFunction varianceFunction = denoiseVarianceRowFunction();
  const int padding = denoisePlanePadding(1 << std::max(0, levels - 1));
  LevelPlanes& pa = scratch.a;
  LevelPlanes& pb = scratch.b;
  pa.reset(n, padding);
  pb.reset(n, padding);
  enum { Valid = kDenoiseFeatures, Unknown, Usable, Shown, Variance, First, Count };
  Planes& fixed = scratch.fixed;
  fixed.reset(Count, n, padding);
  DenoiseRowInputs inputs;
  for (int k = 0; k < kDenoiseFeatures; ++k)
    inputs.features[k] = fixed[k];
  inputs.valid = fixed[Valid], inputs.unknown = fixed[Unknown], inputs.usable = fixed[Usable];
  inputs.shown = fixed[Shown], inputs.variance = fixed[Variance];
  tbb::parallel_for(size_t(0), n, [&](size_t p) {
    for (int k = 0; k < kDenoiseFeatures; ++k)
      fixed[k][p] = im.features[p * kDenoiseFeatures + size_t(k)];
    fixed[Valid][p] = im.valid[p] ? 1.f : 0.f;
    fixed[Unknown][p] = im.unknown[p] ? 1.f : 0.f;
    fixed[Usable][p] = im.valid[p] && !im.unknown[p] ? 1.f : 0.f;
    fixed[First][p] = first[p];
    const vec4f& c = a.color[p];
    const vec3f& e = a.probe[p];
    pa.view.color[0][p] = c.x, pa.view.color[1][p] = c.y, pa.view.color[2][p] = c.z, pa.view.color[3][p] = c.w;
    pa.view.probe[0][p] = e.x, pa.view.probe[1][p] = e.y, pa.view.probe[2][p] = e.z;
    pa.view.lumProbe[p] = a.lumProbe[p];
  });
  float* shownPlane = fixed[Shown];
  float* variancePlane = fixed[Variance];
  for (int l = 0; l < levels; ++l) {
    const DenoisePlanes& in = pa.view;
    levelTiles(regions, l, made, read);
    forTiles(im, read, [&](int, int, size_t p) {
      shownPlane[p] = denoiseShownLuminance(im, vec4f(in.color[0][p], in.color[1][p], in.color[2][p], in.color[3][p]));
    });
    const float* values = l == 0 ? fixed[First] : in.lumProbe;
    forTileRows(im, made, [&](int y, int x0, int x1) {
      varianceFunction(im, inputs, values, l == 0, y, x0, x1, variancePlane);
      rowFunction(im, inputs, in, 1 << l, y, x0, x1, pb.view);
    });
    std::swap(pa, pb);
  }
  tbb::parallel_for(size_t(0), n, [&](size_t p) {
    a.color[p] = vec4f(pa.view.color[0][p], pa.view.color[1][p], pa.view.color[2][p], pa.view.color[3][p]);
    a.probe[p] = vec3f(pa.view.probe[0][p], pa.view.probe[1][p], pa.view.probe[2][p]);
    a.lumProbe[p] = pa.view.lumProbe[p];
  });
}

/// The levels where the guide was drawn: the GPU's kernels, or the CPU's threads (with the
/// memo's planes, where there is a memo).
void filterLevels(const DenoiseImages& im, LevelArrays& a, const std::vector<float>& first,
                  const DenoiseSettings& settings, const TileRegions* regions, Device device, DenoiseMemo* memo) {
  if (device == Device::Cuda) {
    gpu::denoiseLevels(im, a.view(), first.data(), settings.levels);
    return;
  }
  if (memo && !memo->scratch) memo->scratch = std::make_shared<DenoiseScratch>();
  DenoiseScratch local;
  filterOnCpu(im, a, first, settings.levels, regions, settings.perPixel, memo ? *memo->scratch : local);
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
              std::vector<float>* tileNoise, const DenoiseSettings& settings, DenoiseMemo* memo) {
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
  // Given what the last filter of this frame made, only the tiles within the filter's reach of
  // those that took passes since change (the CPU's threads; the GPU filters the whole frame).
  const int tiles = buffer.tileCount();
  std::vector<uint8_t> changed(size_t(tiles), 1), outputs(size_t(tiles), 1);
  std::optional<TileRegions> regions;
  const bool again = memo && guide.device != Device::Cuda && memo->tilePasses.size() == size_t(tiles) &&
                     memo->picture.width == width && memo->picture.height == height;
  if (again) {
    for (int t = 0; t < tiles; ++t)
      changed[size_t(t)] = buffer.tilePasses(t) != memo->tilePasses[size_t(t)];
    regions = regionsAround(changed, buffer.tilesX(), buffer.tilesY(), settings.levels, outputs);
    if (!regions) outputs.assign(size_t(tiles), 1);
  }
  filterLevels(im, a, first, settings, regions ? &*regions : nullptr, guide.device, memo);
  Image out(width, height);
  out.pixels = std::move(a.color);
  std::vector<float> noise(size_t(tiles), 0.f);
  if (regions) { // the tiles the filter did not make are the last filter's
    noise = memo->tileNoise;
    for (int t = 0; t < tiles; ++t)
      if (!outputs[size_t(t)])
        buffer.forTilePixels(t, [&](int, int, size_t p) { out.pixels[p] = memo->picture.pixels[p]; });
  }
  tbb::parallel_for(0, tiles, [&](int tile) {
    if (outputs[size_t(tile)]) noise[size_t(tile)] = buffer.tileRms(tile, [&](size_t p) { return a.probe[p]; });
  });
  if (tileNoise) *tileNoise = noise;
  if (memo) {
    memo->filteredTiles = size_t(std::count(outputs.begin(), outputs.end(), uint8_t(1)));
    memo->picture = out;
    memo->tileNoise = std::move(noise);
    memo->tilePasses.resize(size_t(tiles));
    for (int t = 0; t < tiles; ++t)
      memo->tilePasses[size_t(t)] = buffer.tilePasses(t);
  }
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
  // Each measure filters again only around the tiles that took passes since the last.
  auto memo = std::make_shared<DenoiseMemo>();
  estimate.measure = [&guide, background, picture, settings, memo](const FrameBuffer& buffer,
                                                                   std::vector<float>& tileNoise) {
    Image denoised = denoise(buffer, guide, background, &tileNoise, settings, memo.get());
    if (picture) *picture = std::move(denoised);
  };
  return estimate;
}

} // namespace exa
