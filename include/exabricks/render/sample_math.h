// The per-sample math of the ray marcher, header-only over plain structs so that the CPU driver,
// the tests and a GPU path share one copy: transfer-function tables and their lookup, opacity
// correction, volume and surface shading, front-to-back compositing and the refinement of an
// iso-surface crossing. Free of allocation, exceptions, virtual calls and run-time-indexed
// constant tables.
#pragma once

#include "exabricks/core/color.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace exa {

/// Entries of a tabulated transfer function.
constexpr int kTfTableSize = 4096;

/// Value -> [0, 1] over `range`, linear or logarithmic (base 10), clamped; NaN maps to 0, an
/// unusable range to 0.5; a logarithmic range reaching zero or below is cut six decades under
/// its upper end. Monotonic in the value (space skipping relies on it).
EXA_HOST_DEVICE inline float normalizeValue(const range1f& range, bool logScale, float value) {
  if (value != value) return 0.f;
  double lo = range.lower, hi = range.upper, v = value;
  if (range.empty() || !std::isfinite(lo) || !std::isfinite(hi)) return 0.5f;
  if (logScale) {
    if (!(v > 0.0)) return 0.f;
    if (!(hi > 0.0)) return 1.f; // every positive value lies above the range
    if (!(lo > 0.0)) lo = hi * 1e-6;
    lo = std::log10(lo);
    hi = std::log10(hi);
    v = std::log10(v);
  }
  // A single value: below it 0, above it 1, on it the middle; still monotonic.
  if (!(hi > lo)) return v < lo ? 0.f : (v > hi ? 1.f : 0.5f);
  const double t = (v - lo) / (hi - lo);
  return float(t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t));
}

/// A transfer function tabulated for the marcher: linear-RGB colour and log2 of the
/// transmittance of one reference width (the dataset's finest cell) per normalised value.
struct TfTableView {
  const vec4f* entries = nullptr; ///< kTfTableSize entries
  range1f range;
  bool logScale = false;
  bool fastLinear = false; ///< linear with a proper range: n = (v - lower) * scale
  float lower = 0.f, scale = 0.f;
};

EXA_HOST_DEVICE inline float clamp01(float x) { return x < 0.f ? 0.f : (x > 1.f ? 1.f : x); }

EXA_HOST_DEVICE inline float tfNormalized(const TfTableView& t, float value) {
  return t.fastLinear ? clamp01((value - t.lower) * t.scale) : normalizeValue(t.range, t.logScale, value);
}

/// The table, linearly interpolated, at normalised value n.
EXA_HOST_DEVICE inline vec4f tfTableAt(const TfTableView& t, float n) {
  const float x = n * float(kTfTableSize - 1);
  int i = int(x);
  i = i < 0 ? 0 : (i > kTfTableSize - 2 ? kTfTableSize - 2 : i);
  const float f = clamp01(x - float(i));
  const vec4f a = loadVec4(t.entries + i);
  const vec4f b = loadVec4(t.entries + i + 1);
  return {a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f, a.w + (b.w - a.w) * f};
}

EXA_HOST_DEVICE inline vec4f tfLookup(const TfTableView& t, float value) {
  return tfTableAt(t, tfNormalized(t, value));
}

/// A value range on a table: its normalised ends and the entries between them, [first, last]
/// (none where first > last). The table is linear between entries, so its extremes over the range
/// lie at those entries or at the ends.
struct TfSpan {
  float n0 = 0.f, n1 = 0.f;
  int first = 0, last = -1;
};

EXA_HOST_DEVICE inline TfSpan tfSpanOf(const TfTableView& t, const range1f& r) {
  TfSpan s;
  s.n0 = tfNormalized(t, r.lower), s.n1 = tfNormalized(t, r.upper);
  const int first = int(std::ceil(s.n0 * float(kTfTableSize - 1)));
  const int last = int(std::floor(s.n1 * float(kTfTableSize - 1)));
  s.first = first < 0 ? 0 : first;
  s.last = last > kTfTableSize - 1 ? kTfTableSize - 1 : last;
  return s;
}

/// Calls visit(entry) for the table at both ends of the non-empty range r (interpolated), then
/// at every entry between them (tfSpanOf): among them lie the table's extremes over r. Stops and
/// returns false where visit returns false.
template <typename Visit>
EXA_HOST_DEVICE inline bool tfVisitExtremes(const TfTableView& t, const range1f& r, Visit&& visit) {
  const TfSpan s = tfSpanOf(t, r);
  if (!visit(tfTableAt(t, s.n0)) || !visit(tfTableAt(t, s.n1))) return false;
  for (int i = s.first; i <= s.last; ++i)
    if (!visit(t.entries[i])) return false;
  return true;
}

