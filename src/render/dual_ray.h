// A ray in world and lattice space at once, with the clip interval and the domain applied:
// what every stage along a ray (surfaces, volume, ambient occlusion) starts from.
#pragma once

#include "exabricks/accel/traversal.h"
#include "exabricks/core/math.h"
#include "exabricks/render/scene.h"

#include <limits>

namespace exa {

/// A ray in both spaces: world origin and unit direction, and the lattice ray whose t is in
/// finest lattice units along a unit lattice direction; t = s * kappa for world distance s.
struct DualRay {
  vec3d orgW, dirW;
  Ray lattice;
  double kappa = 1.0;
  double sMin = 0.0, sMax = std::numeric_limits<double>::infinity(); ///< clipped world interval
  /// The interval inside the renderer's domain (meshes are limited to it even when not clipped).
  double domainMin = 0.0, domainMax = std::numeric_limits<double>::infinity();
};

/// World ray -> lattice ray, with the clip interval of `clip` (planes and box, world space)
/// applied unless it is null. The lattice interval may be empty; sMin/sMax keep the clipped
/// world interval.
DualRay makeDualRay(const WorldTransform& world, const vec3d& orgW, const vec3d& dirW, const Clipping* clip);

/// Restricts a ray to a world box (volume, iso-surfaces and meshes alike); domainMin/domainMax
/// get the box's own interval.
void restrictToBox(DualRay& r, const box3d& domain);

/// Ends the ray at world distance `s` from its origin: nothing beyond it is drawn (volume,
/// iso-surfaces and meshes, clipped or not). An infinite `s` leaves the ray as it is.
void limitDistance(DualRay& r, double s);

/// Whether clipping left nothing of the ray.
inline bool clippedAway(const DualRay& r) { return r.sMax < r.sMin; }

} // namespace exa
