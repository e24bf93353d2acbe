// Region traversal: presents the visible active brick regions along a ray as a stream of
// segments (t0, t1, region), front to back. Two interchangeable back ends: an Embree scene with
// one user-geometry primitive per visible region (the CPU counterpart of the paper's RTX user
// geometry, each step finding the next region after the previous exit), and a front-to-back
// walk of the regions' k-d tree. Both clip each region's box with the same slab test, so they
// give identical segments.
#pragma once

#include "exabricks/amr/model.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace exa {

/// A ray in lattice space; dir need not be normalised (t is in units of |dir|).
struct Ray {
  vec3f org;
  vec3f dir;
  float tmin = 0.f;
  float tmax = std::numeric_limits<float>::infinity();
};

struct Segment {
  float t0, t1;
  uint32_t region;
};

/// Slab test of a ray against a closed box. An axis the ray does not move along counts as
/// inside when lower <= org < upper (half-open, like the k-d tree's split rule), so a ray
/// running exactly along a shared face belongs to one region only. Returns false when the ray
/// misses the box.
EXA_HOST_DEVICE inline bool rayBoxInterval(const Ray& ray, const vec3f& invDir, const box3f& box, float& t0,
                                           float& t1) {
  t0 = -std::numeric_limits<float>::infinity();
  t1 = std::numeric_limits<float>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (ray.dir[a] == 0.f) {
      if (!(ray.org[a] >= box.lower[a] && ray.org[a] < box.upper[a])) return false;
      continue;
    }
    const float ta = (box.lower[a] - ray.org[a]) * invDir[a];
    const float tb = (box.upper[a] - ray.org[a]) * invDir[a];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  return t0 <= t1;
}

EXA_HOST_DEVICE inline vec3f safeInverse(const vec3f& d) {
  return {d.x != 0.f ? 1.f / d.x : 0.f, d.y != 0.f ? 1.f / d.y : 0.f, d.z != 0.f ? 1.f / d.z : 0.f};
}

/// The regions' k-d tree as plain arrays, with one visibility flag per region.
struct RegionTreeView {
  const RegionKdNode* nodes = nullptr; ///< null when there are no regions
  const uint8_t* visible = nullptr;
  /// Per node, whether any visible region lies below it (the walk skips the others); null: not
  /// known, every subtree is entered.
  const uint8_t* subtreeVisible = nullptr;
  box3f bounds; ///< box of the root
};

