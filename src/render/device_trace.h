// The device back ends' side of the ray program (ray_program.h) and of the path tracer
// (path_trace.h), host and device code alike: plain views of device-resident arrays (TraceView),
// the meshes through the triangle BVH, the iso-surfaces and the volume one sample after another
// through the visible regions' k-d tree (walkRegionTree, basis reconstruction, sample_math.h).
// The CUDA kernel and the portable back end (CPU threads) run traceSample and tracePathSample.
#pragma once

#include "dual_ray.h"
#include "iso_search.h"
#include "layer_table.h"
#include "path_trace.h"
#include "ray_program.h"

#include "exabricks/accel/sphere_bvh.h"
#include "exabricks/accel/traversal.h"
#include "exabricks/accel/triangle_bvh.h"
#include "exabricks/amr/basis.h"
#include "exabricks/core/random.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/frame_buffer.h"
#include "exabricks/render/sample_math.h"

#include <cmath>
#include <cstdint>
#include <limits>

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
  const float* strides = nullptr; ///< per region, its step's stride (null: 1)
  WorldTransform world;
  float referenceWidth = 1.f, invReferenceWidth = 1.f;
  vec3f invScale{1.f};
  float meanScale = 1.f;
  // The volume.
  bool volume = false;
  RegionTreeView volumeTree;
  int layerCount = 0;
  TraceLayer layers[kTraceMaxLayers];
  VolumeSettings sample; ///< as the CPU's march samples (its rate the frame's)
  // Path tracing (Integrator::PathTrace): the layers as the medium, with a majorant per region.
  bool pathTrace = false;
  MediumLayer mediumLayers[kTraceMaxLayers];
  const float* majorants = nullptr;
  MajorantGridView majorantGrid;
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
  // Particles (the CPU renderer's sphere hierarchy).
  bool particles = false;
  SphereBvhView particleBvh;
  const vec3f* particleColors = nullptr; ///< per sphere, linear RGB
  // Clipping.
  bool clipping = false;
  int planeCount = 0;
  ClipPlane planes[kTraceMaxClipPlanes];
  box3d clipBox;
  // Light, ambient occlusion, what the rays meet.
  RaySettings ray;
  // The frame.
  CameraRays frame;
  int frameIndex = 0;
  uint64_t seed = 0;
};

/// The volume along a lattice ray within [tmin, tmax], one sample after another, front to back
/// into acc (premultiplied): the same samples, lookups, shading and compositing as the CPU's
/// batches. OpacityOnly leaves colour and shading out (occlusion rays). SmoothOne: the scene is
/// one layer with smooth shading (smoothOneLayer), compiled without the other cases' code.
template <bool OpacityOnly, bool SmoothOne = false>
EXA_HOST_DEVICE inline void traceVolume(const TraceView& v, const Ray& ray, float rho, const vec3f& light,
                                        const vec3f& halfVector, vec4f& acc, uint32_t& samples) {
  const ShadingTerms& terms = v.ray.terms;
  if (v.layerCount == 0 || !(ray.tmax > ray.tmin)) return;
  const int layerCount = SmoothOne ? 1 : v.layerCount;
  const bool wantGrad = !SmoothOne && !OpacityOnly && v.sample.shading == Shading::Analytic;
  const bool shade = !OpacityOnly && (SmoothOne || v.sample.shading != Shading::None);
  walkRegionTree(v.volumeTree, ray, [&](const Segment& seg) {
    const Region& region = v.regions[seg.region];
    SegmentMarch sm(std::max(seg.t0, ray.tmin), std::min(seg.t1, ray.tmax), rho,
                    sampleStep(region, v.sample.sampling, v.referenceWidth, v.sample.rate,
                               v.strides ? v.strides[seg.region] : 1.f));
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
          if (!SmoothOne && v.sample.shading == Shading::Smooth && !l.withGradients)
            for (int a = 0; a < 3; ++a)
              if (!sampleRegion(l.grad[a], seg.region, p, grad[a])) grad[a] = 0.f;
          if (!SmoothOne && v.sample.shading == Shading::Central)
            grad = centralGradient(l.view, seg.region, region, p, value);
          const float fade = fadeScaleAt(fadeWidthOf(cellWidth, l.byValue, l.invSpan), l.byValue, value);
          c = shadeVolumeSample(c, grad * v.invScale, light, halfVector, terms, fade);
        }
        colorSum += c * alpha;
        alphaSum += alpha;
        color = c;
      }
      if (!(logSum < 0.f)) continue;
      const float alpha = correctedOpacity(logSum, len, v.invReferenceWidth);
      if (!SmoothOne && layerCount > 1) color = alphaSum > 0.f ? colorSum * (1.f / alphaSum) : vec3f(0.f);
      compositeBehind(acc, color, alpha);
      if (v.sample.earlyTermination && acc.w >= v.sample.terminationOpacity) return false;
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
  const bool found = findIsoCrossing(walk, v.isoView, v.isoValues, v.isoCount, ray, v.sample.sampling, v.referenceWidth,
                                     v.sample.rate, t, region, which, n);
  samples += uint32_t(n);
  return found;
}

