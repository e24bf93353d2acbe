// Vectorised batches of basis reconstruction (see basis_batch.h). Highway compiles the code
// between HWY_BEFORE_NAMESPACE and HWY_AFTER_NAMESPACE once per target instruction set (this file
// includes itself through foreach_target.h) and dispatches at run time.
#include "exabricks/amr/basis_batch.h"

#ifndef EXABRICKS_HAVE_HWY

namespace exa {

void sampleRegionBatch(const FieldView& view, uint32_t regionIndex, SampleBatch& batch, bool gradient) {
  sampleRegionBatchScalar(view, regionIndex, batch, gradient);
}
const char* batchTargetName() { return "scalar"; }
std::vector<std::string> batchTargets() { return {"scalar"}; }
bool useBatchTarget(const std::string& name) { return name.empty() || name == "scalar"; }
} // namespace exa

#else

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "amr/basis_batch.cpp"
#include <hwy/foreach_target.h> // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace exa {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

void SampleBatchImpl(const FieldView& view, uint32_t regionIndex, SampleBatch& batch, bool gradient) {
  const hn::CappedTag<float, kSampleBatch> d;
  const hn::RebindToSigned<decltype(d)> di;
  using V = hn::Vec<decltype(d)>;
  using VI = hn::Vec<decltype(di)>;
  using M = hn::Mask<decltype(d)>;
  const Region& region = view.regions[regionIndex];
  const size_t lanes = hn::Lanes(d);
  const V one = hn::Set(d, 1.f), half = hn::Set(d, 0.5f), zero = hn::Zero(d);
  const VI ione = hn::Set(di, 1), iminus1 = hn::Set(di, -1);
  // Positions beyond count repeat the last one, so that whole vectors are loaded.
  for (int i = batch.count; i < kSampleBatch; ++i) {
    const int last = batch.count > 0 ? batch.count - 1 : 0;
    batch.x[i] = batch.x[last], batch.y[i] = batch.y[last], batch.z[i] = batch.z[last];
  }
  for (size_t base = 0; base < size_t(batch.count); base += lanes) {
    const V p[3] = {hn::LoadU(d, batch.x + base), hn::LoadU(d, batch.y + base), hn::LoadU(d, batch.z + base)};
    V sumW = zero, sumWV = zero, v0 = zero;
    V dW[3] = {zero, zero, zero}, dWV[3] = {zero, zero, zero};
    M haveRef = one < zero; // all false
    for (uint32_t k = 0; k < region.brickCount; ++k) {
      const Brick& brick = view.bricks[view.brickIds[region.brickBegin + k]];
      const float invWs = inverseWidth(brick.level);
      const V invW = hn::Set(d, invWs);
      VI i0[3];
      V h0[3], h1[3];
      M valid0[3], valid1[3];
      for (int a = 0; a < 3; ++a) {
        // As basis.h: position in cell-centre units, the lower of the two nearest centres and
        // the hat factors of both.
        const V q = hn::Sub(hn::Mul(hn::Sub(p[a], hn::Set(d, float(brick.lower[a]))), invW), half);
        const V fl = hn::Floor(q);
        i0[a] = hn::ConvertTo(di, fl);
        const V f = hn::Sub(q, fl);
        h0[a] = hn::Sub(one, f);
        h1[a] = f;
        const VI size = hn::Set(di, brick.size[a]);
        const VI i1 = hn::Add(i0[a], ione);
        valid0[a] = hn::RebindMask(d, hn::And(i0[a] > iminus1, i0[a] < size));
        valid1[a] = hn::RebindMask(d, hn::And(i1 > iminus1, i1 < size));
      }
      const float* values = view.values + brick.valueOffset;
      const VI sx = hn::Set(di, brick.size.x), sy = hn::Set(di, brick.size.y);
      auto index = [&](const VI& x, const VI& y, const VI& z) { return hn::Add(x, hn::Mul(sx, hn::Add(y, hn::Mul(sy, z)))); };
      // The reference value: the first brick that has cells on every axis gives its first cell.
      const M any = hn::And(hn::Or(valid0[0], valid1[0]), hn::And(hn::Or(valid0[1], valid1[1]), hn::Or(valid0[2], valid1[2])));
      if (hn::AllFalse(d, any)) continue;
      const M newRef = hn::AndNot(haveRef, any);
      if (!hn::AllFalse(d, newRef)) {
        VI first[3];
        for (int a = 0; a < 3; ++a)
          first[a] = hn::IfThenElse(hn::RebindMask(di, valid0[a]), i0[a], hn::Add(i0[a], ione));
        const VI at = hn::IfThenElseZero(hn::RebindMask(di, newRef), index(first[0], first[1], first[2]));
        v0 = hn::IfThenElse(newRef, hn::GatherIndex(d, values, at), v0);
        haveRef = hn::Or(haveRef, newRef);
      }
      const V dh0 = hn::Neg(invW), dh1 = invW;
      for (int cz = 0; cz < 2; ++cz) {
        const M mz = cz ? valid1[2] : valid0[2];
        const V hz = cz ? h1[2] : h0[2], dhz = cz ? dh1 : dh0;
        const VI iz = cz ? hn::Add(i0[2], ione) : i0[2];
        for (int cy = 0; cy < 2; ++cy) {
          const M myz = hn::And(mz, cy ? valid1[1] : valid0[1]);
          if (hn::AllFalse(d, myz)) continue;
          const V hy = cy ? h1[1] : h0[1], dhy = cy ? dh1 : dh0;
          const VI iy = cy ? hn::Add(i0[1], ione) : i0[1];
          const V hyz = hn::Mul(hy, hz);
          for (int cx = 0; cx < 2; ++cx) {
            const M m = hn::And(myz, cx ? valid1[0] : valid0[0]);
            if (hn::AllFalse(d, m)) continue;
            const V hx = cx ? h1[0] : h0[0], dhx = cx ? dh1 : dh0;
            const VI ix = cx ? hn::Add(i0[0], ione) : i0[0];
            const VI at = hn::IfThenElseZero(hn::RebindMask(di, m), index(ix, iy, iz));
            const V v = hn::Sub(hn::GatherIndex(d, values, at), v0);
            const V weight = hn::IfThenElseZero(m, hn::Mul(hx, hyz));
            sumW = hn::Add(sumW, weight);
            sumWV = hn::Add(sumWV, hn::Mul(weight, v));
            if (gradient) {
              const V g[3] = {hn::IfThenElseZero(m, hn::Mul(dhx, hyz)), hn::IfThenElseZero(m, hn::Mul(hn::Mul(hx, dhy), hz)),
                              hn::IfThenElseZero(m, hn::Mul(hn::Mul(hx, hy), dhz))};
              for (int a = 0; a < 3; ++a) {
                dW[a] = hn::Add(dW[a], g[a]);
                dWV[a] = hn::Add(dWV[a], hn::Mul(g[a], v));
              }
            }
          }
        }
      }
    }
    const M ok = sumW > zero;
    const V safeW = hn::IfThenElse(ok, sumW, one);
    hn::StoreU(hn::IfThenElseZero(ok, hn::Add(v0, hn::Div(sumWV, safeW))), d, batch.value + base);
    hn::StoreU(hn::VecFromMask(di, hn::RebindMask(di, ok)), di, batch.valid + base);
    if (gradient) {
      const V w2 = hn::Mul(safeW, safeW);
      float* out[3] = {batch.gx + base, batch.gy + base, batch.gz + base};
      for (int a = 0; a < 3; ++a)
        hn::StoreU(hn::IfThenElseZero(ok, hn::Div(hn::Sub(hn::Mul(dWV[a], safeW), hn::Mul(dW[a], sumWV)), w2)), d, out[a]);
    }
  }
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

} // namespace HWY_NAMESPACE
} // namespace exa
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace exa {

HWY_EXPORT(SampleBatchImpl);
HWY_EXPORT(TargetName);

void sampleRegionBatch(const FieldView& view, uint32_t regionIndex, SampleBatch& batch, bool gradient) {
  HWY_DYNAMIC_DISPATCH(SampleBatchImpl)(view, regionIndex, batch, gradient);
}

const char* batchTargetName() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

std::vector<std::string> batchTargets() {
  static const std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets(); // before any mock
  std::vector<std::string> names;
  for (int64_t t : targets) names.push_back(hwy::TargetName(t));
  return names;
}

bool useBatchTarget(const std::string& name) {
  static const std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets();
  int64_t chosen = 0;
  for (int64_t t : targets)
    if (name == hwy::TargetName(t)) chosen = t;
  if (!name.empty() && chosen == 0) return false;
  hwy::SetSupportedTargetsForTest(chosen); // 0: every target the CPU has
  hwy::GetChosenTarget().Update(hwy::SupportedTargets());
  return true;
}
} // namespace exa
#endif

#endif
