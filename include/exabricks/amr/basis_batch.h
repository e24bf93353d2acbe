// Reconstruction of several samples at once: the vectorised form of sampleRegion (basis.h) for
// samples that share one region, as consecutive samples along a ray inside an active brick region
// do. Every lane sums the same cells with the same reference value as basis.h; the trilinear sums
// are factored axis by axis (missing cells get a zero hat factor), so the results equal the scalar
// ones to float round-off. The library is compiled for several instruction sets (SSE4, AVX2,
// AVX-512 where the compiler has them; Highway) and picks the widest the CPU supports at run time;
// without Highway the batch runs the scalar code.
#pragma once

#include "exabricks/amr/basis.h"
#include "exabricks/amr/gradient_pack.h"

#include <cstdint>
#include <string>
#include <vector>

namespace exa {

/// Samples per batch (the lanes of AVX-512 floats; narrower vectors take several steps).
constexpr int kSampleBatch = 16;

/// Positions in (lattice units) and results out; entries at and beyond `count` are ignored.
struct SampleBatch {
  int count = 0;
  /// Positions, with room past kSampleBatch for whole-vector stores of a placement that appends
  /// to a partly filled batch (render/shade_batch.h).
  alignas(64) float x[2 * kSampleBatch], y[2 * kSampleBatch], z[2 * kSampleBatch];
  alignas(64) float value[kSampleBatch];
  alignas(64) float gx[kSampleBatch], gy[kSampleBatch], gz[kSampleBatch]; ///< per lattice unit
  alignas(64) int32_t valid[kSampleBatch];                                ///< nonzero where some cell has weight
};

/// Reconstructs every sample of the batch from the bricks of region `regionIndex` (value, and the
/// gradient when asked).
void sampleRegionBatch(const FieldView& view, uint32_t regionIndex, SampleBatch& batch, bool gradient);

/// The same over an explicit list of bricks (ascending indices into view.bricks) instead of one
/// region's: samples of several neighbouring regions reconstructed at once over the union of their
/// lists. A brick whose support holds none of a sample's neighbourhood weighs nothing there, and
/// the union keeps every list's order, so each sample sums what its own region's list gives it.
void sampleBricksBatch(const FieldView& view, const uint32_t* brickIds, uint32_t brickCount, SampleBatch& batch,
                       bool gradient);

/// The same through basis.h's scalar sampleBricks, one sample after another (the reference).
inline void sampleBricksBatchScalar(const FieldView& view, const uint32_t* brickIds, uint32_t brickCount,
                                    SampleBatch& batch, bool gradient) {
  for (int i = 0; i < batch.count; ++i) {
    float v = 0.f;
    vec3f g(0.f);
    const bool ok =
        sampleBricks(view, brickIds, brickCount, vec3f(batch.x[i], batch.y[i], batch.z[i]), v, gradient ? &g : nullptr);
    batch.valid[i] = ok;
    batch.value[i] = ok ? v : 0.f;
    batch.gx[i] = g.x, batch.gy[i] = g.y, batch.gz[i] = g.z;
  }
}

/// sampleRegionBatch through basis.h's scalar code (the reference).
inline void sampleRegionBatchScalar(const FieldView& view, uint32_t regionIndex, SampleBatch& batch, bool gradient) {
  const Region& region = view.regions[regionIndex];
  sampleBricksBatchScalar(view, view.brickIds + region.brickBegin, region.brickCount, batch, gradient);
}

/// Smooth shading's packed gradient fields of a field (amr/gradients.h): per cell, in the field's
/// brick order, two words, the value's bits and the packed gradient's, and per brick the scale bias
/// the gradients decode with.
struct PackedGradientView {
  const uint32_t* cells = nullptr;
  const int32_t* scaleBias = nullptr;
};

/// A field's value (with `withValue`; out[0], else out[0] is not written) and its gradient
/// (out[1], out[2], out[3]: the packed gradient fields reconstructed like values, each cell
/// decoded to unpackGradient's floats) at every sample of the batch, in one pass over the bricks.
/// `valid`, where not null, gets sampleBricksBatch's valid flags. The batch is left as it is.
void sampleShadedBatch(const FieldView& view, const PackedGradientView& gradients, bool withValue,
                       const uint32_t* brickIds, uint32_t brickCount, const SampleBatch& batch, float* const* out,
                       int32_t* valid = nullptr);

/// The same sample after sample through basis.h's BasisAccumulator4 (the reference).
inline void sampleShadedBatchScalar(const FieldView& view, const PackedGradientView& gradients, bool withValue,
                                    const uint32_t* brickIds, uint32_t brickCount, const SampleBatch& batch,
                                    float* const* out, int32_t* valid = nullptr) {
  for (int i = 0; i < batch.count; ++i) {
    BasisAccumulator4 acc;
    const vec3f p(batch.x[i], batch.y[i], batch.z[i]);
    for (uint32_t k = 0; k < brickCount; ++k) {
      const Brick& brick = view.bricks[brickIds[k]];
      const float* values = view.values + brick.valueOffset;
      const uint32_t* cells = gradients.cells + 2 * size_t(brick.valueOffset);
      const int32_t bias = gradients.scaleBias[brickIds[k]];
      acc.addBrickWith(
          brick,
          [&](uint32_t c) {
            const vec3f g = unpackGradient(cells[2 * size_t(c) + 1], bias);
            return vec4f(withValue ? values[c] : 0.f, g.x, g.y, g.z);
          },
          p);
    }
    const vec4f r = acc.valid() ? acc.value() : vec4f();
    if (withValue) out[0][i] = r.x;
    out[1][i] = r.y, out[2][i] = r.z, out[3][i] = r.w;
    if (valid) valid[i] = acc.valid();
  }
}

/// sampleRegionBatch's implementation for the instruction set chosen now: a caller that makes
/// many batches looks it up once instead of dispatching at every call. Valid until
/// useBatchTarget changes the choice.
using SampleRegionBatchFunction = void (*)(const FieldView&, uint32_t, SampleBatch&, bool);
SampleRegionBatchFunction sampleRegionBatchFunction();
/// sampleBricksBatch's implementation for the instruction set chosen now (as above).
using SampleBricksBatchFunction = void (*)(const FieldView&, const uint32_t*, uint32_t, SampleBatch&, bool);
SampleBricksBatchFunction sampleBricksBatchFunction();
/// sampleShadedBatch's implementation for the instruction set chosen now (as above).
using SampleShadedBatchFunction = void (*)(const FieldView&, const PackedGradientView&, bool, const uint32_t*, uint32_t,
                                           const SampleBatch&, float* const*, int32_t*);
SampleShadedBatchFunction sampleShadedBatchFunction();

/// The instruction set sampleRegionBatch runs with on this CPU ("AVX2", "AVX3", "SSE4", ...;
/// "scalar" when built without Highway).
const char* batchTargetName();
/// The instruction sets this CPU can run sampleRegionBatch with, best first.
std::vector<std::string> batchTargets();
/// Runs sampleRegionBatch with the named instruction set (one of batchTargets()); an empty name
/// returns to the best. False for a name not in the list. For tests and benchmarks; not
/// thread-safe with batches in flight.
bool useBatchTarget(const std::string& name);

} // namespace exa
