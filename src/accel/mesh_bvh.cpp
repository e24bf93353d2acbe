#include "exabricks/accel/mesh_bvh.h"

#include "embree_util.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace exa {

struct MeshBvh::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  ~Impl() { release(); }
  void release() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
    scene = nullptr;
    device = nullptr;
  }
};

MeshBvh::MeshBvh() : impl_(std::make_unique<Impl>()) {}
MeshBvh::~MeshBvh() = default;

void MeshBvh::clear() { impl_->release(); }

bool MeshBvh::empty() const { return impl_->scene == nullptr; }

void MeshBvh::build(const std::vector<const TriangleMesh*>& meshes) {
  Impl& im = *impl_;
  im.release();
  if (meshes.empty()) return;
  im.device = embree::newDevice();
  im.scene = rtcNewScene(im.device);
  rtcSetSceneFlags(im.scene, RTC_SCENE_FLAG_ROBUST);
  for (size_t m = 0; m < meshes.size(); ++m) {
    const TriangleMesh& mesh = *meshes[m];
    RTCGeometry geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), mesh.vertices.size()));
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(uint32_t), mesh.triangles.size()));
    if (!vertices || !indices) {
      rtcReleaseGeometry(geom);
      im.release();
      fail("mesh ", m, ": out of memory for ", mesh.triangles.size(), " triangles");
    }
    for (size_t i = 0; i < mesh.vertices.size(); ++i)
      for (int k = 0; k < 3; ++k)
        vertices[3 * i + size_t(k)] = mesh.vertices[i][k];
    for (size_t i = 0; i < mesh.triangles.size(); ++i)
      for (int k = 0; k < 3; ++k)
        indices[3 * i + size_t(k)] = uint32_t(mesh.triangles[i][k]);
    rtcCommitGeometry(geom);
    const unsigned id = rtcAttachGeometry(im.scene, geom);
    rtcReleaseGeometry(geom);
    EXA_CHECK(id == m);
  }
  rtcCommitScene(im.scene);
}

bool MeshBvh::intersect(const vec3d& org, const vec3d& dir, double sMin, double sMax, MeshHit& hit) const {
  if (!impl_->scene || !(sMax >= sMin)) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh = embree::makeRayHit(vec3f(org), vec3f(dir), float(std::max(sMin, 0.0)),
                                    std::isinf(sMax) ? std::numeric_limits<float>::infinity() : float(sMax));
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit.mesh = int(rh.hit.geomID);
  hit.distance = rh.ray.tfar;
  vec3f n = normalize(vec3f(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
  if (dot(vec3d(n), dir) > 0.0) n = -n;
  hit.normal = n;
  return true;
}

bool MeshBvh::occluded(const vec3d& org, const vec3d& dir, double sMin, double sMax) const {
  if (!impl_->scene || !(sMax > sMin)) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray = embree::makeRay(vec3f(org), vec3f(dir), float(std::max(sMin, 0.0)), float(sMax));
  rtcOccluded1(impl_->scene, &context, &ray);
  return ray.tfar < 0.f;
}

} // namespace exa
