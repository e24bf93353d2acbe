#include "dual_ray.h"

#include <algorithm>
#include <cmath>

namespace exa {
namespace {

/// The lattice interval of the world interval; an empty one collapses to [0, 0].
void setLatticeInterval(DualRay& r) {
  r.lattice.tmin = float(r.sMin * r.kappa);
  r.lattice.tmax = std::isinf(r.sMax) ? std::numeric_limits<float>::infinity() : float(r.sMax * r.kappa);
  if (!(r.lattice.tmax >= r.lattice.tmin)) r.lattice.tmax = r.lattice.tmin = 0.f, r.sMax = -1.0;
}

void clipInterval(DualRay& r, const Clipping& c) {
  const vec3d& orgW = r.orgW;
  for (const ClipPlane& cp : c.planes) {
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

} // namespace

DualRay makeDualRay(const WorldTransform& world, const vec3d& orgW, const vec3d& dirW, const Clipping* clip) {
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

void restrictToBox(DualRay& r, const box3d& domain) {
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

void limitDistance(DualRay& r, double s) {
  if (!(s < std::numeric_limits<double>::infinity())) return;
  r.domainMax = std::min(r.domainMax, s);
  if (r.sMax >= r.sMin) r.sMax = std::min(r.sMax, s); // not clipped away already
  setLatticeInterval(r);
}

} // namespace exa
