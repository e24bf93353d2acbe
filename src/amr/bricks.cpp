#include "exabricks/amr/bricks.h"

#include "exabricks/core/error.h"

#include <tbb/concurrent_vector.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>

namespace exa {
namespace {

/// A cell as seen by the builder: position, level and its index in the input.
struct Item {
  vec3i lower;
  int32_t level;
  uint32_t id;
};

struct NodeInfo {
  box3i bounds; // upper exclusive
  int32_t minLevel = kMaxLevel + 1;
  int32_t maxLevel = -1;

  void add(const Item& it) {
    bounds.extend(it.lower);
    bounds.extend(it.lower + vec3i(int32_t(1) << it.level));
    minLevel = std::min(minLevel, it.level);
    maxLevel = std::max(maxLevel, it.level);
  }
  void add(const NodeInfo& o) {
    bounds.extend(o.bounds);
    minLevel = std::min(minLevel, o.minLevel);
    maxLevel = std::max(maxLevel, o.maxLevel);
  }
};

constexpr size_t kParallelGrain = 8192;

int64_t floorDiv(int64_t a, int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

std::string describe(const Item& it) {
  return strCat("(", it.lower.x, ",", it.lower.y, ",", it.lower.z, ") level ", it.level);
}

class Builder {
public:
  Builder(std::vector<Item>& items, std::vector<uint32_t>& cellOfSlot, int maxWidth)
      : items_(items), cellOfSlot_(cellOfSlot), maxWidth_(maxWidth) {}

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
    Item* mid = std::partition(items_.data() + begin, items_.data() + end,
                               [&](const Item& it) { return it.lower[axis] < split; });
    const size_t m = size_t(mid - items_.data());
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
  NodeInfo analyze(size_t begin, size_t end) const {
    if (end - begin <= kParallelGrain) {
      NodeInfo info;
      for (size_t i = begin; i < end; ++i) info.add(items_[i]);
      return info;
    }
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(begin, end, kParallelGrain), NodeInfo{},
        [&](const tbb::blocked_range<size_t>& r, NodeInfo info) {
          for (size_t i = r.begin(); i < r.end(); ++i) info.add(items_[i]);
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
    for (size_t i = begin; i < end; ++i) cellOfSlot_[i] = UINT32_MAX;
    for (size_t i = begin; i < end; ++i) {
      const vec3i c = (items_[i].lower - info.bounds.lower) / w;
      const size_t slot = begin + size_t(c.x) + size_t(dims.x) * (size_t(c.y) + size_t(dims.y) * c.z);
      if (cellOfSlot_[slot] != UINT32_MAX)
        fail("cells ", cellOfSlot_[slot], " and ", items_[i].id, " are duplicates: both at ",
             describe(items_[i]));
      cellOfSlot_[slot] = items_[i].id;
    }
    bricks.push_back(Brick{info.bounds.lower, info.minLevel, dims, uint32_t(begin)});
    return true;
  }

  /// All cells lie inside one cell of the coarsest level: that cell overlaps the others.
  [[noreturn]] void reportOverlap(size_t begin, size_t end, const NodeInfo& info) const {
    const Item* coarse = nullptr;
    const Item* other = nullptr;
    for (size_t i = begin; i < end; ++i) {
      const Item& it = items_[i];
      if (!coarse && it.level == info.maxLevel)
        coarse = &it;
      else if (!other)
        other = &it;
    }
    EXA_CHECK(coarse && other);
    if (coarse->level == other->level)
      fail("cells ", std::min(coarse->id, other->id), " and ", std::max(coarse->id, other->id),
           " are duplicates: both at ", describe(*coarse));
    fail("cells ", coarse->id, " ", describe(*coarse), " and ", other->id, " ", describe(*other),
         " overlap");
  }

  std::vector<Item>& items_;
  std::vector<uint32_t>& cellOfSlot_;
  int maxWidth_;
};

} // namespace

BrickBuild buildBricks(const std::vector<Cell>& cells, const BrickBuildOptions& options) {
  if (options.maxBrickWidth < 1) fail("maximum brick width must be at least 1");
  if (cells.size() >= size_t(UINT32_MAX)) fail("too many cells: ", cells.size(), " (limit 2^32-1)");
  std::vector<Item> items(cells.size());
  tbb::parallel_for(size_t(0), cells.size(), [&](size_t i) {
    items[i] = Item{cells[i].lower, cells[i].level, uint32_t(i)};
  });
  BrickBuild result;
  result.cellOfSlot.resize(cells.size());
  if (cells.empty()) return result;
  Builder builder(items, result.cellOfSlot, options.maxBrickWidth);
  builder.build(0, items.size());
  result.bricks.assign(builder.bricks.begin(), builder.bricks.end());
  std::sort(result.bricks.begin(), result.bricks.end(),
            [](const Brick& a, const Brick& b) { return a.valueOffset < b.valueOffset; });
  return result;
}

std::vector<float> toBrickOrder(const std::vector<float>& cellValues,
                                const std::vector<uint32_t>& cellOfSlot) {
  std::vector<float> out(cellOfSlot.size());
  tbb::parallel_for(size_t(0), out.size(), [&](size_t i) { out[i] = cellValues[cellOfSlot[i]]; });
  return out;
}

} // namespace exa
