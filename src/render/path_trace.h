// Volume path tracing of the AMR data (Integrator::PathTrace), host and device code: free-flight
// sampling by delta tracking and transmittance by ratio tracking against a majorant per active
// brick region (the largest extinction its value range can reach through the transfer
// functions), through the same region traversal and basis reconstruction as the ray marcher;
// single and multiple scattering with a Henyey-Greenstein phase function, Russian roulette, an
// environment light (uniform, or a sky gradient from the horizon to the zenith and the ground)
// and a sun with next-event estimation; the albedo is the scene's or a layer's own over its
// values. A back end supplies the traversal (a
// callable `traverse(ray, emit)` that emits region segments front to back, as
// RegionTraversal::traverse and walkRegionTree do) and the random numbers.
#pragma once

#include "dual_ray.h"

#include "exabricks/accel/traversal.h"
#include "exabricks/amr/basis.h"
#include "exabricks/amr/macrocells.h"
#include "exabricks/core/random.h"
#include "exabricks/render/sample_math.h"

#include <cmath>

namespace exa {

/// One field of the medium and its tabulated transfer function (log2 transmittance per
/// reference width in w, colour in xyz), and its albedo over the same normalised values
/// (kTfTableSize entries; null: the scene's albedo).
struct MediumLayer {
  FieldView view;
  TfTableView table;
  const float* albedo = nullptr;
};

/// A majorant grid: macrocells (amr/macrocells.h) over the regions' box, each with the largest
/// extinction (per lattice unit) the medium reaches anywhere in it (0: none), and per region
/// whether a ray there walks the grid (where it saves more collisions than its steps cost). Null
/// `majorant`: no grid, the regions' majorants alone.
struct MajorantGridView {
  const float* majorant = nullptr;
  const uint8_t* gridded = nullptr;
  MacrocellGrid grid;
};

/// The macrocells of a majorant grid that a lattice ray crosses from t on, in order (a 3-D DDA
/// over the grid's planes): the current one's majorant and the t where the ray leaves it. Outside
/// the grid, or without one, the majorant is unbounded (infinity) and the exit never comes.
struct MacrocellWalk {
  vec3i cell{0}, step{0};
  vec3f tNext{0.f}, tDelta{0.f};
  vec3i stride{0};   ///< change of `index` per step along each axis
  size_t index = 0;  ///< of `cell` in the grid's arrays
  float tExit = 0.f; ///< the nearest of tNext
  int next = 0;      ///< the axis of that plane (x before z before y where they tie)
  bool inside = false;

