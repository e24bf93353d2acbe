// The settings of light on surface hits beyond the local shading of sample_math.h: how long
// ambient-occlusion rays are and where they start (the rays themselves are the ray program's,
// ray_program.h).
#pragma once

#include "ray_program.h"

#include "exabricks/render/renderer.h"

namespace exa {

/// The world length of ambient-occlusion rays (the scene's, or a tenth of the data's diagonal)
/// and how far from the surface they start.
struct OcclusionLengths {
  double length = 1.0, eps = 1e-5;
};
OcclusionLengths occlusionLengths(const AmbientOcclusion& ao, const DatasetInfo& dataset, const WorldTransform& world);

} // namespace exa
