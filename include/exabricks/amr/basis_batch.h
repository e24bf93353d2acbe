// Reconstruction of several samples at once: the vectorised form of sampleRegion (basis.h) for
// samples that share one region, as consecutive samples along a ray inside an active brick region
// do. Every lane sums the same cells with the same reference value as basis.h; the trilinear sums
// are factored axis by axis (missing cells get a zero hat factor), so the results equal the scalar
// ones to float round-off. The library is compiled for several instruction sets (SSE4, AVX2,
// AVX-512 where the compiler has them; Highway) and picks the widest the CPU supports at run time;
// without Highway the batch runs the scalar code.
#pragma once

#include "exabricks/amr/basis.h"

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

/// Most value arrays sampleFieldsBatch reconstructs in one pass (a field and its three gradient
/// fields).
constexpr int kMaxBatchFields = 4;

/// `fields` (1..kMaxBatchFields) value arrays laid out as view.values (the same bricks: a field and
/// its gradient fields, say) reconstructed at every sample of the batch in one pass over the
/// bricks: each brick's hat factors and corner indices are found once and applied to every array,
/// so out[f][i] equals sampleBricksBatch's value of view with its values replaced by values[f] (0
/// where no cell has weight), to the bit. `valid`, where not null, gets sampleBricksBatch's valid
/// flags (the same for every array). The batch's own results are left as they are.
void sampleFieldsBatch(const FieldView& view, const float* const* values, int fields, const uint32_t* brickIds,
                       uint32_t brickCount, const SampleBatch& batch, float* const* out, int32_t* valid = nullptr);

/// The same field after field through sampleBricksBatchScalar (the reference).
inline void sampleFieldsBatchScalar(const FieldView& view, const float* const* values, int fields,
                                    const uint32_t* brickIds, uint32_t brickCount, const SampleBatch& batch,
                                    float* const* out, int32_t* valid = nullptr) {
  for (int f = 0; f < fields; ++f) {
    FieldView v = view;
    v.values = values[f];
    SampleBatch b;
    b.count = batch.count;
    for (int i = 0; i < batch.count; ++i)
      b.x[i] = batch.x[i], b.y[i] = batch.y[i], b.z[i] = batch.z[i];
    sampleBricksBatchScalar(v, brickIds, brickCount, b, false);
    for (int i = 0; i < batch.count; ++i) {
      out[f][i] = b.valid[i] ? b.value[i] : 0.f;
      if (valid && f == 0) valid[i] = b.valid[i];
    }
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
/// sampleFieldsBatch's implementation for the instruction set chosen now (as above).
using SampleFieldsBatchFunction = void (*)(const FieldView&, const float* const*, int, const uint32_t*, uint32_t,
                                           const SampleBatch&, float* const*, int32_t*);
SampleFieldsBatchFunction sampleFieldsBatchFunction();

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
