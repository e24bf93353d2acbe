#include "exabricks/amr/regions.h"

#include "exabricks/core/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace exa {
namespace {

// The builder works in half lattice units so that supports (a brick grown by half its cell
// width) have integer faces.
struct Fragment {
  box3l box; // half units, [lower, upper]
  uint32_t brick;
};

box3f toLattice(const box3l& half) { return {vec3f(half.lower) * 0.5f, vec3f(half.upper) * 0.5f}; }

/// The region builder's output for one subtree; node 0 is the subtree root.
struct Subtree {
  std::vector<RegionKdNode> nodes;
  std::vector<Region> regions;
  std::vector<uint32_t> brickIds;
};

struct Task {
  box3l box;
  std::vector<Fragment> fragments;
  uint32_t node; // placeholder node in the top tree
};

class RegionBuilder {
public:
  RegionBuilder(const std::vector<Brick>& bricks, double segmentCost) : bricks_(bricks), segmentCost_(segmentCost) {}

  /// Regions of more bricks than this are never merged.
  static constexpr size_t kMaxCollapsedBricks = 16;

  /// Picks the fragment face closest to the box centre, on the widest axis that has one.
  /// Returns false when no face lies strictly inside the box (the box is a leaf).
  static bool choosePlane(const box3l& box, const std::vector<Fragment>& frags, int& axisOut, int64_t& posOut) {
    const vec3l extent = box.size();
    std::array<int, 3> order{0, 1, 2};
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return extent[a] > extent[b]; });
    for (int axis : order) {
      const int64_t lo = box.lower[axis], hi = box.upper[axis];
      const int64_t twiceCentre = lo + hi;
      int64_t best = 0, bestDist = INT64_MAX;
      auto consider = [&](int64_t face) {
        if (face <= lo || face >= hi) return;
        const int64_t d = std::abs(2 * face - twiceCentre);
        if (d < bestDist || (d == bestDist && face < best)) {
          bestDist = d;
          best = face;
        }
      };
      for (const Fragment& f : frags) {
        consider(f.box.lower[axis]);
        consider(f.box.upper[axis]);
      }
      if (bestDist != INT64_MAX) {
        axisOut = axis;
        posOut = best;
        return true;
      }
    }
    return false;
  }

  static void split(const std::vector<Fragment>& frags, int axis, int64_t pos, std::vector<Fragment>& left,
                    std::vector<Fragment>& right) {
    for (const Fragment& f : frags) {
      if (f.box.lower[axis] < pos) {
        Fragment l = f;
        l.box.upper[axis] = std::min(l.box.upper[axis], pos);
        left.push_back(l);
      }
      if (f.box.upper[axis] > pos) {
        Fragment r = f;
        r.box.lower[axis] = std::max(r.box.lower[axis], pos);
        right.push_back(r);
      }
    }
  }

  /// What a subtree costs a ray, and whether it may become one region (see partition).
  struct Cost {
    double cost = 0;
    int32_t level = 0; ///< the finest level of every region in it
    bool collapsible = false;
  };

  /// The cost of `box` as one region of `count` bricks whose finest level is `level`, summed over
  /// uniformly distributed lines (a line meets a convex box in proportion to its surface area,
  /// and the mean chord is 4 volume / area): per segment, segmentCost; per sample and brick, 1.
  /// Samples are half the finest width apart (the rate only scales every leaf alike).
  double leafCost(const box3l& box, size_t count, int32_t level) const {
    const vec3d s = vec3d(box.size()) * 0.5; // lattice units
    const double area = 2.0 * (s.x * s.y + s.y * s.z + s.z * s.x);
    const double volume = s.x * s.y * s.z;
    const double step = 0.5 * double(int64_t(1) << level);
    return segmentCost_ * area + 4.0 * volume / step * double(count);
  }

  /// Recursively partitions `box` into `out`, writing the subtree root at `nodeIndex`. With a
  /// task list, subtrees with few fragments are deferred as tasks instead of being built.
  ///
  /// Every box whose fragments leave no face inside it is a region. A subtree of such regions all
  /// of one finest level (so with the same sampling step) becomes one region, listing all their
  /// bricks, where that costs a ray less: fewer segments against more bricks per sample. Thin
  /// slabs where the supports of neighbouring bricks overlap are where this pays.
  Cost partition(Subtree& out, uint32_t nodeIndex, const box3l& box, std::vector<Fragment> frags,
                 std::vector<Task>* tasks, size_t taskSize) {
    if (frags.empty()) {
      out.nodes[nodeIndex] = RegionKdNode{0.f, kLeafAxis, kNoRegion};
      return {};
    }
    if (tasks && frags.size() <= taskSize) {
      out.nodes[nodeIndex] = RegionKdNode{0.f, kLeafAxis, uint32_t(tasks->size())};
      tasks->push_back(Task{box, std::move(frags), nodeIndex});
      return {};
    }
    int axis;
    int64_t pos;
    if (!choosePlane(box, frags, axis, pos)) {
      const int32_t finest = emitRegion(out, nodeIndex, box, frags);
      return {leafCost(box, frags.size(), finest), finest, true};
    }
    // The bricks of a node that may become one region are kept (few; a fragment per brick).
    const bool mayCollapse = segmentCost_ > 0.0 && frags.size() <= kMaxCollapsedBricks;
    std::vector<Fragment> kept;
    if (mayCollapse) kept = frags;
    std::vector<Fragment> left, right;
    split(frags, axis, pos, left, right);
    frags.clear();
    frags.shrink_to_fit();
    const uint32_t child = uint32_t(out.nodes.size());
    const size_t regionsBefore = out.regions.size(), idsBefore = out.brickIds.size();
    out.nodes.resize(out.nodes.size() + 2);
    out.nodes[nodeIndex] = RegionKdNode{float(pos) * 0.5f, uint32_t(axis), child};
    box3l leftBox = box, rightBox = box;
    leftBox.upper[axis] = pos;
    rightBox.lower[axis] = pos;
    const Cost a = partition(out, child, leftBox, std::move(left), tasks, taskSize);
    const Cost b = partition(out, child + 1, rightBox, std::move(right), tasks, taskSize);
    if (!(a.collapsible && b.collapsible && a.level == b.level)) return {};
    const double split = a.cost + b.cost;
    if (!mayCollapse) return {split, a.level, true};
    const double whole = leafCost(box, kept.size(), a.level);
    if (whole > split) return {split, a.level, true};
    // The children were built depth first: everything they added is at the ends of the arrays.
    out.nodes.resize(child);
    out.regions.resize(regionsBefore);
    out.brickIds.resize(idsBefore);
    emitRegion(out, nodeIndex, box, kept);
    return {whole, a.level, true};
  }

  /// Writes `box` as a region of the fragments' bricks at `nodeIndex`; returns its finest level.
  int32_t emitRegion(Subtree& out, uint32_t nodeIndex, const box3l& box, const std::vector<Fragment>& frags) const {
    Region r;
    r.halfBounds = box3i(vec3i(box.lower), vec3i(box.upper));
    r.brickBegin = uint32_t(out.brickIds.size());
    r.brickCount = uint32_t(frags.size());
    int32_t finest = INT32_MAX;
    for (const Fragment& f : frags) {
      out.brickIds.push_back(f.brick);
      finest = std::min(finest, bricks_[f.brick].level);
    }
    std::sort(out.brickIds.begin() + r.brickBegin, out.brickIds.end());
    r.finestLevel = finest;
    out.nodes[nodeIndex] = RegionKdNode{0.f, kLeafAxis, uint32_t(out.regions.size())};
    out.regions.push_back(r);
    return finest;
  }

