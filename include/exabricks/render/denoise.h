// A denoiser for path-traced frames: an edge-avoiding à-trous wavelet filter (a 5×5 B3-spline
// kernel at steps 1, 2, 4, ... pixels) whose weights stop at edges of noise-free feature buffers
// and at colour differences larger than the noise the passes estimate.
//
// The features are ray-marched pictures of the same frame (DenoiseGuide): unshaded, the medium's
// and the surfaces' colour gathered with their opacity along each ray (albedo and coverage),
// and, where the scene has surfaces, lit with analytic shading, whose brightness follows their
// normals and the density gradient. Being marched, they carry no noise, so the filter keeps every edge of the
// data's structure; the colour term keeps the edges of the light (shadows) that the noise cannot
// explain. Every weight is normalised, so flat areas keep their mean: the filter removes noise,
// not light.
//
// The same weights carry a probe of the passes' noise (each pixel's standard error with a random
// sign), which gives per tile the noise the denoised picture keeps: a noise target (Frame::
// noiseTarget) is then met by the denoised picture, with far fewer passes.
#pragma once

#include "exabricks/core/image.h"
#include "exabricks/render/frame_buffer.h"
#include "exabricks/render/renderer.h"

#include <memory>
#include <vector>

namespace exa {

/// The feature buffers of a frame (each the frame's size, premultiplied RGBA).
struct DenoiseGuide {
  Image albedo; ///< ray-marched without shading: colour and opacity along each ray
  /// Ray-marched with analytic shading: brightness following gradients and normals (only for
  /// scenes with surfaces; empty otherwise).
  Image shaded;
  double seconds = 0; ///< time the two pictures took
  /// Where the filter runs: where the guide was rendered (a frame drawn on the GPU is filtered
  /// there; the CPU and the portable back end filter on the CPU's threads).
  Device device = Device::Cpu;
  bool empty() const { return albedo.pixels.empty(); }
};

/// The guide of `frame` for the renderer's scene: one jittered pass of each marched picture. The
/// renderer's scene is set to each marched variant and back (what differs is rebuilt); on
/// return the renderer holds its scene as before.
DenoiseGuide renderDenoiseGuide(Renderer& renderer, const Frame& frame);

struct DenoiseSettings {
  int levels = 5; ///< à-trous steps 1, 2, ..., 2^(levels-1) pixels
  /// Feature distance (square roots of the premultiplied colours) at 1/e. Larger blurs more of the
  /// data's faint structure (cosmic step: bias 0.67, 0.82, 1.16 of 255 at 0.05, 0.08, 0.15);
  /// smaller leaves more noise for more passes to remove.
  float guideSigma = 0.08f;
  float colorSigma = 8.f; ///< colour difference, in standard errors of the noise, at 1/e
  /// On the CPU, the per-pixel steps the GPU's kernels run instead of their vectorised form (the
  /// same picture to float round-off; for tests and comparisons).
  bool perPixel = false;
};

/// The denoised mean of the buffer's passes (tiles without a pass stay transparent black).
/// `tileNoise`, where given, receives per tile the noise the denoised picture keeps in its 8-bit
/// sRGB image over `background`, in 1/255 steps (RMS over the tile's pixels and channels;
/// infinite for a tile with fewer than two passes).
/// `memo`, where given, keeps what the filter made for the next denoise() of the same frame
/// and guide: that one filters again (on the CPU) only the tiles within the filter's reach of the
/// tiles that took passes in between, and equals a whole filter.
struct DenoiseScratch;
struct DenoiseMemo {
  Image picture;
  std::vector<float> tileNoise;
  std::vector<uint32_t> tilePasses; ///< per tile, the passes filtered
  size_t filteredTiles = 0;         ///< the tiles whose outputs the last filter made
  /// The CPU filter's arrays, kept for the next filter instead of allocated and cleared again.
  std::shared_ptr<DenoiseScratch> scratch;
};
Image denoise(const FrameBuffer& buffer, const DenoiseGuide& guide, const vec3f& background,
              std::vector<float>* tileNoise = nullptr, const DenoiseSettings& settings = {},
              DenoiseMemo* memo = nullptr);

/// A whole frame as the front ends show it: Renderer::render, or where the frame is denoised
/// (denoises()) the guide, the passes to the denoised picture's noise target and the filter (the
/// statistics' seconds count all three).
Image renderPicture(Renderer& renderer, const Frame& frame, RenderStats* stats = nullptr);

/// The noise a frame's denoised picture keeps, per tile (for Renderer::renderSampled): denoise()'s
/// tile noise. The guide (and `picture`) must outlive the estimate. `picture`, where given,
/// receives the denoised picture of each measure: after rounds to a noise target, the picture of
/// the buffer as they left it.
TileNoiseEstimate denoisedNoise(const DenoiseGuide& guide, const vec3f& background, Image* picture = nullptr,
                                const DenoiseSettings& settings = {});

} // namespace exa
