#include "exabricks/amr/gradients.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstring>

namespace exa {

namespace {

/// Per region, the level of all its bricks, or -1 where it holds bricks of more than one level.
std::vector<int32_t> regionLevels(const FieldView& view, size_t regionCount) {
  std::vector<int32_t> out(regionCount, -1);
  tbb::parallel_for(size_t(0), regionCount, [&](size_t r) {
    const Region& region = view.regions[r];
    if (region.brickCount == 0) return;
    int32_t level = view.bricks[view.brickIds[region.brickBegin]].level;
    for (uint32_t k = 1; k < region.brickCount && level >= 0; ++k)
      if (view.bricks[view.brickIds[region.brickBegin + k]].level != level) level = -1;
    out[r] = level;
  });
  return out;
}

bool strictlyInside(const box3f& b, const vec3f& q) {
  return q.x > b.lower.x && q.x < b.upper.x && q.y > b.lower.y && q.y < b.upper.y && q.z > b.lower.z && q.z < b.upper.z;
}

/// The value of the cell of `b` centred at q (a cell centre of b's level), where b holds q.
bool cellValueAt(const FieldView& view, const Brick& b, const vec3f& q, float& v) {
  const box3i bb = b.bounds();
  if (!strictlyInside(box3f(vec3f(bb.lower), vec3f(bb.upper)), q)) return false;
  const float inv = inverseWidth(b.level);
  const int x = int((q.x - float(b.lower.x)) * inv), y = int((q.y - float(b.lower.y)) * inv),
            z = int((q.z - float(b.lower.z)) * inv);
  v = view.values[b.valueOffset + uint32_t((z * b.size.y + y) * b.size.x + x)];
  return true;
}

/// Whether every region that a point of the closed box `box` may lie in, found below the k-d
/// node `from`, holds bricks of `level` alone (`levels` per region, as regionLevels gives).
bool onlyLevelIn(const FieldView& view, uint32_t from, const box3f& box, const std::vector<int32_t>& levels,
                 int32_t level) {
  const RegionKdNode& node = view.nodes[from];
  if (node.axis == kLeafAxis) return node.index != kNoRegion && levels[node.index] == level;
  const int a = int(node.axis);
  // As a point descends: below the plane to the lower child, on it or above to the upper one.
  return (!(box.lower[a] < node.pos) || onlyLevelIn(view, node.index, box, levels, level)) &&
         (!(box.upper[a] >= node.pos) || onlyLevelIn(view, node.index + 1, box, levels, level));
}

/// The reconstruction at q, a cell centre of level `level`, from the bricks of region r, which
/// holds bricks of other levels too: the cells of `level` have hat 1 (the cell centred at q) or
/// 0 there, so only the other levels' bricks are evaluated through their hats.
bool levelCentreValue(const FieldView& view, uint32_t r, const vec3f& q, int level, float& v) {
  const Region& region = view.regions[r];
  BasisAccumulator<float> acc;
  for (uint32_t k = 0; k < region.brickCount; ++k) {
    const Brick& other = view.bricks[view.brickIds[region.brickBegin + k]];
    if (other.level != level) {
      acc.addBrick(other, view.values, q, false);
      continue;
    }
    float value = 0.f;
    if (!cellValueAt(view, other, q, value)) continue;
    if (!acc.haveReference) acc.setReference(value);
    acc.addCell(value, 1.f, 1.f, 1.f, 0.f, 0.f, 0.f, false);
  }
  if (!acc.valid()) return false;
  v = acc.value();
  return true;
}

/// One brick's reconstruction at every cell centre and at the centres one cell beyond each face,
/// each found once (a cell's neighbours are its neighbours' neighbours): a block of the brick's
/// size + 2 per axis, and whether each point has a value.
class CentreBlock {
public:
  CentreBlock(const FieldView& view, const std::vector<int32_t>& levels) : view_(view), levels_(levels) {}

