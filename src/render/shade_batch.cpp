// Vectorised transfer function and volume shading of sampling batches (see shade_batch.h).
// Highway compiles the code between HWY_BEFORE_NAMESPACE and HWY_AFTER_NAMESPACE once per target
// instruction set (this file includes itself through foreach_target.h) and dispatches at run time.
#include "exabricks/render/shade_batch.h"

#ifndef EXABRICKS_HAVE_HWY

namespace exa {

int placeSamples(const vec3f& org, const vec3f& dir, SegmentMarch& m, SampleBatch& batch, float* lengths) {
  return placeSamplesScalar(org, dir, m, batch, lengths);
}

bool tfLookupBatch(const TfTableView& tf, const SampleBatch& batch, TfBatch& out) {
  return tfLookupBatchScalar(tf, batch, out);
}

void shadeVolumeBatch(const SampleBatch& batch, const TfBatch& tf, const float* lengths, const VolumeShadeParams& p,
                      ShadedBatch& out) {
  shadeVolumeBatchScalar(batch, tf, lengths, p, out);
}

BatchFunctions batchFunctions() {
  return {&placeSamples, sampleBricksBatchFunction(), sampleShadedBatchFunction(), &tfLookupBatch, &shadeVolumeBatch};
}

} // namespace exa

#else

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "shade_batch.cpp"
#include <hwy/foreach_target.h> // IWYU pragma: keep
#include <hwy/highway.h>

#include "exp2_batch-inl.h"

