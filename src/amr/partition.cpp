#include "exabricks/amr/partition.h"

#include "exabricks/core/error.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace exa {

box3l Census::bounds() const {
  box3l b;
  for (const CensusBox& c : boxes)
    b.extend(c.box);
  return b;
}

double Census::cells() const {
  double n = 0;
  for (const CensusBox& c : boxes)
    n += c.cells;
  return n;
}

size_t CellCensus::KeyHash::operator()(const Key& k) const {
  uint64_t h = 0xcbf29ce484222325ull;
  for (uint64_t v : {uint64_t(k.x), uint64_t(k.y), uint64_t(k.z), uint64_t(uint32_t(k.level))})
    h = (h ^ v) * 0x100000001b3ull;
  return size_t(h ^ (h >> 29));
}

void CellCensus::add(const Cell& c) {
  const int shift = c.level + 3; // blocks of 8 cells of the cell's level per axis
  ++blocks_[Key{int64_t(c.lower.x) >> shift, int64_t(c.lower.y) >> shift, int64_t(c.lower.z) >> shift, c.level}];
  coarsest_ = std::max(coarsest_, c.level);
  const box3i b = c.bounds();
  cellBounds_.extend(box3l(vec3l(b.lower), vec3l(b.upper)));
}

Census CellCensus::finish() const {
  Census census;
  census.coarsestLevel = coarsest_;
  census.cellBounds = cellBounds_;
  census.levelCells.assign(size_t(kMaxLevel) + 1, 0.0);
  census.boxes.reserve(blocks_.size());
  for (const auto& [key, count] : blocks_) {
    const int64_t side = int64_t(8) << key.level;
    const vec3l lower(key.x * side, key.y * side, key.z * side);
    census.boxes.push_back({box3l(lower, lower + vec3l(side)), double(count)});
    census.levelCells[size_t(key.level)] += double(count);
  }
  // The map's order is arbitrary; a fixed order keeps the partition's sums reproducible.
  std::sort(census.boxes.begin(), census.boxes.end(), [](const CensusBox& a, const CensusBox& b) {
    const vec3l& p = a.box.lower;
    const vec3l& q = b.box.lower;
    if (p.z != q.z) return p.z < q.z;
    if (p.y != q.y) return p.y < q.y;
    if (p.x != q.x) return p.x < q.x;
    return a.box.upper.x < b.box.upper.x;
  });
  return census;
}

Census censusOfBricks(const std::vector<Brick>& bricks) {
  Census census;
  census.boxes.reserve(bricks.size());
  census.levelCells.assign(size_t(kMaxLevel) + 1, 0.0);
  for (const Brick& b : bricks) {
    const box3i bb = b.bounds();
    census.boxes.push_back({box3l(vec3l(bb.lower), vec3l(bb.upper)), double(b.cellCount())});
    census.coarsestLevel = std::max(census.coarsestLevel, b.level);
    census.cellBounds.extend(census.boxes.back().box);
    census.levelCells[size_t(b.level)] += double(b.cellCount());
  }
  return census;
}

box3i haloReadBox(const box3l& part, int coarsestLevel) {
  const int64_t w = int64_t(1) << coarsestLevel;
  box3i out;
  for (int a = 0; a < 3; ++a) {
    out.lower[a] = int32_t(std::clamp(part.lower[a] - w, -kLatticeLimit, kLatticeLimit));
    out.upper[a] = int32_t(std::clamp(part.upper[a] + w, -kLatticeLimit, kLatticeLimit));
  }
  return out;
}

box3l shadingReach(const box3l& part, int coarsestLevel) {
  const int64_t w = int64_t(2) << coarsestLevel;
  return box3l(part.lower - vec3l(w), part.upper + vec3l(w));
}

void keepSupportOf(CellSet& set, const box3l& part) {
  keepCells(set, [&](const Cell& c) { return supportReaches(c.bounds(), c.level, part); });
}

