#include "exabricks/amr/bricks.h"

#include "exabricks/core/error.h"

#include <tbb/concurrent_vector.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>

namespace exa {
namespace {

struct NodeInfo {
  box3i bounds; // upper exclusive
  int32_t minLevel = kMaxLevel + 1;
  int32_t maxLevel = -1;

  void add(const Cell& c) {
    bounds.extend(c.lower);
    bounds.extend(c.lower + vec3i(int32_t(1) << c.level));
    minLevel = std::min(minLevel, c.level);
    maxLevel = std::max(maxLevel, c.level);
  }
  void add(const NodeInfo& o) {
    bounds.extend(o.bounds);
    minLevel = std::min(minLevel, o.minLevel);
    maxLevel = std::max(maxLevel, o.maxLevel);
  }
};

constexpr size_t kParallelGrain = 8192;

int64_t floorDiv(int64_t a, int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

std::string describe(const Cell& c) {
  return strCat("(", c.lower.x, ",", c.lower.y, ",", c.lower.z, ") level ", c.level);
}

/// Builds bricks by permuting the cells and their input indices together in place (the indices
/// end in brick-slot order: they become cellOfSlot), so that the build needs 4 bytes per cell
/// beyond the cells themselves.
class Builder {
public:
  Builder(Cell* cells, uint32_t* ids, int maxWidth) : cells_(cells), ids_(ids), maxWidth_(maxWidth) {}

  void build(size_t begin, size_t end) {
    const NodeInfo info = analyze(begin, end);
    if (info.minLevel == info.maxLevel && tryLeaf(begin, end, info)) return;

    const int64_t coarsest = int64_t(1) << info.maxLevel;
    const vec3i extent = info.bounds.size();
    if (int64_t(reduceMax(extent)) <= coarsest) reportOverlap(begin, end, info);

    // Split the longest axis at the multiple of the coarsest width nearest the centre; such a
    // plane never cuts a cell because every width divides the coarsest.
    const int axis = argMax(extent);
    const int64_t lo = info.bounds.lower[axis], hi = info.bounds.upper[axis];
    const int64_t centre = floorDiv(lo + hi, 2);
    const int64_t first = (floorDiv(lo, coarsest) + 1) * coarsest;
    const int64_t last = -floorDiv(-hi, coarsest) * coarsest - coarsest;
    int32_t split = int32_t(std::clamp(floorDiv(centre + coarsest / 2, coarsest) * coarsest, first, last));
    // Among the planes in the middle half of the node, prefer the one aligned to the largest
    // power of two: block-structured data then splits along its own block boundaries.
    const int64_t quarter = (hi - lo) / 4;
    for (int64_t align = int64_t(1) << 30; align > coarsest; align >>= 1) {
      const int64_t p = floorDiv(centre + align / 2, align) * align;
      if (p > lo + quarter && p < hi - quarter && p >= first && p <= last) {
        split = int32_t(p);
        break;
      }
    }
    const size_t m = partition(begin, end, axis, split);
    EXA_CHECK(m > begin && m < end, "brick split produced an empty side");
    if (end - begin > kParallelGrain)
      tbb::parallel_invoke([&] { build(begin, m); }, [&] { build(m, end); });
    else {
      build(begin, m);
      build(m, end);
    }
  }

  tbb::concurrent_vector<Brick> bricks;

private:
  /// Moves the cells below the plane x[axis] = split before the others (cells and indices
  /// alike); returns the first of the others.
  size_t partition(size_t begin, size_t end, int axis, int32_t split) {
    size_t i = begin, j = end;
    for (;;) {
      while (i < j && cells_[i].lower[axis] < split) ++i;
      while (i < j && !(cells_[j - 1].lower[axis] < split)) --j;
      if (i >= j) return i;
      std::swap(cells_[i], cells_[j - 1]);
      std::swap(ids_[i], ids_[j - 1]);
      ++i, --j;
    }
  }

  NodeInfo analyze(size_t begin, size_t end) const {
    if (end - begin <= kParallelGrain) {
      NodeInfo info;
      for (size_t i = begin; i < end; ++i) info.add(cells_[i]);
      return info;
    }
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(begin, end, kParallelGrain), NodeInfo{},
        [&](const tbb::blocked_range<size_t>& r, NodeInfo info) {
          for (size_t i = r.begin(); i < r.end(); ++i) info.add(cells_[i]);
          return info;
        },
        [](NodeInfo a, const NodeInfo& b) {
          a.add(b);
          return a;
        });
  }

  /// Makes a brick when the same-level cells exactly fill their bounds within the width limit.
  bool tryLeaf(size_t begin, size_t end, const NodeInfo& info) {
    const int32_t w = int32_t(1) << info.minLevel;
    const vec3i dims = info.bounds.size() / w;
    if (reduceMax(dims) > maxWidth_) return false;
    const uint64_t volume = uint64_t(dims.x) * uint64_t(dims.y) * uint64_t(dims.z);
    if (volume != end - begin) return false;
    // The indices into slot order (x fastest) through a buffer of the brick's size.
    std::vector<uint32_t> slots(end - begin, UINT32_MAX);
    for (size_t i = begin; i < end; ++i) {
      const vec3i c = (cells_[i].lower - info.bounds.lower) / w;
      const size_t slot = size_t(c.x) + size_t(dims.x) * (size_t(c.y) + size_t(dims.y) * c.z);
      if (slots[slot] != UINT32_MAX)
        fail("cells ", std::min(slots[slot], ids_[i]), " and ", std::max(slots[slot], ids_[i]),
             " are duplicates: both at ", describe(cells_[i]));
      slots[slot] = ids_[i];
    }
    std::copy(slots.begin(), slots.end(), ids_ + begin);
    bricks.push_back(Brick{info.bounds.lower, info.minLevel, dims, uint32_t(begin)});
    return true;
  }

  /// All cells lie inside one cell of the coarsest level: that cell overlaps the others.
  [[noreturn]] void reportOverlap(size_t begin, size_t end, const NodeInfo& info) const {
    size_t coarse = end, other = end;
    for (size_t i = begin; i < end; ++i) {
      if (coarse == end && cells_[i].level == info.maxLevel)
        coarse = i;
      else if (other == end)
        other = i;
    }
    EXA_CHECK(coarse != end && other != end);
    if (cells_[coarse].level == cells_[other].level)
      fail("cells ", std::min(ids_[coarse], ids_[other]), " and ", std::max(ids_[coarse], ids_[other]),
           " are duplicates: both at ", describe(cells_[coarse]));
    fail("cells ", ids_[coarse], " ", describe(cells_[coarse]), " and ", ids_[other], " ", describe(cells_[other]),
         " overlap");
  }

  Cell* cells_;
  uint32_t* ids_;
  int maxWidth_;
};

} // namespace

BrickBuild buildBricksInPlace(std::vector<Cell>& cells, const BrickBuildOptions& options) {
  if (options.maxBrickWidth < 1) fail("maximum brick width must be at least 1");
  if (cells.size() >= size_t(UINT32_MAX)) fail("too many cells: ", cells.size(), " (limit 2^32-1)");
  BrickBuild result;
  result.cellOfSlot.resize(cells.size());
  tbb::parallel_for(size_t(0), cells.size(), [&](size_t i) { result.cellOfSlot[i] = uint32_t(i); });
  if (cells.empty()) return result;
  Builder builder(cells.data(), result.cellOfSlot.data(), options.maxBrickWidth);
  builder.build(0, cells.size());
  result.bricks.assign(builder.bricks.begin(), builder.bricks.end());
  std::sort(result.bricks.begin(), result.bricks.end(),
            [](const Brick& a, const Brick& b) { return a.valueOffset < b.valueOffset; });
  return result;
}

BrickBuild buildBricks(const std::vector<Cell>& cells, const BrickBuildOptions& options) {
  std::vector<Cell> copy = cells;
  return buildBricksInPlace(copy, options);
}

std::vector<float> toBrickOrder(const std::vector<float>& cellValues,
                                const std::vector<uint32_t>& cellOfSlot) {
  std::vector<float> out(cellOfSlot.size());
  tbb::parallel_for(size_t(0), out.size(), [&](size_t i) { out[i] = cellValues[cellOfSlot[i]]; });
  return out;
}

} // namespace exa