  void fill(const Brick& b) {
    b_ = &b;
    w_ = float(b.cellWidth());
    n_ = b.size;
    padded_ = n_ + vec3i(2);
    value_.assign(size_t(padded_.x) * size_t(padded_.y) * size_t(padded_.z), 0.f);
    has_.assign(value_.size(), 0);
    const box3i own = b.bounds();
    ownBox_ = box3f(vec3f(own.lower), vec3f(own.upper));
    last_ = kNoRegion;
    // Every point lies within half a cell of the brick: their descents share a first part.
    subtree_ = regionSubtree(view_, box3f(ownBox_.lower - vec3f(0.5f * w_), ownBox_.upper + vec3f(0.5f * w_)));
    // Where no brick of another level is active anywhere in the brick, each of its centres has
    // its own cell's value: no region to find for them.
    if (view_.nodes && onlyLevelIn(view_, subtree_, ownBox_, levels_, b.level)) {
      for (int z = 0; z < n_.z; ++z)
        for (int y = 0; y < n_.y; ++y) {
          const float* row = view_.values + b.valueOffset + uint32_t((z * n_.y + y) * n_.x);
          std::copy(row, row + n_.x, value_.begin() + std::ptrdiff_t(at(0, y, z)));
          std::fill_n(has_.begin() + std::ptrdiff_t(at(0, y, z)), n_.x, uint8_t(1));
        }
    } else {
      for (int z = 0; z < n_.z; ++z)
        for (int y = 0; y < n_.y; ++y)
          for (int x = 0; x < n_.x; ++x)
            evaluate(x, y, z);
    }
    for (int z = 0; z < n_.z; ++z)
      for (int y = 0; y < n_.y; ++y)
        evaluate(-1, y, z), evaluate(n_.x, y, z);
    for (int z = 0; z < n_.z; ++z)
      for (int x = 0; x < n_.x; ++x)
        evaluate(x, -1, z), evaluate(x, n_.y, z);
    for (int y = 0; y < n_.y; ++y)
      for (int x = 0; x < n_.x; ++x)
        evaluate(x, y, -1), evaluate(x, y, n_.z);
  }

  /// The brick's cells' central differences (one-sided where a neighbour has no value, 0 where
  /// neither has), cell after cell in the brick's order: put(index in the brick, gradient).
  template <class Put> void differences(Put&& put) const {
    const size_t step[3] = {1, size_t(padded_.x), size_t(padded_.x) * size_t(padded_.y)};
    uint32_t slot = 0;
    for (int z = 0; z < n_.z; ++z)
      for (int y = 0; y < n_.y; ++y)
        for (int x = 0; x < n_.x; ++x, ++slot) {
          const size_t c = at(x, y, z);
          vec3f g(0.f);
          for (int a = 0; a < 3; ++a) {
            const size_t p = c + step[a], m = c - step[a];
            if (has_[p] && has_[m])
              g[a] = (value_[p] - value_[m]) / (2.f * w_);
            else if (has_[p] && has_[c])
              g[a] = (value_[p] - value_[c]) / w_;
            else if (has_[m] && has_[c])
              g[a] = (value_[c] - value_[m]) / w_;
          }
          put(slot, g);
        }
  }

private:
  size_t at(int x, int y, int z) const {
    return (size_t(z + 1) * size_t(padded_.y) + size_t(y + 1)) * size_t(padded_.x) + size_t(x + 1);
  }

