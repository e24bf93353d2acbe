#include "exabricks/amr/bricks.h"

#include "exabricks/core/error.h"

#include <tbb/concurrent_vector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <utility>

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

std::string describe(const Cell& c) {
  return strCat("(", c.lower.x, ",", c.lower.y, ",", c.lower.z, ") level ", c.level);
}

/// The message for two conflicting input cells, `a` (index ia) and `b` (index ib).
std::string conflictText(uint64_t ia, const Cell& a, uint64_t ib, const Cell& b, bool duplicate) {
  if (duplicate)
    return strCat("cells ", std::min(ia, ib), " and ", std::max(ia, ib), " are duplicates: both at ", describe(a));
  return strCat("cells ", ia, " ", describe(a), " and ", ib, " ", describe(b), " overlap");
}

/// Builds bricks by permuting the cells in place together with what travels with them: their
/// input indices (which end in brick-slot order and become cellOfSlot) and/or the field values
/// (which end in brick order).
class Builder {
public:
  Builder(Cell* cells, uint32_t* ids, std::vector<float*> values, int maxWidth)
      : cells_(cells), ids_(ids), values_(std::move(values)), maxWidth_(maxWidth) {}

  void build(size_t begin, size_t end) {
    const NodeInfo info = analyze(begin, end);
    if (info.minLevel == info.maxLevel && tryLeaf(begin, end, info)) return;

    const int64_t coarsest = int64_t(1) << info.maxLevel;
    const vec3i extent = info.bounds.size();
    if (int64_t(reduceMax(extent)) <= coarsest) reportOverlap(begin, end, info);

    const auto [axis, split] = chooseSplit(begin, end, info);
    const size_t m = partition(begin, end, axis, split);
    EXA_CHECK(m > begin && m < end, "brick split produced an empty side");
    if (end - begin > kParallelGrain)
      tbb::parallel_invoke([&] { build(begin, m); }, [&] { build(m, end); });
    else {
      build(begin, m);
      build(m, end);
    }
  }

  /// The split of a sparse node: on its longest axis, the multiple of the coarsest width nearest
  /// the centre, or among the planes in the middle half the one aligned to the largest power of
  /// two.
  static std::pair<int, int32_t> alignedSplit(const NodeInfo& info) {
    const int64_t coarsest = int64_t(1) << info.maxLevel;
    const int axis = argMax(info.bounds.size());
    const int64_t lo = info.bounds.lower[axis], hi = info.bounds.upper[axis];
    const int64_t centre = floorDiv(lo + hi, 2);
    const int64_t first = (floorDiv(lo, coarsest) + 1) * coarsest;
    const int64_t last = -floorDiv(-hi, coarsest) * coarsest - coarsest;
    int64_t split = std::clamp(floorDiv(centre + coarsest / 2, coarsest) * coarsest, first, last);
    const int64_t quarter = (hi - lo) / 4;
    for (int64_t align = int64_t(1) << 30; align > coarsest; align >>= 1) {
      const int64_t p = floorDiv(centre + align / 2, align) * align;
      if (p > lo + quarter && p < hi - quarter && p >= first && p <= last) {
        split = p;
        break;
      }
    }
    return {axis, int32_t(split)};
  }

