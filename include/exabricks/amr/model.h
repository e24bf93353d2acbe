// The built model: bricks, active brick regions and brick-ordered fields, plus the numbers that
// `info` reports. Built from a CellSet or read from a model file.
#pragma once

#include "exabricks/amr/basis.h"
#include "exabricks/amr/cells.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace exa {

/// One field's brick-ordered values, read-only: owned, or a view into a mapped model file that
/// the array keeps mapped while any copy of it lives. Copies share the values.
class ValueArray {
public:
  using value_type = float;
  using const_iterator = const float*;
  using iterator = const float*;

  ValueArray() = default;
  ValueArray(std::vector<float>&& values); // NOLINT: implicit, takes the values over
  /// A view of `size` values at `data`, which `keep` keeps valid.
  ValueArray(std::shared_ptr<const void> keep, const float* data, size_t size)
      : keep_(std::move(keep)), data_(data), size_(size) {}

  const float* data() const { return data_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const float* begin() const { return data_; }
  const float* end() const { return data_ + size_; }
  float operator[](size_t i) const { return data_[i]; }
  std::vector<float> toVector() const { return {begin(), end()}; }
  friend bool operator==(const ValueArray& a, const ValueArray& b);

private:
  std::shared_ptr<const void> keep_;
  const float* data_ = nullptr;
  size_t size_ = 0;
};

struct BuildOptions {
  BrickBuildOptions bricks;
  RegionBuildOptions regions;
};

struct BuildStats {
  double brickSeconds = 0;
  double regionSeconds = 0;
  double rangeSeconds = 0;
  int parts = 1; ///< the bricks were built in this many parts, each read alone
};

struct Model {
  WorldTransform world;
  SimulationState simulation; ///< from the reader (not stored in model files)
  std::vector<Brick> bricks;
  std::vector<std::string> fieldNames;
  std::vector<std::string> fieldUnits; ///< per field, empty where unknown (not stored in model files)
  std::vector<ValueArray> fieldValues; ///< per field, brick-ordered values
  RegionSet regions;
  BuildStats stats;

  uint64_t cellCount() const;
  int fieldIndex(const std::string& name) const;
  /// The field's units, empty where unknown.
  std::string unitsOf(int field) const;
  /// Index of `name`; when `name` is empty, the default field: "scalar", "Density", "density",
  /// "dens" or "rho" (the first present), else the first in file order. Throws when the field is
  /// unknown.
  int requireField(const std::string& name) const;
  FieldView view(int field) const;
  /// Lattice box covered by cells (upper exclusive).
  box3i cellBounds() const;
  /// The box covered by cells in world coordinates.
  box3d worldBounds() const { return world.toWorld(cellBounds()); }
  /// Reconstructs field `field` at a world position: value and gradient per world unit; false
  /// where no cell has weight (or the position is not finite).
  bool sampleWorld(int field, const vec3d& position, double& value, vec3d& gradient) const;
};

/// Numbers that describe a built model (what `info` prints).
struct ModelSummary {
  struct Level {
    int level = 0;
    uint64_t cells = 0, bricks = 0;
  };
  uint64_t cells = 0, bricks = 0, singleCellBricks = 0, regions = 0;
  std::vector<Level> levels; ///< finest first, only levels that hold cells
  double bricksPerRegionByCount = 0, bricksPerRegionByVolume = 0;
  uint64_t maxBricksPerRegion = 0;
  std::vector<range1f> fieldRanges;
  uint64_t brickBytes = 0, valueBytes = 0, regionBytes = 0;
};
ModelSummary summarize(const Model& model);

/// Builds bricks and regions from validated cells; moves the field values into brick order.
Model buildModel(CellSet&& cells, const BuildOptions& options = {});

/// The same model as buildModel for cells whose fields are named but hold no values yet: the
/// bricks are built from the cells alone (permuted in place), the cells freed, and only then
/// each field's values are taken from `valuesOf(field)` (in input cell order) and moved into
/// brick order, one field at a time. The peak memory is the cells and a 4-byte slot index per
/// cell, or the slot index, the fields already placed and one field twice, whichever is more,
/// instead of the cells and every field together.
Model buildModelValuesAfter(CellSet&& cells, const std::function<std::vector<float>(size_t field)>& valuesOf,
                            const BuildOptions& options = {});

/// What a model's structure was built from, kept to give the next data of a time series the same
/// bricks and regions when its hierarchy (cells, levels, world transform, brick options) is
/// unchanged: then only the values are reordered and the region value ranges recomputed.
struct ModelStructure {
  std::vector<Cell> cells;
  std::vector<uint32_t> cellOfSlot;
  WorldTransform world;
  BrickBuildOptions bricks;
  /// Whether `cells` have exactly this structure's hierarchy.
  bool matches(const CellSet& cells, const BuildOptions& options) const;
};

/// buildModel that also returns the structure it built from.
Model buildModel(CellSet&& cells, const BuildOptions& options, ModelStructure& structure);

/// A model over `like`'s bricks and regions with the values of `cells`, which must match
/// `structure` (the structure `like` was built from); equal to buildModel(cells) but without
/// building bricks or regions. Throws exa::Error when the cells do not match.
Model rebuildValues(const Model& like, const ModelStructure& structure, CellSet&& cells);

/// Builds the regions (and value ranges) of a model whose bricks and fields are set.
void buildRegionsOf(Model& model, const RegionBuildOptions& options = {});

} // namespace exa
