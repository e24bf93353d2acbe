#include "majorant_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace exa {

MajorantGrid::MajorantGrid(const Model& model) : model_(model) {
  if (!model.regions.regions.empty()) grid_ = macrocellsOver(model.regions.bounds);
  planes_ = hatPlanesOf(model.bricks);
}

namespace {

/// The sum over the layers of the largest extinction each gives its field's range in macrocell i.
template <typename Ranges>
float majorantOf(const std::vector<TableMaxExtinction>& maxima, const Ranges& ranges, size_t i) {
  float sum = 0.f;
  for (size_t l = 0; l < maxima.size(); ++l)
    sum += maxima[l](ranges[l]->values[i]);
  return sum;
}

} // namespace

void MajorantGrid::narrowCostly(const std::vector<LayerTable>& layers, const std::vector<FieldRanges*>& ranges,
                                const std::vector<TableMaxExtinction>& maxima) {
  // The macrocells whose majorant costs a ray crossing them a collision or more and whose ranges
  // have not been narrowed, costliest first, as many as the budget of points allows.
  std::vector<uint32_t> costly;
  for (size_t i = 0; i < majorants_.size(); ++i) {
    if (!(majorants_[i] * grid_.cellSize >= 1.f)) continue;
    bool open = false;
    for (const FieldRanges* r : ranges)
      open = open || !r->narrowed[i];
    if (open) costly.push_back(uint32_t(i));
  }
  if (costly.empty()) return;
  std::stable_sort(costly.begin(), costly.end(), [&](uint32_t a, uint32_t b) { return majorants_[a] > majorants_[b]; });
  const FieldView any = model_.view(layers.front().field);
  size_t points = 0, chosen = 0;
  for (; chosen < costly.size() && points < kMajorantNarrowingPoints; ++chosen)
    points += std::min(kMajorantNarrowingPointsPerCell,
                       macrocellRangePoints(grid_, grid_.cellAt(costly[chosen]), any, planes_)) *
              ranges.size();
  tbb::parallel_for(size_t(0), chosen, [&](size_t k) {
    const uint32_t i = costly[k];
    for (size_t l = 0; l < ranges.size(); ++l) {
      FieldRanges& r = *ranges[l];
      if (r.narrowed[i]) continue; // a field of two layers
      r.narrowed[i] = 1;
      range1f exact;
      if (macrocellRange(grid_, grid_.cellAt(i), model_.view(layers[l].field), planes_, kMajorantNarrowingPointsPerCell,
                         exact))
        r.values[i] = {std::max(r.values[i].lower, exact.lower), std::min(r.values[i].upper, exact.upper)};
    }
    majorants_[i] = majorantOf(maxima, ranges, i);
  });
}

void MajorantGrid::update(const std::vector<LayerTable>& layers, const std::vector<TableMaxExtinction>& maxima,
                          const std::vector<float>& regionMajorants) {
  majorants_.clear();
  gridded_.clear();
  if (model_.regions.regions.empty() || layers.empty()) return;
  std::vector<FieldRanges*> ranges;
  for (const LayerTable& layer : layers) {
    auto it = ranges_.find(layer.field);
    if (it == ranges_.end()) {
      FieldRanges r;
      r.values = macrocellValueRanges(grid_, model_.bricks, model_.fieldValues.at(size_t(layer.field)).data());
      r.narrowed.assign(r.values.size(), 0);
      it = ranges_.emplace(layer.field, std::move(r)).first;
    }
    ranges.push_back(&it->second);
  }
  majorants_.assign(grid_.count(), 0.f);
  tbb::parallel_for(size_t(0), majorants_.size(), [&](size_t i) { majorants_[i] = majorantOf(maxima, ranges, i); });
  narrowCostly(layers, ranges, maxima);
  // Per region, the mean over the macrocells it overlaps of the majorant a ray there would use.
  const std::vector<Region>& regions = model_.regions.regions;
  gridded_.assign(regions.size(), 0);
  tbb::parallel_for(size_t(0), regions.size(), [&](size_t r) {
    const float own = regionMajorants[r];
    if (!(own > 0.f)) return;
    const box3f b = regions[r].bounds();
    vec3i lo, hi;
    for (int a = 0; a < 3; ++a) {
      grid_.span(a, b.lower[a], b.upper[a], false, lo[a], hi[a]);
      lo[a] = std::min(lo[a], grid_.dims[a] - 1), hi[a] = std::max(hi[a], lo[a]); // at least one
    }
    double sum = 0;
    for (int z = lo.z; z <= hi.z; ++z)
      for (int y = lo.y; y <= hi.y; ++y)
        for (int x = lo.x; x <= hi.x; ++x)
          sum += std::min(own, majorants_[grid_.index({x, y, z})]);
    const double cells = double(hi.x - lo.x + 1) * double(hi.y - lo.y + 1) * double(hi.z - lo.z + 1);
    gridded_[r] = (double(own) - sum / cells) * double(grid_.cellSize) >= double(kMajorantGridMinSaving);
  });
}

MajorantGridView MajorantGrid::view() const {
  if (majorants_.empty()) return {};
  return {majorants_.data(), gridded_.data(), grid_};
}

} // namespace exa
