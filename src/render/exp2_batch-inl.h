// The vector form of exp2Negative (sample_math.h), lane by lane the same operations: 2^x for
// x <= 0 as the Taylor polynomial of 2^f on the fraction times 2^i built in the exponent bits,
// zero below -126. Included inside a Highway target's namespace by the files that compile once
// per instruction set (shade_batch.cpp, denoise_batch.cpp).
#if defined(EXABRICKS_RENDER_EXP2_BATCH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef EXABRICKS_RENDER_EXP2_BATCH_INL_H_
#undef EXABRICKS_RENDER_EXP2_BATCH_INL_H_
#else
#define EXABRICKS_RENDER_EXP2_BATCH_INL_H_
#endif

#include "exabricks/render/sample_math.h"

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace exa {
namespace HWY_NAMESPACE {

template <class D> HWY_INLINE hwy::HWY_NAMESPACE::Vec<D> Exp2Negative(D d, hwy::HWY_NAMESPACE::Vec<D> x) {
  namespace hn = hwy::HWY_NAMESPACE;
  const hn::RebindToSigned<D> di;
  using V = hn::Vec<D>;
  const V lowest = hn::Set(d, -126.f);
  const V i = hn::Round(x);
  const V f = hn::Sub(x, i);
  V p = hn::Set(d, kExp2Taylor6);
  p = hn::MulAdd(p, f, hn::Set(d, kExp2Taylor5));
  p = hn::MulAdd(p, f, hn::Set(d, kExp2Taylor4));
  p = hn::MulAdd(p, f, hn::Set(d, kExp2Taylor3));
  p = hn::MulAdd(p, f, hn::Set(d, kExp2Taylor2));
  p = hn::MulAdd(p, f, hn::Set(d, kExp2Taylor1));
  p = hn::MulAdd(p, f, hn::Set(d, 1.f));
  const auto exponent = hn::ConvertTo(di, hn::Max(i, lowest));
  const V scale = hn::BitCast(d, hn::ShiftLeft<23>(hn::Add(exponent, hn::Set(di, 127))));
  return hn::IfThenZeroElse(hn::Lt(x, lowest), hn::Mul(p, scale));
}

} // namespace HWY_NAMESPACE
} // namespace exa
HWY_AFTER_NAMESPACE();

#endif