namespace {

/// Cells of the item on the low side of the plane x[axis] = s (even spread over the item).
double cellsBelow(const CensusBox& item, int axis, int64_t s) {
  const int64_t lo = item.box.lower[axis], hi = item.box.upper[axis];
  if (s <= lo) return 0.0;
  if (s >= hi) return item.cells;
  return item.cells * double(s - lo) / double(hi - lo);
}

struct Builder {
  std::vector<KdPartition::Node>& nodes;
  std::vector<box3l>& boxes;
  int64_t grain = 1; ///< split planes are multiples of this

  /// The plane that divides `items` between `parts` parts: the low parts' share of the cells below
  /// it, on the data's longest axis.
  void choosePlane(const std::vector<CensusBox>& items, int parts, const box3l& region, int& axis,
                   int64_t& split) const {
    box3l data;
    double total = 0;
    for (const CensusBox& c : items) {
      data.extend(c.box);
      total += c.cells;
    }
    const int lowParts = parts / 2;
    if (data.empty()) {
      // Nothing left to divide: the parts split the region's middle (or the origin when
      // unbounded); they render nothing.
      axis = argMax(region.size());
      const int64_t lo = std::max(region.lower[axis], -kUnboundedLattice / 2);
      const int64_t hi = std::min(region.upper[axis], kUnboundedLattice / 2);
      split = floorDiv(lo + (hi - lo) / 2, grain) * grain;
    } else {
      const vec3l extent = data.size();
      axis = argMax(extent);
      const int64_t lo = data.lower[axis], hi = data.upper[axis];
      // Candidate planes k * grain strictly inside the data, k in [ka, kb].
      const int64_t ka = floorDiv(lo, grain) + 1, kb = -floorDiv(-hi, grain) - 1;
      if (ka > kb) {
        split = -floorDiv(-hi, grain) * grain; // no plane inside: the high parts hold none of it
      } else {
        // The smallest plane inside the data with at least the low parts' share below it, or the
        // plane before it when that is closer to the share.
        const double target = total * double(lowParts) / double(parts);
        auto below = [&](int64_t k) {
          double n = 0;
          for (const CensusBox& c : items)
            n += cellsBelow(c, axis, k * grain);
          return n;
        };
        int64_t a = ka, b = kb;
        while (a < b) {
          const int64_t m = a + (b - a) / 2;
          if (below(m) >= target)
            b = m;
          else
            a = m + 1;
        }
        if (a > ka && std::abs(below(a - 1) - target) <= std::abs(below(a) - target)) --a;
        split = a * grain;
      }
    }
  }

  /// The items' parts below and above x[axis] = split, their cells spread evenly.
  static void divide(const std::vector<CensusBox>& items, int axis, int64_t split, std::vector<CensusBox>& low,
                     std::vector<CensusBox>& high) {
    for (const CensusBox& c : items) {
      if (c.box.lower[axis] < split) {
        CensusBox part = c;
        part.box.upper[axis] = std::min(c.box.upper[axis], split);
        part.cells = cellsBelow(c, axis, split);
        low.push_back(part);
      }
      if (c.box.upper[axis] > split) {
        CensusBox part = c;
        part.box.lower[axis] = std::max(c.box.lower[axis], split);
        part.cells = c.cells - cellsBelow(c, axis, split);
        high.push_back(part);
      }
    }
  }

