// The ray marcher's per-pixel program, written once as host and device code: the camera ray
// (clipping, the renderer's domain, the depth limit), the nearest surface (meshes, then an
// iso-surface in front of them), the volume in front of it, the surface's colour, ambient
// occlusion and lighting, composited front to back. A back end supplies only what it keeps
// differently (RayBackEnd below): how meshes are intersected (Embree on the CPU, the triangle
// BVH on devices), the iso-surfaces' traversal, and the volume march (the CPU's batches, the
// devices' one sample after another). The path tracer (path_trace.h) takes the same camera ray
// and nearest surface.
//
// RayBackEnd, as the functions below use it:
//   bool hasMeshes() const;                                 // meshes or particles
//   bool meshHit(const DualRay&, double sMin, double sMax, SurfaceHit&) const; // kind, distance, normal, index
//   bool meshOccludes(const DualRay&, double sMin, double sMax) const;
//   bool hasIso() const;
//   bool isoHit(const Ray& lattice, float& t, uint32_t& region, int& which, RayCounts&) const;
//   const FieldView& isoView() const;
//   const vec3f& invScale() const;                          // world units per lattice unit, inverted
//   vec3f surfaceColor(const SurfaceHit&) const;
//   template <bool OpacityOnly> void march(const Ray&, float rho, const RayLight&, vec4f& acc, RayCounts&) const;
#pragma once

#include "dual_ray.h"
#include "iso_search.h"

#include "exabricks/accel/sphere_bvh.h"
#include "exabricks/core/random.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/sample_math.h"

#include <cstdint>