private:
  const std::vector<Brick>& bricks_;
  double segmentCost_;
};

/// Appends subtree `sub` to `set`, replacing the placeholder leaf `node`.
void graft(RegionSet& set, uint32_t node, const Subtree& sub) {
  const uint32_t nodeBase = uint32_t(set.nodes.size()) - 1; // local node i>0 maps to base + i
  const uint32_t regionBase = uint32_t(set.regions.size());
  const uint32_t idBase = uint32_t(set.brickIds.size());
  auto fix = [&](RegionKdNode n) {
    if (n.axis != kLeafAxis)
      n.index += nodeBase;
    else if (n.index != kNoRegion)
      n.index += regionBase;
    return n;
  };
  set.nodes[node] = fix(sub.nodes[0]);
  for (size_t i = 1; i < sub.nodes.size(); ++i)
    set.nodes.push_back(fix(sub.nodes[i]));
  for (Region r : sub.regions) {
    r.brickBegin += idBase;
    set.regions.push_back(r);
  }
  set.brickIds.insert(set.brickIds.end(), sub.brickIds.begin(), sub.brickIds.end());
}

} // namespace

size_t RegionSet::memoryBytes() const {
  size_t bytes =
      regions.size() * sizeof(Region) + brickIds.size() * sizeof(uint32_t) + nodes.size() * sizeof(RegionKdNode);
  for (const auto& r : valueRanges)
    bytes += r.size() * sizeof(range1f);
  return bytes;
}