/// Whether any value in r can be visible through the table.
EXA_HOST_DEVICE inline bool tfMayBeVisible(const TfTableView& t, const range1f& r) {
  return !r.empty() && !tfVisitExtremes(t, r, [](const vec4f& e) { return !(e.w < 0.f); });
}

/// The largest extinction (per lattice unit) a table gives any value of a range: its log2
/// transmittance is piecewise linear between entries, so the extremes lie at entries or ends.
/// In constant time for the many ranges of the path tracer's majorants: kept per entry and power
/// of two, the smallest log2 transmittance of that many entries from it.
class TableMaxExtinction {
public:
  TableMaxExtinction(const TfTableView& t, float extinctionPerLog2) : t_(t), perLog2_(extinctionPerLog2) {
    smallest_.resize(size_t(kLevels) * kTfTableSize);
    for (int i = 0; i < kTfTableSize; ++i)
      smallest_[size_t(i)] = t.entries[i].w;
    for (int k = 1; k < kLevels; ++k)
      for (int i = 0; i + (1 << k) <= kTfTableSize; ++i)
        smallest_[size_t(k) * kTfTableSize + size_t(i)] = std::min(at(k - 1, i), at(k - 1, i + (1 << (k - 1))));
  }
  float operator()(const range1f& r) const {
    if (r.empty()) return 0.f;
    const TfSpan s = tfSpanOf(t_, r);
    float w = std::min(tfTableAt(t_, s.n0).w, tfTableAt(t_, s.n1).w);
    if (s.first <= s.last) {
      int k = 0;
      while ((2 << k) <= s.last - s.first + 1)
        ++k;
      w = std::min({w, at(k, s.first), at(k, s.last - (1 << k) + 1)});
    }
    return -w * perLog2_;
  }

private:
  static constexpr int kLevels = 13; ///< 2^12 = kTfTableSize
  float at(int k, int i) const { return smallest_[size_t(k) * kTfTableSize + size_t(i)]; }
  TfTableView t_;
  float perLog2_;
  std::vector<float> smallest_;
};

/// A region's look is uniform where, over its value range, the transfer function's linear colour
/// varies by at most kUniformVariation in every channel and its optical depth across the
/// region's diagonal by at most kUniformVariation: its samples differ only in their shading, and
/// a ray takes kUniformStride times the region's step there. Shaded samples vary with their
/// gradients all the same, and a longer step averages that variation over fewer samples, so for
/// them the region must also be nearly transparent: its optical depth across its diagonal at most
/// kUniformShadedDepth, which bounds what its whole contribution can change. Measured on held-out
/// data (docs/performance.md, "Uniform regions").
constexpr float kUniformVariation = 0.005f;
constexpr float kUniformShadedDepth = 0.02f;
constexpr float kUniformStride = 4.f;

/// The stride of a region's step (sampleStep) for the given layers' tables over its value ranges
/// (one per layer): kUniformStride where every layer's look is uniform (and, for `shaded`
/// samples, the layers together nearly transparent), 1 otherwise. `diagonal` is the region's
/// diagonal and extinctionPerLog2 the optical depth per lattice unit of a table's log2
/// transmittance -1, as the marcher's.
inline float regionStride(const std::vector<const TfTableView*>& tables, const std::vector<range1f>& ranges,
                          float diagonal, float extinctionPerLog2, bool shaded = false) {
  float densest = 0.f; // the layers' summed largest optical depth across the region
  for (size_t l = 0; l < tables.size(); ++l) {
    if (ranges[l].empty()) continue; // no values: nothing this layer shows changes
    constexpr float inf = std::numeric_limits<float>::infinity();
    vec4f lo(inf, inf, inf, inf), hi(-inf, -inf, -inf, -inf);
    // Stops at the first entry that makes the look vary: a wide range rarely reads many.
    const bool uniform = tfVisitExtremes(*tables[l], ranges[l], [&](const vec4f& e) {
      lo = vec4f(std::min(lo.x, e.x), std::min(lo.y, e.y), std::min(lo.z, e.z), std::min(lo.w, e.w));
      hi = vec4f(std::max(hi.x, e.x), std::max(hi.y, e.y), std::max(hi.z, e.z), std::max(hi.w, e.w));
      const float colour = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
      const float depth = (hi.w - lo.w) * extinctionPerLog2 * diagonal;
      return colour <= kUniformVariation && depth <= kUniformVariation;
    });
    if (!uniform) return 1.f;
    densest += -lo.w * extinctionPerLog2 * diagonal;
  }
  return shaded && !(densest <= kUniformShadedDepth) ? 1.f : kUniformStride;
}

