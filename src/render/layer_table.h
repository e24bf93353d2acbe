// A field with its transfer function tabulated for sampling (LayerTable), and the per-region
// quantities every stage that samples a field shares: the step and the shading fade.
#pragma once

#include "exabricks/amr/basis.h"
#include "exabricks/amr/basis_batch.h"
#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/sample_math.h"
#include "exabricks/render/transfer_function.h"

#include <array>
#include <vector>

namespace exa {

/// A transfer function tabulated for the marcher (the storage behind a TfTableView).
struct LayerTable {
  int field = 0;
  FieldView view;
  PackedGradientView gradients; ///< smooth shading: the field's packed gradient fields (gradients.h)
  TransferFunction tf;
  std::vector<vec4f> table;
  TfTableView t;
  std::vector<float> albedo;       ///< the path tracer's albedo per table entry (empty: the scene's)
  float span = 0.f, invSpan = 0.f; ///< width of the value range (the scale of shading weights)

  /// The field's table: an empty value range is the field's range, an opacity scale of 0 the
  /// dataset's default.
  void build(const Model& model, const DatasetInfo& dataset, int fieldIndex, const TransferFunction& tfIn);
  vec4f lookup(float value) const { return tfLookup(t, value); }

  /// Cell width (world) over the scale of the field's changes: how much of the gradient shading
  /// a sample gets (shadeVolumeSample). The scale is the transfer function's value range, or for
  /// logarithmic mapping (or an empty range) the value itself.
  bool fadeByValue() const { return tf.logScale || !(span > 0.f); }
  float fadeWidth(const Region& region, float meanScale) const {
    return fadeWidthOf(region.finestWidth() * meanScale, fadeByValue(), invSpan);
  }
  float fade(const Region& region, float meanScale, float value) const {
    return fadeScaleAt(fadeWidth(region, meanScale), fadeByValue(), value);
  }
};

/// Lattice step of a region at the given rate: half its finest cell width (adaptive) or half the
/// dataset's (fixed), over the rate, times the region's stride (regionStride: more than 1 only
/// where the transfer function shows the region uniformly).
EXA_HOST_DEVICE inline float sampleStep(const Region& region, Sampling sampling, float referenceWidth, float rate,
                                        float stride = 1.f) {
  const float width = sampling == Sampling::Adaptive ? region.finestWidth() : referenceWidth;
  return 0.5f * width * stride / rate;
}

/// Central differences at p over half the region's finest width each way; each point
/// reconstructed from the region's bricks where it lies inside the region, else where it
/// falls; one-sided where a point has no value. Per lattice unit.
EXA_HOST_DEVICE inline vec3f centralGradient(const FieldView& view, uint32_t regionIndex, const Region& region,
                                             const vec3f& p, float value) {
  vec3f grad;
  const float h = 0.5f * region.finestWidth();
  const box3f rb = region.bounds();
  auto at = [&](const vec3f& q, float& v) {
    const bool inside = q.x >= rb.lower.x && q.x <= rb.upper.x && q.y >= rb.lower.y && q.y <= rb.upper.y &&
                        q.z >= rb.lower.z && q.z <= rb.upper.z;
    return inside ? sampleRegion(view, regionIndex, q, v) : sampleField(view, q, v);
  };
  for (int ax = 0; ax < 3; ++ax) {
    vec3f pp = p, pm = p;
    pp[ax] += h;
    pm[ax] -= h;
    float vp = value, vm = value;
    if (!at(pp, vp)) vp = value, pp[ax] = p[ax];
    if (!at(pm, vm)) vm = value, pm[ax] = p[ax];
    const float span = pp[ax] - pm[ax];
    grad[ax] = span > 0.f ? (vp - vm) / span : 0.f;
  }
  return grad;
}

} // namespace exa