  /// The split plane of a node: a multiple of the coarsest width (such a plane never cuts a cell
  /// because every width divides the coarsest) in the middle half of an axis, or anywhere when
  /// the middle halves hold none. Among those, the plane that separates the fewest same-level
  /// cells facing each other across it: per level, the cells in the slab just below the plane and
  /// in the slab just above, the smaller count times the cells' face area. Block-structured data
  /// then splits along its blocks' faces and keeps same-level blocks whole. Ties go to the plane
  /// nearest the centre, on the longest axis first.
  std::pair<int, int32_t> chooseSplit(size_t begin, size_t end, const NodeInfo& info) const {
    const int levels = info.maxLevel - info.minLevel + 1;
    const int32_t fine = int32_t(1) << info.minLevel;
    const int64_t coarsest = int64_t(1) << info.maxLevel;
    const vec3i extent = info.bounds.size();
    // Per axis and level, the cells in each slab one finest width thick.
    size_t offset[4] = {0, 0, 0, 0}, perLevel[3];
    for (int a = 0; a < 3; ++a) {
      perLevel[a] = size_t(extent[a] >> info.minLevel);
      offset[a + 1] = offset[a] + size_t(levels) * perLevel[a];
    }
    // Sparse nodes (cells far apart) would need counters by the extent, not by the cells: they
    // split at the plane aligned to the largest power of two instead, which separates them.
    if (offset[3] > std::max<size_t>(size_t(1) << 16, 4 * (end - begin))) return alignedSplit(info);
    // Nodes of more than 2^22 cells count every stride-th cell: an empty slab stays empty, so
    // the planes between blocks keep their zero cost.
    const size_t stride = std::max<size_t>(1, (end - begin) >> 22);
    auto count = [&](size_t from, size_t to, std::vector<uint32_t>& slabs) {
      uint32_t* out = slabs.data();
      for (size_t k = from; k < to; ++k) {
        const Cell& c = cells_[begin + k * stride];
        const size_t row = size_t(c.level - info.minLevel);
        for (int a = 0; a < 3; ++a)
          ++out[offset[a] + row * perLevel[a] + size_t(uint32_t(c.lower[a] - info.bounds.lower[a]) >> info.minLevel)];
      }
    };
    const size_t counted = (end - begin + stride - 1) / stride;
    std::vector<uint32_t> slabs(offset[3], 0u);
    if (counted <= kParallelGrain) {
      count(0, counted, slabs);
    } else {
      tbb::enumerable_thread_specific<std::vector<uint32_t>> parts(
          [&] { return std::vector<uint32_t>(offset[3], 0u); });
      tbb::parallel_for(tbb::blocked_range<size_t>(0, counted, kParallelGrain),
                        [&](const tbb::blocked_range<size_t>& r) { count(r.begin(), r.end(), parts.local()); });
      for (const std::vector<uint32_t>& part : parts)
        for (size_t i = 0; i < slabs.size(); ++i)
          slabs[i] += part[i];
    }
    const int longest = argMax(extent);
    int bestAxis = -1;
    int32_t bestPlane = 0;
    double bestCost = 0.0, bestDistance = 0.0;
    for (const bool middle : {true, false}) {
      for (int k = 0; k < 3; ++k) {
        const int a = (longest + k) % 3;
        const int64_t lo = info.bounds.lower[a], hi = info.bounds.upper[a];
        const int64_t margin = middle ? (hi - lo) / 4 : 0;
        const int64_t first = (floorDiv(lo + margin, coarsest) + 1) * coarsest;
        const int64_t last = -floorDiv(-(hi - margin), coarsest) * coarsest - coarsest;
        for (int64_t p = first; p <= last; p += coarsest) {
          double cost = 0.0;
          for (int l = 0; l < levels; ++l) {
            const int64_t w = int64_t(1) << (info.minLevel + l);
            const uint32_t* row = slabs.data() + offset[a] + size_t(l) * perLevel[a];
            const uint32_t below = p - w >= lo ? row[size_t((p - w - lo) / fine)] : 0u;
            const uint32_t above = row[size_t((p - lo) / fine)];
            cost += double(std::min(below, above)) * double(w) * double(w);
          }
          const double distance = std::abs(double(p) - 0.5 * double(lo + hi)) / double(hi - lo);
          if (bestAxis < 0 || cost < bestCost || (cost == bestCost && distance < bestDistance)) {
            bestAxis = a, bestPlane = int32_t(p);
            bestCost = cost, bestDistance = distance;
          }
        }
      }
      if (bestAxis >= 0) break;
    }
    EXA_CHECK(bestAxis >= 0, "no brick split plane in a node wider than its coarsest cell");
    return {bestAxis, bestPlane};
  }

  tbb::concurrent_vector<Brick> bricks;

private:
  /// Moves the cells below the plane x[axis] = split before the others (cells and indices
  /// alike); returns the first of the others.
  size_t partition(size_t begin, size_t end, int axis, int32_t split) {
    size_t i = begin, j = end;
    for (;;) {
      while (i < j && cells_[i].lower[axis] < split)
        ++i;
      while (i < j && !(cells_[j - 1].lower[axis] < split))
        --j;
      if (i >= j) return i;
      std::swap(cells_[i], cells_[j - 1]);
      if (ids_) std::swap(ids_[i], ids_[j - 1]);
      for (float* v : values_)
        std::swap(v[i], v[j - 1]);
      ++i, --j;
    }
  }

