// The implicit iso-surface along a ray, host and device code alike: the search for the nearest
// crossing of an iso-value through a walk over the regions that may hold one, the normal at a
// crossing and the default colours.
#pragma once

#include "layer_table.h"

#include "exabricks/accel/traversal.h"
#include "exabricks/amr/basis.h"
#include "exabricks/render/sample_math.h"

#include <cmath>
#include <limits>

namespace exa {

/// Default iso-surface colours (linear RGB), cycled over the iso-values.
EXA_HOST_DEVICE inline vec3f defaultIsoColor(int index) {
  switch (index & 3) {
  case 0:
    return {0.80f, 0.80f, 0.78f};
  case 1:
    return {0.85f, 0.35f, 0.20f};
  case 2:
    return {0.20f, 0.45f, 0.85f};
  default:
    return {0.35f, 0.70f, 0.30f};
  }
}

/// Nearest crossing of one of `values` along a lattice ray within [ray.tmin, ray.tmax], over the
/// segments `walk(ray, emit)` presents front to back: each region is stepped at its step for
/// `rate` (and at its entry and exit), and a sign change of value - isovalue is refined by
/// bisection to 1e-3 of the region's finest cell width, then by one secant step. Returns the
/// lattice t, the region and the iso-value's index; counts the reconstructions into `samples`.
template <typename Walk>
EXA_HOST_DEVICE inline bool findIsoCrossing(Walk&& walk, const FieldView& view, const float* values, int valueCount,
                                            const Ray& ray, Sampling sampling, float referenceWidth, float rate,
                                            float& tHit, uint32_t& regionHit, int& which, uint64_t& samples) {
  if (valueCount == 0 || !(ray.tmax > ray.tmin)) return false;
  bool found = false;
  walk(ray, [&](const Segment& seg) {
    const float t0 = std::max(seg.t0, ray.tmin), t1 = std::min(seg.t1, ray.tmax);
    if (!(t1 > t0)) return true;
    const Region& region = view.regions[seg.region];
    const float dt = sampleStep(region, sampling, referenceWidth, rate);
    const float tolerance = 1e-3f * region.finestWidth();
    auto value = [&](float t, float& v) {
      ++samples;
      return sampleRegion(view, seg.region, ray.org + ray.dir * t, v);
    };
    const int steps = std::max(1, int(std::ceil((t1 - t0) / dt)));
    float ta = t0, va = 0.f;
    bool aValid = value(ta, va);
    for (int i = 1; i <= steps; ++i) {
      const float tb = i == steps ? t1 : t0 + (t1 - t0) * float(i) / float(steps);
      float vb = 0.f;
      const bool bValid = value(tb, vb);
      if (aValid && bValid) {
        float best = std::numeric_limits<float>::infinity();
        int bestIndex = -1;
        for (int j = 0; j < valueCount; ++j) {
          const float c = values[j];
          const bool sideA = va >= c, sideB = vb >= c;
          if (sideA == sideB) continue;
          const float t = refineCrossing(value, ta, tb, va, vb, c, sideA, tolerance);
          if (t < best) best = t, bestIndex = j;
        }
        if (bestIndex >= 0) {
          tHit = best;
          regionHit = seg.region;
          which = bestIndex;
          found = true;
          return false;
        }
      }
      ta = tb, va = vb, aValid = bValid;
    }
    return true;
  });
  return found;
}

/// World normal of the iso-surface at lattice point p of `region`, facing the ray's origin
/// (world direction dirW): along the field's gradient, or against the ray where it has none.
EXA_HOST_DEVICE inline vec3f isoNormal(const FieldView& view, uint32_t region, const vec3f& p, const vec3d& dirW,
                                       const vec3f& invScale) {
  vec3f n = -vec3f(dirW);
  float v;
  vec3f g;
  if (sampleRegion(view, region, p, v, &g)) {
    const vec3f gw = g * invScale;
    if (length(gw) > 1e-30f) n = normalize(gw);
  }
  if (dot(vec3d(n), dirW) > 0.0) n = -n;
  return n;
}

} // namespace exa
