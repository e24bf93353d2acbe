#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/render/renderer.h"

#include <algorithm>
#include <cmath>

namespace exa {

DatasetInfo DatasetInfo::of(const Model& m) {
  int finest = kMaxLevel;
  for (const Brick& b : m.bricks)
    finest = std::min(finest, b.level);
  std::vector<range1f> ranges(m.fieldValues.size());
  for (size_t f = 0; f < m.fieldValues.size() && f < m.regions.valueRanges.size(); ++f)
    for (const range1f& r : m.regions.valueRanges[f])
      ranges[f].extend(r);
  return from(finest, m.cellBounds(), m.world.scale, std::move(ranges));
}

DatasetInfo DatasetInfo::from(int finestLevel, const box3i& cb, const vec3d& worldScale,
                              std::vector<range1f> valueRanges) {
  DatasetInfo d;
  d.referenceWidth = float(1 << std::clamp(finestLevel, 0, kMaxLevel));
  if (!cb.empty()) d.worldDiagonal = length(vec3d(cb.size()) * worldScale);
  d.valueRanges = std::move(valueRanges);
  const float extentCells = cb.empty() ? 1.f : float(reduceMax(cb.size())) / d.referenceWidth;
  d.extentCells = extentCells;
  d.defaultOpacityScale = std::min(1.f, 8.f / std::max(1.f, extentCells));
  return d;
}

const DatasetInfo& DatasetInfo::checkedFor(const Model& m) const {
  if (valueRanges.size() != m.fieldValues.size())
    fail("dataset information holds ", valueRanges.size(), " value ranges for ", m.fieldValues.size(), " fields");
  if (!(referenceWidth > 0.f) || !std::isfinite(referenceWidth))
    fail("dataset reference width must be a positive number");
  return *this;
}

} // namespace exa