  /// Continues to the macrocell at t (ahead along the ray): a few steps, or a new start (also
  /// where `started` is false).
  EXA_HOST_DEVICE void moveTo(const MajorantGridView& g, const Ray& ray, float t, bool started) {
    if (!g.majorant) return;
    for (int k = 0; started && k < 4; ++k) {
      if (!inside) break;
      if (exit() > t) return;
      advance(g);
    }
    start(g, ray, t);
  }
  /// Starts at the macrocell that holds the point at t (the nearest one where rounding puts the
  /// point just outside the grid).
  EXA_HOST_DEVICE void start(const MajorantGridView& g, const Ray& ray, float t) {
    inside = g.majorant != nullptr;
    if (!inside) return;
    const vec3f p = ray.org + ray.dir * t;
    const vec3i strides(1, g.grid.dims.x, g.grid.dims.x * g.grid.dims.y);
    for (int a = 0; a < 3; ++a) {
      cell[a] = g.grid.cellAlong(a, p[a]);
      const float d = ray.dir[a];
      step[a] = d > 0.f ? 1 : (d < 0.f ? -1 : 0);
      stride[a] = step[a] * strides[a];
      const float plane = g.grid.lower[a] + float(cell[a] + (d > 0.f ? 1 : 0)) * g.grid.cellSize;
      tNext[a] = d != 0.f ? (plane - ray.org[a]) / d : INFINITY;
      tDelta[a] = d != 0.f ? g.grid.cellSize / fabsf(d) : INFINITY;
    }
    index = g.grid.index(cell);
    nextPlane();
  }
  EXA_HOST_DEVICE float exit() const { return inside ? tExit : INFINITY; }
  EXA_HOST_DEVICE float majorant(const MajorantGridView& g) const { return inside ? g.majorant[index] : INFINITY; }
  EXA_HOST_DEVICE void advance(const MajorantGridView& g) {
    int along;
    if (next == 0) {
      cell.x += step.x, tNext.x += tDelta.x, along = stride.x;
      inside = cell.x >= 0 && cell.x < g.grid.dims.x;
    } else if (next == 1) {
      cell.y += step.y, tNext.y += tDelta.y, along = stride.y;
      inside = cell.y >= 0 && cell.y < g.grid.dims.y;
    } else {
      cell.z += step.z, tNext.z += tDelta.z, along = stride.z;
      inside = cell.z >= 0 && cell.z < g.grid.dims.z;
    }
    index += size_t(ptrdiff_t(along));
    nextPlane();
  }

private:
  EXA_HOST_DEVICE void nextPlane() {
    next = tNext.x <= tNext.y ? (tNext.x <= tNext.z ? 0 : 2) : (tNext.y <= tNext.z ? 1 : 2);
    tExit = next == 0 ? tNext.x : (next == 1 ? tNext.y : tNext.z);
  }
};

/// The medium as plain data: the layers (their extinctions add), a majorant per region
/// (extinction per lattice unit; 0 where nothing can be seen) and a majorant grid (the smaller
/// of the two bounds holds), the factor from a table's -log2 transmittance to extinction per
/// lattice unit (ln 2 over the reference width), and the albedo of layers without one of their
/// own.
struct MediumView {
  const MediumLayer* layers = nullptr;
  int layerCount = 0;
  const float* majorant = nullptr;
  MajorantGridView grid;
  float extinctionPerLog2 = 1.f;
  float albedo = 0.8f;
};

/// The path tracer's settings for one pass, from the scene (directions world, unit). The
/// environment's radiance is `environment` at the horizon, blending linearly in the sine of the
/// elevation above it to `zenith` straight up and to `ground` straight down (all three equal:
/// uniform).
struct PathSettings {
  float albedo = 0.8f, anisotropy = 0.f, emission = 0.f;
  int bounces = 4;
  vec3f environment{1.f}, zenith{1.f}, ground{1.f};
  vec3d up{0.0, 0.0, 1.0};
  vec3d towardsSun{0.0, 0.0, 1.0};
  float sunIntensity = 0.f;
  float sunCosHalfAngle = 1.f;
  double surfaceOffset = 1e-6; ///< world distance rays leave a surface from, along its normal
};

/// The settings of a scene's path tracing; rays leave surfaces a small fraction of the data's
/// world diagonal away. The sky's zenith (`up`) is the frame's: skyUp.
inline PathSettings pathSettingsOf(const PathTracing& p, double worldDiagonal) {
  PathSettings s;
  s.albedo = p.albedo;
  s.anisotropy = p.anisotropy;
  s.emission = p.emission;
  s.bounces = p.bounces;
  s.environment = p.environment;
  s.zenith = p.sky ? *p.sky : p.environment;
  s.ground = p.ground ? *p.ground : p.environment;
  s.towardsSun = -normalize(vec3d(p.sunDirection));
  s.sunIntensity = p.sunIntensity;
  s.sunCosHalfAngle = float(std::cos(0.5 * double(p.sunAngle) * 3.14159265358979 / 180.0));
  s.surfaceOffset = 1e-5 * worldDiagonal;
  return s;
}

/// The sky's zenith: the camera's up direction.
inline vec3d skyUp(const vec3d& cameraUp) {
  return length(cameraUp) > 0.0 ? normalize(cameraUp) : vec3d(0.0, 0.0, 1.0);
}

/// The environment's radiance arriving from direction `towards` (world, unit).
EXA_HOST_DEVICE inline vec3f environmentRadiance(const PathSettings& s, const vec3d& towards) {
  const float h = float(dot(towards, s.up));
  const vec3f& end = h >= 0.f ? s.zenith : s.ground;
  return s.environment + (end - s.environment) * fabsf(h);
}

/// The nearest opaque surface along a ray (an iso-surface or a mesh), as the back end finds it:
/// world distance and normal (facing the ray's origin), and its diffuse colour.
struct PathSurface {
  double distance = 0.0;
  vec3d normal{0.0};
  vec3f color{0.f};
};

/// A layer's albedo table, linearly interpolated, at normalised value n.
EXA_HOST_DEVICE inline float albedoTableAt(const float* table, float n) {
  const float x = n * float(kTfTableSize - 1);
  int i = int(x);
  i = i < 0 ? 0 : (i > kTfTableSize - 2 ? kTfTableSize - 2 : i);
  const float f = clamp01(x - float(i));
  return table[i] + (table[i + 1] - table[i]) * f;
}

/// The medium at one point: extinction per lattice unit summed over the layers, and their
/// extinction-weighted colour and albedo.
struct MediumSample {
  float extinction = 0.f;
  vec3f color{0.f};
  float albedo = 0.f;
};

/// The medium at p (lattice) in `region`.
EXA_HOST_DEVICE inline MediumSample mediumAt(const MediumView& m, uint32_t region, const vec3f& p) {
  MediumSample out;
  vec3f c(0.f);
  float albedo = 0.f;
  for (int i = 0; i < m.layerCount; ++i) {
    const MediumLayer& layer = m.layers[i];
    float v;
    if (!sampleRegion(layer.view, region, p, v)) continue;
    const float n = tfNormalized(layer.table, v);
    const vec4f e = tfTableAt(layer.table, n);
    const float s = -e.w * m.extinctionPerLog2;
    out.extinction += s;
    c = c + vec3f(e.x, e.y, e.z) * s;
    albedo += (layer.albedo ? albedoTableAt(layer.albedo, n) : m.albedo) * s;
  }
  if (out.extinction > 0.f) {
    out.color = c * (1.f / out.extinction);
    out.albedo = albedo / out.extinction;
  }
  return out;
}

/// A unit vector at angle acos(cosTheta) from `axis` (unit), turned by phi around it.
EXA_HOST_DEVICE inline vec3d aroundAxis(const vec3d& axis, double cosTheta, double phi) {
  const vec3d helper = fabs(axis.x) < 0.9 ? vec3d(1.0, 0.0, 0.0) : vec3d(0.0, 1.0, 0.0);
  const vec3d u = normalize(cross(helper, axis));
  const vec3d v = cross(axis, u);
  const double sinTheta = sqrt(fmax(0.0, 1.0 - cosTheta * cosTheta));
  return normalize(u * (sinTheta * cos(phi)) + v * (sinTheta * sin(phi)) + axis * cosTheta);
}

/// A direction drawn with density cos(theta) / pi around the unit normal n.
EXA_HOST_DEVICE inline vec3d sampleCosine(const vec3d& n, PixelRandom& rng) {
  const double u = double(rng.next());
  return aroundAxis(n, sqrt(1.0 - u), 6.283185307 * double(rng.next()));
}

/// Henyey-Greenstein phase function (per steradian) at the cosine between the direction light
/// travelled and the one it leaves along.
EXA_HOST_DEVICE inline float henyeyGreenstein(float g, float cosTheta) {
  const float denom = 1.f + g * g - 2.f * g * cosTheta;
  return (1.f - g * g) / (4.f * 3.14159265f * denom * sqrtf(fmaxf(denom, 1e-12f)));
}

/// A direction drawn from the phase function around `dir` (the direction of travel), exactly
/// (its weight is one).
EXA_HOST_DEVICE inline vec3d sampleHenyeyGreenstein(const vec3d& dir, float g, PixelRandom& rng) {
  const float u = rng.next(), phi = 6.28318531f * rng.next();
  float cosTheta;
  if (fabsf(g) < 1e-3f) {
    cosTheta = 1.f - 2.f * u;
  } else {
    const float s = (1.f - g * g) / (1.f + g - 2.f * g * u);
    cosTheta = (1.f + g * g - s * s) / (2.f * g);
  }
  return aroundAxis(dir, fmin(1.0, fmax(-1.0, double(cosTheta))), phi);
}

/// Tentative collisions along a lattice ray (unit direction) within [tmin, tmax]: exponential
/// steps against a piecewise-constant majorant (in each region segment, per macrocell the smaller
/// of the region's and the macrocell's). Each step draws an optical depth and spends it piece by
/// piece (a piece costs its length times its majorant), so crossing a piece costs no random
/// number. At each collision `visit(t, ratio, color)` gets the ratio of the extinction there to
/// the majorant and the medium there, until it returns false. `samples` counts them.
template <typename Traverse, typename Visit>
EXA_HOST_DEVICE inline void tentativeCollisions(const MediumView& m, Traverse&& traverse, const Ray& ray,
                                                PixelRandom& rng, uint64_t& samples, Visit&& visit) {
  float depth = -logf(1.f - rng.next()); // optical depth left to the next tentative collision
  MacrocellWalk walk;                    // carried from segment to segment along the ray
  bool walking = false;
  traverse(ray, [&](const Segment& seg) {
    const float regionMajorant = m.majorant[seg.region];
    if (!(regionMajorant > 0.f)) return true;
    float t = maxOf(seg.t0, ray.tmin);
    const float end = minOf(seg.t1, ray.tmax);
    if (!(t < end)) return true;
    const bool gridded = m.grid.majorant && m.grid.gridded[seg.region];
    if (gridded) {
      walk.moveTo(m.grid, ray, t, walking);
      walking = true;
    }
    for (;;) {
      const float pieceEnd = gridded ? minOf(walk.exit(), end) : end;
      const float majorant = gridded ? minOf(regionMajorant, walk.majorant(m.grid)) : regionMajorant;
      if (majorant > 0.f)
        for (;;) {
          const float reach = (pieceEnd - t) * majorant;
          if (!(depth < reach)) {
            depth -= maxOf(reach, 0.f);
            break;
          }
          t += depth / majorant;
          depth = -logf(1.f - rng.next());
          ++samples;
          const MediumSample here = mediumAt(m, seg.region, ray.org + ray.dir * t);
          if (!visit(t, minOf(1.f, here.extinction / majorant), here)) return false;
        }
      if (pieceEnd >= end) return true;
      t = maxOf(t, pieceEnd);
      walk.advance(m.grid);
    }
  });
}

/// Delta tracking: the first real collision's t and the medium there; false when the ray leaves
/// the medium.
template <typename Traverse>
EXA_HOST_DEVICE inline bool freeFlight(const MediumView& m, Traverse&& traverse, const Ray& ray, PixelRandom& rng,
                                       float& tHit, MediumSample& at, uint64_t& samples) {
  bool hit = false;
  tentativeCollisions(m, traverse, ray, rng, samples, [&](float t, float ratio, const MediumSample& here) {
    if (!(rng.next() < ratio)) return true;
    tHit = t;
    at = here;
    hit = true;
    return false;
  });
  return hit;
}

/// Ratio tracking: an unbiased estimate of the transmittance, with Russian roulette once it
/// falls below a tenth.
template <typename Traverse>
EXA_HOST_DEVICE inline float transmittance(const MediumView& m, Traverse&& traverse, const Ray& ray, PixelRandom& rng,
                                           uint64_t& samples) {
  float T = 1.f;
  tentativeCollisions(m, traverse, ray, rng, samples, [&](float, float ratio, const MediumSample&) {
    T *= 1.f - ratio;
    if (T < 0.1f) {
      if (rng.next() < 0.5f) {
        T = 0.f;
        return false;
      }
      T *= 2.f;
    }
    return true;
  });
  return T;
}

/// The sun's light reaching `at` along a direction within its disc (returned in `towards`):
/// irradiance times the transmittance of the medium, zero behind a surface.
template <typename Traverse, typename Nearest>
EXA_HOST_DEVICE inline float sunlight(const MediumView& m, Traverse&& traverse, Nearest&& nearest,
                                      const WorldTransform& world, const ClipView* clip, const vec3d& at,
                                      const PathSettings& s, PixelRandom& rng, vec3d& towards, uint64_t& samples) {
  const double cosTheta = 1.0 - double(rng.next()) * (1.0 - double(s.sunCosHalfAngle));
  towards = aroundAxis(s.towardsSun, cosTheta, 6.283185307 * double(rng.next()));
  const DualRay shadow = makeDualRay(world, at, towards, clip);
  PathSurface blocker;
  if (nearest(shadow, blocker)) return 0.f;
  if (clippedAway(shadow)) return s.sunIntensity;
  return s.sunIntensity * transmittance(m, traverse, shadow.lattice, rng, samples);
}

/// One path from a primary ray: premultiplied radiance in xyz, and in w whether the path met the
/// medium or a surface (its average over passes is the pixel's opacity). Surfaces are opaque and
/// diffuse (Lambertian, their colour as albedo); `nearest(const DualRay&, PathSurface&)` finds
/// them. Secondary rays are clipped as the primary one (`clip`, may be null).
template <typename Traverse, typename Nearest>
EXA_HOST_DEVICE inline vec4f tracePath(const MediumView& m, Traverse&& traverse, Nearest&& nearest,
                                       const WorldTransform& world, const ClipView* clip, const DualRay& primary,
                                       const PathSettings& s, PixelRandom& rng, uint64_t& samples) {
  vec3f radiance(0.f), throughput(1.f);
  float met = 0.f;
  DualRay ray = primary;
  auto times = [](const vec3f& a, const vec3f& b) { return vec3f(a.x * b.x, a.y * b.y, a.z * b.z); };
  for (int bounce = 0;; ++bounce) {
    float t;
    MediumSample medium;
    PathSurface surface;
    const bool haveSurface = nearest(ray, surface);
    Ray lattice = ray.lattice;
    if (haveSurface) lattice.tmax = fminf(lattice.tmax, float(surface.distance * ray.kappa));
    const bool inMedium = !clippedAway(ray) && freeFlight(m, traverse, lattice, rng, t, medium, samples);
    if (!inMedium && haveSurface) {
      // A diffuse surface: the sun by next-event estimation, then a cosine-weighted bounce.
      met = 1.f;
      if (bounce >= s.bounces) break;
      throughput = times(throughput, surface.color);
      const vec3d at = ray.orgW + ray.dirW * surface.distance + surface.normal * s.surfaceOffset;
      if (s.sunIntensity > 0.f && dot(s.towardsSun, surface.normal) > 0.0) {
        vec3d towards;
        const float light = sunlight(m, traverse, nearest, world, clip, at, s, rng, towards, samples);
        const float cosine = float(fmax(0.0, dot(towards, surface.normal)));
        radiance = radiance + throughput * (light * cosine / 3.14159265f);
      }
      if (bounce >= 2) {
        const float q = fminf(1.f, fmaxf(throughput.x, fmaxf(throughput.y, throughput.z)));
        if (rng.next() >= q) break;
        throughput = throughput * (1.f / q);
      }
      ray = makeDualRay(world, at, sampleCosine(surface.normal, rng), clip);
      continue;
    }
    if (!inMedium) {
      if (bounce > 0) radiance = radiance + times(throughput, environmentRadiance(s, ray.dirW));
      break;
    }
    met = 1.f;
    // Absorption emits; the rest scatters (expected values of both, one path).
    if (s.emission > 0.f) radiance = radiance + times(throughput, medium.color) * ((1.f - medium.albedo) * s.emission);
    if (!(medium.albedo > 0.f) || bounce >= s.bounces) break;
    throughput = times(throughput, medium.color) * medium.albedo;
    const vec3d at = ray.orgW + ray.dirW * (double(t) / ray.kappa);
    // The sun by next-event estimation: a direction within its disc, shadowed by ratio tracking.
    if (s.sunIntensity > 0.f) {
      vec3d towards;
      const float light = sunlight(m, traverse, nearest, world, clip, at, s, rng, towards, samples);
      radiance = radiance + throughput * (henyeyGreenstein(s.anisotropy, float(dot(towards, ray.dirW))) * light);
    }
    // Russian roulette after the first bounces.
    if (bounce >= 2) {
      const float q = fminf(1.f, fmaxf(throughput.x, fmaxf(throughput.y, throughput.z)));
      if (rng.next() >= q) break;
      throughput = throughput * (1.f / q);
    }
    ray = makeDualRay(world, at, sampleHenyeyGreenstein(ray.dirW, s.anisotropy, rng), clip);
  }
  return {radiance.x, radiance.y, radiance.z, met};
}

} // namespace exa