  /// Builds node `index` (of nodes sized 2 * parts - 1 in all, depth first, low child first) over
  /// parts `part`, ... of boxes: the two children of a node hold separate ranges of both, so they
  /// are built at once, numbered as one after the other would number them.
  void build(std::vector<CensusBox> items, int parts, const box3l& region, int index, int part) {
    if (parts == 1) {
      nodes[size_t(index)].part = part;
      boxes[size_t(part)] = region;
      return;
    }
    const int lowParts = parts / 2;
    int axis = 0;
    int64_t split = 0;
    choosePlane(items, parts, region, axis, split);
    std::vector<CensusBox> low, high;
    divide(items, axis, split, low, high);
    items.clear();
    items.shrink_to_fit();
    box3l lowRegion = region, highRegion = region;
    lowRegion.upper[axis] = split;
    highRegion.lower[axis] = split;
    const int c0 = index + 1, c1 = index + 2 * lowParts; // the low subtree has 2 * lowParts - 1 nodes
    auto buildLow = [&] { build(std::move(low), lowParts, lowRegion, c0, part); };
    auto buildHigh = [&] { build(std::move(high), parts - lowParts, highRegion, c1, part + lowParts); };
    if (low.size() + high.size() > 4096)
      tbb::parallel_invoke(buildLow, buildHigh);
    else
      buildLow(), buildHigh();
    KdPartition::Node& n = nodes[size_t(index)];
    n.axis = axis;
    n.split = split;
    n.child[0] = c0;
    n.child[1] = c1;
  }
};

} // namespace

KdPartition KdPartition::balance(const Census& census, int parts, int64_t grain) {
  if (parts < 1 || parts > 1 << 20) fail("a partition needs 1 to 2^20 parts, not ", parts);
  if (grain < 1 || grain > kLatticeLimit) fail("a partition's planes need a grain of 1 to 2^29, not ", grain);
  KdPartition p;
  Builder b{p.nodes_, p.boxes_, grain};
  std::vector<CensusBox> items;
  items.reserve(census.boxes.size());
  for (const CensusBox& c : census.boxes)
    if (!c.box.empty() && c.cells > 0) items.push_back(c);
  p.nodes_.resize(size_t(2 * parts - 1));
  p.boxes_.resize(size_t(parts));
  b.build(std::move(items), parts, box3l(vec3l(-kUnboundedLattice), vec3l(kUnboundedLattice)), 0, 0);
  return p;
}

KdPartition KdPartition::whole() { return balance(Census{}, 1); }

template <typename NearLow> std::vector<int> KdPartition::order(NearLow&& nearLow) const {
  std::vector<int> out;
  out.reserve(boxes_.size());
  std::function<void(int)> visit = [&](int i) {
    const Node& n = nodes_[size_t(i)];
    if (n.axis < 0) {
      out.push_back(n.part);
      return;
    }
    const int first = nearLow(n) ? 0 : 1;
    visit(n.child[first]);
    visit(n.child[1 - first]);
  };
  if (!nodes_.empty()) visit(0);
  return out;
}

int KdPartition::partAt(const vec3d& lattice) const {
  if (nodes_.empty() || !(std::isfinite(lattice.x) && std::isfinite(lattice.y) && std::isfinite(lattice.z))) return -1;
  int i = 0;
  while (nodes_[size_t(i)].axis >= 0) {
    const Node& n = nodes_[size_t(i)];
    i = n.child[lattice[n.axis] < double(n.split) ? 0 : 1];
  }
  return nodes_[size_t(i)].part;
}

void KdPartition::forEachPartNear(const box3l& box, int64_t margin, const std::function<void(int)>& visit) const {
  if (nodes_.empty()) return;
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const Node& n = nodes_[size_t(stack.back())];
    stack.pop_back();
    if (n.axis < 0) {
      visit(n.part);
      continue;
    }
    // Low parts lie below the plane, high parts above it: grown, each side reaches `margin` over.
    if (box.lower[n.axis] < n.split + margin) stack.push_back(n.child[0]);
    if (box.upper[n.axis] > n.split - margin) stack.push_back(n.child[1]);
  }
}

