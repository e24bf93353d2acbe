// A ray in world and lattice space at once, with the clip interval and the domain applied:
// what every stage along a ray (surfaces, volume, ambient occlusion) starts from. Host and device
// code alike (the CPU renderer and the device back ends build their rays here).
#pragma once

#include "exabricks/accel/traversal.h"
#include "exabricks/core/math.h"
#include "exabricks/core/random.h"
#include "exabricks/render/camera.h"
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

/// Clipping as plain data: planes (each removes its half-space) and a box (when not empty, only
/// its inside stays), world space.
struct ClipView {
  const ClipPlane* planes = nullptr;
  int planeCount = 0;
  box3d box;
};

inline ClipView clipViewOf(const Clipping& c) { return {c.planes.data(), int(c.planes.size()), c.box}; }

/// The lattice interval of the world interval; an empty one collapses to [0, 0].
EXA_HOST_DEVICE inline void setLatticeInterval(DualRay& r) {
  r.lattice.tmin = float(r.sMin * r.kappa);
  r.lattice.tmax = std::isinf(r.sMax) ? std::numeric_limits<float>::infinity() : float(r.sMax * r.kappa);
  if (!(r.lattice.tmax >= r.lattice.tmin)) r.lattice.tmax = r.lattice.tmin = 0.f, r.sMax = -1.0;
}

/// Narrows the world interval by the clip planes and box.
EXA_HOST_DEVICE inline void clipInterval(DualRay& r, const ClipView& c) {
  const vec3d& orgW = r.orgW;
  for (int i = 0; i < c.planeCount; ++i) {
    const ClipPlane& cp = c.planes[i];
    const double g0 = dot(orgW - cp.point, cp.normal), dn = dot(r.dirW, cp.normal);
    if (dn == 0.0) {
      if (g0 > 0.0) r.sMax = -1.0;
    } else if (dn > 0.0) {
      r.sMax = std::min(r.sMax, -g0 / dn);
    } else {
      r.sMin = std::max(r.sMin, -g0 / dn);
    }
  }
  if (c.box.empty()) return;
  for (int a = 0; a < 3; ++a) {
    if (r.dirW[a] == 0.0) {
      if (orgW[a] < c.box.lower[a] || orgW[a] > c.box.upper[a]) r.sMax = -1.0;
      continue;
    }
    const double ta = (c.box.lower[a] - orgW[a]) / r.dirW[a];
    const double tb = (c.box.upper[a] - orgW[a]) / r.dirW[a];
    r.sMin = std::max(r.sMin, std::min(ta, tb));
    r.sMax = std::min(r.sMax, std::max(ta, tb));
  }
}

/// World ray -> lattice ray, with the clip interval of `clip` (planes and box, world space)
/// applied unless it is null. The lattice interval may be empty; sMin/sMax keep the clipped
/// world interval.
EXA_HOST_DEVICE inline DualRay makeDualRay(const WorldTransform& world, const vec3d& orgW, const vec3d& dirW,
                                           const ClipView* clip) {
  DualRay r;
  r.orgW = orgW;
  r.dirW = normalize(dirW);
  const vec3d orgL = world.toLattice(orgW);
  const vec3d dL = r.dirW / world.scale;
  r.kappa = length(dL);
  r.lattice.org = vec3f(orgL);
  r.lattice.dir = vec3f(dL / r.kappa);
  if (clip) clipInterval(r, *clip);
  setLatticeInterval(r);
  return r;
}

inline DualRay makeDualRay(const WorldTransform& world, const vec3d& orgW, const vec3d& dirW, const Clipping* clip) {
  if (!clip) return makeDualRay(world, orgW, dirW, static_cast<const ClipView*>(nullptr));
  const ClipView view = clipViewOf(*clip);
  return makeDualRay(world, orgW, dirW, &view);
}

/// Restricts a ray to a world box (volume, iso-surfaces and meshes alike); domainMin/domainMax
/// get the box's own interval.
EXA_HOST_DEVICE inline void restrictToBox(DualRay& r, const box3d& domain) {
  // The domain's interval on its own (meshes that clipping leaves use it), then with the clip.
  for (int a = 0; a < 3; ++a) {
    if (r.dirW[a] == 0.0) {
      if (r.orgW[a] < domain.lower[a] || r.orgW[a] >= domain.upper[a]) r.domainMax = -1.0;
      continue;
    }
    const double ta = (domain.lower[a] - r.orgW[a]) / r.dirW[a];
    const double tb = (domain.upper[a] - r.orgW[a]) / r.dirW[a];
    r.domainMin = std::max(r.domainMin, std::min(ta, tb));
    r.domainMax = std::min(r.domainMax, std::max(ta, tb));
  }
  if (r.sMax >= r.sMin) { // not clipped away already
    r.sMin = std::max(r.sMin, r.domainMin);
    r.sMax = std::min(r.sMax, r.domainMax);
  }
  setLatticeInterval(r);
}

/// Ends the ray at world distance `s` from its origin: nothing beyond it is drawn (volume,
/// iso-surfaces and meshes, clipped or not). An infinite `s` leaves the ray as it is.
EXA_HOST_DEVICE inline void limitDistance(DualRay& r, double s) {
  if (!(s < std::numeric_limits<double>::infinity())) return;
  r.domainMax = std::min(r.domainMax, s);
  if (r.sMax >= r.sMin) r.sMax = std::min(r.sMax, s); // not clipped away already
  setLatticeInterval(r);
}

/// The primary ray of pixel (x, y) for one pass, from its random numbers: the offset within the
/// pixel (its centre without pixel jitter) and the sample offset rho along the ray (0.5 without
/// jitter), world origin and direction; `rng` continues for what the ray needs next.
EXA_HOST_DEVICE inline void primaryRay(const Camera& camera, int x, int y, int width, int height, double aspect,
                                       bool pixelJitter, bool jitter, PixelRandom& rng, float& rho, vec3d& orgW,
                                       vec3d& dirW) {
  const float jx = pixelJitter ? rng.next() : 0.5f;
  const float jy = pixelJitter ? rng.next() : 0.5f;
  rho = jitter ? rng.next() : 0.5f;
  camera.ray((x + jx) / width, (y + jy) / height, aspect, orgW, dirW);
}

/// Ends the ray at a pixel's depth limit: a distance along the ray, or with `planar` a depth
/// along the view direction `forward`.
EXA_HOST_DEVICE inline void applyDepthLimit(DualRay& r, double limit, bool planar, const vec3d& forward) {
  limitDistance(r, planar ? limit / dot(r.dirW, forward) : limit);
}

/// Whether clipping left nothing of the ray.
EXA_HOST_DEVICE inline bool clippedAway(const DualRay& r) { return r.sMax < r.sMin; }

} // namespace exa
