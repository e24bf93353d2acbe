// Transfer function, opacity correction and volume shading for a whole sampling batch: the
// vectorised form of sample_math.h's tfLookup, correctedOpacity and shadeVolumeSample, lane by
// lane the same operations, so the results equal the scalar ones to float round-off. Compiled for
// the same instruction sets as the reconstruction batches (amr/basis_batch.h) and dispatched with
// them; without Highway the scalar functions run lane after lane.
#pragma once

#include "exabricks/amr/basis_batch.h"
#include "exabricks/render/sample_math.h"

#include <algorithm>
#include <cmath>

namespace exa {

/// Appends the segment's next samples on the ray org + t dir to `batch`, as many as fit (up to
/// kSampleBatch in all): their positions from index batch.count on (count updated), their
/// intervals' lengths into `lengths` at the same indices (2 kSampleBatch entries: whole vectors
/// are stored); advances the march. Returns how many it appended, 0 at the segment's end.
int placeSamples(const vec3f& org, const vec3f& dir, SegmentMarch& m, SampleBatch& batch, float* lengths);

/// The same interval after interval (the reference, and where the vector form cannot promise
/// the same positions).
inline int placeSamplesScalar(const vec3f& org, const vec3f& dir, SegmentMarch& m, SampleBatch& batch, float* lengths) {
  const int first = batch.count;
  int n = first;
  while (n < kSampleBatch && m.a < m.end) {
    const float b = m.intervalEnd();
    if (!(b > m.a)) break;
    m.k += 1.f;
    lengths[n] = b - m.a;
    const vec3f p = org + dir * (0.5f * (m.a + b));
    batch.x[n] = p.x, batch.y[n] = p.y, batch.z[n] = p.z;
    ++n;
    m.a = b;
  }
  batch.count = n;
  return n - first;
}

/// The transfer function at every sample of a batch, one array per channel: linear RGB and log2
/// of the transmittance of one reference width (0 where the sample has no value).
struct TfBatch {
  alignas(64) float r[kSampleBatch], g[kSampleBatch], b[kSampleBatch];
  alignas(64) float logT[kSampleBatch];
};

/// Looks up the first `batch.count` samples; returns whether any of them shows (logT < 0).
bool tfLookupBatch(const TfTableView& tf, const SampleBatch& batch, TfBatch& out);

/// What the volume shading of a batch needs besides the samples.
struct VolumeShadeParams {
  float invReferenceWidth = 1.f; ///< opacity correction: lengths per reference width
  bool shade = true;             ///< gradient shading (batch gradients filled); else the plain colour
  vec3f gradientScale{1.f};      ///< lattice to world gradient units, per axis
  vec3f light{0.f}, halfVector{0.f};
  ShadingTerms terms;
  /// shadeVolumeSample's fade scale, as fadeScaleAt(fadeWidth[i], fadeByValue, value), per sample
  /// (kSampleBatch entries: the samples of one batch may come from regions of several widths).
  const float* fadeWidth = nullptr;
  bool fadeByValue = false;
};

/// Opacity and colour of every sample (`lengths` has kSampleBatch entries): alpha = correctedOpacity(logT, lengths[i]);
/// colour the table's, shaded by shadeVolumeSample where asked. Samples with logT >= 0 get alpha 0.
struct ShadedBatch {
  alignas(64) float alpha[kSampleBatch];
  alignas(64) float r[kSampleBatch], g[kSampleBatch], b[kSampleBatch];
};

void shadeVolumeBatch(const SampleBatch& batch, const TfBatch& tf, const float* lengths, const VolumeShadeParams& p,
                      ShadedBatch& out);

/// placeSamples, sampleBricksBatch, sampleShadedBatch, tfLookupBatch and shadeVolumeBatch for the
/// instruction set
/// chosen now, looked up once for the many batches of a ray (see sampleRegionBatchFunction).
struct BatchFunctions {
  int (*place)(const vec3f&, const vec3f&, SegmentMarch&, SampleBatch&, float*);
  SampleBricksBatchFunction sample;
  SampleShadedBatchFunction sampleShaded;
  bool (*tfLookup)(const TfTableView&, const SampleBatch&, TfBatch&);
  void (*shade)(const SampleBatch&, const TfBatch&, const float*, const VolumeShadeParams&, ShadedBatch&);
};
BatchFunctions batchFunctions();

/// The same lane after lane through sample_math.h (the reference, and the path without Highway).
inline bool tfLookupBatchScalar(const TfTableView& tf, const SampleBatch& batch, TfBatch& out) {
  bool any = false;
  for (int i = 0; i < batch.count; ++i) {
    const vec4f c = batch.valid[i] ? tfLookup(tf, batch.value[i]) : vec4f();
    out.r[i] = c.x, out.g[i] = c.y, out.b[i] = c.z, out.logT[i] = c.w;
    any = any || c.w < 0.f;
  }
  return any;
}

inline void shadeVolumeBatchScalar(const SampleBatch& batch, const TfBatch& tf, const float* lengths,
                                   const VolumeShadeParams& p, ShadedBatch& out) {
  for (int i = 0; i < batch.count; ++i) {
    vec3f c(tf.r[i], tf.g[i], tf.b[i]);
    out.alpha[i] = tf.logT[i] < 0.f ? correctedOpacity(tf.logT[i], lengths[i], p.invReferenceWidth) : 0.f;
    if (p.shade) {
      const float fade = fadeScaleAt(p.fadeWidth[i], p.fadeByValue, batch.value[i]);
      const vec3f grad = vec3f(batch.gx[i], batch.gy[i], batch.gz[i]) * p.gradientScale;
      c = shadeVolumeSample(c, grad, p.light, p.halfVector, p.terms, fade);
    }
    out.r[i] = c.x, out.g[i] = c.y, out.b[i] = c.z;
  }
}

/// The same four functions lane after lane (the reference table; RendererOptions::vectorized off).
inline BatchFunctions scalarBatchFunctions() {
  return {placeSamplesScalar, sampleBricksBatchScalar, sampleShadedBatchScalar, tfLookupBatchScalar,
          shadeVolumeBatchScalar};
}

} // namespace exa
