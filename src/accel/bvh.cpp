#include "exabricks/accel/bvh.h"

#include "exabricks/core/error.h"

#include <tbb/blocked_range.h>
#include <tbb/concurrent_vector.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <numeric>

namespace exa {
namespace {

constexpr int kBins = 12;
/// Nodes with more primitives than this bin and split their halves in parallel.
constexpr uint32_t kParallelBelow = 4096;

float area(const box3f& b) {
  if (b.empty()) return 0.f;
  const vec3f d = b.upper - b.lower;
  return d.x * d.y + d.y * d.z + d.z * d.x;
}

/// A node's primitives binned by their centres along each axis.
struct Bins {
  box3f box[3][kBins];
  uint32_t count[3][kBins] = {};
  void merge(const Bins& o) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < kBins; ++b)
        box[a][b].extend(o.box[a][b]), count[a][b] += o.count[a][b];
  }
};

int binOf(float c, float lo, float hi) { return std::min(kBins - 1, int(float(kBins) * (c - lo) / (hi - lo))); }

class Builder {
public:
  Builder(const std::vector<box3f>& boxes, const std::vector<vec3f>& centres, uint32_t leafSize,
          std::vector<uint32_t>& order)
      : boxes_(boxes), centres_(centres), leafSize_(std::max(1u, leafSize)), order_(order) {}

  void build(size_t node, uint32_t first, uint32_t count) {
    box3f bounds, centreBounds;
    boundsOf(first, count, bounds, centreBounds);
    nodes_[node].bounds = bounds;
    int axis = -1, split = 0;
    if (count > leafSize_) cheapestSplit(first, count, bounds, centreBounds, axis, split);
    if (axis < 0 && count > 16 * leafSize_) axis = 3; // centres alike (or no cheaper split): halve
    if (axis < 0) {
      nodes_[node].first = first;
      nodes_[node].count = count;
      return;
    }
    uint32_t mid = first + count / 2;
    if (axis < 3) {
      const float lo = centreBounds.lower[axis], hi = centreBounds.upper[axis];
      const auto it = std::partition(order_.begin() + first, order_.begin() + first + count,
                                     [&](uint32_t p) { return binOf(centres_[p][axis], lo, hi) < split; });
      mid = uint32_t(it - order_.begin());
    }
    const size_t children = size_t(nodes_.grow_by(2) - nodes_.begin());
    nodes_[node].first = uint32_t(children);
    nodes_[node].count = 0;
    auto lower = [&] { build(children, first, mid - first); };
    auto upper = [&] { build(children + 1, mid, first + count - mid); };
    if (count > kParallelBelow)
      tbb::parallel_invoke(lower, upper);
    else
      lower(), upper();
  }

  void run(std::vector<BvhNode>& nodes) {
    nodes_.grow_by(1);
    build(0, 0, uint32_t(order_.size()));
    nodes.assign(nodes_.begin(), nodes_.end());
  }

private:
  void boundsOf(uint32_t first, uint32_t count, box3f& bounds, box3f& centreBounds) const {
    using Pair = std::pair<box3f, box3f>;
    auto add = [&](const tbb::blocked_range<uint32_t>& r, Pair p) {
      for (uint32_t i = r.begin(); i != r.end(); ++i) {
        const uint32_t k = order_[i];
        p.first.extend(boxes_[k]);
        p.second.extend(box3f(centres_[k], centres_[k]));
      }
      return p;
    };
    const tbb::blocked_range<uint32_t> all(first, first + count, kParallelBelow);
    const Pair p = count > kParallelBelow ? tbb::parallel_reduce(all, Pair(), add,
                                                                 [](Pair a, const Pair& b) {
                                                                   a.first.extend(b.first);
                                                                   a.second.extend(b.second);
                                                                   return a;
                                                                 })
                                          : add(all, Pair());
    bounds = p.first;
    centreBounds = p.second;
  }

