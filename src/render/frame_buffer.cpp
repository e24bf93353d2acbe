#include "exabricks/render/frame_buffer.h"

#include "exabricks/core/error.h"
#include "exabricks/render/transfer_function.h"

#include "exabricks/core/color.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace exa {

RenderStats& RenderStats::operator+=(const RenderStats& o) {
  seconds += o.seconds;
  rays += o.rays;
  samples += o.samples;
  regionsVisited += o.regionsVisited;
  surfaceHits += o.surfaceHits;
  isoSamples += o.isoSamples;
  aoRays += o.aoRays;
  tiles += o.tiles;
  deviceSeconds += o.deviceSeconds;
  return *this;
}

void FrameBuffer::resize(int width, int height) {
  if (width < 1 || height < 1 || width > 32768 || height > 32768)
    fail("frame buffer size ", width, "x", height, " is out of range (1..32768)");
  width_ = width;
  height_ = height;
  tilesX_ = (width + kRenderTile - 1) / kRenderTile;
  tilesY_ = (height + kRenderTile - 1) / kRenderTile;
  sum_.resize(size_t(width) * size_t(height));
  squares_.resize(size_t(width) * size_t(height));
  steps_.resize(size_t(width) * size_t(height));
  tilePasses_.resize(size_t(tilesX_) * size_t(tilesY_));
  counters_.resize(size_t(tilesX_) * size_t(tilesY_));
  passTiles_.reserve(counters_.size());
  clear();
}

void FrameBuffer::clear() {
  std::fill(sum_.begin(), sum_.end(), vec4f());
  std::fill(squares_.begin(), squares_.end(), vec4f());
  std::fill(steps_.begin(), steps_.end(), 0.f);
  std::fill(tilePasses_.begin(), tilePasses_.end(), 0u);
  stats_ = RenderStats();
}

FrameBuffer::Sums FrameBuffer::sums() {
  static_assert(sizeof(vec4f) == 4 * sizeof(float), "vec4f must be four packed floats");
  return {reinterpret_cast<float*>(sum_.data()),
          reinterpret_cast<float*>(squares_.data()),
          steps_.data(),
          sum_.size(),
          tilePasses_.data(),
          tilePasses_.size(),
          &stats_,
          &stepsView_};
}

uint32_t FrameBuffer::passes() const {
  if (tilePasses_.empty()) return 0;
  return *std::min_element(tilePasses_.begin(), tilePasses_.end());
}

double FrameBuffer::meanPasses() const {
  double passes = 0, pixels = 0;
  for (int t = 0; t < tileCount(); ++t) {
    if (tilePasses_[size_t(t)] == 0) continue;
    const int tx = t % tilesX_, ty = t / tilesX_;
    const double area = double(std::min(kRenderTile, width_ - tx * kRenderTile)) *
                        double(std::min(kRenderTile, height_ - ty * kRenderTile));
    passes += area * tilePasses_[size_t(t)];
    pixels += area;
  }
  return pixels > 0 ? passes / pixels : 0.0;
}

uint32_t FrameBuffer::pixelPasses(size_t pixel) const {
  const size_t x = pixel % size_t(width_), y = pixel / size_t(width_);
  return tilePasses_[(y / kRenderTile) * size_t(tilesX_) + x / kRenderTile];
}

vec4f FrameBuffer::pixelError(size_t pixel) const {
  const uint32_t n = pixelPasses(pixel);
  if (n < 2) {
    const float inf = std::numeric_limits<float>::infinity();
    return {inf, inf, inf, inf};
  }
  const float inv = 1.f / float(n);
  // The squared standard error of a mean of n samples: (E[x²] - E[x]²) / (n - 1).
  auto error = [&](float sum, float squares) {
    const float mean = sum * inv;
    return std::sqrt(std::max(0.f, squares * inv - mean * mean) / float(n - 1));
  };
  const vec4f& s = sum_[pixel];
  const vec4f& q = squares_[pixel];
  return {error(s.x, q.x), error(s.y, q.y), error(s.z, q.z), error(s.w, q.w)};
}

vec3f FrameBuffer::pixelNoise(size_t pixel, const vec3f& background) const {
  const uint32_t n = pixelPasses(pixel);
  if (n < 2) return vec3f(std::numeric_limits<float>::infinity());
  const float inv = 1.f / float(n);
  const vec4f s = sum_[pixel] * inv, e = pixelError(pixel);
  const float means[3] = {s.x, s.y, s.z}, errors[3] = {e.x, e.y, e.z},
              behind[3] = {background.x, background.y, background.z};
  float steps[3];
  for (int c = 0; c < 3; ++c) {
    // Over the background: colour + (1 - alpha) background; its error at most the sum of both.
    const float shown = means[c] + (1.f - s.w) * behind[c];
    const float err = errors[c] + behind[c] * e.w;
    steps[c] = (linearToSrgb(std::clamp(shown + err, 0.f, 1.f)) - linearToSrgb(std::clamp(shown - err, 0.f, 1.f))) *
               0.5f * 255.f;
  }
  return {steps[0], steps[1], steps[2]};
}

float FrameBuffer::tileNoise(int tile, const vec3f& background) const {
  return tileRms(tile, [&](size_t i) { return pixelNoise(i, background); });
}

void FrameBuffer::resolve(Image& out) const {
  if (out.width != width_ || out.height != height_) out = Image(width_, height_);
  auto tilePassesAt = [&](int x, int y) {
    return tilePasses_[size_t(y / kRenderTile) * size_t(tilesX_) + size_t(x / kRenderTile)];
  };
  // The steps view: samples per ray, averaged over the passes, scaled to the image's maximum.
  float maxSteps = 1.f;
  if (stepsView_)
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x)
        if (const uint32_t n = tilePassesAt(x, y))
          maxSteps = std::max(maxSteps, steps_[size_t(y) * size_t(width_) + size_t(x)] * (1.f / float(n)));
  const ColorMap heat = stepsView_ ? builtinColorMap("inferno") : ColorMap();
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const size_t i = size_t(y) * size_t(width_) + size_t(x);
      const uint32_t n = tilePassesAt(x, y);
      if (n == 0) {
        out.pixels[i] = vec4f();
        continue;
      }
      const float inv = 1.f / float(n);
      if (stepsView_) {
        const vec3f c = heat.at(steps_[i] * inv / maxSteps);
        out.pixels[i] = {c.x, c.y, c.z, 1.f};
      } else {
        const vec4f& s = sum_[i];
        out.pixels[i] = {s.x * inv, s.y * inv, s.z * inv, s.w * inv};
      }
    }
}

Image FrameBuffer::resolve() const {
  Image image;
  resolve(image);
  return image;
}

} // namespace exa