/// The device back ends' side of the ray program: the triangle BVH, the iso region set's k-d
/// tree and the volume one sample after another (SmoothOne: the scene is one layer with smooth
/// shading; occlusion rays take the general march, which reads no gradients).
template <bool SmoothOne> struct DeviceRays {
  const TraceView& v;

  EXA_HOST_DEVICE bool hasMeshes() const { return v.meshes || v.particles; }
  EXA_HOST_DEVICE bool meshHit(const DualRay& r, double s0, double s1, SurfaceHit& hit) const {
    if (!(s1 >= s0)) return false;
    const float f0 = float(s0 > 0.0 ? s0 : 0.0);
    float f1 = std::isinf(s1) ? std::numeric_limits<float>::infinity() : float(s1);
    bool found = false;
    TriangleHit th;
    if (v.meshes && intersectTriangles(v.meshBvh, vec3f(r.orgW), vec3f(r.dirW), f0, f1, false, th)) {
      hit.kind = SurfaceHit::Mesh;
      hit.distance = th.t;
      hit.index = th.mesh;
      hit.normal = th.normal;
      f1 = th.t;
      found = true;
    }
    if (v.particles && particleHit(v.particleBvh, r, s0, f1, hit)) found = true;
    return found;
  }
  EXA_HOST_DEVICE bool meshOccludes(const DualRay& r, double s0, double s1) const {
    if (!(s1 > s0)) return false;
    const float f0 = float(s0 > 0.0 ? s0 : 0.0), f1 = float(s1);
    TriangleHit th;
    return (v.meshes && intersectTriangles(v.meshBvh, vec3f(r.orgW), vec3f(r.dirW), f0, f1, true, th)) ||
           (v.particles && particleOccludes(v.particleBvh, r, s0, s1));
  }
  EXA_HOST_DEVICE bool hasIso() const { return v.iso; }
  EXA_HOST_DEVICE bool isoHit(const Ray& ray, float& t, uint32_t& region, int& which, RayCounts& c) const {
    auto walk = [&](const Ray& r, auto&& emit) { walkRegionTree(v.isoTree, r, emit); };
    uint64_t n = 0;
    const bool found = findIsoCrossing(walk, v.isoView, v.isoValues, v.isoCount, ray, v.sample.sampling,
                                       v.referenceWidth, v.sample.rate, t, region, which, n);
    c.isoSamples += uint32_t(n);
    return found;
  }
  EXA_HOST_DEVICE const FieldView& isoView() const { return v.isoView; }
  EXA_HOST_DEVICE const vec3f& invScale() const { return v.invScale; }
  EXA_HOST_DEVICE vec3f surfaceColor(const SurfaceHit& hit) const {
    const SurfaceColors colors{v.meshColors, v.particleColors, v.isoColors, v.isoColorCount,
                               v.isoColored, v.isoColorView,   v.isoColorTf};
    return surfaceColorOf(colors, v.world, hit);
  }
  template <bool OpacityOnly>
  EXA_HOST_DEVICE void march(const Ray& ray, float rho, const RayLight& light, vec4f& acc, RayCounts& c) const {
    traceVolume<OpacityOnly, SmoothOne && !OpacityOnly>(v, ray, rho, light.light, light.halfVector, acc, c.samples);
  }
};

/// One ray-marched sample of pixel (x, y) for pass v.frameIndex (marchSample): premultiplied
/// colour. `Surfaces`: the scene may have surfaces (false compiles the volume alone, which needs
/// fewer registers on a GPU).
template <bool Surfaces, bool SmoothOne = false>
EXA_HOST_DEVICE inline vec4f traceSample(const TraceView& v, int x, int y, RayCounts& c) {
  PixelRandom rng(x, y, v.frameIndex, v.seed);
  float rho;
  const ClipView clip{v.planes, v.planeCount, v.clipBox};
  const DualRay dr = cameraRay(v.frame, v.world, &clip, x, y, rng, rho);
  return marchSample<Surfaces>(DeviceRays<SmoothOne>{v}, v.ray, v.world, &clip, dr, rho, rng, c,
                               frontOpacityOf(v.frame, x, y));
}

/// One path-traced sample of pixel (x, y) for pass v.frameIndex (tracePath, path_trace.h): the
/// same primary ray, medium and surfaces as the CPU renderer's, over the device arrays.
template <bool Surfaces> EXA_HOST_DEVICE inline vec4f tracePathSample(const TraceView& v, int x, int y, RayCounts& c) {
  PixelRandom rng(x, y, v.frameIndex, v.seed);
  float rho;
  const ClipView clip{v.planes, v.planeCount, v.clipBox};
  const DualRay dr = cameraRay(v.frame, v.world, &clip, x, y, rng, rho);
  const MediumView medium{v.mediumLayers, v.volume ? v.layerCount : 0, v.majorants,
                          v.majorantGrid, v.extinctionPerLog2,         v.path.albedo};
  auto traverse = [&](const Ray& ray, auto&& emit) {
    if (v.volume) walkRegionTree(v.volumeTree, ray, emit);
  };
  auto nearest = [&](const DualRay& r, PathSurface& out) {
    if constexpr (!Surfaces) {
      return false;
    } else {
      const DeviceRays<false> b{v};
      SurfaceHit h;
      if (!nearestSurface(b, r, v.ray.clipMeshes, h, c)) return false;
      out.distance = h.distance;
      out.normal = vec3d(h.normal);
      out.color = b.surfaceColor(h);
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
  return v.layerCount == 1 && v.sample.shading == Shading::Smooth && v.layers[0].withGradients != nullptr;
}

/// Whether pixel (x, y) lies in a tile the pass renders (PassControl's selection, kRenderTile
/// pixels square, row-major).
EXA_HOST_DEVICE inline bool tileSelected(int x, int y, int tilesX, int tileBegin, int tileEnd, int tileStride) {
  const int tile = (y / kRenderTile) * tilesX + x / kRenderTile;
  return tile >= tileBegin && tile < tileEnd && (tile - tileBegin) % tileStride == 0;
}

} // namespace exa
