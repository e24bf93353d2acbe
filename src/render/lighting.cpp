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

VolumeSettings volumeSettingsOf(const Scene& scene, float rate) {
  VolumeSettings v;
  v.shading = scene.shading;
  v.sampling = scene.integration.sampling;
  v.earlyTermination = scene.integration.earlyTermination;
  v.terminationOpacity = scene.integration.terminationOpacity;
  v.rate = rate;
  return v;
}

RaySettings raySettingsOf(const Scene& scene, const DatasetInfo& dataset, const WorldTransform& world) {
  RaySettings r;
  r.volume = scene.volume;
  r.clipMeshes = scene.clip.meshes;
  r.terms = scene.light.terms;
  r.headlight = scene.light.headlight;
  r.lightWorld = normalize(scene.light.direction);
  r.aoRays = scene.ao.rays;
  r.aoVolume = scene.volume && scene.ao.volume;
  const OcclusionLengths lengths = occlusionLengths(scene.ao, dataset, world);
  r.aoLength = lengths.length;
  r.aoEps = lengths.eps;
  if (scene.integration.earlyTermination) r.stopOpacity = scene.integration.terminationOpacity;
  return r;
}

} // namespace exa
