#include "exabricks/accel/triangle_bvh.h"

#include "exabricks/core/error.h"

#include <algorithm>
#include <numeric>

namespace exa {
namespace {

constexpr int kBins = 12;
constexpr uint32_t kLeafTriangles = 4;

float area(const box3f& b) {
  if (b.empty()) return 0.f;
  const vec3f d = b.upper - b.lower;
  return d.x * d.y + d.y * d.z + d.z * d.x;
}

/// Appends the meshes' triangles to `triangles`, and their bounding boxes and centres to `boxes`
/// and `centres`.
void collectTriangles(const std::vector<const TriangleMesh*>& meshes, std::vector<BvhTriangle>& triangles,
                      std::vector<box3f>& boxes, std::vector<vec3f>& centres) {
  for (size_t m = 0; m < meshes.size(); ++m) {
    const TriangleMesh& mesh = *meshes[m];
    for (const vec3i& t : mesh.triangles) {
      const vec3f a = mesh.vertices[size_t(t.x)], b = mesh.vertices[size_t(t.y)], c = mesh.vertices[size_t(t.z)];
      triangles.push_back({a, b - a, c - a, int(m)});
      box3f box(a, a);
      box.extend(box3f(b, b));
      box.extend(box3f(c, c));
      boxes.push_back(box);
      centres.push_back((a + b + c) * (1.f / 3.f));
    }
  }
}

/// The binned split of a node's `count` triangles (`order`) with the least surface-area cost,
/// where one costs less than a leaf: its axis and first bin of the upper side in `bestAxis` and
/// `bestSplit` (bestAxis unchanged where none does).
void cheapestSplit(const std::vector<box3f>& boxes, const std::vector<vec3f>& centres, const uint32_t* order,
                   uint32_t count, const box3f& bounds, const box3f& centreBounds, int& bestAxis, int& bestSplit) {
  float bestCost = float(count) * area(bounds);
  for (int a = 0; a < 3; ++a) {
    const float lo = centreBounds.lower[a], hi = centreBounds.upper[a];
    if (!(hi > lo)) continue;
    box3f binBox[kBins];
    uint32_t binCount[kBins] = {};
    for (uint32_t i = 0; i < count; ++i) {
      const int b = std::min(kBins - 1, int(float(kBins) * (centres[order[i]][a] - lo) / (hi - lo)));
      binBox[b].extend(boxes[order[i]]);
      ++binCount[b];
    }
    for (int split = 1; split < kBins; ++split) {
      box3f left, right;
      uint32_t nl = 0, nr = 0;
      for (int b = 0; b < split; ++b)
        left.extend(binBox[b]), nl += binCount[b];
      for (int b = split; b < kBins; ++b)
        right.extend(binBox[b]), nr += binCount[b];
      if (nl == 0 || nr == 0) continue;
      const float cost = 0.5f * area(bounds) + float(nl) * area(left) + float(nr) * area(right);
      if (cost < bestCost) bestCost = cost, bestAxis = a, bestSplit = split;
    }
  }
}

} // namespace

void TriangleBvh::build(const std::vector<const TriangleMesh*>& meshes) {
  nodes_.clear();
  triangles_.clear();
  std::vector<box3f> boxes;
  std::vector<vec3f> centres;
  collectTriangles(meshes, triangles_, boxes, centres);
  if (triangles_.empty()) return;
  if (triangles_.size() > (size_t(1) << 31)) fail("meshes of ", triangles_.size(), " triangles are too many");
  std::vector<uint32_t> order(triangles_.size());
  std::iota(order.begin(), order.end(), 0u);
  // Top-down with binned surface-area costs; a node's triangles are order[first, first + count).
  struct Task {
    uint32_t node, first, count;
  };
  nodes_.push_back({});
  std::vector<Task> tasks{{0, 0, uint32_t(order.size())}};
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    box3f bounds, centreBounds;
    for (uint32_t i = task.first; i < task.first + task.count; ++i) {
      bounds.extend(boxes[order[i]]);
      centreBounds.extend(box3f(centres[order[i]], centres[order[i]]));
    }
    nodes_[task.node].bounds = bounds;
    int bestAxis = -1, bestSplit = 0;
    if (task.count > kLeafTriangles)
      cheapestSplit(boxes, centres, order.data() + task.first, task.count, bounds, centreBounds, bestAxis, bestSplit);
    if (bestAxis < 0 && task.count > 64) {
      // Centres all alike (or no cheaper split): halve the list to bound the leaves.
      bestAxis = 3;
    }
    if (bestAxis < 0) {
      nodes_[task.node].first = task.first;
      nodes_[task.node].count = task.count;
      continue;
    }
    uint32_t mid;
    if (bestAxis == 3) {
      mid = task.first + task.count / 2;
    } else {
      const float lo = centreBounds.lower[bestAxis], hi = centreBounds.upper[bestAxis];
      const auto it =
          std::partition(order.begin() + task.first, order.begin() + task.first + task.count, [&](uint32_t t) {
            const int b = std::min(kBins - 1, int(float(kBins) * (centres[t][bestAxis] - lo) / (hi - lo)));
            return b < bestSplit;
          });
      mid = uint32_t(it - order.begin());
    }
    const uint32_t children = uint32_t(nodes_.size());
    nodes_.push_back({});
    nodes_.push_back({});
    nodes_[task.node].first = children;
    nodes_[task.node].count = 0;
    tasks.push_back({children, task.first, mid - task.first});
    tasks.push_back({children + 1, mid, task.first + task.count - mid});
  }
  std::vector<BvhTriangle> sorted(triangles_.size());
  for (size_t i = 0; i < order.size(); ++i)
    sorted[i] = triangles_[order[i]];
  triangles_ = std::move(sorted);
}

} // namespace exa
