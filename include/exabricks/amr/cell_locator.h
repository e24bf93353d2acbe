// The cell-location baseline the paper compares against (its Table 2): the same basis
// reconstruction, but every sample finds each contributing cell by a top-down search of a k-d
// tree over the bricks instead of reading the bricks listed by its active brick region. Used by
// the benchmarks and tests only; it must give the same values as sampleRegion/sampleField.
#pragma once

#include "exabricks/amr/model.h"

#include <memory>

namespace exa {

class CellLocator {
public:
  explicit CellLocator(const Model& model);
  ~CellLocator();
  CellLocator(const CellLocator&) = delete;
  CellLocator& operator=(const CellLocator&) = delete;

  /// Reconstructs field `field` at p (lattice units) from every cell whose support holds p,
  /// each found by its own top-down search. Returns false where no cell has weight; the
  /// gradient is per lattice unit, as for sampleField.
  bool sample(int field, const vec3f& p, float& value, vec3f* gradient = nullptr) const;

  /// Nodes of the k-d tree over the bricks (for statistics and tests).
  size_t nodeCount() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace exa