std::vector<double> cellsReadByParts(const Census& census, const KdPartition& partition) {
  const int parts = partition.parts();
  std::vector<box3l> readBoxes(static_cast<size_t>(parts));
  int64_t margin = 0; // the most any part's read box reaches beyond the part
  for (int p = 0; p < parts; ++p) {
    const box3l& b = partition.box(p);
    const box3i r = haloReadBox(shadingReach(b, census.coarsestLevel), census.coarsestLevel);
    readBoxes[size_t(p)] = box3l(vec3l(r.lower), vec3l(r.upper));
    for (int a = 0; a < 3; ++a)
      margin = std::max({margin, b.lower[a] - int64_t(r.lower[a]), int64_t(r.upper[a]) - b.upper[a]});
  }
  // Per box, the parts whose read box it overlaps, found down the partition's tree; then per part
  // the cells of its boxes summed in the boxes' order.
  const std::vector<CensusBox>& boxes = census.boxes;
  std::vector<std::vector<int>> near(boxes.size());
  tbb::parallel_for(size_t(0), boxes.size(), [&](size_t i) {
    const box3l& c = boxes[i].box;
    partition.forEachPartNear(c, margin, [&](int p) {
      const box3l& r = readBoxes[size_t(p)];
      bool overlaps = true;
      for (int a = 0; a < 3 && overlaps; ++a)
        overlaps = std::max(c.lower[a], r.lower[a]) < std::min(c.upper[a], r.upper[a]);
      if (overlaps) near[i].push_back(p);
    });
  });
  std::vector<std::vector<uint32_t>> of(static_cast<size_t>(parts));
  for (size_t i = 0; i < boxes.size(); ++i)
    for (int p : near[i])
      of[size_t(p)].push_back(uint32_t(i));
  std::vector<double> cells(static_cast<size_t>(parts), 0.0);
  tbb::parallel_for(0, parts, [&](int p) {
    for (uint32_t i : of[size_t(p)])
      cells[size_t(p)] += boxes[i].cells;
  });
  return cells;
}

std::vector<int> KdPartition::orderFrom(const vec3d& eye) const {
  return order([&](const Node& n) { return eye[n.axis] < double(n.split); });
}

std::vector<int> KdPartition::orderAlong(const vec3d& direction) const {
  return order([&](const Node& n) { return direction[n.axis] >= 0.0; });
}

std::vector<int64_t> KdPartition::encode() const {
  std::vector<int64_t> out{int64_t(nodes_.size()), int64_t(boxes_.size())};
  for (const Node& n : nodes_)
    out.insert(out.end(), {n.axis, n.split, n.child[0], n.child[1], n.part});
  for (const box3l& b : boxes_)
    out.insert(out.end(), {b.lower.x, b.lower.y, b.lower.z, b.upper.x, b.upper.y, b.upper.z});
  return out;
}

KdPartition KdPartition::decode(const std::vector<int64_t>& d) {
  auto bad = [](const char* what) { fail("corrupt partition: ", what); };
  if (d.size() < 2) bad("too short");
  const int64_t nodeCount = d[0], partCount = d[1];
  if (nodeCount < 1 || partCount < 1 || nodeCount != 2 * partCount - 1 ||
      d.size() != size_t(2 + 5 * nodeCount + 6 * partCount))
    bad("sizes");
  KdPartition p;
  size_t at = 2;
  for (int64_t i = 0; i < nodeCount; ++i, at += 5) {
    Node n;
    n.axis = int(d[at]);
    n.split = d[at + 1];
    n.child[0] = int(d[at + 2]);
    n.child[1] = int(d[at + 3]);
    n.part = int(d[at + 4]);
    if (n.axis < -1 || n.axis > 2) bad("axis");
    if (n.axis < 0 ? (n.part < 0 || n.part >= partCount)
                   : (n.child[0] <= i || n.child[1] <= i || n.child[0] >= nodeCount || n.child[1] >= nodeCount))
      bad("links");
    p.nodes_.push_back(n);
  }
  for (int64_t i = 0; i < partCount; ++i, at += 6)
    p.boxes_.push_back(box3l(vec3l(d[at], d[at + 1], d[at + 2]), vec3l(d[at + 3], d[at + 4], d[at + 5])));
  return p;
}

} // namespace exa
