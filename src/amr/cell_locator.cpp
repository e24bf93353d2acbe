#include "exabricks/amr/cell_locator.h"

#include "exabricks/core/error.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace exa {
namespace {

/// k-d tree node over the bricks. Inner nodes split `axis` at the integer lattice plane `pos`,
/// which cuts no brick: a cell with corner < pos lies in child `a`, the others in child `a + 1`.
/// Leaves (axis 3) list `b` bricks from `a` on in the leaf brick list; one brick in practice,
/// more only where no plane separates the bricks, none for empty space.
struct Node {
  int32_t pos;
  uint32_t axis;
  uint32_t a;
  uint32_t b;
};
constexpr uint32_t kLeaf = 3;

} // namespace

struct CellLocator::Impl {
  const Model& model;
  std::vector<Node> nodes;
  std::vector<uint32_t> leafBricks;
  std::vector<int> levels; ///< levels that hold bricks, finest first
  box3f sampleBounds;      ///< box of every support: outside it no cell has weight

  explicit Impl(const Model& m) : model(m) {
    std::vector<uint32_t> ids(m.bricks.size());
    std::iota(ids.begin(), ids.end(), 0u);
    if (!ids.empty()) {
      nodes.push_back({});
      build(0, ids.begin(), ids.end());
    }
    uint32_t present = 0;
    box3f b;
    for (const Brick& brick : m.bricks) {
      present |= 1u << brick.level;
      const box3i bb = brick.bounds();
      const float half = 0.5f * float(brick.cellWidth());
      b.extend(vec3f(bb.lower) - vec3f(half));
      b.extend(vec3f(bb.upper) + vec3f(half));
    }
    sampleBounds = b;
    for (int l = 0; l <= kMaxLevel; ++l)
      if (present & (1u << l)) levels.push_back(l);
  }

  /// Builds the subtree of node `n` over bricks [begin, end).
  void build(uint32_t n, std::vector<uint32_t>::iterator begin, std::vector<uint32_t>::iterator end) {
    const size_t count = size_t(end - begin);
    auto makeLeaf = [&] {
      nodes[n] = {0, kLeaf, uint32_t(leafBricks.size()), uint32_t(count)};
      leafBricks.insert(leafBricks.end(), begin, end);
    };
    if (count <= 1) return makeLeaf();
    // Candidate planes per axis: a brick's lower face such that every brick before it in the
    // order of lower faces ends at or below it. Pick the one that balances the counts best.
    int bestAxis = -1;
    int32_t bestPos = 0;
    size_t bestImbalance = count;
    std::vector<uint32_t> order(begin, end);
    for (int axis = 0; axis < 3; ++axis) {
      std::sort(order.begin(), order.end(),
                [&](uint32_t x, uint32_t y) { return model.bricks[x].lower[axis] < model.bricks[y].lower[axis]; });
      int32_t maxUpper = model.bricks[order[0]].bounds().upper[axis];
      for (size_t i = 1; i < order.size(); ++i) {
        const Brick& brick = model.bricks[order[i]];
        if (brick.lower[axis] >= maxUpper && brick.lower[axis] > model.bricks[order[i - 1]].lower[axis]) {
          const size_t imbalance = i > count - i ? i - (count - i) : (count - i) - i;
          if (imbalance < bestImbalance) {
            bestImbalance = imbalance;
            bestAxis = axis;
            bestPos = brick.lower[axis];
          }
        }
        maxUpper = std::max(maxUpper, brick.bounds().upper[axis]);
      }
    }
    if (bestAxis < 0) return makeLeaf(); // no plane separates these bricks
    const auto mid =
        std::partition(begin, end, [&](uint32_t id) { return model.bricks[id].lower[bestAxis] < bestPos; });
    const uint32_t children = uint32_t(nodes.size());
    nodes[n] = {bestPos, uint32_t(bestAxis), children, 0};
    nodes.push_back({});
    nodes.push_back({});
    build(children, begin, mid);
    build(children + 1, mid, end);
  }

  /// The value slot of the cell of `level` with lower corner c, found by a descent from the
  /// root; nullptr when no such cell exists.
  const float* findCell(const float* values, const vec3i& c, int level) const {
    uint32_t n = 0;
    while (nodes[n].axis != kLeaf) {
      const Node& node = nodes[n];
      n = node.a + (c[int(node.axis)] >= node.pos ? 1u : 0u);
    }
    const Node& leaf = nodes[n];
    for (uint32_t k = 0; k < leaf.b; ++k) {
      const Brick& brick = model.bricks[leafBricks[leaf.a + k]];
      if (brick.level != level) continue;
      const box3i bb = brick.bounds();
      if (c.x < bb.lower.x || c.y < bb.lower.y || c.z < bb.lower.z || c.x >= bb.upper.x || c.y >= bb.upper.y ||
          c.z >= bb.upper.z)
        continue;
      const int shift = level;
      const uint32_t ix = uint32_t(c.x - brick.lower.x) >> shift;
      const uint32_t iy = uint32_t(c.y - brick.lower.y) >> shift;
      const uint32_t iz = uint32_t(c.z - brick.lower.z) >> shift;
      return values + brick.valueOffset + ix + size_t(brick.size.x) * (iy + size_t(brick.size.y) * iz);
    }
    return nullptr;
  }
};

CellLocator::CellLocator(const Model& model) : impl_(std::make_unique<Impl>(model)) {}
CellLocator::~CellLocator() = default;

bool CellLocator::sample(int field, const vec3f& p, float& value, vec3f* gradient) const {
  const Impl& im = *impl_;
  if (im.nodes.empty()) return false;
  for (int a = 0; a < 3; ++a)
    if (!(p[a] >= im.sampleBounds.lower[a] && p[a] <= im.sampleBounds.upper[a])) return false;
  const float* values = im.model.fieldValues[size_t(field)].data();
  // The same sums and weights as the region path (BasisAccumulator), but every cell is found
  // on its own.
  BasisAccumulator<float> acc;
  for (const int level : im.levels) {
    const float invW = inverseWidth(level);
    int idx[3][2];
    float h[3][2], dh[3][2];
    for (int a = 0; a < 3; ++a) {
      // Position in cell-centre units of this level: cell i (corner i * w) has its centre at i.
      // In double, so that the fraction is as exact far from the origin as the brick-relative
      // position the region sampler uses.
      const double q = double(p[a]) * double(invW) - 0.5;
      const double fl = std::floor(q);
      const int i0 = int(fl);
      const float f = float(q - fl);
      idx[a][0] = i0;
      h[a][0] = 1.f - f;
      dh[a][0] = -invW;
      idx[a][1] = i0 + 1;
      h[a][1] = f;
      dh[a][1] = invW;
    }
    const int32_t w = int32_t(1) << level;
    for (int iz = 0; iz < 2; ++iz)
      for (int iy = 0; iy < 2; ++iy)
        for (int ix = 0; ix < 2; ++ix) {
          const vec3i corner(idx[0][ix] * w, idx[1][iy] * w, idx[2][iz] * w);
          const float* slot = im.findCell(values, corner, level);
          if (!slot) continue;
          if (!acc.haveReference) acc.setReference(*slot);
          acc.addCell(*slot, h[0][ix], h[1][iy], h[2][iz], dh[0][ix], dh[1][iy], dh[2][iz], gradient != nullptr);
        }
  }
  if (!acc.valid()) return false;
  value = acc.value();
  if (gradient) *gradient = acc.gradient();
  return true;
}

size_t CellLocator::nodeCount() const { return impl_->nodes.size(); }

} // namespace exa
