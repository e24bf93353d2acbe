// Light on surface hits beyond the local shading of sample_math.h: ambient occlusion, rays over
// the hemisphere of the hit's normal that surfaces, meshes and (optionally) the volume block.
#pragma once

#include "surfaces.h"
#include "volume_marcher.h"

#include "exabricks/core/random.h"
#include "exabricks/render/frame_buffer.h"

namespace exa {

/// What ambient-occlusion rays meet: the scene's clipping, its surfaces and, where `volume` is
/// set, the volume's opacity.
struct OcclusionScene {
  const Model& model;
  const DatasetInfo& dataset;
  const Clipping& clip;
  const Surfaces& surfaces;
  const VolumeMarcher& marcher;
  bool volume = false; ///< the volume attenuates the rays (scene volume and ao.volume on)
};

/// The world length of ambient-occlusion rays (the scene's, or a tenth of the data's diagonal)
/// and how far from the surface they start.
struct OcclusionLengths {
  double length = 1.0, eps = 1e-5;
};
OcclusionLengths occlusionLengths(const AmbientOcclusion& ao, const DatasetInfo& dataset, const WorldTransform& world);

/// Fraction of unoccluded cosine-weighted rays over the hemisphere of the hit's normal (1 with no
/// rays); random numbers from rng, rays and samples counted into c.
float ambientOcclusion(const SurfaceHit& hit, const AmbientOcclusion& ao, const OcclusionScene& scene,
                       const MarchSettings& march, PixelRandom& rng, FrameBuffer::TileCounters& c);

} // namespace exa
