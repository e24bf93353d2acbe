// One level of the denoiser's à-trous filter over a row of pixels on the CPU, vectorised across
// the row: denoise_filter.h's denoiseLevelPixel for many pixels at once, lane by lane the same
// taps, weights and sums in the same order (the exponential as exp2Negative's polynomial), so
// that the results equal the per-pixel steps (which the GPU's kernels run) to float round-off.
// The arrays are planes (one float per pixel) with room before and after them for the taps that
// reach past the frame's ends, which are weighed zero. Compiled for the instruction sets of the
// sampling batches and dispatched with them; without Highway the per-pixel steps run.
#pragma once

#include "denoise_filter.h"

namespace exa {

/// One level's colour (premultiplied RGBA) and noise probes, a plane each.
struct DenoisePlanes {
  float* color[4] = {};
  float* probe[3] = {};
  float* lumProbe = nullptr;
};

/// What a level reads besides its input: the guide's features; 1 where a pixel's tile holds
/// passes (else 0), 1 where the pixel has fewer than two passes, 1 where both hold and neither
/// ("usable": its noise is estimated); per pixel the shown luminance of the input and the
/// variance its colour term compares.
struct DenoiseRowInputs {
  const float* features[kDenoiseFeatures] = {};
  const float* valid = nullptr;
  const float* unknown = nullptr;
  const float* usable = nullptr;
  const float* shown = nullptr;
  const float* variance = nullptr;
};

/// Planes reach this many pixels before the first pixel and after the last: the taps of a level
/// at `step` reach 2 step pixels, and a vector of pixels may run 63 past a row's end.
constexpr int denoisePlanePadding(int largestStep) { return 2 * largestStep + 64; }

/// Writes `out` at pixels x0 .. x1 - 1 of row y (at most the frame's width) from `in` around
/// them: denoiseLevelPixel at each.
using DenoiseRowFunction = void (*)(const DenoiseImages& im, const DenoiseRowInputs& inputs, const DenoisePlanes& in,
                                    int step, int y, int x0, int x1, const DenoisePlanes& out);

/// Writes `variance` at pixels x0 .. x1 - 1 of row y: denoiseVariance at each, from the passes'
/// own estimate `values` (`first`) or from the luminance probe `values`.
using DenoiseVarianceRowFunction = void (*)(const DenoiseImages& im, const DenoiseRowInputs& inputs,
                                            const float* values, bool first, int y, int x0, int x1, float* variance);

/// The forms for the instruction set chosen now (null without Highway).
DenoiseRowFunction denoiseRowFunction();
DenoiseVarianceRowFunction denoiseVarianceRowFunction();

} // namespace exa
