#include "exabricks/render/renderer.h"

#include "exabricks/amr/cell_locator.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/io/mesh.h"

#include "../accel/embree_util.h"

#include <tbb/blocked_range2d.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>

namespace exa {
namespace {

constexpr int kTableSize = 4096;
constexpr int kTile = 16;

uint64_t mixBits(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  return x ^ (x >> 33);
}

/// Deterministic per-pixel, per-sample random numbers in [0, 1).
struct PixelRandom {
  uint64_t state;
  PixelRandom(int x, int y, int sample, uint64_t seed)
      : state(mixBits(seed * 0x9e3779b97f4a7c15ull ^ mixBits((uint64_t(uint32_t(y)) << 32) | uint32_t(x)) ^
                      (uint64_t(sample) << 48))) {}
  float next() {
    state = mixBits(state + 0x9e3779b97f4a7c15ull);
    return float(state >> 40) * (1.f / 16777216.f);
  }
};

vec3f hashColor(uint32_t id) {
  const uint64_t h = mixBits(uint64_t(id) + 12345);
  return vec3f(0.15f + 0.85f * float(h & 255) / 255.f, 0.15f + 0.85f * float((h >> 8) & 255) / 255.f,
               0.15f + 0.85f * float((h >> 16) & 255) / 255.f);
}

/// Colours for levels 0..7, cycling: distinct hues, finest warm.
vec3f levelColor(int level) {
  static const vec3f colors[8] = {{0.90f, 0.10f, 0.10f}, {0.95f, 0.55f, 0.05f}, {0.90f, 0.85f, 0.10f},
                                  {0.20f, 0.75f, 0.20f}, {0.10f, 0.60f, 0.85f}, {0.25f, 0.25f, 0.90f},
                                  {0.60f, 0.20f, 0.80f}, {0.55f, 0.55f, 0.55f}};
  return colors[level & 7];
}

/// 2^x for x <= 0 to float precision (relative error below 2e-7): a degree-6 Taylor
/// polynomial of 2^f on [-1/2, 1/2] times 2^i built from the exponent bits. Cheaper than a libm
/// call on the hot path of every sample's opacity correction.
inline float exp2Negative(float x) {
  if (x < -126.f) return 0.f;
  const float i = std::nearbyint(x);
  const float f = x - i;
  float p = 0.00015403530393381606f;
  p = p * f + 0.0013333558146428443f;
  p = p * f + 0.009618129107628477f;
  p = p * f + 0.05550410866482158f;
  p = p * f + 0.2402265069591007f;
  p = p * f + 0.6931471805599453f;
  p = p * f + 1.f;
  const uint32_t bits = uint32_t(int32_t(i) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

/// Schlick's rational approximation of x^e for x in [0, 1]: exact at 0 and 1, one division
/// instead of a power per sample.
inline float specularPower(float x, float e) { return x / (e - (e - 1.f) * x); }

/// A transfer function tabulated for the marcher: colour and log2 of the transmittance of one
/// finest cell width over the normalised value.
struct LayerTable {
  int field = 0;
  FieldView view;
  TransferFunction tf;
  std::vector<vec4f> table;
  bool fastLinear = false; ///< t = (value - normLower) * normScale, else tf.normalize
  float normLower = 0.f, normScale = 0.f;

  void build(const Model& model, int fieldIndex, const TransferFunction& tfIn) {
    if (fieldIndex < 0 || size_t(fieldIndex) >= model.fieldValues.size())
      fail("field index ", fieldIndex, " is out of range (", model.fieldValues.size(), " fields)");
    field = fieldIndex;
    view = model.view(fieldIndex);
    tf = tfIn;
    if (tf.valueRange.empty()) {
      range1f r;
      for (const range1f& rr : model.regions.valueRanges[size_t(field)]) r.extend(rr);
      tf.valueRange = r;
    }
    table.resize(kTableSize);
    for (int i = 0; i < kTableSize; ++i) {
      const vec4f c = tf.atNormalized(float(i) / float(kTableSize - 1));
      table[size_t(i)] = {c.x, c.y, c.z, std::log2(1.f - std::min(c.w, 0.999999f))};
    }
    const range1f r = tf.valueRange;
    fastLinear = !tf.logScale && r.upper > r.lower;
    normLower = r.lower;
    normScale = fastLinear ? 1.f / (r.upper - r.lower) : 0.f;
  }

  float normalized(float value) const {
    return fastLinear ? std::clamp((value - normLower) * normScale, 0.f, 1.f) : tf.normalize(value);
  }

  /// The tabulated transfer function, linearly interpolated, at normalised value n.
  vec4f tableAt(float n) const {
    const float t = n * float(kTableSize - 1);
    const int i = std::clamp(int(t), 0, kTableSize - 2);
    const float f = std::clamp(t - float(i), 0.f, 1.f);
    const vec4f& a = table[size_t(i)];
    const vec4f& b = table[size_t(i) + 1];
    return {a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f, a.w + (b.w - a.w) * f};
  }

  vec4f lookup(float value) const { return tableAt(normalized(value)); }

  /// Whether any value in r can be visible through the tabulated function the marcher uses
  /// (its log transmittance is piecewise linear, so its extremes lie at table entries or ends).
  bool mayBeVisible(const range1f& r) const {
    if (r.empty()) return false;
    const float n0 = normalized(r.lower), n1 = normalized(r.upper);
    if (tableAt(n0).w < 0.f || tableAt(n1).w < 0.f) return true;
    const int first = int(std::ceil(n0 * float(kTableSize - 1)));
    const int last = int(std::floor(n1 * float(kTableSize - 1)));
    for (int i = std::max(first, 0); i <= std::min(last, kTableSize - 1); ++i)
      if (table[size_t(i)].w < 0.f) return true;
    return false;
  }
};

/// Default iso-surface colours (linear RGB), cycled over the iso-values.
const vec3f kIsoColors[4] = {{0.80f, 0.80f, 0.78f}, {0.85f, 0.35f, 0.20f}, {0.20f, 0.45f, 0.85f},
                             {0.35f, 0.70f, 0.30f}};

/// Per-thread counters of a frame.
struct Counters {
  uint64_t rays = 0, samples = 0, regions = 0, surfaceHits = 0, isoSamples = 0, aoRays = 0;
};

/// A ray in both spaces: world origin and unit direction, and the lattice ray whose t is in
/// finest lattice units along a unit lattice direction; t = s * kappa for world distance s.
struct DualRay {
  vec3d orgW, dirW;
  Ray lattice;
  double kappa = 1.0;
  double sMin = 0.0, sMax = std::numeric_limits<double>::infinity(); ///< clipped world interval
};

/// Unit vectors perpendicular to n (and to each other).
void orthonormalBasis(const vec3f& n, vec3f& u, vec3f& v) {
  const vec3f a = std::abs(n.x) > 0.9f ? vec3f(0.f, 1.f, 0.f) : vec3f(1.f, 0.f, 0.f);
  u = normalize(cross(a, n));
  v = cross(n, u);
}

} // namespace

struct Renderer::Impl {
  const Model& model;
  int field;                 ///< the renderer's field (single-layer transfer function)
  std::vector<LayerTable> layers;
  std::vector<uint8_t> visible;
  std::unique_ptr<RegionTraversal> traversal;
  std::unique_ptr<CellLocator> locator; ///< only for Reconstruction::CellLocation
  float finestWidth = 1.f;   ///< dataset's finest cell width, lattice units (opacity reference)
  float invFinestWidth = 1.f;
  vec3f invScale{1.f};       ///< world units per lattice unit, inverted (for gradients)
  double worldDiagonal = 1.0;
  double minScale = 1.0;

  // Iso-surfaces: their own set of regions (value range holds an iso-value) and traversal.
  IsoSurfaces iso;
  FieldView isoView;
  std::vector<uint8_t> isoVisible;
  std::unique_ptr<RegionTraversal> isoTraversal;
  LayerTable isoColor;       ///< colour map of iso.colorField

  // Triangle meshes in world space.
  RTCDevice device = nullptr;
  RTCScene meshScene = nullptr;
  std::vector<vec3f> meshColors;

  Impl(const Model& m, int f) : model(m), field(f) {
    if (f < 0 || size_t(f) >= m.fieldValues.size())
      fail("field index ", f, " is out of range (", m.fieldValues.size(), " fields)");
    int finest = kMaxLevel;
    for (const Brick& b : m.bricks) finest = std::min(finest, b.level);
    finestWidth = float(1 << finest);
    invFinestWidth = 1.f / finestWidth;
    invScale = vec3f(1.0 / m.world.scale.x, 1.0 / m.world.scale.y, 1.0 / m.world.scale.z);
    minScale = reduceMin(m.world.scale);
    const box3i cb = m.cellBounds();
    if (!cb.empty()) worldDiagonal = length(vec3d(cb.size()) * m.world.scale);
  }

  ~Impl() {
    if (meshScene) rtcReleaseScene(meshScene);
    if (device) rtcReleaseDevice(device);
  }

  /// World ray -> lattice ray with the clip interval applied (planes and box, world space).
  /// The lattice interval may be empty; sMin/sMax keep the clipped world interval.
  DualRay makeRay(const vec3d& orgW, const vec3d& dirWIn, const RenderOptions& o, bool clip) const {
    DualRay r;
    r.orgW = orgW;
    r.dirW = normalize(dirWIn);
    const vec3d orgL = model.world.toLattice(orgW);
    const vec3d dL = r.dirW / model.world.scale;
    r.kappa = length(dL);
    r.lattice.org = vec3f(orgL);
    r.lattice.dir = vec3f(dL / r.kappa);
    if (clip) {
      for (const ClipPlane& cp : o.clipPlanes) {
        const double g0 = dot(orgW - cp.point, cp.normal), dn = dot(r.dirW, cp.normal);
        if (dn == 0.0) {
          if (g0 > 0.0) r.sMax = -1.0;
        } else if (dn > 0.0) {
          r.sMax = std::min(r.sMax, -g0 / dn);
        } else {
          r.sMin = std::max(r.sMin, -g0 / dn);
        }
      }
      if (!o.clipBox.empty()) {
        for (int a = 0; a < 3; ++a) {
          if (r.dirW[a] == 0.0) {
            if (orgW[a] < o.clipBox.lower[a] || orgW[a] > o.clipBox.upper[a]) r.sMax = -1.0;
            continue;
          }
          const double ta = (o.clipBox.lower[a] - orgW[a]) / r.dirW[a];
          const double tb = (o.clipBox.upper[a] - orgW[a]) / r.dirW[a];
          r.sMin = std::max(r.sMin, std::min(ta, tb));
          r.sMax = std::min(r.sMax, std::max(ta, tb));
        }
      }
    }
    r.lattice.tmin = float(r.sMin * r.kappa);
    r.lattice.tmax = std::isinf(r.sMax) ? std::numeric_limits<float>::infinity() : float(r.sMax * r.kappa);
    if (!(r.lattice.tmax >= r.lattice.tmin)) r.lattice.tmax = r.lattice.tmin = 0.f, r.sMax = -1.0;
    return r;
  }

  bool clippedAway(const DualRay& r) const { return r.sMax < r.sMin; }

  /// Nearest mesh hit within [sMin, sMax] (world distances along the unit direction).
  bool traceMesh(const DualRay& r, double sMin, double sMax, SurfaceHit& hit) const {
    if (!meshScene || !(sMax >= sMin)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh = embree::makeRayHit(vec3f(r.orgW), vec3f(r.dirW), float(std::max(sMin, 0.0)),
                                      std::isinf(sMax) ? std::numeric_limits<float>::infinity() : float(sMax));
    rtcIntersect1(meshScene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.kind = SurfaceHit::Mesh;
    hit.index = int(rh.hit.geomID);
    hit.distance = rh.ray.tfar;
    hit.position = r.orgW + r.dirW * hit.distance;
    vec3f n = normalize(vec3f(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
    if (dot(vec3d(n), r.dirW) > 0.0) n = -n;
    hit.normal = n;
    return true;
  }

  /// Whether any mesh lies within [sMin, sMax] along the ray.
  bool meshOccludes(const DualRay& r, double sMin, double sMax) const {
    if (!meshScene || !(sMax > sMin)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = embree::makeRay(vec3f(r.orgW), vec3f(r.dirW), float(std::max(sMin, 0.0)), float(sMax));
    rtcOccluded1(meshScene, &context, &ray);
    return ray.tfar < 0.f;
  }

  /// Nearest iso-surface crossing along a lattice ray within [ray.tmin, ray.tmax]: each region
  /// is stepped at its adaptive rate (and at its entry and exit), and a sign change of
  /// value - isovalue is refined by bisection to 1e-3 of the region's finest cell width, then
  /// by one secant step. Returns the lattice t, the region and the iso-value's index.
  bool findIso(const Ray& ray, const RenderOptions& o, float& tHit, uint32_t& regionHit, int& which,
               uint64_t& samples) const {
    if (!isoTraversal || iso.values.empty() || !(ray.tmax > ray.tmin)) return false;
    bool found = false;
    isoTraversal->traverse(ray, [&](const Segment& seg) {
      const float t0 = std::max(seg.t0, ray.tmin), t1 = std::min(seg.t1, ray.tmax);
      if (!(t1 > t0)) return true;
      const Region& region = model.regions.regions[seg.region];
      const float width = o.sampling == Sampling::Adaptive ? region.finestWidth() : finestWidth;
      const float dt = 0.5f * width / o.rate;
      const float tolerance = 1e-3f * region.finestWidth();
      auto value = [&](float t, float& v) {
        ++samples;
        return sampleRegion(isoView, seg.region, ray.org + ray.dir * t, v);
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
          for (size_t j = 0; j < iso.values.size(); ++j) {
            const float c = iso.values[j];
            const bool sideA = va >= c, sideB = vb >= c;
            if (sideA == sideB) continue;
            float lo = ta, hi = tb, vlo = va, vhi = vb;
            while (hi - lo > tolerance) {
              const float mid = 0.5f * (lo + hi);
              if (!(mid > lo && mid < hi)) break; // float resolution reached
              float vm;
              if (!value(mid, vm)) {
                hi = mid, vhi = vm = vlo; // no value inside: keep the near part
                break;
              }
              if ((vm >= c) == sideA)
                lo = mid, vlo = vm;
              else
                hi = mid, vhi = vm;
            }
            const float denom = vhi - vlo;
            const float t = denom != 0.f ? lo + (hi - lo) * std::clamp((c - vlo) / denom, 0.f, 1.f) : hi;
            if (t < best) best = t, bestIndex = int(j);
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

  /// Nearest surface (mesh or iso-surface) along a primary ray.
  bool nearestSurface(const DualRay& r, const RenderOptions& o, SurfaceHit& hit, uint64_t& isoSamples) const {
    bool have = false;
    if (meshScene) {
      const double s0 = o.clipMeshes ? r.sMin : 0.0;
      const double s1 = o.clipMeshes ? r.sMax : std::numeric_limits<double>::infinity();
      have = traceMesh(r, s0, s1, hit);
    }
    if (isoTraversal && !clippedAway(r)) {
      Ray lr = r.lattice;
      if (have) lr.tmax = std::min(lr.tmax, float(hit.distance * r.kappa));
      float t;
      uint32_t region;
      int which;
      if (findIso(lr, o, t, region, which, isoSamples)) {
        const vec3f p = lr.org + lr.dir * t;
        float v;
        vec3f g;
        hit.kind = SurfaceHit::Iso;
        hit.index = which;
        hit.distance = double(t) / r.kappa;
        hit.position = r.orgW + r.dirW * hit.distance;
        vec3f n = -vec3f(r.dirW);
        if (sampleRegion(isoView, region, p, v, &g)) {
          const vec3f gw = g * invScale;
          if (length(gw) > 1e-30f) n = normalize(gw);
        }
        if (dot(vec3d(n), r.dirW) > 0.0) n = -n;
        hit.normal = n;
        have = true;
      }
    }
    return have;
  }

  /// Colour of a surface hit before lighting.
  vec3f surfaceColor(const SurfaceHit& hit) const {
    if (hit.kind == SurfaceHit::Mesh) return meshColors[size_t(hit.index)];
    if (iso.colorField >= 0) {
      float v;
      const vec3d pl = model.world.toLattice(hit.position);
      if (sampleField(isoColor.view, vec3f(pl), v)) {
        const vec4f c = isoColor.lookup(v);
        return {c.x, c.y, c.z};
      }
    }
    if (!iso.colors.empty()) return iso.colors[size_t(hit.index) % iso.colors.size()];
    return kIsoColors[hit.index % 4];
  }

  /// Fraction of unoccluded cosine-weighted rays over the hemisphere of the hit's normal.
  float ambientOcclusion(const SurfaceHit& hit, const RenderOptions& o, PixelRandom& rng, Counters& c) const {
    const double lengthW = o.aoLength > 0.f ? double(o.aoLength) : 0.1 * worldDiagonal;
    const double eps = std::max(1e-5 * worldDiagonal, 1e-2 * double(finestWidth) * minScale);
    vec3f u, v;
    orthonormalBasis(hit.normal, u, v);
    float open = 0.f;
    for (int i = 0; i < o.aoRays; ++i) {
      const float r1 = rng.next(), r2 = rng.next();
      const float radius = std::sqrt(r1), phi = 6.2831853f * r2;
      const vec3f d = u * (radius * std::cos(phi)) + v * (radius * std::sin(phi)) +
                      hit.normal * std::sqrt(std::max(0.f, 1.f - r1));
      ++c.aoRays;
      const DualRay ar = makeRay(hit.position + vec3d(hit.normal) * eps, vec3d(d), o, true);
      const double meshMin = o.clipMeshes ? ar.sMin : 0.0;
      const double meshMax = o.clipMeshes ? std::min(ar.sMax, lengthW) : lengthW;
      if (meshOccludes(ar, meshMin, meshMax)) continue;
      Ray lr = ar.lattice;
      lr.tmax = std::min(lr.tmax, float(lengthW * ar.kappa));
      float t;
      uint32_t region;
      int which;
      if (!clippedAway(ar) && findIso(lr, o, t, region, which, c.isoSamples)) continue;
      float visibility = 1.f;
      if (o.aoVolume && o.volume && !clippedAway(ar) && lr.tmax > lr.tmin) {
        vec4f acc;
        uint64_t samples = 0, regions = 0;
        integrate<true>(lr, 0.5f, vec3f(0.f), vec3f(0.f), o, acc, samples, regions);
        c.samples += samples;
        visibility = 1.f - acc.w;
      }
      open += visibility;
    }
    return o.aoRays > 0 ? open / float(o.aoRays) : 1.f;
  }

  /// Marches the visible regions along the lattice ray within [tmin, tmax], compositing front to
  /// back into acc (premultiplied). OpacityOnly skips colour and shading (shadow-like rays).
  template <bool OpacityOnly>
  void integrate(const Ray& ray, float rho, const vec3f& light, const vec3f& halfVector, const RenderOptions& o,
                 vec4f& acc, uint64_t& raySamples, uint64_t& regionCount) const {
    if (layers.empty() || !(ray.tmax > ray.tmin)) return;
    const size_t layerCount = layers.size();
    const bool wantGrad = !OpacityOnly && o.shading == Shading::Analytic;
    traversal->traverse(ray, [&](const Segment& seg) {
      ++regionCount;
      const Region& region = model.regions.regions[seg.region];
      const float width = o.sampling == Sampling::Adaptive ? region.finestWidth() : finestWidth;
      const float dt = 0.5f * width / o.rate;
      const float segEnd = std::min(seg.t1, ray.tmax);
      // Sample positions (k + rho) dt delimit intervals; each interval is sampled at its
      // midpoint and weighted by its length.
      float a = std::max(seg.t0, ray.tmin);
      float k = std::floor(a / dt - rho) + 1.f;
      while (a < segEnd) {
        float b = std::min((k + rho) * dt, segEnd);
        if (!(b > a)) b = std::min(a + dt, segEnd); // guards float round-off
        if (!(b > a)) break;
        k += 1.f;
        const float len = b - a;
        const float tm = 0.5f * (a + b);
        a = b;
        const vec3f p = ray.org + ray.dir * tm;
        ++raySamples;
        float logSum = 0.f, alphaSum = 0.f, alpha = 0.f;
        vec3f colorSum(0.f), color(0.f);
        for (size_t li = 0; li < layerCount; ++li) {
          const LayerTable& layer = layers[li];
          float value;
          vec3f grad;
          const bool found =
              o.reconstruction == Reconstruction::Regions
                  ? sampleRegion(layer.view, seg.region, p, value, wantGrad ? &grad : nullptr)
                  : locator->sample(layer.field, p, value, wantGrad ? &grad : nullptr);
          if (!found) break; // no value here for any field: the cells are shared
          const vec4f rgba = layer.lookup(value);
          if (rgba.w >= 0.f) continue; // log2 transmittance 0: fully transparent
          // Opacity correction: 1 - (1 - alpha)^(len / finest width).
          const float layerAlpha = 1.f - exp2Negative(rgba.w * len * invFinestWidth);
          logSum += rgba.w;
          if (OpacityOnly) continue;
          vec3f c(rgba.x, rgba.y, rgba.z);
          if (o.shading != Shading::None) {
            if (o.shading == Shading::Central || o.shading == Shading::ClampedCentral) {
              const float h = 0.5f * region.finestWidth();
              const box3f rb = region.bounds();
              for (int ax = 0; ax < 3; ++ax) {
                vec3f pp = p, pm = p;
                pp[ax] += h;
                pm[ax] -= h;
                float vp = value, vm = value;
                if (o.shading == Shading::ClampedCentral) {
                  pp[ax] = std::min(pp[ax], rb.upper[ax]);
                  pm[ax] = std::max(pm[ax], rb.lower[ax]);
                  sampleRegion(layer.view, seg.region, pp, vp);
                  sampleRegion(layer.view, seg.region, pm, vm);
                } else {
                  sampleField(layer.view, pp, vp);
                  sampleField(layer.view, pm, vm);
                }
                const float span = pp[ax] - pm[ax];
                grad[ax] = span > 0.f ? (vp - vm) / span : 0.f;
              }
            }
            const vec3f gw = grad * invScale; // per world unit
            const float gl = length(gw);
            float shade = o.ambient + o.diffuse;
            float spec = 0.f;
            if (gl > 1e-20f) {
              const vec3f n = gw * (1.f / gl);
              const float ndl = std::abs(dot(n, light));
              shade = o.ambient + o.diffuse * ndl;
              spec = o.specular * specularPower(std::abs(dot(n, halfVector)), o.shininess);
            }
            c = c * shade + vec3f(spec);
          }
          if (layerCount == 1) {
            alpha = layerAlpha;
            color = c;
          } else {
            colorSum += c * layerAlpha;
            alphaSum += layerAlpha;
          }
        }
        if (!(logSum < 0.f)) continue;
        if (OpacityOnly || layerCount > 1) alpha = 1.f - exp2Negative(logSum * len * invFinestWidth);
        if (!OpacityOnly && layerCount > 1) color = alphaSum > 0.f ? colorSum * (1.f / alphaSum) : vec3f(0.f);
        const float wgt = (1.f - acc.w) * alpha;
        if (!OpacityOnly) {
          acc.x += wgt * color.x;
          acc.y += wgt * color.y;
          acc.z += wgt * color.z;
        }
        acc.w += wgt;
        if (o.earlyTermination && acc.w >= o.terminationOpacity) return false;
      }
      return true;
    });
  }
};

Renderer::Renderer(const Model& model, int field, const RenderOptions& options)
    : impl_(std::make_unique<Impl>(model, field)), options_(options) {
  if (options_.width < 1 || options_.height < 1 || options_.width > 32768 || options_.height > 32768)
    fail("image size ", options_.width, "x", options_.height, " is out of range (1..32768)");
  if (options_.samplesPerPixel < 1) fail("samples per pixel must be at least 1");
  if (!(options_.rate > 0.f) || options_.rate > 1024.f) fail("sampling rate must be in (0, 1024]");
  if (options_.aoRays < 0 || options_.aoRays > 1024) fail("ambient occlusion rays must be in 0..1024");
  if (!(options_.aoLength >= 0.f) || std::isinf(options_.aoLength))
    fail("ambient occlusion length must be a finite non-negative number");
  for (const ClipPlane& p : options_.clipPlanes)
    if (!(length(p.normal) > 0.0) || !std::isfinite(length(p.normal)) || !std::isfinite(length(p.point)))
      fail("a clip plane needs a finite point and a non-zero normal");
}

Renderer::~Renderer() = default;

TraversalKind Renderer::traversalInUse() const {
  return impl_->traversal ? impl_->traversal->kind() : options_.traversal;
}

size_t Renderer::visibleRegions() const {
  return impl_->traversal ? impl_->traversal->visibleCount() : 0;
}

size_t Renderer::isoRegions() const { return impl_->isoTraversal ? impl_->isoTraversal->visibleCount() : 0; }

size_t Renderer::meshCount() const { return impl_->meshColors.size(); }

double Renderer::setTransferFunction(const TransferFunction& tf) {
  return setVolumeLayers({VolumeLayer{impl_->field, tf}});
}

double Renderer::setVolumeLayers(const std::vector<VolumeLayer>& layersIn) {
  Timer timer;
  Impl& im = *impl_;
  std::vector<LayerTable> layers(layersIn.size());
  for (size_t i = 0; i < layersIn.size(); ++i) layers[i].build(im.model, layersIn[i].field, layersIn[i].tf);
  im.layers = std::move(layers);
  // Space skipping: a region whose value ranges map to zero opacity in every layer cannot
  // contribute.
  const size_t regionCount = im.model.regions.regions.size();
  im.visible.assign(regionCount, im.layers.empty() ? 0 : 1);
  if (options_.spaceSkipping && options_.debug == DebugView::None && !im.layers.empty())
    tbb::parallel_for(size_t(0), regionCount, [&](size_t i) {
      bool any = false;
      for (const LayerTable& layer : im.layers)
        any = any || layer.mayBeVisible(im.model.regions.valueRanges[size_t(layer.field)][i]);
      im.visible[i] = any;
    });
  TraversalKind kind = options_.traversal;
  if (options_.autoTraversal) {
    size_t count = 0;
    for (uint8_t v : im.visible) count += v;
    kind = double(count) < double(options_.embreeBelowVisibleFraction) * double(im.visible.size())
               ? TraversalKind::Embree
               : TraversalKind::KdTree;
  }
  if (!im.traversal || im.traversal->kind() != kind)
    im.traversal = std::make_unique<RegionTraversal>(im.model, kind);
  im.traversal->setVisible(im.visible);
  if (options_.reconstruction == Reconstruction::CellLocation && !im.locator)
    im.locator = std::make_unique<CellLocator>(im.model);
  return timer.seconds();
}

double Renderer::setIsoSurfaces(const IsoSurfaces& isoIn) {
  Timer timer;
  Impl& im = *impl_;
  const size_t fieldCount = im.model.fieldValues.size();
  if (isoIn.field >= int(fieldCount)) fail("iso-surface field index ", isoIn.field, " is out of range");
  if (isoIn.colorField >= int(fieldCount)) fail("iso-surface colour field index ", isoIn.colorField, " is out of range");
  for (float v : isoIn.values)
    if (!std::isfinite(v)) fail("iso-values must be finite numbers");
  im.iso = isoIn;
  if (isoIn.field < 0 || isoIn.values.empty()) {
    im.isoTraversal.reset();
    im.isoVisible.clear();
    return timer.seconds();
  }
  im.isoView = im.model.view(isoIn.field);
  if (isoIn.colorField >= 0) im.isoColor.build(im.model, isoIn.colorField, isoIn.colorTf);
  const auto& ranges = im.model.regions.valueRanges[size_t(isoIn.field)];
  im.isoVisible.assign(ranges.size(), 0);
  tbb::parallel_for(size_t(0), ranges.size(), [&](size_t i) {
    const range1f& r = ranges[i];
    bool any = false;
    for (float v : isoIn.values) any = any || (!r.empty() && r.lower <= v && v <= r.upper);
    im.isoVisible[i] = any;
  });
  size_t count = 0;
  for (uint8_t v : im.isoVisible) count += v;
  // Iso-surfaces are sparse: Embree skips the empty space in its BVH unless most regions hold one.
  const TraversalKind kind = double(count) < double(options_.embreeBelowVisibleFraction) * double(ranges.size())
                                 ? TraversalKind::Embree
                                 : TraversalKind::KdTree;
  if (!im.isoTraversal || im.isoTraversal->kind() != kind)
    im.isoTraversal = std::make_unique<RegionTraversal>(im.model, kind);
  im.isoTraversal->setVisible(im.isoVisible);
  return timer.seconds();
}

void Renderer::addMesh(const TriangleMesh& mesh, const vec3f& color) {
  Impl& im = *impl_;
  const size_t meshNumber = im.meshColors.size();
  if (mesh.triangles.empty()) fail("mesh ", meshNumber, " has no triangles");
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const vec3f& v = mesh.vertices[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      fail("mesh ", meshNumber, ": vertex ", i, " is not finite");
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (mesh.triangles[i][k] < 0 || size_t(mesh.triangles[i][k]) >= mesh.vertices.size())
        fail("mesh ", meshNumber, ": triangle ", i, " refers to vertex ", mesh.triangles[i][k], " of ",
             mesh.vertices.size());
  if (!im.device) {
    im.device = embree::newDevice();
    im.meshScene = rtcNewScene(im.device);
    rtcSetSceneFlags(im.meshScene, RTC_SCENE_FLAG_ROBUST);
  }
  RTCGeometry geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), mesh.vertices.size()));
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(uint32_t), mesh.triangles.size()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geom);
    fail("mesh ", meshNumber, ": out of memory for ", mesh.triangles.size(), " triangles");
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) vertices[3 * i + size_t(k)] = mesh.vertices[i][k];
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) indices[3 * i + size_t(k)] = uint32_t(mesh.triangles[i][k]);
  rtcCommitGeometry(geom);
  const unsigned id = rtcAttachGeometry(im.meshScene, geom);
  rtcReleaseGeometry(geom);
  EXA_CHECK(id == meshNumber);
  rtcCommitScene(im.meshScene);
  im.meshColors.push_back(color);
}

bool Renderer::pick(const vec3d& origin, const vec3d& direction, SurfaceHit& hit) const {
  if (!(length(direction) > 0.0)) return false;
  const DualRay r = impl_->makeRay(origin, direction, options_, true);
  uint64_t samples = 0;
  return impl_->nearestSurface(r, options_, hit, samples);
}

Image Renderer::render(const Camera& camera, RenderStats* statsOut) const {
  const Impl& im = *impl_;
  if (!im.traversal) fail("no transfer function set");
  if (options_.reconstruction == Reconstruction::CellLocation && !im.locator)
    fail("cell-location reconstruction was chosen after the transfer function was set");
  const RenderOptions& o = options_;
  Image image(o.width, o.height);
  const double aspect = double(o.width) / double(o.height);
  const vec3f lightWorld = normalize(o.lightDirection);
  const bool surfaces = (im.isoTraversal || im.meshScene) && o.debug == DebugView::None;
  const bool clipping = !o.clipPlanes.empty() || !o.clipBox.empty();

  tbb::combinable<Counters> counters;
  const int tilesX = (o.width + kTile - 1) / kTile, tilesY = (o.height + kTile - 1) / kTile;
  Progress progress("rendering", uint64_t(tilesX) * uint64_t(tilesY));
  if (!o.progress) progress.finish();
  std::vector<float> steps; // per pixel, for the steps view
  if (o.debug == DebugView::Steps) steps.assign(size_t(o.width) * size_t(o.height), 0.f);
  Timer timer;

  tbb::parallel_for(
      tbb::blocked_range2d<int>(0, tilesY, 1, 0, tilesX, 1), [&](const tbb::blocked_range2d<int>& tiles) {
        Counters& c = counters.local();
        for (int ty = tiles.rows().begin(); ty < tiles.rows().end(); ++ty)
          for (int tx = tiles.cols().begin(); tx < tiles.cols().end(); ++tx) {
            for (int y = ty * kTile; y < std::min(o.height, (ty + 1) * kTile); ++y)
              for (int x = tx * kTile; x < std::min(o.width, (tx + 1) * kTile); ++x) {
                vec4f sum;
                uint64_t pixelSteps = 0;
                for (int s = 0; s < o.samplesPerPixel; ++s) {
                  PixelRandom rng(x, y, s, o.seed);
                  const bool jitter = o.jitter && o.debug == DebugView::None;
                  const float jx = o.samplesPerPixel > 1 && jitter ? rng.next() : 0.5f;
                  const float jy = o.samplesPerPixel > 1 && jitter ? rng.next() : 0.5f;
                  const float rho = jitter ? rng.next() : 0.5f;
                  vec3d orgW, dirW;
                  camera.ray((x + jx) / o.width, (y + jy) / o.height, aspect, orgW, dirW);
                  // March in lattice space with a unit-length lattice direction: t is in
                  // finest-level lattice units.
                  const DualRay dr = im.makeRay(orgW, dirW, o, clipping && o.debug == DebugView::None);
                  const Ray& ray = dr.lattice;
                  const vec3f viewW = vec3f(dr.dirW);
                  const vec3f light = o.headlight ? viewW : lightWorld;
                  const vec3f halfVector = normalize(light + viewW);
                  ++c.rays;
                  vec4f acc; // premultiplied, front to back
                  uint64_t raySamples = 0;

                  if (o.debug == DebugView::Level || o.debug == DebugView::Region || o.debug == DebugView::Brick) {
                    im.traversal->traverse(ray, [&](const Segment& seg) {
                      const Region& region = im.model.regions.regions[seg.region];
                      vec3f color;
                      if (o.debug == DebugView::Region) {
                        color = hashColor(seg.region);
                      } else {
                        // The brick whose cells hold the segment's midpoint; where no cell does (the
                        // margin of the supports), the region's finest brick.
                        const vec3f p = ray.org + ray.dir * (0.5f * (seg.t0 + seg.t1));
                        uint32_t brickId = kNoRegion;
                        for (uint32_t k = 0; k < region.brickCount; ++k) {
                          const uint32_t id = im.model.regions.brickIds[region.brickBegin + k];
                          const box3i b = im.model.bricks[id].bounds();
                          if (brickId == kNoRegion || im.model.bricks[id].level < im.model.bricks[brickId].level)
                            brickId = id;
                          if (p.x >= b.lower.x && p.x < b.upper.x && p.y >= b.lower.y && p.y < b.upper.y &&
                              p.z >= b.lower.z && p.z < b.upper.z) {
                            brickId = id;
                            break;
                          }
                        }
                        color = o.debug == DebugView::Level ? levelColor(im.model.bricks[brickId].level)
                                                            : hashColor(brickId);
                      }
                      acc = {color.x, color.y, color.z, 1.f};
                      ++c.regions;
                      return false;
                    });
                    sum.x += acc.x, sum.y += acc.y, sum.z += acc.z, sum.w += acc.w;
                    continue;
                  }

                  SurfaceHit hit;
                  const bool haveHit = surfaces && im.nearestSurface(dr, o, hit, c.isoSamples);
                  Ray volumeRay = ray;
                  if (haveHit) volumeRay.tmax = std::min(volumeRay.tmax, float(hit.distance * dr.kappa));
                  if (o.volume && !im.clippedAway(dr))
                    im.integrate<false>(volumeRay, rho, light, halfVector, o, acc, raySamples, c.regions);
                  if (haveHit && acc.w < 1.f) {
                    ++c.surfaceHits;
                    const vec3f base = im.surfaceColor(hit);
                    const float ao = o.aoRays > 0 ? im.ambientOcclusion(hit, o, rng, c) : 1.f;
                    const float ndl = std::max(0.f, -dot(hit.normal, light));
                    const float spec = o.specular * specularPower(std::max(0.f, -dot(hit.normal, halfVector)), o.shininess);
                    const vec3f color = base * (o.ambient * ao + o.diffuse * ndl * (0.5f + 0.5f * ao)) + vec3f(spec);
                    const float wgt = 1.f - acc.w;
                    acc.x += wgt * color.x;
                    acc.y += wgt * color.y;
                    acc.z += wgt * color.z;
                    acc.w = 1.f;
                  }
                  c.samples += raySamples;
                  pixelSteps += raySamples;
                  sum.x += acc.x, sum.y += acc.y, sum.z += acc.z, sum.w += acc.w;
                }
                const float inv = 1.f / float(o.samplesPerPixel);
                image.at(x, y) = {sum.x * inv, sum.y * inv, sum.z * inv, sum.w * inv};
                if (!steps.empty()) steps[size_t(y) * size_t(o.width) + size_t(x)] = float(pixelSteps) * inv;
              }
            progress.advance(1);
          }
      });
  progress.finish();

  if (!steps.empty()) {
    // Steps per ray as a heat map, scaled to the image's maximum.
    float maxSteps = 1.f;
    for (float st : steps) maxSteps = std::max(maxSteps, st);
    const ColorMap heat = builtinColorMap("inferno");
    for (size_t i = 0; i < steps.size(); ++i) {
      const vec3f col = heat.at(steps[i] / maxSteps);
      image.pixels[i] = {col.x, col.y, col.z, 1.f};
    }
  }

  RenderStats st;
  st.seconds = timer.seconds();
  counters.combine_each([&](const Counters& c) {
    st.rays += c.rays;
    st.samples += c.samples;
    st.regionsVisited += c.regions;
    st.surfaceHits += c.surfaceHits;
    st.isoSamples += c.isoSamples;
    st.aoRays += c.aoRays;
  });
  if (statsOut) *statsOut = st;
  return image;
}

} // namespace exa
