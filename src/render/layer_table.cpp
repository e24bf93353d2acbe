#include "layer_table.h"

namespace exa {

void LayerTable::build(const Model& model, const DatasetInfo& dataset, int fieldIndex, const TransferFunction& tfIn) {
  field = fieldIndex;
  view = model.view(fieldIndex);
  tf = tfIn;
  if (tf.valueRange.empty() && size_t(field) < dataset.valueRanges.size())
    tf.valueRange = dataset.valueRanges[size_t(field)];
  if (tf.opacityScale == 0.f) tf.opacityScale = dataset.defaultOpacityScale;
  table = tabulateTransferFunction(tf);
  albedo = tabulateAlbedo(tf);
  const range1f r = tf.valueRange;
  t.entries = table.data();
  t.range = r;
  t.logScale = tf.logScale;
  t.fastLinear = !tf.logScale && r.upper > r.lower;
  t.lower = r.lower;
  t.scale = t.fastLinear ? 1.f / (r.upper - r.lower) : 0.f;
  span = r.empty() ? 0.f : r.upper - r.lower;
  invSpan = span > 0.f ? 1.f / span : 0.f;
}

} // namespace exa
