// The sums of a progressive image (FrameBuffer): what a renderer's passes add to and what a
// caller resolves into an image, with the statistics of the passes.
#pragma once

#include "exabricks/core/image.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace exa {

struct RenderStats {
  double seconds = 0; ///< wall time of the pass(es)
  uint64_t rays = 0;
  uint64_t samples = 0;        ///< reconstructed samples (value + gradient each)
  uint64_t regionsVisited = 0; ///< segments integrated
  uint64_t surfaceHits = 0;    ///< primary rays that ended on a mesh or iso-surface
  uint64_t isoSamples = 0;     ///< samples taken to find iso-surfaces (incl. root finding)
  uint64_t aoRays = 0;
  uint64_t tiles = 0;       ///< tiles rendered
  double deviceSeconds = 0; ///< a GPU renderer: the time its kernels ran (within `seconds`)
  double samplesPerSecond() const { return seconds > 0 ? double(samples) / double(seconds) : 0; }
  RenderStats& operator+=(const RenderStats& o);
};

/// Square tiles of this many pixels are the unit of work, progress and cancellation.
constexpr int kRenderTile = 16;

/// The sums of a progressive image: per pixel the premultiplied colours of every pass and their
/// squares, and per tile the number of passes added. Owned by the caller; resize() allocates, passes do not.
class FrameBuffer {
public:
  /// Counters of one tile in the last pass that covered it.
  struct TileCounters {
    uint64_t rays = 0, samples = 0, regions = 0, surfaceHits = 0, isoSamples = 0, aoRays = 0;
  };

  FrameBuffer() = default;
  FrameBuffer(int width, int height) { resize(width, height); }
  /// Sets the size and clears; keeps the memory when the size is unchanged.
  void resize(int width, int height);
  void clear();
  int width() const { return width_; }
  int height() const { return height_; }
  int tilesX() const { return tilesX_; }
  int tilesY() const { return tilesY_; }
  int tileCount() const { return tilesX_ * tilesY_; }
  /// Passes added to a tile, and the fewest over all tiles (complete passes).
  uint32_t tilePasses(int tile) const { return tilePasses_[size_t(tile)]; }
  uint32_t passes() const;
  /// Calls f(x, y, pixel index) for the pixels of `tile`, row by row.
  template <typename F> void forTilePixels(int tile, F&& f) const {
    const int tx = tile % tilesX_, ty = tile / tilesX_;
    for (int y = ty * kRenderTile; y < std::min(height_, (ty + 1) * kRenderTile); ++y)
      for (int x = tx * kRenderTile; x < std::min(width_, (tx + 1) * kRenderTile); ++x)
        f(x, y, size_t(y) * size_t(width_) + size_t(x));
  }
  /// Calls f(x, y, pixel index) for the pixels of `tile` in Morton order (2 x 2 blocks, then
  /// 4 x 4, ...): neighbouring rays follow each other, so that the cells one ray brings into the
  /// cache are still there for the rays beside it and below it.
  template <typename F> void forTilePixelsNear(int tile, F&& f) const {
    static_assert(kRenderTile <= 256 && (kRenderTile & (kRenderTile - 1)) == 0, "Morton order of a power of two");
    const int x0 = tile % tilesX_ * kRenderTile, y0 = tile / tilesX_ * kRenderTile;
    for (int i = 0; i < kRenderTile * kRenderTile; ++i) {
      int dx = 0, dy = 0;
      for (int b = 0; (1 << b) < kRenderTile; ++b) {
        dx |= ((i >> (2 * b)) & 1) << b;
        dy |= ((i >> (2 * b + 1)) & 1) << b;
      }
      const int x = x0 + dx, y = y0 + dy;
      if (x < width_ && y < height_) f(x, y, size_t(y) * size_t(width_) + size_t(x));
    }
  }
  /// The RMS over a tile's pixels and channels of `perPixel(pixel index)` (a vec3f each);
  /// infinite for a tile with fewer than two passes (its noise is not known).
  template <typename F> float tileRms(int tile, F&& perPixel) const {
    if (tilePasses_.at(size_t(tile)) < 2) return std::numeric_limits<float>::infinity();
    double squared = 0;
    int count = 0;
    forTilePixels(tile, [&](int, int, size_t i) {
      const vec3f v = perPixel(i);
      squared += double(v.x) * double(v.x) + double(v.y) * double(v.y) + double(v.z) * double(v.z);
      count += 3;
    });
    return count ? float(std::sqrt(squared / count)) : 0.f;
  }
  /// Passes per pixel, averaged over the pixels of the tiles that hold any.
  double meanPasses() const;
  /// The noise a tile's passes estimate in its 8-bit sRGB image composited over `background`
  /// (linear RGB): per pixel and channel the standard error of the mean, carried through the sRGB
  /// curve, in 1/255 steps; RMS over the tile. Infinite with fewer than two passes.
  float tileNoise(int tile, const vec3f& background) const;
  /// Passes added to the tile of a pixel.
  uint32_t pixelPasses(size_t pixel) const;
  /// A pixel's standard error of the mean of its passes, per premultiplied channel (infinite with
  /// fewer than two passes).
  vec4f pixelError(size_t pixel) const;
  /// A pixel's noise per channel as tileNoise() measures it, in 1/255 steps of its 8-bit sRGB
  /// value over `background`.
  vec3f pixelNoise(size_t pixel, const vec3f& background) const;
  /// The mean of the passes (each tile divided by its own count; tiles without a pass are
  /// transparent black). The steps debug view resolves to a heat map scaled to its maximum.
  void resolve(Image& out) const;
  Image resolve() const;
  /// Statistics summed over the passes since the last clear.
  const RenderStats& stats() const { return stats_; }

  /// The buffer's sums as plain arrays, for combining the tile shares that several processes
  /// rendered into buffers of one size: adding the arrays element by element (tiles a process did
  /// not render hold zeros) gives the buffer of all the shares, bit for bit.
  struct Sums {
    float* colors;  ///< 4 per pixel (premultiplied RGBA)
    float* squares; ///< 4 per pixel, the colours' squares
    float* steps;   ///< 1 per pixel (steps debug view)
    size_t pixels;
    uint32_t* tilePasses; ///< 1 per tile
    size_t tiles;
    RenderStats* stats;
    bool* stepsView; ///< whether the sums are of the steps debug view
  };
  Sums sums();

private:
  friend class Renderer;
  void add(size_t pixel, const vec4f& color) {
    sum_[pixel] += color;
    squares_[pixel] += color * color;
  }
  int width_ = 0, height_ = 0, tilesX_ = 0, tilesY_ = 0;
  std::vector<vec4f> sum_, squares_;
  std::vector<float> steps_; ///< samples per pixel, summed (steps debug view)
  std::vector<uint32_t> tilePasses_;
  std::vector<TileCounters> counters_;
  std::vector<int> passTiles_; ///< the tiles of the pass under way (room for every tile)
  bool stepsView_ = false;
  RenderStats stats_;
};

} // namespace exa