/// The Taylor coefficients (ln 2)^k / k! of 2^f, k = 1..6 (exp2Negative and its vector form).
constexpr float kExp2Taylor1 = 0.6931471805599453f, kExp2Taylor2 = 0.2402265069591007f,
                kExp2Taylor3 = 0.05550410866482158f, kExp2Taylor4 = 0.009618129107628477f,
                kExp2Taylor5 = 0.0013333558146428443f, kExp2Taylor6 = 0.00015403530393381606f;

/// 2^x for x <= 0 to float precision (relative error below 2.5e-7): a degree-6 Taylor
/// polynomial of 2^f on [-1/2, 1/2] times 2^i built from the exponent bits. Cheaper than a libm
/// call on the hot path of every sample's opacity correction.
EXA_HOST_DEVICE inline float exp2Negative(float x) {
  if (x < -126.f) return 0.f;
  const float i = std::nearbyint(x);
  const float f = x - i;
  float p = kExp2Taylor6;
  p = p * f + kExp2Taylor5;
  p = p * f + kExp2Taylor4;
  p = p * f + kExp2Taylor3;
  p = p * f + kExp2Taylor2;
  p = p * f + kExp2Taylor1;
  p = p * f + 1.f;
  const uint32_t bits = uint32_t(int32_t(i) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

/// Opacity correction: a step of `length` through a medium whose transmittance over one
/// reference width is 2^log2Transmittance has opacity 1 - (1 - alpha)^(length / reference).
EXA_HOST_DEVICE inline float correctedOpacity(float log2Transmittance, float length, float invReferenceWidth) {
  return 1.f - exp2Negative(log2Transmittance * length * invReferenceWidth);
}

/// Schlick's rational approximation of x^e for x in [0, 1]: exact at 0 and 1, one division
/// instead of a power per sample.
EXA_HOST_DEVICE inline float specularPower(float x, float e) { return x / (e - (e - 1.f) * x); }

/// Blinn-Phong terms.
struct ShadingTerms {
  float ambient = 0.3f, diffuse = 0.7f, specular = 0.25f, shininess = 40.f;
};

/// How much of the gradient shading a volume sample gets: the gradient's relative change per
/// cell, |g| w / scale (w the cell width, scale the value range of the transfer function or, for
/// logarithmic mapping, the value itself), below 1e-5 is round-off of a nearly constant field and
/// gets none (shading it would draw its noise as lines and haze), above 1e-4 gets full shading,
/// and linearly between. `relative` is |g| w / scale.
constexpr float kShadingFadeLow = 1e-5f, kShadingFadeHigh = 1e-4f;
EXA_HOST_DEVICE inline float shadingWeight(float relative) {
  if (relative >= kShadingFadeHigh) return 1.f;
  if (!(relative > kShadingFadeLow)) return 0.f;
  return (relative - kShadingFadeLow) / (kShadingFadeHigh - kShadingFadeLow);
}

/// shadeVolumeSample's fade scale at `value`: the cell width over the scale of the field's changes,
/// that is fadeWidth (cell width / value range) for a linear transfer function, or
/// fadeWidth / |value| (fadeWidth the cell width; 0 at 0) where the value itself is the scale.
EXA_HOST_DEVICE inline float fadeScaleAt(float fadeWidth, bool byValue, float value) {
  return byValue ? (value != 0.f ? fadeWidth / std::abs(value) : 0.f) : fadeWidth;
}

/// A volume sample's colour lit two-sided by the normal along its gradient (any units); the
/// shaded term is weighted by shadingWeight(|gradient| x fadeScale) (fadeScale = cell width /
/// scale, in the gradient's units), so where the gradient is round-off the sample is lit as if
/// facing the light, without highlight.
EXA_HOST_DEVICE inline vec3f shadeVolumeSample(const vec3f& color, const vec3f& gradient, const vec3f& light,
                                               const vec3f& halfVector, const ShadingTerms& s, float fadeScale) {
  const float gl = length(gradient);
  const float weight = shadingWeight(gl * fadeScale);
  float shade = s.ambient + s.diffuse;
  float spec = 0.f;
  if (gl > 1e-20f && weight > 0.f) {
    const vec3f n = gradient * (1.f / gl);
    const float ndl = std::abs(dot(n, light));
    const float lit = s.ambient + s.diffuse * ndl;
    const float highlight = s.specular * specularPower(std::abs(dot(n, halfVector)), s.shininess);
    if (weight >= 1.f) {
      shade = lit;
      spec = highlight;
    } else {
      shade = shade + (lit - shade) * weight;
      spec = highlight * weight;
    }
  }
  return color * shade + vec3f(spec);
}

/// A surface's colour lit one-sided (normal facing the viewer), with ambient occlusion `ao`
/// (1: open) dimming the ambient term fully and the diffuse term by half.
EXA_HOST_DEVICE inline vec3f shadeSurface(const vec3f& base, const vec3f& normal, const vec3f& light,
                                          const vec3f& halfVector, float ao, const ShadingTerms& s) {
  const float ndl = -dot(normal, light) > 0.f ? -dot(normal, light) : 0.f;
  const float nh = -dot(normal, halfVector) > 0.f ? -dot(normal, halfVector) : 0.f;
  const float spec = s.specular * specularPower(nh, s.shininess);
  return base * (s.ambient * ao + s.diffuse * ndl * (0.5f + 0.5f * ao)) + vec3f(spec);
}

/// Front-to-back compositing into a premultiplied accumulator: what lies behind is seen
/// through what is already in front.
EXA_HOST_DEVICE inline void compositeBehind(vec4f& acc, const vec3f& color, float alpha) {
  const float wgt = (1.f - acc.w) * alpha;
  acc.x += wgt * color.x;
  acc.y += wgt * color.y;
  acc.z += wgt * color.z;
  acc.w += wgt;
}

/// An opaque surface behind everything accumulated so far.
EXA_HOST_DEVICE inline void compositeOpaqueBehind(vec4f& acc, const vec3f& color) {
  const float wgt = 1.f - acc.w;
  acc.x += wgt * color.x;
  acc.y += wgt * color.y;
  acc.z += wgt * color.z;
  acc.w = 1.f;
}

/// Where a segment's samples lie: the positions (k + rho) dt delimit intervals, each sampled at
/// its midpoint and weighted by its length. The march's state between batches.
struct SegmentMarch {
  float a = 0.f;   ///< start of the next interval
  float k = 0.f;   ///< index of the next position (a whole number)
  float rho = 0.f; ///< offset of the positions, in steps
  float dt = 1.f;  ///< step
  float end = 0.f; ///< end of the segment

  EXA_HOST_DEVICE SegmentMarch(float t0, float t1, float rhoIn, float dtIn)
      : a(t0), k(std::floor(t0 / dtIn - rhoIn) + 1.f), rho(rhoIn), dt(dtIn), end(t1) {}

  /// End of the interval that starts at a: the next position, or one step on where float
  /// round-off put that at or before a; not beyond a when float resolution runs out.
  EXA_HOST_DEVICE float intervalEnd() const {
    const float b = std::min((k + rho) * dt, end);
    return b > a ? b : std::min(a + dt, end);
  }
};

/// Unit vectors perpendicular to n (and to each other).
EXA_HOST_DEVICE inline void orthonormalBasis(const vec3f& n, vec3f& u, vec3f& v) {
  const vec3f a = std::abs(n.x) > 0.9f ? vec3f(0.f, 1.f, 0.f) : vec3f(1.f, 0.f, 0.f);
  u = normalize(cross(a, n));
  v = cross(n, u);
}

/// A cosine-weighted direction over the hemisphere of the unit normal n from two uniform
/// random numbers in [0, 1).
EXA_HOST_DEVICE inline vec3f cosineHemisphere(const vec3f& n, float r1, float r2) {
  vec3f u, v;
  orthonormalBasis(n, u, v);
  const float radius = std::sqrt(r1), phi = 6.2831853f * r2;
  return u * (radius * std::cos(phi)) + v * (radius * std::sin(phi)) + n * std::sqrt(std::max(0.f, 1.f - r1));
}

/// Width over which a volume sample's gradient shading fades (shadeVolumeSample's fade scale
/// before fadeScaleAt): the cell width, over the transfer function's value span unless the value
/// itself is the scale (`byValue`).
EXA_HOST_DEVICE inline float fadeWidthOf(float cellWidth, bool byValue, float invSpan) {
  return byValue ? cellWidth : cellWidth * invSpan;
}

/// Refines a crossing of `level` between lo and hi (values vlo, vhi on opposite sides;
/// `loAbove` says whether vlo >= level) by bisection down to `tolerance`, then one secant step.
/// `value(t, v)` reconstructs at t and returns false where there is no value; there the search
/// keeps the near part. Returns the crossing's t.
template <typename ValueAt>
EXA_HOST_DEVICE inline float refineCrossing(ValueAt&& value, float lo, float hi, float vlo, float vhi, float level,
                                            bool loAbove, float tolerance) {
  while (hi - lo > tolerance) {
    const float mid = 0.5f * (lo + hi);
    if (!(mid > lo && mid < hi)) break; // float resolution reached
    float vm;
    if (!value(mid, vm)) {
      hi = mid, vhi = vlo; // no value inside: keep the near part
      break;
    }
    if ((vm >= level) == loAbove)
      lo = mid, vlo = vm;
    else
      hi = mid, vhi = vm;
  }
  const float denom = vhi - vlo;
  return denom != 0.f ? lo + (hi - lo) * clamp01((level - vlo) / denom) : hi;
}

} // namespace exa
