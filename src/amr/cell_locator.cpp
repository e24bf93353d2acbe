#include "exabricks/amr/cell_locator.h"

#include "exabricks/core/error.h"

namespace exa {

struct CellLocator::Impl {
  const Model& model;
};

CellLocator::CellLocator(const Model& model) : impl_(std::make_unique<Impl>(Impl{model})) {}
CellLocator::~CellLocator() = default;

bool CellLocator::sample(int field, const vec3f& p, float& value, vec3f* gradient) const {
  // Placeholder until the k-d tree over the bricks lands: falls back to region sampling.
  return sampleField(impl_->model.view(field), p, value, gradient);
}

size_t CellLocator::nodeCount() const { return 0; }

} // namespace exa
