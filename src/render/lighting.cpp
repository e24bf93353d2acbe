#include "lighting.h"

#include <algorithm>
#include <cmath>

namespace exa {

OcclusionLengths occlusionLengths(const AmbientOcclusion& ao, const DatasetInfo& dataset, const WorldTransform& world) {
  OcclusionLengths l;
  l.length = ao.length > 0.f ? double(ao.length) : 0.1 * dataset.worldDiagonal;
  l.eps = std::max(1e-5 * dataset.worldDiagonal, 1e-2 * double(dataset.referenceWidth) * reduceMin(world.scale));
  return l;
}

float ambientOcclusion(const SurfaceHit& hit, const AmbientOcclusion& ao, const OcclusionScene& scene,
                       const MarchSettings& march, PixelRandom& rng, FrameBuffer::TileCounters& c) {
  const OcclusionLengths lengths = occlusionLengths(ao, scene.dataset, scene.model.world);
  const double lengthW = lengths.length, eps = lengths.eps;
  float open = 0.f;
  for (int i = 0; i < ao.rays; ++i) {
    const float r1 = rng.next(), r2 = rng.next();
    const vec3f d = cosineHemisphere(hit.normal, r1, r2);
    ++c.aoRays;
    const DualRay ar = makeDualRay(scene.model.world, hit.position + vec3d(hit.normal) * eps, vec3d(d), &scene.clip);
    const double meshMin = scene.clip.meshes ? ar.sMin : 0.0;
    const double meshMax = scene.clip.meshes ? std::min(ar.sMax, lengthW) : lengthW;
    if (scene.surfaces.meshOccludes(ar, meshMin, meshMax)) continue;
    Ray lr = ar.lattice;
    lr.tmax = std::min(lr.tmax, float(lengthW * ar.kappa));
    float t;
    uint32_t region;
    int which;
    if (!clippedAway(ar) && scene.surfaces.findIso(lr, march.sampling, march.rate, t, region, which, c.isoSamples))
      continue;
    float visibility = 1.f;
    if (scene.volume && !clippedAway(ar) && lr.tmax > lr.tmin) {
      vec4f acc;
      uint64_t samples = 0, regions = 0;
      scene.marcher.march<true>(lr, 0.5f, RayLight{}, march, acc, samples, regions);
      c.samples += samples;
      visibility = 1.f - acc.w;
    }
    open += visibility;
  }
  return ao.rays > 0 ? open / float(ao.rays) : 1.f;
}

} // namespace exa