  /// The binned split with the least surface-area cost, where one costs less than a leaf: its
  /// axis and first bin of the upper side (axis unchanged where none does).
  void cheapestSplit(uint32_t first, uint32_t count, const box3f& bounds, const box3f& centres, int& bestAxis,
                     int& bestSplit) const {
    auto add = [&](const tbb::blocked_range<uint32_t>& r, Bins bins) {
      for (uint32_t i = r.begin(); i != r.end(); ++i) {
        const uint32_t k = order_[i];
        for (int a = 0; a < 3; ++a) {
          const float lo = centres.lower[a], hi = centres.upper[a];
          if (!(hi > lo)) continue;
          const int b = binOf(centres_[k][a], lo, hi);
          bins.box[a][b].extend(boxes_[k]);
          ++bins.count[a][b];
        }
      }
      return bins;
    };
    const tbb::blocked_range<uint32_t> all(first, first + count, kParallelBelow);
    const Bins bins = count > kParallelBelow ? tbb::parallel_reduce(all, Bins(), add,
                                                                    [](Bins a, const Bins& b) {
                                                                      a.merge(b);
                                                                      return a;
                                                                    })
                                             : add(all, Bins());
    float bestCost = float(count) * area(bounds);
    for (int a = 0; a < 3; ++a) {
      if (!(centres.upper[a] > centres.lower[a])) continue;
      for (int split = 1; split < kBins; ++split) {
        box3f left, right;
        uint32_t nl = 0, nr = 0;
        for (int b = 0; b < split; ++b)
          left.extend(bins.box[a][b]), nl += bins.count[a][b];
        for (int b = split; b < kBins; ++b)
          right.extend(bins.box[a][b]), nr += bins.count[a][b];
        if (nl == 0 || nr == 0) continue;
        const float cost = 0.5f * area(bounds) + float(nl) * area(left) + float(nr) * area(right);
        if (cost < bestCost) bestCost = cost, bestAxis = a, bestSplit = split;
      }
    }
  }

  const std::vector<box3f>& boxes_;
  const std::vector<vec3f>& centres_;
  uint32_t leafSize_;
  std::vector<uint32_t>& order_;
  tbb::concurrent_vector<BvhNode> nodes_;
};

/// 10 bits of x, spread to every third bit.
uint32_t spread(uint32_t x) {
  x = (x | (x << 16)) & 0x030000FFu;
  x = (x | (x << 8)) & 0x0300F00Fu;
  x = (x | (x << 4)) & 0x030C30C3u;
  return (x | (x << 2)) & 0x09249249u;
}

/// The primitives in the order of their centres along a Morton curve, so that the builder's
/// passes over a node's primitives read memory mostly in order.
std::vector<uint32_t> mortonOrder(const std::vector<vec3f>& centres) {
  box3f bounds;
  for (const vec3f& c : centres)
    bounds.extend(box3f(c, c));
  const vec3f size = bounds.upper - bounds.lower;
  std::vector<std::pair<uint32_t, uint32_t>> keys(centres.size());
  tbb::parallel_for(size_t(0), centres.size(), [&](size_t i) {
    uint32_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const float t = size[a] > 0.f ? (centres[i][a] - bounds.lower[a]) / size[a] : 0.f;
      code |= spread(uint32_t(std::clamp(t, 0.f, 1.f) * 1023.f)) << a;
    }
    keys[i] = {code, uint32_t(i)};
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<uint32_t> order(keys.size());
  for (size_t i = 0; i < keys.size(); ++i)
    order[i] = keys[i].second;
  return order;
}

} // namespace

void buildBvh(const std::vector<box3f>& boxes, const std::vector<vec3f>& centres, uint32_t leafSize,
              std::vector<BvhNode>& nodes, std::vector<uint32_t>& order) {
  nodes.clear();
  order.resize(boxes.size());
  std::iota(order.begin(), order.end(), 0u);
  if (boxes.empty()) return;
  if (boxes.size() > (size_t(1) << 31)) fail(boxes.size(), " primitives are too many for one hierarchy");
  if (boxes.size() <= kParallelBelow) return Builder(boxes, centres, leafSize, order).run(nodes);
  // Many primitives: built over copies in Morton order, then the order mapped back.
  const std::vector<uint32_t> morton = mortonOrder(centres);
  std::vector<box3f> sortedBoxes(boxes.size());
  std::vector<vec3f> sortedCentres(centres.size());
  tbb::parallel_for(size_t(0), morton.size(), [&](size_t i) {
    sortedBoxes[i] = boxes[morton[i]];
    sortedCentres[i] = centres[morton[i]];
  });
  Builder(sortedBoxes, sortedCentres, leafSize, order).run(nodes);
  tbb::parallel_for(size_t(0), order.size(), [&](size_t i) { order[i] = morton[order[i]]; });
}

} // namespace exa
