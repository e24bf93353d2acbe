#include "debug_views.h"

#include "exabricks/core/random.h"
#include "exabricks/render/renderer.h"

namespace exa {

vec3f debugLevelColor(int level) {
  switch (level & 7) {
  case 0:
    return {0.90f, 0.10f, 0.10f};
  case 1:
    return {0.95f, 0.55f, 0.05f};
  case 2:
    return {0.90f, 0.85f, 0.10f};
  case 3:
    return {0.20f, 0.75f, 0.20f};
  case 4:
    return {0.10f, 0.60f, 0.85f};
  case 5:
    return {0.25f, 0.25f, 0.90f};
  case 6:
    return {0.60f, 0.20f, 0.80f};
  default:
    return {0.55f, 0.55f, 0.55f};
  }
}

namespace {

/// The brick of a region whose cells hold p; where no cell does (the margin of the supports),
/// the region's finest brick.
uint32_t brickAt(const Model& model, const Region& region, const vec3f& p) {
  uint32_t brickId = kNoRegion;
  for (uint32_t k = 0; k < region.brickCount; ++k) {
    const uint32_t id = model.regions.brickIds[region.brickBegin + k];
    const box3i b = model.bricks[id].bounds();
    if (brickId == kNoRegion || model.bricks[id].level < model.bricks[brickId].level) brickId = id;
    if (p.x >= b.lower.x && p.x < b.upper.x && p.y >= b.lower.y && p.y < b.upper.y && p.z >= b.lower.z &&
        p.z < b.upper.z)
      return id;
  }
  return brickId;
}

} // namespace

vec4f debugColor(const Model& model, const RegionTraversal& traversal, DebugView view, const Ray& ray,
                 FrameBuffer::TileCounters& c) {
  vec4f acc;
  traversal.traverse(ray, [&](const Segment& seg) {
    vec3f color;
    if (view == DebugView::Region) {
      color = hashColor(seg.region);
    } else {
      const Region& region = model.regions.regions[seg.region];
      const uint32_t brickId = brickAt(model, region, ray.org + ray.dir * (0.5f * (seg.t0 + seg.t1)));
      color = view == DebugView::Level ? debugLevelColor(model.bricks[brickId].level) : hashColor(brickId);
    }
    acc = {color.x, color.y, color.z, 1.f};
    ++c.regions;
    return false;
  });
  return acc;
}

} // namespace exa
