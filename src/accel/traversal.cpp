#include "exabricks/accel/traversal.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include "embree_util.h"

namespace exa {

namespace {
struct Payload {
  const Model* model;
  const uint32_t* primToRegion;
};
} // namespace

struct RegionTraversal::EmbreeScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<uint32_t> primToRegion;
  Payload payload{}; ///< user data of the geometry; lives as long as the scene

  ~EmbreeScene() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

namespace {

void boundsFunction(const RTCBoundsFunctionArguments* args) {
  const auto* p = static_cast<const Payload*>(args->geometryUserPtr);
  // Slightly grown, so that the BVH never culls a ray that grazes a face; the intersection
  // function decides exactly.
  const box3f b = p->model->regions.regions[p->primToRegion[args->primID]].bounds();
  auto grow = [](float v, float sign) { return v + sign * 1e-5f * (std::abs(v) + 1.f); };
  args->bounds_o->lower_x = grow(b.lower.x, -1.f);
  args->bounds_o->lower_y = grow(b.lower.y, -1.f);
  args->bounds_o->lower_z = grow(b.lower.z, -1.f);
  args->bounds_o->upper_x = grow(b.upper.x, 1.f);
  args->bounds_o->upper_y = grow(b.upper.y, 1.f);
  args->bounds_o->upper_z = grow(b.upper.z, 1.f);
}

/// Accepts a region when its box has an interval beyond ray.tnear; the hit distance is the
/// entry (clamped to tnear) and the exit goes into hit.u.
void intersectFunction(const RTCIntersectFunctionNArguments* args) {
  if (!args->valid[0]) return;
  const auto* p = static_cast<const Payload*>(args->geometryUserPtr);
  RTCRayHit* rh = reinterpret_cast<RTCRayHit*>(args->rayhit);
  Ray ray;
  ray.org = vec3f(rh->ray.org_x, rh->ray.org_y, rh->ray.org_z);
  ray.dir = vec3f(rh->ray.dir_x, rh->ray.dir_y, rh->ray.dir_z);
  float t0, t1;
  const box3f b = p->model->regions.regions[p->primToRegion[args->primID]].bounds();
  if (!rayBoxInterval(ray, safeInverse(ray.dir), b, t0, t1)) return;
  t0 = std::max(t0, rh->ray.tnear);
  if (!(t1 > t0) || t0 >= rh->ray.tfar) return;
  rh->ray.tfar = t0;
  rh->hit.u = t1;
  rh->hit.v = 0.f;
  rh->hit.Ng_x = rh->hit.Ng_y = rh->hit.Ng_z = 0.f;
  rh->hit.primID = args->primID;
  rh->hit.geomID = args->geomID;
  rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

} // namespace

RegionTraversal::RegionTraversal(const Model& model, TraversalKind kind) : model_(model), kind_(kind) {
  setVisible(std::vector<uint8_t>(model.regions.regions.size(), 1));
}

RegionTraversal::~RegionTraversal() = default;

double RegionTraversal::setVisible(const std::vector<uint8_t>& visible) {
  Timer timer;
  EXA_CHECK(visible.size() == model_.regions.regions.size());
  visible_ = visible;
  visibleCount_ = 0;
  for (uint8_t v : visible_)
    visibleCount_ += v != 0;
  if (kind_ != TraversalKind::Embree) {
    markVisibleSubtrees();
    return timer.seconds();
  }

  if (!embree_) {
    embree_ = std::make_unique<EmbreeScene>();
    embree_->device = embree::newDevice();
  }
  EmbreeScene* es = embree_.get();
  if (es->scene) rtcReleaseScene(es->scene);
  es->scene = rtcNewScene(es->device);
  rtcSetSceneBuildQuality(es->scene, RTC_BUILD_QUALITY_MEDIUM);
  rtcSetSceneFlags(es->scene, RTC_SCENE_FLAG_ROBUST);
  es->primToRegion.clear();
  for (uint32_t r = 0; r < visible_.size(); ++r)
    if (visible_[r]) es->primToRegion.push_back(r);
  if (!es->primToRegion.empty()) {
    RTCGeometry geom = rtcNewGeometry(es->device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geom, unsigned(es->primToRegion.size()));
    es->payload = Payload{&model_, es->primToRegion.data()};
    rtcSetGeometryUserData(geom, &es->payload);
    rtcSetGeometryBoundsFunction(geom, boundsFunction, nullptr);
    rtcSetGeometryIntersectFunction(geom, intersectFunction);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(es->scene, geom);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(es->scene);
  return timer.seconds();
}

std::vector<uint8_t> visibleSubtrees(const std::vector<RegionKdNode>& nodes, const std::vector<uint8_t>& visible) {
  std::vector<uint8_t> below(nodes.size(), 0);
  if (nodes.empty()) return below;
  // Post-order with an explicit stack: a node is done once both children are.
  std::vector<std::pair<uint32_t, bool>> stack{{0u, false}};
  while (!stack.empty()) {
    const auto [node, childrenDone] = stack.back();
    stack.pop_back();
    const RegionKdNode& n = nodes[node];
    if (n.axis == kLeafAxis) {
      below[node] = n.index != kNoRegion && visible[n.index];
    } else if (childrenDone) {
      below[node] = below[n.index] | below[n.index + 1];
    } else {
      stack.push_back({node, true});
      stack.push_back({n.index, false});
      stack.push_back({n.index + 1, false});
    }
  }
  return below;
}

void RegionTraversal::markVisibleSubtrees() { subtreeVisible_ = visibleSubtrees(model_.regions.nodes, visible_); }

bool RegionTraversal::nextEmbree(const Ray& ray, float tnear, Segment& seg) const {
  if (!embree_ || embree_->primToRegion.empty()) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh = embree::makeRayHit(ray.org, ray.dir, tnear, ray.tmax);
  rtcIntersect1(embree_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  seg.t0 = rh.ray.tfar;
  seg.t1 = std::min(rh.hit.u, ray.tmax);
  seg.region = embree_->primToRegion[rh.hit.primID];
  return true;
}

} // namespace exa
