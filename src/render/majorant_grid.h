// The path tracer's majorant grid: per macrocell (amr/macrocells.h) the largest extinction the
// layers' transfer functions give anywhere in it, so that delta tracking takes few null
// collisions where dense and empty space share a coarse region. The macrocells' value ranges are
// built once per field; the majorants again with every transfer function. Where a macrocell's
// majorant would cost rays many collisions, its range is narrowed to the reconstruction's range
// there, exact where it has a value everywhere (kept for every later transfer function): a
// cell's value otherwise reaches a whole cell beyond its support's ramp, which at an opaque
// boundary in clear space is most of the collisions.
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
  /// largest extinction the table gives the field's values there (`maxima`, one per layer, as
  /// the regions' majorants were found; no layers: no grid); and the regions (with their own
  /// majorants) where walking the grid pays.
  void update(const std::vector<LayerTable>& layers, const std::vector<TableMaxExtinction>& maxima,
              const std::vector<float>& regionMajorants);
  /// The grid as plain data (null majorants: no grid).
  MajorantGridView view() const;
  const std::vector<float>& majorants() const { return majorants_; }
  const std::vector<uint8_t>& gridded() const { return gridded_; }

private:
  struct FieldRanges {
    std::vector<range1f> values;
    std::vector<uint8_t> narrowed; ///< per macrocell: its reconstruction's range was tried
  };
  /// Narrows the ranges of the macrocells whose majorant costs most, up to a budget of points.
  void narrowCostly(const std::vector<LayerTable>& layers, const std::vector<FieldRanges*>& ranges,
                    const std::vector<TableMaxExtinction>& maxima);

  const Model& model_;
  MacrocellGrid grid_;
  HatPlanes planes_;
  std::map<int, FieldRanges> ranges_; ///< per model field, built when first needed
  std::vector<float> majorants_;
  std::vector<uint8_t> gridded_; ///< per region
};

/// The collisions a ray must expect to save per macrocell it crosses in a region (the region's
/// majorant less the grid's there, times the macrocell's width) for the grid to be walked there.
constexpr float kMajorantGridMinSaving = 0.1f;
/// The reconstructions an update may spend narrowing macrocells' ranges (majorant_grid.h).
constexpr size_t kMajorantNarrowingPoints = size_t(1) << 21;
/// The most reconstructions one macrocell's exact range may take.
constexpr size_t kMajorantNarrowingPointsPerCell = 4096;

} // namespace exa