RegionSet buildRegions(const std::vector<Brick>& bricks, const RegionBuildOptions& options) {
  RegionSet set;
  if (bricks.empty()) return set;
  std::vector<Fragment> frags(bricks.size());
  box3l all;
  for (size_t i = 0; i < bricks.size(); ++i) {
    const Brick& b = bricks[i];
    const int64_t w = b.cellWidth();
    const vec3l lo = vec3l(b.lower) * int64_t(2) - vec3l(w);
    const vec3l hi = (vec3l(b.lower) + vec3l(b.size) * w) * int64_t(2) + vec3l(w);
    frags[i] = Fragment{box3l(lo, hi), uint32_t(i)};
    all.extend(frags[i].box);
  }
  set.bounds = toLattice(all);

  // Top levels are expanded sequentially into deferred tasks, which are built in parallel and
  // grafted in task order, so the result does not depend on scheduling.
  if (!(options.segmentCost >= 0.0) || !std::isfinite(options.segmentCost))
    fail("region segment cost must be a non-negative number");
  RegionBuilder builder(bricks, options.segmentCost);
  Subtree top;
  top.nodes.resize(1);
  std::vector<Task> tasks;
  const size_t taskSize = std::max<size_t>(256, bricks.size() / 256);
  builder.partition(top, 0, all, std::move(frags), &tasks, taskSize);
  std::vector<Subtree> subs(tasks.size());
  tbb::parallel_for(size_t(0), tasks.size(), [&](size_t t) {
    subs[t].nodes.resize(1);
    builder.partition(subs[t], 0, tasks[t].box, std::move(tasks[t].fragments), nullptr, 0);
  });

  set.nodes = top.nodes;
  set.regions = top.regions;
  set.brickIds = top.brickIds;
  // Placeholder leaves of the top tree carry task indices, not regions: graft in task order.
  for (size_t t = 0; t < tasks.size(); ++t) {
    graft(set, tasks[t].node, subs[t]);
    Subtree().nodes.swap(subs[t].nodes);
  }
  return set;
}

std::vector<range1f> computeValueRanges(const RegionSet& set, const std::vector<Brick>& bricks, const float* values) {
  std::vector<range1f> ranges(set.regions.size());
  tbb::parallel_for(size_t(0), set.regions.size(), [&](size_t ri) {
    const Region& region = set.regions[ri];
    range1f range;
    const vec3l a = vec3l(region.halfBounds.lower), b = vec3l(region.halfBounds.upper);
    for (uint32_t k = 0; k < region.brickCount; ++k) {
      const Brick& brick = bricks[set.brickIds[region.brickBegin + k]];
      const int64_t w = brick.cellWidth();
      vec3i lo, hi; // inclusive cell index range whose open support meets the region's interior
      for (int ax = 0; ax < 3; ++ax) {
        const int64_t L2 = 2 * int64_t(brick.lower[ax]);
        // cell i's support is (L2 + 2iw - w, L2 + 2iw + 3w) in half units
        const int64_t first = floorDiv(a[ax] - L2 - 3 * w, 2 * w) + 1;
        const int64_t last = -floorDiv(-(b[ax] - L2 + w), 2 * w) - 1;
        lo[ax] = int32_t(std::max<int64_t>(first, 0));
        hi[ax] = int32_t(std::min<int64_t>(last, brick.size[ax] - 1));
      }
      for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y) {
          const float* row = values + brick.valueOffset + size_t(brick.size.x) * (y + size_t(brick.size.y) * z);
          for (int x = lo.x; x <= hi.x; ++x)
            range.extend(row[x]);
        }
    }
    ranges[ri] = range;
  });
  return ranges;
}

} // namespace exa
