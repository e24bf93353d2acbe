// The denoiser's levels vectorised across rows (see denoise_batch.h). Highway compiles the code
// between HWY_BEFORE_NAMESPACE and HWY_AFTER_NAMESPACE once per target instruction set (this file
// includes itself through foreach_target.h) and dispatches at run time.
#include "denoise_batch.h"

#include <cstddef>

#ifndef EXABRICKS_HAVE_HWY

namespace exa {
DenoiseRowFunction denoiseRowFunction() { return nullptr; }
DenoiseVarianceRowFunction denoiseVarianceRowFunction() { return nullptr; }
} // namespace exa

#else

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "denoise_batch.cpp"
#include <hwy/foreach_target.h> // IWYU pragma: keep
#include <hwy/highway.h>

#include "exp2_batch-inl.h"

HWY_BEFORE_NAMESPACE();
namespace exa {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// Lanes whose tap, dx pixels along the row from the lanes' own `columns`, lies in the row: the
/// others read a neighbouring row (or the planes' room before and after).
template <class D, class VI> HWY_INLINE hn::Mask<D> TapInRow(D d, VI columns, int dx, int width) {
  const hn::RebindToSigned<D> di;
  const VI qx = hn::Add(columns, hn::Set(di, dx));
  return hn::RebindMask(d, hn::And(hn::Not(hn::Lt(qx, hn::Zero(di))), hn::Lt(qx, hn::Set(di, width))));
}

/// Stores the lanes of pixels x .. x1 - 1 at `to` (the pixel of x), not those past the row's end.
template <class D> HWY_INLINE void StoreRow(D d, hn::Vec<D> v, float* to, int x, int x1) {
  if (x + int(hn::Lanes(d)) <= x1)
    hn::StoreU(v, d, to);
  else
    hn::BlendedStore(v, hn::FirstN(d, size_t(x1 - x)), d, to);
}

void DenoiseRowImpl(const DenoiseImages& im, const DenoiseRowInputs& inputs, const DenoisePlanes& in, int step, int y,
                    int x0, int x1, const DenoisePlanes& out) {
  const hn::ScalableTag<float> d;
  const hn::RebindToSigned<decltype(d)> di;
  using V = hn::Vec<decltype(d)>;
  const int lanes = int(hn::Lanes(d));
  const V zero = hn::Zero(d), one = hn::Set(d, 1.f);
  const V guideScale = hn::Set(d, im.guideScale), colorSigma = hn::Set(d, im.colorSigma);
  const V errorFloor = hn::Set(d, kDenoiseErrorFloor), log2e = hn::Set(d, -kDenoiseLog2E);
  const size_t row = size_t(y) * size_t(im.width);
  for (int x = x0; x < x1; x += lanes) {
    const size_t p = row + size_t(x);
    const auto pixelValid = hn::Gt(hn::LoadU(d, inputs.valid + p), zero);
    const V lp = hn::LoadU(d, inputs.shown + p);
    // denoiseColorScale
    const V colorScale = hn::Div(one, hn::MulAdd(colorSigma, hn::Sqrt(hn::LoadU(d, inputs.variance + p)), errorFloor));
    V fp[kDenoiseFeatures];
    for (int k = 0; k < kDenoiseFeatures; ++k)
      fp[k] = hn::LoadU(d, inputs.features[k] + p);
    V color[4] = {zero, zero, zero, zero}, probe[3] = {zero, zero, zero};
    V weights = zero, lumProbe = zero;
    const auto columns = hn::Add(hn::Iota(di, 0), hn::Set(di, x));
    for (int j = 0; j < 5; ++j) {
      const int qy = y + (j - 2) * step;
      if (qy < 0 || qy >= im.height) continue;
      for (int i = 0; i < 5; ++i) {
        const int dx = (i - 2) * step;
        const ptrdiff_t q = ptrdiff_t(qy) * im.width + x + dx; // may point into the room before
        const auto tap = hn::And(TapInRow(d, columns, dx, im.width), hn::Gt(hn::LoadU(d, inputs.valid + q), zero));
        V distance = zero;
        for (int k = 0; k < kDenoiseFeatures; ++k) {
          const V diff = hn::Sub(fp[k], hn::LoadU(d, inputs.features[k] + q));
          distance = hn::MulAdd(diff, diff, distance);
        }
        // denoiseTapWeight
        const V colorTerm = hn::Mul(hn::Abs(hn::Sub(lp, hn::LoadU(d, inputs.shown + q))), colorScale);
        const V exponent = hn::Mul(hn::MulAdd(distance, guideScale, colorTerm), log2e);
        const V w =
            hn::IfThenElseZero(tap, hn::Mul(hn::Set(d, denoiseB3(i) * denoiseB3(j)), Exp2Negative(d, exponent)));
        for (int c = 0; c < 4; ++c)
          color[c] = hn::MulAdd(hn::LoadU(d, in.color[c] + q), w, color[c]);
        for (int c = 0; c < 3; ++c)
          probe[c] = hn::MulAdd(hn::LoadU(d, in.probe[c] + q), w, probe[c]);
        lumProbe = hn::MulAdd(w, hn::LoadU(d, in.lumProbe + q), lumProbe);
        weights = hn::Add(weights, w);
      }
    }
    // The pixel itself weighs (3/8)² > 0 where it is valid; the others keep their input.
    const V inv = hn::Div(one, hn::IfThenElse(pixelValid, weights, one));
    const auto store = [&](V filtered, const float* from, float* to) {
      StoreRow(d, hn::IfThenElse(pixelValid, hn::Mul(filtered, inv), hn::LoadU(d, from + p)), to + p, x, x1);
    };
    for (int c = 0; c < 4; ++c)
      store(color[c], in.color[c], out.color[c]);
    for (int c = 0; c < 3; ++c)
      store(probe[c], in.probe[c], out.probe[c]);
    store(lumProbe, in.lumProbe, out.lumProbe);
  }
}

void DenoiseVarianceRowImpl(const DenoiseImages& im, const DenoiseRowInputs& inputs, const float* values, bool first,
                            int y, int x0, int x1, float* variance) {
  const hn::ScalableTag<float> d;
  const hn::RebindToSigned<decltype(d)> di;
  using V = hn::Vec<decltype(d)>;
  const int lanes = int(hn::Lanes(d));
  const V zero = hn::Zero(d);
  const int r = first ? 1 : 2;
  const size_t row = size_t(y) * size_t(im.width);
  for (int x = x0; x < x1; x += lanes) {
    const size_t p = row + size_t(x);
    const auto columns = hn::Add(hn::Iota(di, 0), hn::Set(di, x));
    V sum = zero, weights = zero;
    for (int dy = -r; dy <= r; ++dy) {
      const int qy = y + dy;
      if (qy < 0 || qy >= im.height) continue;
      for (int dx = -r; dx <= r; ++dx) {
        const ptrdiff_t q = ptrdiff_t(qy) * im.width + x + dx; // may point into the room before
        const auto tap = hn::And(TapInRow(d, columns, dx, im.width), hn::Gt(hn::LoadU(d, inputs.usable + q), zero));
        const V v = hn::LoadU(d, values + q);
        const V w = hn::IfThenElseZero(tap, hn::Set(d, denoiseVarianceWeight(first, dx, dy)));
        sum = hn::MulAdd(w, first ? v : hn::Mul(v, v), sum);
        weights = hn::Add(weights, w);
      }
    }
    const auto some = hn::Gt(weights, zero);
    V v = hn::IfThenElseZero(some, hn::Div(sum, hn::IfThenElse(some, weights, hn::Set(d, 1.f))));
    v = hn::IfThenElse(hn::Gt(hn::LoadU(d, inputs.unknown + p), zero), hn::Set(d, kDenoiseUnknownVariance), v);
    StoreRow(d, v, variance + p, x, x1);
  }
}

} // namespace HWY_NAMESPACE
} // namespace exa
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "exabricks/core/simd_dispatch.h"

namespace exa {

HWY_EXPORT(DenoiseRowImpl);
HWY_EXPORT(DenoiseVarianceRowImpl);

DenoiseRowFunction denoiseRowFunction() { return chosenBatchFunction(HWY_DISPATCH_TABLE(DenoiseRowImpl)); }

DenoiseVarianceRowFunction denoiseVarianceRowFunction() {
  return chosenBatchFunction(HWY_DISPATCH_TABLE(DenoiseVarianceRowImpl));
}

} // namespace exa
#endif

#endif
