#include "majorant_grid.h"

#include <tbb/parallel_for.h>

namespace exa {

MajorantGrid::MajorantGrid(const Model& model) : model_(model) {
  if (!model.regions.regions.empty()) grid_ = macrocellsOver(model.regions.bounds);
}

void MajorantGrid::update(const std::vector<LayerTable>& layers, float extinctionPerLog2) {
  majorants_.clear();
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
}

MajorantGridView MajorantGrid::view() const {
  if (majorants_.empty()) return {};
  return {majorants_.data(), grid_.dims, grid_.lower, grid_.cellSize};
}

} // namespace exa
