// Transfer function, opacity correction and volume shading for a whole sampling batch: the
// vectorised form of sample_math.h's tfLookup, correctedOpacity and shadeVolumeSample, lane by
// lane the same operations, so the results equal the scalar ones to float round-off. Compiled for
// the same instruction sets as the reconstruction batches (amr/basis_batch.h) and dispatched with
// them; without Highway the scalar functions run lane after lane.
#pragma once

#include "exabricks/amr/basis_batch.h"
#include "exabricks/render/sample_math.h"

namespace exa {

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
  /// shadeVolumeSample's fade scale, as fadeScaleAt(fadeWidth, fadeByValue, value).
  float fadeWidth = 0.f;
  bool fadeByValue = false;
};

/// Opacity and colour of every sample (`lengths` has kSampleBatch entries): alpha = correctedOpacity(logT, lengths[i]); colour the
/// table's, shaded by shadeVolumeSample where asked. Samples with logT >= 0 get alpha 0.
struct ShadedBatch {
  alignas(64) float alpha[kSampleBatch];
  alignas(64) float r[kSampleBatch], g[kSampleBatch], b[kSampleBatch];
};

void shadeVolumeBatch(const SampleBatch& batch, const TfBatch& tf, const float* lengths, const VolumeShadeParams& p,
                      ShadedBatch& out);

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
      const float fade = fadeScaleAt(p.fadeWidth, p.fadeByValue, batch.value[i]);
      const vec3f grad = vec3f(batch.gx[i], batch.gy[i], batch.gz[i]) * p.gradientScale;
      c = shadeVolumeSample(c, grad, p.light, p.halfVector, p.terms, fade);
    }
    out.r[i] = c.x, out.g[i] = c.y, out.b[i] = c.z;
  }
}

} // namespace exa
