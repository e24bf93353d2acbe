// One sample of one pixel for the device back ends, host and device code alike: the camera ray,
// clipping and domain (dual_ray.h), the nearest iso-surface (iso_search.h), the volume one sample
// after another through the visible regions' k-d tree (walkRegionTree, basis reconstruction,
// sample_math.h), ambient occlusion and the surface's shading. The same steps as the CPU
// renderer's tracePixel, over plain views of device-resident arrays (TraceView) instead of the
// CPU's batches and Embree; the CUDA kernel and the portable back end (CPU threads) run it.
#pragma once

#include "dual_ray.h"
#include "iso_search.h"
#include "layer_table.h"
#include "path_trace.h"

#include "exabricks/accel/traversal.h"
#include "exabricks/accel/triangle_bvh.h"
#include "exabricks/amr/basis.h"
#include "exabricks/core/random.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/frame_buffer.h"
#include "exabricks/render/sample_math.h"

#include <cstdint>

namespace exa {

constexpr int kTraceMaxLayers = 8;
constexpr int kTraceMaxClipPlanes = 16;
constexpr int kTraceMaxIsoValues = 16;
constexpr int kTraceMaxIsoColors = 16;

/// One volume layer: its field, its gradient fields (smooth shading) and its transfer function.
struct TraceLayer {
  FieldView view;
  FieldView grad[3];
  /// Smooth shading: the field and its gradient fields interleaved per cell (value, gx, gy, gz),
  /// reconstructed at once (sampleRegion4); null: `grad` serves.
  const vec4f* withGradients = nullptr;
  TfTableView tf;
  bool byValue = false; ///< LayerTable::fadeByValue
  float invSpan = 0.f;
};

/// Everything a pass's rays read, as plain data (pointers to arrays where the pass runs).
struct TraceView {
  // The data.
  const Region* regions = nullptr;
  WorldTransform world;
  float referenceWidth = 1.f, invReferenceWidth = 1.f;
  vec3f invScale{1.f};
  float meanScale = 1.f;
  // The volume.
  bool volume = false;
  RegionTreeView volumeTree;
  int layerCount = 0;
  TraceLayer layers[kTraceMaxLayers];
  Shading shading = Shading::Smooth;
  ShadingTerms terms;
  Sampling sampling = Sampling::Adaptive;
  bool earlyTermination = true;
  float terminationOpacity = 0.98f;
  float rate = 1.f;
  // Path tracing (Integrator::PathTrace): the layers as the medium, with a majorant per region.
  bool pathTrace = false;
  MediumLayer mediumLayers[kTraceMaxLayers];
  const float* majorants = nullptr;
  float extinctionPerLog2 = 1.f;
  PathSettings path;
  // Iso-surfaces.
  bool iso = false;
  RegionTreeView isoTree;
  FieldView isoView;
  int isoCount = 0;
  float isoValues[kTraceMaxIsoValues] = {};
  bool isoColored = false;
  FieldView isoColorView;
  TfTableView isoColorTf;
  int isoColorCount = 0;
  vec3f isoColors[kTraceMaxIsoColors];
  // Triangle meshes.
  bool meshes = false;
  TriangleBvhView meshBvh;
  const vec3f* meshColors = nullptr; ///< per mesh, linear RGB
  bool clipMeshes = false;           ///< Clipping::meshes
  // Clipping and the renderer's domain.
  bool clipping = false;
  int planeCount = 0;
  ClipPlane planes[kTraceMaxClipPlanes];
  box3d clipBox;
  bool hasDomain = false;
  box3d domain;
  // Light.
  bool headlight = true;
  vec3f lightWorld{0.f, 0.f, -1.f};
  int aoRays = 0;
  bool aoVolume = false;
  double aoLength = 1.0, aoEps = 1e-5; ///< world
  // The frame.
  Camera camera;
  int width = 1, height = 1;
  double aspect = 1.0;
  int frameIndex = 0;
  uint64_t seed = 0;
  bool jitter = true, pixelJitter = false;
  /// Frame::depthLimit (per pixel, where the pass runs) and how to read it.
  const float* depthLimit = nullptr;
  bool depthLimitPlanar = false;
  vec3d forward{0.0, 0.0, -1.0}; ///< the camera's view direction (planar depth limits)
};

/// Counts of one ray.
struct TraceCounts {
  uint32_t samples = 0, isoSamples = 0, aoRays = 0, surfaceHits = 0;
};

/// The volume along a lattice ray within [tmin, tmax], one sample after another, front to back
/// into acc (premultiplied): the same samples, lookups, shading and compositing as the CPU's
/// batches. OpacityOnly leaves colour and shading out (occlusion rays). SmoothOne: the scene is
/// one layer with smooth shading (smoothOneLayer), compiled without the other cases' code.
template <bool OpacityOnly, bool SmoothOne = false>
EXA_HOST_DEVICE inline void traceVolume(const TraceView& v, const Ray& ray, float rho, const vec3f& light,
                                        const vec3f& halfVector, vec4f& acc, uint32_t& samples) {
  if (v.layerCount == 0 || !(ray.tmax > ray.tmin)) return;
  const int layerCount = SmoothOne ? 1 : v.layerCount;
  const bool wantGrad = !SmoothOne && !OpacityOnly && v.shading == Shading::Analytic;
  const bool shade = !OpacityOnly && (SmoothOne || v.shading != Shading::None);
  walkRegionTree(v.volumeTree, ray, [&](const Segment& seg) {
    const Region& region = v.regions[seg.region];
    SegmentMarch sm(std::max(seg.t0, ray.tmin), std::min(seg.t1, ray.tmax), rho,
                    sampleStep(region, v.sampling, v.referenceWidth, v.rate));
    const float cellWidth = region.finestWidth() * v.meanScale;
    while (sm.a < sm.end) {
      const float b = sm.intervalEnd();
      if (!(b > sm.a)) break;
      sm.k += 1.f;
      const float len = b - sm.a;
      const vec3f p = ray.org + ray.dir * (0.5f * (sm.a + b));
      sm.a = b;
      ++samples;
      float logSum = 0.f, alphaSum = 0.f;
      vec3f colorSum(0.f), color(0.f);
      for (int li = 0; li < layerCount; ++li) {
        const TraceLayer& l = v.layers[li];
        float value;
        vec3f grad(0.f);
        if (SmoothOne || l.withGradients) {
          vec4f r;
          if (!sampleRegion4(l.view, l.withGradients, seg.region, p, r)) break;
          value = r.x, grad = vec3f(r.y, r.z, r.w);
        } else if (!sampleRegion(l.view, seg.region, p, value, wantGrad ? &grad : nullptr)) {
          break;
        }
        const vec4f rgba = tfLookup(l.tf, value);
        if (rgba.w >= 0.f) continue;
        logSum += rgba.w;
        if (OpacityOnly) continue;
        const float alpha = correctedOpacity(rgba.w, len, v.invReferenceWidth);
        vec3f c = rgba.rgb();
        if (shade) {
          if (!SmoothOne && v.shading == Shading::Smooth && !l.withGradients)
            for (int a = 0; a < 3; ++a)
              if (!sampleRegion(l.grad[a], seg.region, p, grad[a])) grad[a] = 0.f;
          if (!SmoothOne && v.shading == Shading::Central) grad = centralGradient(l.view, seg.region, region, p, value);
          const float fade = fadeScaleAt(fadeWidthOf(cellWidth, l.byValue, l.invSpan), l.byValue, value);
          c = shadeVolumeSample(c, grad * v.invScale, light, halfVector, v.terms, fade);
        }
        colorSum += c * alpha;
        alphaSum += alpha;
        color = c;
      }
      if (!(logSum < 0.f)) continue;
      const float alpha = correctedOpacity(logSum, len, v.invReferenceWidth);
      if (!SmoothOne && layerCount > 1) color = alphaSum > 0.f ? colorSum * (1.f / alphaSum) : vec3f(0.f);
      compositeBehind(acc, color, alpha);
      if (v.earlyTermination && acc.w >= v.terminationOpacity) return false;
    }
    return true;
  });
}

/// Nearest iso-surface crossing along a lattice ray (see findIsoCrossing).
EXA_HOST_DEVICE inline bool traceIso(const TraceView& v, const Ray& ray, float& t, uint32_t& region, int& which,
                                     uint32_t& samples) {
  if (!v.iso) return false;
  auto walk = [&](const Ray& r, auto&& emit) { walkRegionTree(v.isoTree, r, emit); };
  uint64_t n = 0;
  const bool found = findIsoCrossing(walk, v.isoView, v.isoValues, v.isoCount, ray, v.sampling, v.referenceWidth,
                                     v.rate, t, region, which, n);
  samples += uint32_t(n);
  return found;
}

/// Fraction of unoccluded cosine-weighted rays over the hemisphere of a surface point's normal.
EXA_HOST_DEVICE inline float traceOcclusion(const TraceView& v, const vec3d& position, const vec3f& normal,
                                            PixelRandom& rng, TraceCounts& c) {
  const ClipView clip{v.planes, v.planeCount, v.clipBox};
  float open = 0.f;
  for (int i = 0; i < v.aoRays; ++i) {
    const float r1 = rng.next(), r2 = rng.next();
    const vec3f d = cosineHemisphere(normal, r1, r2);
    ++c.aoRays;
    const DualRay ar = makeDualRay(v.world, position + vec3d(normal) * v.aoEps, vec3d(d), &clip);
    if (v.meshes) {
      const double s0 = v.clipMeshes ? ar.sMin : 0.0;
      const double s1 = v.clipMeshes ? std::min(ar.sMax, v.aoLength) : v.aoLength;
      TriangleHit th;
      if (s1 > s0 &&
          intersectTriangles(v.meshBvh, vec3f(ar.orgW), vec3f(ar.dirW), float(std::max(s0, 0.0)), float(s1), true, th))
        continue;
    }
    Ray lr = ar.lattice;
    lr.tmax = std::min(lr.tmax, float(v.aoLength * ar.kappa));
    float t;
    uint32_t region;
    int which;
    if (!clippedAway(ar) && traceIso(v, lr, t, region, which, c.isoSamples)) continue;
    float visibility = 1.f;
    if (v.aoVolume && !clippedAway(ar) && lr.tmax > lr.tmin) {
      vec4f acc;
      traceVolume<true>(v, lr, 0.5f, vec3f(0.f), vec3f(0.f), acc, c.samples);
      visibility = 1.f - acc.w;
    }
    open += visibility;
  }
  return v.aoRays > 0 ? open / float(v.aoRays) : 1.f;
}

/// The camera ray of pixel (x, y) for pass v.frameIndex: clipped, inside the domain, up to the
/// depth limit; rho is the sample offset along it.
EXA_HOST_DEVICE inline DualRay cameraRay(const TraceView& v, int x, int y, PixelRandom& rng, float& rho) {
  vec3d orgW, dirW;
  primaryRay(v.camera, x, y, v.width, v.height, v.aspect, v.pixelJitter, v.jitter, rng, rho, orgW, dirW);
  const ClipView clip{v.planes, v.planeCount, v.clipBox};
  DualRay dr = makeDualRay(v.world, orgW, dirW, &clip);
  if (v.hasDomain) restrictToBox(dr, v.domain);
  if (v.depthLimit)
    applyDepthLimit(dr, v.depthLimit[size_t(y) * size_t(v.width) + size_t(x)], v.depthLimitPlanar, v.forward);
  return dr;
}

/// The nearest surface along a ray: a mesh (within the clip interval, or with meshes unclipped
/// the domain's), then an iso-surface in front of it.
struct DeviceSurfaceHit {
  double distance = 0.0; ///< world
  vec3f normal{0.f};     ///< world, facing the ray's origin
  bool iso = false;
  int which = 0; ///< mesh, or iso-value
};

EXA_HOST_DEVICE inline bool nearestSurface(const TraceView& v, const DualRay& dr, DeviceSurfaceHit& h,
                                           uint32_t& isoSamples) {
  bool haveHit = false;
  if (v.meshes) {
    const double s0 = v.clipMeshes ? dr.sMin : dr.domainMin, s1 = v.clipMeshes ? dr.sMax : dr.domainMax;
    TriangleHit th;
    if (s1 >= s0 &&
        intersectTriangles(v.meshBvh, vec3f(dr.orgW), vec3f(dr.dirW), float(std::max(s0, 0.0)),
                           std::isinf(s1) ? std::numeric_limits<float>::infinity() : float(s1), false, th)) {
      haveHit = true;
      h.distance = th.t;
      h.which = th.mesh;
      h.normal = th.normal;
    }
  }
  if (v.iso && !clippedAway(dr)) {
    Ray lr = dr.lattice;
    if (haveHit) lr.tmax = std::min(lr.tmax, float(h.distance * dr.kappa));
    float tHit = 0.f;
    uint32_t region = 0;
    int index = 0;
    if (traceIso(v, lr, tHit, region, index, isoSamples)) {
      haveHit = h.iso = true;
      h.distance = double(tHit) / dr.kappa;
      h.which = index;
      h.normal = isoNormal(v.isoView, region, lr.org + lr.dir * tHit, dr.dirW, v.invScale);
    }
  }
  return haveHit;
}

/// A surface's own colour at `position` (world): its mesh's, its iso-value's, or the iso colour
/// field's through its map.
EXA_HOST_DEVICE inline vec3f surfaceColor(const TraceView& v, const DeviceSurfaceHit& h, const vec3d& position) {
  if (!h.iso) return v.meshColors[h.which];
  vec3f base = v.isoColorCount > 0 ? v.isoColors[h.which % v.isoColorCount] : defaultIsoColor(h.which);
  float value;
  if (v.isoColored && sampleField(v.isoColorView, vec3f(v.world.toLattice(position)), value))
    base = tfLookup(v.isoColorTf, value).rgb();
  return base;
}

/// One sample of pixel (x, y) for pass v.frameIndex: premultiplied colour. `Surfaces`: the scene
/// may have iso-surfaces (false compiles the volume alone, which needs fewer registers on a GPU).
template <bool Surfaces, bool SmoothOne = false>
EXA_HOST_DEVICE inline vec4f traceSample(const TraceView& v, int x, int y, TraceCounts& c) {
  PixelRandom rng(x, y, v.frameIndex, v.seed);
  float rho;
  const DualRay dr = cameraRay(v, x, y, rng, rho);
  const vec3f viewW = vec3f(dr.dirW);
  const vec3f light = v.headlight ? viewW : v.lightWorld;
  const vec3f halfVector = normalize(light + viewW);

  vec4f acc;
  DeviceSurfaceHit hit;
  bool haveHit = false;
  if constexpr (Surfaces) haveHit = nearestSurface(v, dr, hit, c.isoSamples);
  Ray volumeRay = dr.lattice;
  if (haveHit) volumeRay.tmax = std::min(volumeRay.tmax, float(hit.distance * dr.kappa));
  if (v.volume && !clippedAway(dr)) traceVolume<false, SmoothOne>(v, volumeRay, rho, light, halfVector, acc, c.samples);
  if constexpr (!Surfaces) return acc;
  if (haveHit && acc.w < 1.f) {
    ++c.surfaceHits;
    const vec3d position = dr.orgW + dr.dirW * hit.distance;
    const vec3f base = surfaceColor(v, hit, position);
    const float ao = v.aoRays > 0 ? traceOcclusion(v, position, hit.normal, rng, c) : 1.f;
    compositeOpaqueBehind(acc, shadeSurface(base, hit.normal, light, halfVector, ao, v.terms));
  }
  return acc;
}

/// One path-traced sample of pixel (x, y) for pass v.frameIndex (tracePath, path_trace.h): the
/// same primary ray, medium and surfaces as the CPU renderer's, over the device arrays.
template <bool Surfaces>
EXA_HOST_DEVICE inline vec4f tracePathSample(const TraceView& v, int x, int y, TraceCounts& c) {
  PixelRandom rng(x, y, v.frameIndex, v.seed);
  float rho;
  const DualRay dr = cameraRay(v, x, y, rng, rho);
  const ClipView clip{v.planes, v.planeCount, v.clipBox};
  const MediumView medium{v.mediumLayers, v.volume ? v.layerCount : 0, v.majorants, v.extinctionPerLog2, v.path.albedo};
  auto traverse = [&](const Ray& ray, auto&& emit) {
    if (v.volume) walkRegionTree(v.volumeTree, ray, emit);
  };
  auto nearest = [&](const DualRay& r, PathSurface& out) {
    if constexpr (!Surfaces) {
      return false;
    } else {
      DeviceSurfaceHit h;
      if (!nearestSurface(v, r, h, c.isoSamples)) return false;
      out.distance = h.distance;
      out.normal = vec3d(h.normal);
      out.color = surfaceColor(v, h, r.orgW + r.dirW * h.distance);
      return true;
    }
  };
  uint64_t samples = 0;
  const vec4f out = tracePath(medium, traverse, nearest, v.world, &clip, dr, v.path, rng, samples);
  c.samples += uint32_t(samples);
  return out;
}

/// Whether the scene is one layer with smooth shading read with its values (the common case,
/// which traceVolume<..., true> serves with less code).
EXA_HOST_DEVICE inline bool smoothOneLayer(const TraceView& v) {
  return v.layerCount == 1 && v.shading == Shading::Smooth && v.layers[0].withGradients != nullptr;
}

/// Whether pixel (x, y) lies in a tile the pass renders (PassControl's selection, kRenderTile
/// pixels square, row-major).
EXA_HOST_DEVICE inline bool tileSelected(int x, int y, int tilesX, int tileBegin, int tileEnd, int tileStride) {
  const int tile = (y / kRenderTile) * tilesX + x / kRenderTile;
  return tile >= tileBegin && tile < tileEnd && (tile - tileBegin) % tileStride == 0;
}

} // namespace exa
