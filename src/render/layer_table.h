// A field with its transfer function tabulated for sampling (LayerTable), and the per-region
// quantities every stage that samples a field shares: the step and the shading fade.
#pragma once

#include "exabricks/amr/basis.h"
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
  std::array<FieldView, 3> grad{}; ///< smooth shading: the field's gradient fields (cellGradients)
  TransferFunction tf;
  std::vector<vec4f> table;
  TfTableView t;
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
    const float cellWidth = region.finestWidth() * meanScale;
    return fadeByValue() ? cellWidth : cellWidth * invSpan;
  }
  float fade(const Region& region, float meanScale, float value) const {
    return fadeScaleAt(fadeWidth(region, meanScale), fadeByValue(), value);
  }
};

/// Lattice step of a region at the given rate: half its finest cell width (adaptive) or half the
/// dataset's (fixed), over the rate.
inline float sampleStep(const Region& region, Sampling sampling, float referenceWidth, float rate) {
  const float width = sampling == Sampling::Adaptive ? region.finestWidth() : referenceWidth;
  return 0.5f * width / rate;
}

} // namespace exa