  NodeInfo analyze(size_t begin, size_t end) const {
    if (end - begin <= kParallelGrain) {
      NodeInfo info;
      for (size_t i = begin; i < end; ++i)
        info.add(cells_[i]);
      return info;
    }
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(begin, end, kParallelGrain), NodeInfo{},
        [&](const tbb::blocked_range<size_t>& r, NodeInfo info) {
          for (size_t i = r.begin(); i < r.end(); ++i)
            info.add(cells_[i]);
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
    // What travels with the cells goes into slot order (x fastest) through buffers of the
    // brick's size: `local` holds the cell (from begin) at each slot.
    std::vector<uint32_t> local(end - begin, UINT32_MAX);
    for (size_t i = begin; i < end; ++i) {
      const vec3i c = (cells_[i].lower - info.bounds.lower) / w;
      const size_t slot = size_t(c.x) + size_t(dims.x) * (size_t(c.y) + size_t(dims.y) * c.z);
      if (local[slot] != UINT32_MAX) conflict(begin + local[slot], i, true);
      local[slot] = uint32_t(i - begin);
    }
    if (ids_) {
      std::vector<uint32_t> ordered(local.size());
      for (size_t s = 0; s < local.size(); ++s)
        ordered[s] = ids_[begin + local[s]];
      std::copy(ordered.begin(), ordered.end(), ids_ + begin);
    }
    std::vector<float> ordered(values_.empty() ? 0 : local.size());
    for (float* v : values_) {
      for (size_t s = 0; s < local.size(); ++s)
        ordered[s] = v[begin + local[s]];
      std::copy(ordered.begin(), ordered.end(), v + begin);
    }
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
    conflict(coarse, other, cells_[coarse].level == cells_[other].level);
  }

  /// Cells i and j (positions in the work arrays) conflict: named by their input indices where
  /// those travel with the cells, else by position only.
  [[noreturn]] void conflict(size_t i, size_t j, bool duplicate) const {
    if (ids_) throw Error(conflictText(ids_[i], cells_[i], ids_[j], cells_[j], duplicate));
    throw CellConflict(cells_[i], cells_[j], duplicate);
  }

  Cell* cells_;
  uint32_t* ids_;
  std::vector<float*> values_;
  int maxWidth_;
};

/// Runs the builder; returns the bricks in value order.
std::vector<Brick> runBuilder(std::vector<Cell>& cells, uint32_t* ids, std::vector<float*> values,
                              const BrickBuildOptions& options) {
  std::vector<Brick> bricks;
  if (cells.empty()) return bricks;
  Builder builder(cells.data(), ids, std::move(values), options.maxBrickWidth);
  builder.build(0, cells.size());
  bricks.assign(builder.bricks.begin(), builder.bricks.end());
  std::sort(bricks.begin(), bricks.end(), [](const Brick& a, const Brick& b) { return a.valueOffset < b.valueOffset; });
  return bricks;
}

void checkBuildInput(size_t cellCount, const BrickBuildOptions& options) {
  if (options.maxBrickWidth < 1) fail("maximum brick width must be at least 1");
  if (options.maxBrickWidth > kMaxBrickWidth)
    fail("maximum brick width ", options.maxBrickWidth, " exceeds the limit of ", kMaxBrickWidth, " cells");
  if (cellCount >= size_t(UINT32_MAX)) fail("too many cells: ", cellCount, " (limit 2^32-1)");
}

} // namespace

CellConflict::CellConflict(const Cell& a, const Cell& b, bool isDuplicate)
    : Error(isDuplicate ? strCat("two cells are duplicates: both at ", describe(a))
                        : strCat("cell ", describe(a), " and cell ", describe(b), " overlap")),
      first(a), second(b), duplicate(isDuplicate) {}

std::string locateConflict(const CellConflict& c, const std::vector<Cell>& cells) {
  // The first occurrence of each cell; for duplicates, the first two.
  const size_t none = cells.size();
  size_t ia = none, ib = none;
  for (size_t i = 0; i < cells.size() && (ia == none || ib == none); ++i) {
    if (ia == none && cells[i] == c.first)
      ia = i;
    else if (ib == none && cells[i] == c.second)
      ib = i;
  }
  if (ia == none || ib == none) return c.what();
  return conflictText(ia, c.first, ib, c.second, c.duplicate);
}

BrickBuild buildBricksInPlace(std::vector<Cell>& cells, const BrickBuildOptions& options) {
  checkBuildInput(cells.size(), options);
  BrickBuild result;
  result.cellOfSlot.resize(cells.size());
  tbb::parallel_for(size_t(0), cells.size(), [&](size_t i) { result.cellOfSlot[i] = uint32_t(i); });
  result.bricks = runBuilder(cells, result.cellOfSlot.data(), {}, options);
  return result;
}

std::vector<Brick> buildBricksReordering(std::vector<Cell>& cells, const std::vector<std::vector<float>*>& values,
                                         const BrickBuildOptions& options) {
  checkBuildInput(cells.size(), options);
  std::vector<float*> arrays;
  for (std::vector<float>* v : values) {
    EXA_CHECK(v->size() == cells.size(), "one value per cell");
    arrays.push_back(v->data());
  }
  return runBuilder(cells, nullptr, std::move(arrays), options);
}

BrickBuild buildBricks(const std::vector<Cell>& cells, const BrickBuildOptions& options) {
  std::vector<Cell> copy = cells;
  return buildBricksInPlace(copy, options);
}

std::vector<float> toBrickOrder(const std::vector<float>& cellValues, const std::vector<uint32_t>& cellOfSlot) {
  std::vector<float> out(cellOfSlot.size());
  tbb::parallel_for(size_t(0), out.size(), [&](size_t i) { out[i] = cellValues[cellOfSlot[i]]; });
  return out;
}

} // namespace exa