HWY_BEFORE_NAMESPACE();
namespace exa {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

int PlaceSamplesImpl(const vec3f& org, const vec3f& dir, SegmentMarch& m, SampleBatch& batch, float* lengths) {
  // Lane i's interval runs from position k + i - 1 (lane 0: from a) to position k + i, both
  // computed as the scalar march computes them. That is the scalar march's result unless
  // round-off made an interval empty (then the scalar march's own step decides), or k + i is
  // not exact in floats.
  if (!(m.a < m.end && m.dt > 0.f && m.k >= -8388608.f && m.k + float(kSampleBatch) <= 8388608.f))
    return placeSamplesScalar(org, dir, m, batch, lengths);
  const int first = std::max(batch.count, 0), limit = kSampleBatch - first;
  const hn::CappedTag<float, kSampleBatch> d;
  using V = hn::Vec<decltype(d)>;
  const size_t lanes = hn::Lanes(d);
  const V one = hn::Set(d, 1.f), half = hn::Set(d, 0.5f), rho = hn::Set(d, m.rho), dt = hn::Set(d, m.dt),
          end = hn::Set(d, m.end);
  const V ox = hn::Set(d, org.x), oy = hn::Set(d, org.y), oz = hn::Set(d, org.z);
  const V dx = hn::Set(d, dir.x), dy = hn::Set(d, dir.y), dz = hn::Set(d, dir.z);
  alignas(64) float ends[kSampleBatch];
  size_t n = 0;
  for (size_t base = 0; int(base) < limit; base += lanes) {
    const V k = hn::Add(hn::Iota(d, float(base)), hn::Set(d, m.k));
    const V b = hn::Min(hn::Mul(hn::Add(k, rho), dt), end);
    V a = hn::Min(hn::Mul(hn::Add(hn::Sub(k, one), rho), dt), end);
    if (base == 0) a = hn::IfThenElse(hn::FirstN(d, 1), hn::Set(d, m.a), a);
    const auto live = hn::And(hn::Lt(a, end), hn::FirstN(d, size_t(limit) - base));
    if (!hn::AllTrue(d, hn::Or(hn::Not(live), hn::Gt(b, a)))) return placeSamplesScalar(org, dir, m, batch, lengths);
    const V mid = hn::Mul(half, hn::Add(a, b));
    hn::StoreU(hn::Sub(b, a), d, lengths + first + base);
    hn::StoreU(hn::MulAdd(dx, mid, ox), d, batch.x + first + base);
    hn::StoreU(hn::MulAdd(dy, mid, oy), d, batch.y + first + base);
    hn::StoreU(hn::MulAdd(dz, mid, oz), d, batch.z + first + base);
    hn::StoreU(b, d, ends + base);
    const size_t count = hn::CountTrue(d, live);
    n += count;
    if (count < lanes) break;
  }
  if (n > 0) {
    m.a = ends[n - 1];
    m.k += float(n);
  }
  batch.count = first + int(n);
  return int(n);
}

bool TfLookupBatchImpl(const TfTableView& tf, const SampleBatch& batch, TfBatch& out) {
  const hn::CappedTag<float, kSampleBatch> d;
  const hn::RebindToSigned<decltype(d)> di;
  const hn::CappedTag<float, 4> d4; // one table entry: r, g, b, log2 transmittance
  using V = hn::Vec<decltype(d)>;
  const size_t lanes = hn::Lanes(d);
  const V zero = hn::Zero(d), one = hn::Set(d, 1.f);
  const float* entries = reinterpret_cast<const float*>(tf.entries);
  // Normalised values: linear ranges in the vector code, the others (logarithmic, degenerate)
  // through normalizeValue lane by lane.
  alignas(64) float normalized[kSampleBatch];
  if (!tf.fastLinear)
    for (int i = 0; i < batch.count; ++i)
      normalized[i] = normalizeValue(tf.range, tf.logScale, batch.value[i]);
  // tfTableAt: the entry below x and the one above, blended by x's fraction. Both entries are
  // one 32-byte load per sample, blended as four channels at once (cheaper than gathering each
  // channel), then sorted into channels.
  alignas(64) int32_t index[kSampleBatch];
  alignas(64) float fraction[kSampleBatch];
  alignas(64) float blended[4 * kSampleBatch];
  const size_t count = size_t(batch.count);
  for (size_t base = 0; base < count; base += lanes) {
    V n;
    if (tf.fastLinear)
      n = hn::Min(
          hn::Max(hn::Mul(hn::Sub(hn::LoadU(d, batch.value + base), hn::Set(d, tf.lower)), hn::Set(d, tf.scale)), zero),
          one);
    else
      n = hn::LoadU(d, normalized + base);
    const V x = hn::Mul(n, hn::Set(d, float(kTfTableSize - 1)));
    auto i = hn::ConvertTo(di, x);
    i = hn::Min(hn::Max(i, hn::Zero(di)), hn::Set(di, kTfTableSize - 2));
    hn::StoreU(hn::ShiftLeft<2>(i), di, index + base); // four floats per entry
    hn::StoreU(hn::Min(hn::Max(hn::Sub(x, hn::ConvertTo(d, i)), zero), one), d, fraction + base);
  }
  const size_t channelStep = hn::Lanes(d4); // 4, or 1 without vectors
  for (size_t j = 0; j < count; ++j) {
    const auto f = hn::Set(d4, fraction[j]);
    for (size_t c = 0; c < 4; c += channelStep) {
      const float* e = entries + index[j] + c;
      const auto a = hn::LoadU(d4, e);
      const auto b = hn::LoadU(d4, e + 4);
      hn::StoreU(hn::MulAdd(hn::Sub(b, a), f, a), d4, blended + 4 * j + c);
    }
  }
  auto anyShown = hn::Lt(one, zero); // all false
  for (size_t base = 0; base < count; base += lanes) {
    const auto live = hn::And(hn::FirstN(d, count - base),
                              hn::RebindMask(d, hn::Ne(hn::LoadU(di, batch.valid + base), hn::Zero(di))));
    V r, g, b, logT;
    hn::LoadInterleaved4(d, blended + 4 * base, r, g, b, logT);
    logT = hn::IfThenElseZero(live, logT);
    hn::StoreU(hn::IfThenElseZero(live, r), d, out.r + base);
    hn::StoreU(hn::IfThenElseZero(live, g), d, out.g + base);
    hn::StoreU(hn::IfThenElseZero(live, b), d, out.b + base);
    hn::StoreU(logT, d, out.logT + base);
    anyShown = hn::Or(anyShown, hn::And(live, hn::Lt(logT, zero)));
  }
  return !hn::AllFalse(d, anyShown);
}

// 1 / x and 1 / sqrt(x) from the instructions' estimates (12 or 14 bits) refined by one Newton
// step (about 22 bits): a shaded vector's divisions and square root made a chain of dependent
// latencies that its few other instructions could not hide. The estimates are used only where
// every lane of `live` is a normal float whose reciprocal is normal too (else the quotients), and
// only on the x86 targets, whose estimates are the instructions'.
#if HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX2 || HWY_TARGET == HWY_SSE4
template <class D> HWY_INLINE bool EstimatesHold(D d, hn::Vec<D> x, hn::Mask<D> live) {
  const hn::Vec<D> a = hn::Abs(x);
  const auto normal = hn::And(hn::Gt(a, hn::Set(d, 0x1p-125f)), hn::Lt(a, hn::Set(d, 0x1p125f)));
  return hn::AllTrue(d, hn::Or(normal, hn::Not(live)));
}
#else
template <class D> HWY_INLINE bool EstimatesHold(D, hn::Vec<D>, hn::Mask<D>) { return false; }
#endif

template <class D> HWY_INLINE hn::Vec<D> Reciprocal(D d, hn::Vec<D> x, hn::Mask<D> live) {
  if (!EstimatesHold(d, x, live)) return hn::Div(hn::Set(d, 1.f), x);
  const hn::Vec<D> r = hn::ApproximateReciprocal(x);
  return hn::Mul(r, hn::NegMulAdd(x, r, hn::Set(d, 2.f)));
}

// |g| and 1 / |g| (1 where g is zero) from the squared length `g2`.
template <class D>
HWY_INLINE void LengthAndInverse(D d, hn::Vec<D> g2, hn::Mask<D> live, hn::Vec<D>& length, hn::Vec<D>& inverse) {
  const hn::Vec<D> zero = hn::Zero(d), one = hn::Set(d, 1.f);
  const hn::Vec<D> x = hn::IfThenElse(hn::Gt(g2, zero), g2, one);
  if (EstimatesHold(d, x, live)) {
    const hn::Vec<D> r = hn::ApproximateReciprocalSqrt(x);
    inverse = hn::Mul(r, hn::NegMulAdd(hn::Mul(hn::Set(d, 0.5f), x), hn::Mul(r, r), hn::Set(d, 1.5f)));
    length = hn::Mul(g2, inverse);
  } else {
    length = hn::Sqrt(g2);
    inverse = hn::Div(one, hn::IfThenElse(hn::Gt(length, zero), length, one));
  }
}

void ShadeVolumeBatchImpl(const SampleBatch& batch, const TfBatch& tf, const float* lengths, const VolumeShadeParams& p,
                          ShadedBatch& out) {
  const hn::CappedTag<float, kSampleBatch> d;
  using V = hn::Vec<decltype(d)>;
  const size_t lanes = hn::Lanes(d);
  const V zero = hn::Zero(d), one = hn::Set(d, 1.f);
  const ShadingTerms& s = p.terms;
  for (size_t base = 0; base < size_t(batch.count); base += lanes) {
    const V logT = hn::LoadU(d, tf.logT + base);
    // correctedOpacity: 1 - 2^(logT length / reference), 2^x as exp2Negative computes it.
    const V e = hn::Mul(hn::Mul(logT, hn::LoadU(d, lengths + base)), hn::Set(d, p.invReferenceWidth));
    const V transmitted = Exp2Negative(d, e);
    hn::StoreU(hn::IfThenElseZero(hn::Lt(logT, zero), hn::Sub(one, transmitted)), d, out.alpha + base);
    V r = hn::LoadU(d, tf.r + base), g = hn::LoadU(d, tf.g + base), b = hn::LoadU(d, tf.b + base);
    if (p.shade) {
      // shadeVolumeSample, with its branches as selections.
      const auto live = hn::FirstN(d, size_t(batch.count) - base);
      const V gx = hn::Mul(hn::LoadU(d, batch.gx + base), hn::Set(d, p.gradientScale.x));
      const V gy = hn::Mul(hn::LoadU(d, batch.gy + base), hn::Set(d, p.gradientScale.y));
      const V gz = hn::Mul(hn::LoadU(d, batch.gz + base), hn::Set(d, p.gradientScale.z));
      V gl, inv;
      LengthAndInverse(d, hn::MulAdd(gz, gz, hn::MulAdd(gy, gy, hn::Mul(gx, gx))), live, gl, inv);
      V fade = hn::LoadU(d, p.fadeWidth + base);
      if (p.fadeByValue) {
        const V av = hn::Abs(hn::LoadU(d, batch.value + base));
        const auto nonzero = hn::Gt(av, zero);
        fade = hn::IfThenElseZero(nonzero, hn::Mul(fade, Reciprocal(d, hn::IfThenElse(nonzero, av, one), live)));
      }
      const V rel = hn::Mul(gl, fade);
      const V low = hn::Set(d, kShadingFadeLow), high = hn::Set(d, kShadingFadeHigh);
      const auto full = hn::Ge(rel, high);
      const V weight = hn::IfThenElse(
          full, one,
          hn::IfThenElseZero(hn::Gt(rel, low),
                             hn::Mul(hn::Sub(rel, low), hn::Set(d, 1.f / (kShadingFadeHigh - kShadingFadeLow)))));
      const auto lit = hn::And(hn::Gt(gl, hn::Set(d, 1e-20f)), hn::Gt(weight, zero));
      const V nx = hn::Mul(gx, inv), ny = hn::Mul(gy, inv), nz = hn::Mul(gz, inv);
      auto dotWith = [&](const vec3f& v) {
        return hn::MulAdd(nz, hn::Set(d, v.z), hn::MulAdd(ny, hn::Set(d, v.y), hn::Mul(nx, hn::Set(d, v.x))));
      };
      const V ambient = hn::Set(d, s.ambient), diffuse = hn::Set(d, s.diffuse);
      const V litShade = hn::MulAdd(diffuse, hn::Abs(dotWith(p.light)), ambient);
      const V nh = hn::Abs(dotWith(p.halfVector));
      const V exponent = hn::Set(d, s.shininess);
      const V highlight =
          hn::Mul(hn::Set(d, s.specular),
                  hn::Mul(nh, Reciprocal(d, hn::NegMulAdd(hn::Sub(exponent, one), nh, exponent), live)));
      const V flat = hn::Add(ambient, diffuse);
      const V shadeValue =
          hn::IfThenElse(lit, hn::IfThenElse(full, litShade, hn::MulAdd(hn::Sub(litShade, flat), weight, flat)), flat);
      const V spec = hn::IfThenElseZero(lit, hn::IfThenElse(full, highlight, hn::Mul(highlight, weight)));
      r = hn::MulAdd(r, shadeValue, spec);
      g = hn::MulAdd(g, shadeValue, spec);
      b = hn::MulAdd(b, shadeValue, spec);
    }
    hn::StoreU(r, d, out.r + base);
    hn::StoreU(g, d, out.g + base);
    hn::StoreU(b, d, out.b + base);
  }
}

} // namespace HWY_NAMESPACE
} // namespace exa
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "exabricks/core/simd_dispatch.h"

