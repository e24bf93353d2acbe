// The path tracer's majorant grid: per macrocell (amr/macrocells.h) the largest extinction the
// layers' transfer functions give anywhere in it, so that delta tracking takes few null
// collisions where dense and empty space share a coarse region. The macrocells' value ranges are
// built once per field; the majorants again with every transfer function.
#pragma once

#include "layer_table.h"
#include "path_trace.h"

#include "exabricks/amr/macrocells.h"
#include "exabricks/amr/model.h"

#include <map>
#include <vector>

namespace exa {

class MajorantGrid {
public:
  explicit MajorantGrid(const Model& model);

  /// The majorants for the layers' current tables: per macrocell, the sum over the layers of the
  /// largest extinction the table gives the field's values there (no layers: no grid); and the
  /// regions (with their own majorants) where walking the grid pays.
  void update(const std::vector<LayerTable>& layers, float extinctionPerLog2,
              const std::vector<float>& regionMajorants);
  /// The grid as plain data (null majorants: no grid).
  MajorantGridView view() const;
  const std::vector<float>& majorants() const { return majorants_; }
  const std::vector<uint8_t>& gridded() const { return gridded_; }

private:
  const Model& model_;
  MacrocellGrid grid_;
  std::map<int, std::vector<range1f>> ranges_; ///< per model field, built when first needed
  std::vector<float> majorants_;
  std::vector<uint8_t> gridded_; ///< per region
};

/// The collisions a ray must expect to save per macrocell it crosses in a region (the region's
/// majorant less the grid's there, times the macrocell's width) for the grid to be walked there.
constexpr float kMajorantGridMinSaving = 0.25f;

} // namespace exa
