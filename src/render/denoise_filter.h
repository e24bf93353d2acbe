// The per-pixel steps of the denoiser's à-trous filter (render/denoise.h), written once for the
// CPU's threads and the CUDA back end's kernels: the variance a pixel's colour term compares and
// one level of the edge-avoiding 5×5 B3-spline kernel. Pointers are to the host's or the device's
// arrays of width × height pixels.
#pragma once

#include "exabricks/core/color.h"
#include "exabricks/render/sample_math.h"

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace exa {

/// Per pixel: square roots of the guide's premultiplied colours (albedo RGBA, shaded RGB).
constexpr int kDenoiseFeatures = 7;

/// What stays the same through the levels.
struct DenoiseImages {
  int width = 0, height = 0;
  const float* features = nullptr;  ///< kDenoiseFeatures per pixel
  const uint8_t* valid = nullptr;   ///< the pixel's tile holds passes
  const uint8_t* unknown = nullptr; ///< fewer than two passes: no estimate of the noise (no colour term)
  vec3f background{0.f};
  float guideScale = 0.f; ///< 1 / guide sigma²
  float colorSigma = 0.f; ///< colour difference at 1/e, in standard errors of the noise
};

/// What one level filters: the colour (premultiplied RGBA) and two probes of its noise, carried
/// with the same weights: per channel in 1/255 steps of the 8-bit sRGB picture, and its luminance
/// over the background (linear), whose square estimates the variance the colour term compares.
struct DenoiseLevel {
  vec4f* color = nullptr;
  vec3f* probe = nullptr;
  float* lumProbe = nullptr;
  /// Per pixel, denoiseShownLuminance of `color`, where the caller has it (null: found at each of
  /// the 25 taps that read the pixel).
  const float* shown = nullptr;
};

/// The variance of a pixel without an estimate of its noise (fewer than two passes): no colour
/// term; finite, since its weights squared may be zero.
constexpr float kDenoiseUnknownVariance = 1e30f;
/// Added to the colour term's standard error, so that a pixel without noise divides by no zero.
constexpr float kDenoiseErrorFloor = 1e-6f;
/// log2 e: e^-x is 2^-(x log2 e).
constexpr float kDenoiseLog2E = 1.44269504f;

/// The B3 spline's weights 1/16, 1/4, 3/8, 1/4, 1/16.
EXA_HOST_DEVICE inline float denoiseB3(int i) { return i == 2 ? 0.375f : (i == 1 || i == 3) ? 0.25f : 0.0625f; }

EXA_HOST_DEVICE inline float denoiseShownLuminance(const DenoiseImages& im, const vec4f& c) {
  return luminance(c.rgb() + im.background * (1.f - c.w));
}

/// A neighbour's weight in denoiseVariance, (dx, dy) from the pixel: the 3×3 binomial's before
/// the first level, else 1.
EXA_HOST_DEVICE inline float denoiseVarianceWeight(bool first, int dx, int dy) {
  return first ? (dx == 0 ? 2.f : 1.f) * (dy == 0 ? 2.f : 1.f) : 1.f;
}

/// The variance of pixel (x, y)'s luminance that the colour term compares: the passes' own
/// estimate `first` (a 3×3 binomial blur of it: one pixel's is noisy) before the first level, or
/// (first == nullptr) the luminance probe's square averaged over 5×5 pixels. The probe carries
/// the correlation the levels leave between neighbours, which a variance filtered with the
/// squared weights misses; missed, the colour term would take the blotches of the remaining
/// noise for edges.
EXA_HOST_DEVICE inline float denoiseVariance(const DenoiseImages& im, const DenoiseLevel& in, const float* first, int x,
                                             int y) {
  const size_t p = size_t(y) * size_t(im.width) + size_t(x);
  if (im.unknown[p]) return kDenoiseUnknownVariance;
  const int r = first ? 1 : 2;
  float sum = 0.f, weights = 0.f;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const int qx = x + dx, qy = y + dy;
      if (qx < 0 || qy < 0 || qx >= im.width || qy >= im.height) continue;
      const size_t q = size_t(qy) * size_t(im.width) + size_t(qx);
      if (!im.valid[q] || im.unknown[q]) continue;
      const float w = denoiseVarianceWeight(first != nullptr, dx, dy);
      sum += w * (first ? first[q] : in.lumProbe[q] * in.lumProbe[q]);
      weights += w;
    }
  return weights > 0.f ? sum / weights : 0.f;
}

/// The colour term's scale at a pixel whose luminance has `variance`: 1 over colorSigma standard
/// errors of its noise.
EXA_HOST_DEVICE inline float denoiseColorScale(const DenoiseImages& im, float variance) {
  return 1.f / (im.colorSigma * std::sqrt(variance) + kDenoiseErrorFloor);
}

/// A tap's weight: `spline` (the B3 spline's of its two axes) times e^-(the squared distance of
/// the features over the guide's sigma² + the shown luminances' difference over colorScale),
/// the exponential as 2^-(... log2 e) by the polynomial the opacities take (a libm call per tap
/// took a third of the CPU's filter).
EXA_HOST_DEVICE inline float denoiseTapWeight(const DenoiseImages& im, float spline, float distance, float lp, float lq,
                                              float colorScale) {
  const float colorTerm = std::fabs(lp - lq) * colorScale;
  return spline * exp2Negative(-(distance * im.guideScale + colorTerm) * kDenoiseLog2E);
}

/// One à-trous level at `step` pixels for pixel (x, y): `out` at the pixel from `in` around it.
EXA_HOST_DEVICE inline void denoiseLevelPixel(const DenoiseImages& im, const DenoiseLevel& in, const float* variance,
                                              int step, int x, int y, const DenoiseLevel& out) {
  const size_t p = size_t(y) * size_t(im.width) + size_t(x);
  if (!im.valid[p]) {
    out.color[p] = in.color[p];
    out.probe[p] = in.probe[p];
    out.lumProbe[p] = in.lumProbe[p];
    return;
  }
  const float lp = in.shown ? in.shown[p] : denoiseShownLuminance(im, in.color[p]);
  const float colorScale = denoiseColorScale(im, variance[p]);
  const float* fp = im.features + p * kDenoiseFeatures;
  vec4f color;
  vec3f probe(0.f);
  float weights = 0.f, lumProbe = 0.f;
  for (int j = 0; j < 5; ++j) {
    const int qy = y + (j - 2) * step;
    if (qy < 0 || qy >= im.height) continue;
    for (int i = 0; i < 5; ++i) {
      const int qx = x + (i - 2) * step;
      if (qx < 0 || qx >= im.width) continue;
      const size_t q = size_t(qy) * size_t(im.width) + size_t(qx);
      if (!im.valid[q]) continue;
      const float* fq = im.features + q * kDenoiseFeatures;
      float distance = 0.f;
      for (int k = 0; k < kDenoiseFeatures; ++k) {
        const float d = fp[k] - fq[k];
        distance += d * d;
      }
      const float lq = in.shown ? in.shown[q] : denoiseShownLuminance(im, in.color[q]);
      const float w = denoiseTapWeight(im, denoiseB3(i) * denoiseB3(j), distance, lp, lq, colorScale);
      color += in.color[q] * w;
      probe = probe + in.probe[q] * w;
      lumProbe += w * in.lumProbe[q];
      weights += w;
    }
  }
  const float inv = 1.f / weights; // the pixel itself weighs (3/8)² > 0
  out.color[p] = color * inv;
  out.probe[p] = probe * inv;
  out.lumProbe[p] = lumProbe * inv;
}

} // namespace exa