/// Front-to-back walk of the k-d tree with an explicit stack: calls `emit(const Segment&)` for
/// every visible region the ray passes through, in order, until it returns false. Each leaf's
/// segment is the interval the split planes leave it, clipped to the previous exit. Subtrees
/// without visible regions are not entered.
template <typename Emit>
EXA_HOST_DEVICE inline void walkRegionTree(const RegionTreeView& tree, const Ray& ray, Emit&& emit) {
  if (!tree.nodes) return;
  const vec3f inv = safeInverse(ray.dir);
  float t0, t1;
  if (!rayBoxInterval(ray, inv, tree.bounds, t0, t1)) return;
  t0 = std::max(t0, ray.tmin);
  t1 = std::min(t1, ray.tmax);
  if (!(t0 <= t1)) return;
  struct Entry {
    uint32_t node;
    float t0, t1;
  };
  Entry stack[128];
  int top = 0;
  stack[top++] = {0, t0, t1};
  float last = ray.tmin;
  auto skipped = [&](uint32_t node) { return tree.subtreeVisible && !tree.subtreeVisible[node]; };
  // Per-axis lookups by index from arrays (vec3's operator[] selects among three members).
  const float org[3] = {ray.org.x, ray.org.y, ray.org.z}, dir[3] = {ray.dir.x, ray.dir.y, ray.dir.z};
  const float invDir[3] = {inv.x, inv.y, inv.z};
  while (top > 0) {
    Entry e = stack[--top];
    while (tree.nodes[e.node].axis != kLeafAxis && !skipped(e.node)) {
      const RegionKdNode& n = tree.nodes[e.node];
      const int a = int(n.axis);
      const float o = org[a], d = dir[a];
      const bool lowerFirst = o < n.pos || (o == n.pos && d < 0.f);
      const uint32_t nearChild = n.index + (lowerFirst ? 0u : 1u);
      const uint32_t farChild = n.index + (lowerFirst ? 1u : 0u);
      if (d == 0.f) {
        e.node = nearChild;
        continue;
      }
      const float ts = (n.pos - o) * invDir[a];
      if (ts >= e.t1 || ts <= 0.f) { // never crosses the plane ahead of the origin
        e.node = nearChild;
      } else if (ts <= e.t0) {
        e.node = farChild;
      } else {
        if (top < 128 && !skipped(farChild)) stack[top++] = {farChild, ts, e.t1};
        e.node = nearChild;
        e.t1 = ts;
      }
    }
    if (tree.nodes[e.node].axis != kLeafAxis) continue; // a subtree without visible regions
    const uint32_t r = tree.nodes[e.node].index;
    if (r == kNoRegion || !tree.visible[r]) continue;
    // A region's box is its leaf's cell, so the walk's interval is the region's slab interval:
    // both are the extremes of the same plane crossings (computed alike), clipped to the ray's.
    const float b0 = std::max(e.t0, last), b1 = e.t1;
    if (!(b1 > b0)) continue;
    if (!emit(Segment{b0, b1, r})) return;
    last = b1;
  }
}

/// Per k-d node, whether a visible region lies below it (RegionTreeView::subtreeVisible).
std::vector<uint8_t> visibleSubtrees(const std::vector<RegionKdNode>& nodes, const std::vector<uint8_t>& visible);

enum class TraversalKind { Embree, KdTree };

class RegionTraversal {
public:
  RegionTraversal(const Model& model, TraversalKind kind);
  ~RegionTraversal();
  RegionTraversal(const RegionTraversal&) = delete;
  RegionTraversal& operator=(const RegionTraversal&) = delete;

  /// Sets which regions take part (one flag per region); returns the update time in seconds.
  double setVisible(const std::vector<uint8_t>& visible);
  size_t visibleCount() const { return visibleCount_; }
  TraversalKind kind() const { return kind_; }

  /// Calls `emit(const Segment&)` for every visible region the ray passes through, in order,
  /// until it returns false. Segments tile the ray's path through the visible regions.
  template <typename Emit> void traverse(const Ray& ray, Emit&& emit) const;

private:
  /// Fills subtreeVisible_ from visible_.
  void markVisibleSubtrees();
  /// Next visible region whose exit lies beyond tnear, via Embree; false when there is none.
  bool nextEmbree(const Ray& ray, float tnear, Segment& seg) const;

  const Model& model_;
  TraversalKind kind_;
  std::vector<uint8_t> visible_;
  std::vector<uint8_t> subtreeVisible_; ///< per k-d node: any visible region below
  size_t visibleCount_ = 0;
  struct EmbreeScene;
  std::unique_ptr<EmbreeScene> embree_;
};

template <typename Emit> void RegionTraversal::traverse(const Ray& ray, Emit&& emit) const {
  if (kind_ == TraversalKind::Embree) {
    float tnear = ray.tmin;
    Segment seg;
    while (tnear < ray.tmax && nextEmbree(ray, tnear, seg)) {
      if (!emit(seg)) return;
      tnear = seg.t1;
    }
    return;
  }
  RegionTreeView tree;
  tree.nodes = model_.regions.nodes.empty() ? nullptr : model_.regions.nodes.data();
  tree.visible = visible_.data();
  tree.subtreeVisible = subtreeVisible_.empty() ? nullptr : subtreeVisible_.data();
  tree.bounds = model_.regions.bounds;
  walkRegionTree(tree, ray, emit);
}

} // namespace exa
