#include "majorant_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace exa {

MajorantGrid::MajorantGrid(const Model& model) : model_(model) {
  if (!model.regions.regions.empty()) grid_ = macrocellsOver(model.regions.bounds);
}

void MajorantGrid::update(const std::vector<LayerTable>& layers, float extinctionPerLog2,
                          const std::vector<float>& regionMajorants) {
  majorants_.clear();
  gridded_.clear();
  if (model_.regions.regions.empty() || layers.empty()) return;
  std::vector<const std::vector<range1f>*> ranges;
  for (const LayerTable& layer : layers) {
    auto it = ranges_.find(layer.field);
    if (it == ranges_.end())
      it = ranges_
               .emplace(layer.field,
                        macrocellValueRanges(grid_, model_.bricks, model_.fieldValues.at(size_t(layer.field)).data()))
               .first;
    ranges.push_back(&it->second);
  }
  majorants_.assign(grid_.count(), 0.f);
  tbb::parallel_for(size_t(0), majorants_.size(), [&](size_t i) {
    float sum = 0.f;
    for (size_t l = 0; l < layers.size(); ++l)
      sum += tableMaxExtinction(layers[l].t, (*ranges[l])[i], extinctionPerLog2);
    majorants_[i] = sum;
  });
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