namespace exa {

HWY_EXPORT(PlaceSamplesImpl);
HWY_EXPORT(TfLookupBatchImpl);
HWY_EXPORT(ShadeVolumeBatchImpl);

int placeSamples(const vec3f& org, const vec3f& dir, SegmentMarch& m, SampleBatch& batch, float* lengths) {
  return HWY_DYNAMIC_DISPATCH(PlaceSamplesImpl)(org, dir, m, batch, lengths);
}

bool tfLookupBatch(const TfTableView& tf, const SampleBatch& batch, TfBatch& out) {
  return HWY_DYNAMIC_DISPATCH(TfLookupBatchImpl)(tf, batch, out);
}

void shadeVolumeBatch(const SampleBatch& batch, const TfBatch& tf, const float* lengths, const VolumeShadeParams& p,
                      ShadedBatch& out) {
  HWY_DYNAMIC_DISPATCH(ShadeVolumeBatchImpl)(batch, tf, lengths, p, out);
}

BatchFunctions batchFunctions() {
  return {chosenBatchFunction(HWY_DISPATCH_TABLE(PlaceSamplesImpl)), sampleBricksBatchFunction(),
          sampleShadedBatchFunction(), chosenBatchFunction(HWY_DISPATCH_TABLE(TfLookupBatchImpl)),
          chosenBatchFunction(HWY_DISPATCH_TABLE(ShadeVolumeBatchImpl))};
}

} // namespace exa
#endif

#endif