  void evaluate(int x, int y, int z) {
    const vec3f q = vec3f(b_->lower) + (vec3f(float(x), float(y), float(z)) + vec3f(0.5f)) * w_;
    // The region of the point before: the next is most often strictly inside it too, where the
    // k-d tree would find the same region.
    const bool again = last_ != kNoRegion && strictlyInside(lastBox_, q);
    const uint32_t r = again ? last_ : locateRegion(view_, q, subtree_);
    if (!again) last_ = r, lastBox_ = r != kNoRegion ? view_.regions[r].bounds() : box3f();
    if (r == kNoRegion) return;
    const size_t i = at(x, y, z);
    float& v = value_[i];
    // q is a cell centre of this brick's level. Where every brick active in q's region is of
    // that level, each hat is 1 or 0 at q (cell corners are multiples of the width, so the
    // centres of one level are whole widths apart): the reconstruction there is the value of the
    // cell centred at q, or none where no brick has that cell. Elsewhere (at level jumps) it is
    // reconstructed.
    if (levels_[r] != b_->level) {
      has_[i] = levelCentreValue(view_, r, q, b_->level, v);
    } else if (strictlyInside(ownBox_, q)) {
      v = view_.values[b_->valueOffset + uint32_t((z * n_.y + y) * n_.x + x)];
      has_[i] = 1;
    } else {
      const Region& region = view_.regions[r];
      for (uint32_t k = 0; k < region.brickCount && !has_[i]; ++k)
        has_[i] = cellValueAt(view_, view_.bricks[view_.brickIds[region.brickBegin + k]], q, v);
    }
  }

  const FieldView& view_;
  const std::vector<int32_t>& levels_;
  const Brick* b_ = nullptr;
  float w_ = 1.f;
  vec3i n_{0}, padded_{0};
  box3f ownBox_, lastBox_;
  uint32_t subtree_ = 0, last_ = kNoRegion;
  std::vector<float> value_;
  std::vector<uint8_t> has_;
};

} // namespace

namespace {
/// Each brick of `which` on the worker threads, its centres' block filled, then handed to
/// use(brick index, block).
template <class Use>
void forBrickBlocks(const FieldView& view, const std::vector<Brick>& bricks, size_t regionCount,
                    const std::vector<uint32_t>& which, Use&& use) {
  if (which.empty()) return;
  const std::vector<int32_t> levels = regionLevels(view, regionCount);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, which.size()), [&](const tbb::blocked_range<size_t>& range) {
    CentreBlock block(view, levels);
    for (size_t i = range.begin(); i < range.end(); ++i) {
      block.fill(bricks[which[i]]);
      use(which[i], block);
    }
  });
}
} // namespace

std::array<std::vector<float>, 3> cellGradients(const FieldView& view, const std::vector<Brick>& bricks,
                                                size_t regionCount, size_t valueCount) {
  std::array<std::vector<float>, 3> out;
  for (std::vector<float>& g : out)
    g.assign(valueCount, 0.f);
  std::vector<uint32_t> all(bricks.size());
  for (size_t i = 0; i < all.size(); ++i)
    all[i] = uint32_t(i);
  forBrickBlocks(view, bricks, regionCount, all, [&](uint32_t b, const CentreBlock& block) {
    const size_t offset = bricks[b].valueOffset;
    block.differences([&](uint32_t slot, const vec3f& g) {
      for (int a = 0; a < 3; ++a)
        out[size_t(a)][offset + slot] = g[a];
    });
  });
  return out;
}

void GradientFields::reset(const float* values, size_t count, size_t bricks) {
  cells.assign(2 * count, 0u);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      std::memcpy(&cells[2 * i], &values[i], sizeof(float));
  });
  scaleBias.assign(bricks, gradientScaleBias(kGradientBaseMin));
  built.assign(bricks, 0);
  missing = bricks;
}

void fillPackedGradients(const FieldView& view, const std::vector<Brick>& bricks, size_t regionCount,
                         const std::vector<uint32_t>& which, GradientFields& out) {
  forBrickBlocks(view, bricks, regionCount, which, [&](uint32_t b, const CentreBlock& block) {
    // The differences twice (cheap next to filling the block): the brick's largest exponent
    // first, then each cell packed above the base it gives.
    int largest = kGradientBaseMin;
    block.differences([&](uint32_t, const vec3f& g) { largest = std::max(largest, packedGradientExponent(g)); });
    const int base = gradientBase(largest);
    out.scaleBias[b] = gradientScaleBias(base);
    uint32_t* cells = out.cells.data() + 2 * size_t(bricks[b].valueOffset);
    block.differences([&](uint32_t slot, const vec3f& g) { cells[2 * size_t(slot) + 1] = packGradient(g, base); });
  });
}

} // namespace exa