namespace exa {

/// What one camera ray and the rays it spawns counted; a back end sums them per tile or block.
struct RayCounts {
  uint32_t samples = 0;      ///< volume samples, occlusion rays' included
  uint32_t marchSamples = 0; ///< the camera ray's own volume samples (the steps view)
  uint32_t isoSamples = 0;   ///< iso-surface search samples
  uint32_t aoRays = 0;       ///< ambient-occlusion rays
  uint32_t surfaceHits = 0;  ///< camera rays that reached a surface
  uint32_t regions = 0;      ///< region segments the volume march visited
};

/// A ray's lighting: the direction towards the light and the half vector with the view (world, unit).
struct RayLight {
  vec3f light{0.f}, halfVector{0.f};
};

/// How rays sample the volume, from the scene and the frame's rate (volumeSettingsOf): the same
/// for the CPU's batched march and the per-ray code of the device back ends.
struct VolumeSettings {
  Shading shading = Shading::Smooth;
  Sampling sampling = Sampling::Adaptive;
  bool earlyTermination = true;
  float terminationOpacity = 0.98f;
  float rate = 1.f; ///< samples per half region's finest width
};

/// The volume settings of a scene at a frame's rate (lighting.cpp).
VolumeSettings volumeSettingsOf(const Scene& scene, float rate);

/// The settings every ray of a pass shares, from the scene (raySettingsOf).
struct RaySettings {
  bool volume = true; ///< the volume is integrated
  bool clipMeshes = false;
  ShadingTerms terms;
  bool headlight = true;
  vec3f lightWorld{0.f, 0.f, -1.f}; ///< unit, towards the light
  int aoRays = 0;
  bool aoVolume = false;               ///< the volume attenuates occlusion rays
  double aoLength = 1.0, aoEps = 1e-5; ///< world
  float stopOpacity = 2.f;             ///< the volume is not marched once this is gathered (early termination)
};

/// The ray settings of a scene over a dataset (lighting.cpp).
RaySettings raySettingsOf(const Scene& scene, const DatasetInfo& dataset, const WorldTransform& world);

/// How a pass makes its camera rays, from the frame.
struct CameraRays {
  Camera camera;
  int width = 1, height = 1;
  double aspect = 1.0;
  bool jitter = true, pixelJitter = false;
  bool hasDomain = false; ///< rays see only the inside of `domain` (world)
  box3d domain;
  /// Frame::depthLimit (per pixel, where the pass runs) and how to read it.
  const float* depthLimit = nullptr;
  bool depthLimitPlanar = false;
  vec3d forward{0.0, 0.0, -1.0};       ///< the camera's view direction (planar depth limits)
  const float* frontOpacity = nullptr; ///< Frame::frontOpacity, where the pass runs
};

/// The camera rays of a frame (without its depth limit's storage, which the back end places).
inline CameraRays cameraRaysOf(const Frame& frame) {
  CameraRays c;
  c.camera = frame.camera;
  c.width = frame.width;
  c.height = frame.height;
  c.aspect = double(frame.width) / double(frame.height);
  c.jitter = frame.jitter;
  c.pixelJitter = frame.samplesPerPixel > 1 && frame.jitter;
  c.depthLimit = frame.depthLimit;
  c.depthLimitPlanar = frame.depthLimitPlanar;
  c.frontOpacity = frame.frontOpacity;
  c.forward = normalize(frame.camera.lookAt - frame.camera.position);
  return c;
}

/// The camera ray of pixel (x, y): clipped by `clip` (may be null), inside the domain, up to the
/// depth limit; rho is the sample offset along it.
EXA_HOST_DEVICE inline DualRay cameraRay(const CameraRays& c, const WorldTransform& world, const ClipView* clip, int x,
                                         int y, PixelRandom& rng, float& rho) {
  vec3d orgW, dirW;
  primaryRay(c.camera, x, y, c.width, c.height, c.aspect, c.pixelJitter, c.jitter, rng, rho, orgW, dirW);
  DualRay dr = makeDualRay(world, orgW, dirW, clip);
  if (c.hasDomain) restrictToBox(dr, c.domain);
  if (c.depthLimit)
    applyDepthLimit(dr, c.depthLimit[size_t(y) * size_t(c.width) + size_t(x)], c.depthLimitPlanar, c.forward);
  return dr;
}

/// The opacity the data in front of the domain gathered along pixel (x, y)'s ray (0 without).
EXA_HOST_DEVICE inline float frontOpacityOf(const CameraRays& c, int x, int y) {
  return c.frontOpacity ? c.frontOpacity[size_t(y) * size_t(c.width) + size_t(x)] : 0.f;
}

/// The light of a ray travelling along viewW: the headlight's or the scene's direction.
EXA_HOST_DEVICE inline RayLight rayLightOf(const RaySettings& s, const vec3f& viewW) {
  RayLight l;
  l.light = s.headlight ? viewW : s.lightWorld;
  l.halfVector = normalize(l.light + viewW);
  return l;
}

/// What colours a surface before lighting: per mesh, per particle, per iso-value (cycled; default colours
/// without them), or an iso colour field through its table.
struct SurfaceColors {
  const vec3f* meshColors = nullptr;
  const vec3f* particleColors = nullptr;
  const vec3f* isoColors = nullptr;
  int isoColorCount = 0;
  bool isoColored = false;
  FieldView isoColorView;
  TfTableView isoColorTable;
};

EXA_HOST_DEVICE inline vec3f surfaceColorOf(const SurfaceColors& s, const WorldTransform& world,
                                            const SurfaceHit& hit) {
  if (hit.kind == SurfaceHit::Mesh) return s.meshColors[hit.index];
  if (hit.kind == SurfaceHit::Particle) return s.particleColors[hit.index];
  if (s.isoColored) {
    float v;
    if (sampleField(s.isoColorView, vec3f(world.toLattice(hit.position)), v)) return tfLookup(s.isoColorTable, v).rgb();
  }
  if (s.isoColorCount > 0) return s.isoColors[hit.index % s.isoColorCount];
  return defaultIsoColor(hit.index);
}

/// The nearest particle sphere within [s0, s1] along the ray (world distances): its kind,
/// distance, normal and sphere number, as both back ends' meshHit find it after the meshes.
EXA_HOST_DEVICE inline bool particleHit(const SphereBvhView& spheres, const DualRay& r, double s0, double s1,
                                        SurfaceHit& hit) {
  SphereHit sh;
  if (!spheres.nodes || !(s1 >= s0) ||
      !intersectSpheres(spheres, vec3f(r.orgW), vec3f(r.dirW), float(s0 > 0.0 ? s0 : 0.0), float(s1), false, sh))
    return false;
  hit.kind = SurfaceHit::Particle;
  hit.index = int(sh.sphere);
  hit.distance = sh.t;
  hit.normal = sh.normal;
  return true;
}

/// Whether a particle sphere lies within [s0, s1] along the ray.
EXA_HOST_DEVICE inline bool particleOccludes(const SphereBvhView& spheres, const DualRay& r, double s0, double s1) {
  SphereHit sh;
  return spheres.nodes && s1 > s0 &&
         intersectSpheres(spheres, vec3f(r.orgW), vec3f(r.dirW), float(s0 > 0.0 ? s0 : 0.0), float(s1), true, sh);
}

/// The nearest surface along a ray: a mesh within the clip interval (with meshes unclipped, the
/// domain's), then an iso-surface in front of it where the ray is not clipped away.
template <typename B>
EXA_HOST_DEVICE inline bool nearestSurface(const B& b, const DualRay& r, bool clipMeshes, SurfaceHit& hit,
                                           RayCounts& c) {
  bool have = false;
  if (b.hasMeshes()) {
    const double s0 = clipMeshes ? r.sMin : r.domainMin, s1 = clipMeshes ? r.sMax : r.domainMax;
    have = b.meshHit(r, s0, s1, hit);
    if (have) hit.position = r.orgW + r.dirW * hit.distance;
  }
  if (!b.hasIso() || clippedAway(r)) return have;
  Ray lr = r.lattice;
  if (have) lr.tmax = fminf(lr.tmax, float(hit.distance * r.kappa));
  float t;
  uint32_t region;
  int which;
  if (!b.isoHit(lr, t, region, which, c)) return have;
  hit.kind = SurfaceHit::Iso;
  hit.index = which;
  hit.distance = double(t) / r.kappa;
  hit.position = r.orgW + r.dirW * hit.distance;
  hit.normal = isoNormal(b.isoView(), region, lr.org + lr.dir * t, r.dirW, b.invScale());
  return true;
}

/// Ambient occlusion: the fraction of cosine-weighted rays over the hemisphere of a surface
/// point's normal that no mesh, iso-surface or (with aoVolume) volume opacity blocks within
/// aoLength.
template <typename B>
EXA_HOST_DEVICE inline float occlusion(const B& b, const RaySettings& s, const WorldTransform& world,
                                       const ClipView* clip, const vec3d& position, const vec3f& normal,
                                       PixelRandom& rng, RayCounts& c) {
  float open = 0.f;
  for (int i = 0; i < s.aoRays; ++i) {
    const float r1 = rng.next(), r2 = rng.next();
    const vec3f d = cosineHemisphere(normal, r1, r2);
    ++c.aoRays;
    const DualRay ar = makeDualRay(world, position + vec3d(normal) * s.aoEps, vec3d(d), clip);
    const double meshMin = s.clipMeshes ? ar.sMin : 0.0;
    const double meshMax = s.clipMeshes ? fmin(ar.sMax, s.aoLength) : s.aoLength;
    if (b.hasMeshes() && b.meshOccludes(ar, meshMin, meshMax)) continue;
    Ray lr = ar.lattice;
    lr.tmax = fminf(lr.tmax, float(s.aoLength * ar.kappa));
    float t;
    uint32_t region;
    int which;
    if (!clippedAway(ar) && b.hasIso() && b.isoHit(lr, t, region, which, c)) continue;
    float visibility = 1.f;
    if (s.aoVolume && !clippedAway(ar) && lr.tmax > lr.tmin) {
      vec4f acc;
      b.template march<true>(lr, 0.5f, RayLight{}, acc, c);
      visibility = 1.f - acc.w;
    }
    open += visibility;
  }
  return s.aoRays > 0 ? open / float(s.aoRays) : 1.f;
}

/// One ray-marched sample along camera ray `r` (sample offset rho): the volume in front of the
/// nearest surface, then the surface lit and occluded, premultiplied. `Surfaces` false compiles
/// the volume alone (fewer registers on a GPU). `front`: the opacity gathered in front of the
/// domain (Frame::frontOpacity); the ray continues from it.
template <bool Surfaces, typename B>
EXA_HOST_DEVICE inline vec4f marchSample(const B& b, const RaySettings& s, const WorldTransform& world,
                                         const ClipView* clip, const DualRay& r, float rho, PixelRandom& rng,
                                         RayCounts& c, float front = 0.f) {
  const RayLight light = rayLightOf(s, vec3f(r.dirW));
  vec4f acc(0.f, 0.f, 0.f, front);
  SurfaceHit hit;
  bool haveHit = false;
  if constexpr (Surfaces) haveHit = nearestSurface(b, r, s.clipMeshes, hit, c);
  Ray volumeRay = r.lattice;
  if (haveHit) volumeRay.tmax = fminf(volumeRay.tmax, float(hit.distance * r.kappa));
  if (s.volume && !clippedAway(r) && !(front > 0.f && front >= s.stopOpacity)) {
    b.template march<false>(volumeRay, rho, light, acc, c);
    c.marchSamples = c.samples;
  }
  if constexpr (Surfaces) {
    if (haveHit && acc.w < 1.f) {
      ++c.surfaceHits;
      const vec3f base = b.surfaceColor(hit);
      const float ao = s.aoRays > 0 ? occlusion(b, s, world, clip, hit.position, hit.normal, rng, c) : 1.f;
      compositeOpaqueBehind(acc, shadeSurface(base, hit.normal, light.light, light.halfVector, ao, s.terms));
    }
  }
  return acc;
}

} // namespace exa
