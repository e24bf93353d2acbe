// Vectorised batches of basis reconstruction (see basis_batch.h). Highway compiles the code
// between HWY_BEFORE_NAMESPACE and HWY_AFTER_NAMESPACE once per target instruction set (this file
// includes itself through foreach_target.h) and dispatches at run time.
#include "exabricks/amr/basis_batch.h"

#include <algorithm>

#ifndef EXABRICKS_HAVE_HWY

namespace exa {

void sampleRegionBatch(const FieldView& view, uint32_t regionIndex, SampleBatch& batch, bool gradient) {
  sampleRegionBatchScalar(view, regionIndex, batch, gradient);
}
void sampleBricksBatch(const FieldView& view, const uint32_t* brickIds, uint32_t brickCount, SampleBatch& batch,
                       bool gradient) {
  sampleBricksBatchScalar(view, brickIds, brickCount, batch, gradient);
}
SampleRegionBatchFunction sampleRegionBatchFunction() { return &sampleRegionBatch; }
SampleBricksBatchFunction sampleBricksBatchFunction() { return &sampleBricksBatch; }
void sampleShadedBatch(const FieldView& view, const PackedGradientView& gradients, bool withValue,
                       const uint32_t* brickIds, uint32_t brickCount, const SampleBatch& batch, float* const* out,
                       int32_t* valid) {
  sampleShadedBatchScalar(view, gradients, withValue, brickIds, brickCount, batch, out, valid);
}
SampleShadedBatchFunction sampleShadedBatchFunction() { return &sampleShadedBatch; }
const char* batchTargetName() { return "scalar"; }
std::vector<std::string> batchTargets() { return {"scalar"}; }
bool useBatchTarget(const std::string& name) { return name.empty() || name == "scalar"; }
} // namespace exa

#else

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "basis_batch.cpp"
#include <hwy/foreach_target.h> // IWYU pragma: keep
#include <hwy/highway.h>

#include "row_loads-inl.h" // per target, like this file

HWY_BEFORE_NAMESPACE();
namespace exa {
namespace HWY_NAMESPACE {
static_assert(kMaxBrickWidth < (1 << 23), "brick indices convert exactly through floats");
namespace hn = hwy::HWY_NAMESPACE;

// One brick's hat factors per axis, as basis.h: position in cell-centre units, the lower of the two
// nearest centres, and the hat factors and derivatives of both, zero where that cell lies outside
// the brick. A corner's weight is the product of its three factors, so a missing cell weighs
// nothing; its index is clamped into the brick so that every load stays inside.
template <class D> struct BrickHats {
  using V = hn::Vec<D>;
  using VI = hn::Vec<hn::RebindToSigned<D>>;
  using M = hn::Mask<D>;
  V q[3], fl[3];
  M any; // the lane lies in the brick's support on every axis
  VI lo[3];
  M both[3]; // both cells present: the upper one is one stride on
  V h0[3], h1[3], dh0[3], dh1[3];
};

// First only whether any lane lies in the brick's support (most listed bricks of a merged region
// reach none of a batch's samples). The tests stay in floats (the floor is an exact small integer).
template <class D>
HWY_INLINE bool BrickSupport(D d, const Brick& brick, const hn::Vec<D> (&p)[3], hn::Vec<D> invW, BrickHats<D>& h) {
  const hn::Vec<D> one = hn::Set(d, 1.f), half = hn::Set(d, 0.5f), zero = hn::Zero(d), minusOne = hn::Set(d, -1.f);
  h.any = hn::Not(hn::Lt(one, zero)); // all true
  for (int a = 0; a < 3; ++a) {
    h.q[a] = hn::Sub(hn::Mul(hn::Sub(p[a], hn::Set(d, float(brick.lower[a]))), invW), half);
    h.fl[a] = hn::Floor(h.q[a]);
    h.any = hn::And(h.any, hn::And(hn::Ge(h.fl[a], minusOne), hn::Lt(h.fl[a], hn::Set(d, float(brick.size[a])))));
  }
  return !hn::AllFalse(d, h.any);
}

// Then the rest, for a brick some lane reaches. The clamping stays in floats; only the clamped
// index is converted.
template <class D> HWY_INLINE void BrickFactors(D d, const Brick& brick, hn::Vec<D> invW, BrickHats<D>& h) {
  using V = hn::Vec<D>;
  using M = hn::Mask<D>;
  const hn::RebindToSigned<D> di;
  const V one = hn::Set(d, 1.f), zero = hn::Zero(d), minusOne = hn::Set(d, -1.f);
  const V magic = hn::Set(d, 8388608.f); // 2^23
  for (int a = 0; a < 3; ++a) {
    const V f = hn::Sub(h.q[a], h.fl[a]);
    const V size = hn::Set(d, float(brick.size[a])), last = hn::Set(d, float(brick.size[a] - 1));
    const M valid0 = hn::And(hn::Ge(h.fl[a], zero), hn::Lt(h.fl[a], size));
    const M valid1 = hn::And(hn::Ge(h.fl[a], minusOne), hn::Lt(h.fl[a], last));
    h.both[a] = hn::And(valid0, valid1);
    h.h0[a] = hn::IfThenElseZero(valid0, hn::Sub(one, f));
    h.h1[a] = hn::IfThenElseZero(valid1, f);
    h.dh0[a] = hn::IfThenElseZero(valid0, hn::Neg(invW));
    h.dh1[a] = hn::IfThenElseZero(valid1, invW);
    // The clamped index as an integer: below kMaxBrickWidth < 2^23, i + 2^23 holds i in
    // its mantissa bits.
    const V clamped = hn::Min(hn::Max(h.fl[a], zero), last);
    h.lo[a] = hn::Sub(hn::BitCast(di, hn::Add(clamped, magic)), hn::BitCast(di, magic));
  }
}

// Where a brick's eight corners lie for every lane: two neighbours along x per (y, z) row, the
// first at `at`, the rows `offset[1]` and `offset[2]` on (zero where the upper cell is missing).
// `above` is set where the pair's second cell is the lane's lower existing one. With pair loads the
// x hat factors move with the cells (once per brick, however many arrays are then fetched).
template <class D> struct CornerIndex {
  using VI = hn::Vec<hn::RebindToSigned<D>>;
  VI at, offset[3];
  hn::Mask<D> above;
  hn::Mask<D> live; // lanes in the brick's support: only theirs are loaded where loads can be masked
  bool pairs = false;
};

template <class D> HWY_INLINE void IndexCorners(D d, const Brick& brick, BrickHats<D>& h, CornerIndex<D>& ci) {
  using VI = hn::Vec<hn::RebindToSigned<D>>;
  const hn::RebindToSigned<D> di;
  const VI ione = hn::Set(di, 1);
  const VI sx = hn::Set(di, brick.size.x), sxy = hn::Set(di, brick.size.x * brick.size.y);
  ci.offset[0] = hn::IfThenElseZero(hn::RebindMask(di, h.both[0]), ione);
  ci.offset[1] = hn::IfThenElseZero(hn::RebindMask(di, h.both[1]), sx);
  ci.offset[2] = hn::IfThenElseZero(hn::RebindMask(di, h.both[2]), sxy);
  // Each lane's first corner: its lower x cell plus the start of its (y, z) row.
  const VI rowStart = hn::Add(hn::Mul(sx, h.lo[1]), hn::Mul(sxy, h.lo[2]));
  ci.at = hn::Add(h.lo[0], rowStart);
  ci.above = hn::Lt(hn::Set(d, 1.f), hn::Zero(d));
  ci.live = h.any;
#if EXA_PAIR_LOADS
  ci.pairs = brick.size.x >= 2;
  if (ci.pairs) {
    using V = hn::Vec<D>;
    // Pairs along x start at cell b = clamp(floor, 0, size - 2), so that both lie in the
    // brick. Where the floor is -1 (left of the first centre) b is its upper cell; where it
    // is size - 1 (right of the last) b + 1 is its lower one. The hat factors move with the
    // cells; the missing cell's factor is zero either way, so the sums are the same.
    const V magic = hn::Set(d, 8388608.f); // 2^23
    const V b = hn::Min(hn::Max(h.fl[0], hn::Zero(d)), hn::Set(d, float(brick.size.x - 2)));
    const hn::Mask<D> same = hn::Eq(b, h.fl[0]), below = hn::Lt(h.fl[0], b);
    ci.above = hn::Gt(h.fl[0], b);
    const V g0 = hn::IfThenElse(same, h.h0[0], hn::IfThenElseZero(below, h.h1[0]));
    const V g1 = hn::IfThenElse(same, h.h1[0], hn::IfThenElseZero(ci.above, h.h0[0]));
    const V dg0 = hn::IfThenElse(same, h.dh0[0], hn::IfThenElseZero(below, h.dh1[0]));
    const V dg1 = hn::IfThenElse(same, h.dh1[0], hn::IfThenElseZero(ci.above, h.dh0[0]));
    h.h0[0] = g0, h.h1[0] = g1, h.dh0[0] = dg0, h.dh1[0] = dg1;
    ci.at = hn::Add(hn::Sub(hn::BitCast(di, hn::Add(b, magic)), hn::BitCast(di, magic)), rowStart);
  }
#endif
}

// The values of the eight corners from `values` (the brick's first value): c0[z][y] the lower x
// cell of each row, c1[z][y] the upper.
template <class D>
HWY_INLINE void FetchCorners(D d, const float* values, const CornerIndex<D>& ci, hn::Vec<D> (&c0)[2][2],
                             hn::Vec<D> (&c1)[2][2]) {
  using V = hn::Vec<D>;
  using VI = hn::Vec<hn::RebindToSigned<D>>;
  const auto fetchRow = [&](const VI& row, V& r0, V& r1) {
#if EXA_PAIR_LOADS
    if (ci.pairs) return loadPairs(d, values, row, r0, r1, ci.live);
#endif
    r0 = hn::GatherIndex(d, values, row);
    r1 = hn::GatherIndex(d, values, hn::Add(row, ci.offset[0]));
  };
  fetchRow(ci.at, c0[0][0], c1[0][0]);
  fetchRow(hn::Add(ci.at, ci.offset[1]), c0[0][1], c1[0][1]);
  fetchRow(hn::Add(ci.at, ci.offset[2]), c0[1][0], c1[1][0]);
  fetchRow(hn::Add(hn::Add(ci.at, ci.offset[1]), ci.offset[2]), c0[1][1], c1[1][1]);
}

// The values (c0, c1, as FetchCorners') and packed gradients' bits (b0, b1) of the eight corners
// from `pairs`, the brick's first cell's two words (gradients.h).
template <class D>
HWY_INLINE void FetchCornersWithGradients(D d, const float* pairs, const CornerIndex<D>& ci, hn::Vec<D> (&c0)[2][2],
                                          hn::Vec<D> (&c1)[2][2], hn::Vec<D> (&b0)[2][2], hn::Vec<D> (&b1)[2][2]) {
  using V = hn::Vec<D>;
  using VI = hn::Vec<hn::RebindToSigned<D>>;
  const auto fetchRow = [&](const VI& row, V& v0, V& g0, V& v1, V& g1) {
#if EXA_PAIR_LOADS
    if (ci.pairs) return loadQuads(d, pairs, row, v0, g0, v1, g1);
#endif
    const VI at = hn::Add(row, row), next = hn::Add(at, hn::Add(ci.offset[0], ci.offset[0]));
    v0 = hn::GatherIndex(d, pairs, at);
    g0 = hn::GatherIndex(d, pairs + 1, at);
    v1 = hn::GatherIndex(d, pairs, next);
    g1 = hn::GatherIndex(d, pairs + 1, next);
  };
  const VI y = ci.offset[1], z = ci.offset[2];
  fetchRow(ci.at, c0[0][0], b0[0][0], c1[0][0], b1[0][0]);
  fetchRow(hn::Add(ci.at, y), c0[0][1], b0[0][1], c1[0][1], b1[0][1]);
  fetchRow(hn::Add(ci.at, z), c0[1][0], b0[1][0], c1[1][0], b1[1][0]);
  fetchRow(hn::Add(hn::Add(ci.at, y), z), c0[1][1], b0[1][1], c1[1][1], b1[1][1]);
}

// A batch's running sums over its bricks, and the reference value they are relative to.
template <class D> struct BatchSums {
  using V = hn::Vec<D>;
  V sumW, sumWV, v0;
  V dW[3], dWV[3];
  hn::Mask<D> haveRef;
};

// The eight corners summed axis by axis: along x per (y, z) row, then y, then z. The same sums as
// basis.h's cell-by-cell loop, factored.
template <bool gradient, class D>
HWY_INLINE void AddCorners(const BrickHats<D>& h, const hn::Vec<D> (&c0)[2][2], const hn::Vec<D> (&c1)[2][2],
                           BatchSums<D>& s) {
  using V = hn::Vec<D>;
  V ex[2][2], gxx[2][2];
  for (int cz = 0; cz < 2; ++cz)
    for (int cy = 0; cy < 2; ++cy) {
      const V a0 = hn::Sub(c0[cz][cy], s.v0), a1 = hn::Sub(c1[cz][cy], s.v0);
      ex[cz][cy] = hn::MulAdd(h.h1[0], a1, hn::Mul(h.h0[0], a0));
      if constexpr (gradient) gxx[cz][cy] = hn::MulAdd(h.dh1[0], a1, hn::Mul(h.dh0[0], a0));
    }
  const V wx = hn::Add(h.h0[0], h.h1[0]), wy = hn::Add(h.h0[1], h.h1[1]), wz = hn::Add(h.h0[2], h.h1[2]);
  V eyz[2], gxyz[2], gyyz[2];
  for (int cz = 0; cz < 2; ++cz) {
    eyz[cz] = hn::MulAdd(h.h1[1], ex[cz][1], hn::Mul(h.h0[1], ex[cz][0]));
    if constexpr (gradient) {
      gxyz[cz] = hn::MulAdd(h.h1[1], gxx[cz][1], hn::Mul(h.h0[1], gxx[cz][0]));
      gyyz[cz] = hn::MulAdd(h.dh1[1], ex[cz][1], hn::Mul(h.dh0[1], ex[cz][0]));
    }
  }
  s.sumW = hn::MulAdd(wx, hn::Mul(wy, wz), s.sumW);
  s.sumWV = hn::Add(s.sumWV, hn::MulAdd(h.h1[2], eyz[1], hn::Mul(h.h0[2], eyz[0])));
  if constexpr (gradient) {
    s.dW[0] = hn::MulAdd(hn::Add(h.dh0[0], h.dh1[0]), hn::Mul(wy, wz), s.dW[0]);
    s.dW[1] = hn::MulAdd(hn::Add(h.dh0[1], h.dh1[1]), hn::Mul(wx, wz), s.dW[1]);
    s.dW[2] = hn::MulAdd(hn::Add(h.dh0[2], h.dh1[2]), hn::Mul(wx, wy), s.dW[2]);
    s.dWV[0] = hn::Add(s.dWV[0], hn::MulAdd(h.h1[2], gxyz[1], hn::Mul(h.h0[2], gxyz[0])));
    s.dWV[1] = hn::Add(s.dWV[1], hn::MulAdd(h.h1[2], gyyz[1], hn::Mul(h.h0[2], gyyz[0])));
    s.dWV[2] = hn::Add(s.dWV[2], hn::MulAdd(h.dh1[2], eyz[1], hn::Mul(h.dh0[2], eyz[0])));
  }
}

// The value (and gradient) of the samples from `base` on: the quotients of the sums, zero where
// no cell has weight.
template <bool gradient, class D>
HWY_INLINE void StoreSums(D d, const BatchSums<D>& s, SampleBatch& batch, size_t base) {
  using V = hn::Vec<D>;
  const hn::RebindToSigned<D> di;
  const V one = hn::Set(d, 1.f), zero = hn::Zero(d);
  const hn::Mask<D> ok = s.sumW > zero;
  const V safeW = hn::IfThenElse(ok, s.sumW, one);
  hn::StoreU(hn::IfThenElseZero(ok, hn::Add(s.v0, hn::Div(s.sumWV, safeW))), d, batch.value + base);
  hn::StoreU(hn::VecFromMask(di, hn::RebindMask(di, ok)), di, batch.valid + base);
  if constexpr (gradient) {
    const V w2 = hn::Mul(safeW, safeW);
    float* out[3] = {batch.gx + base, batch.gy + base, batch.gz + base};
    for (int a = 0; a < 3; ++a)
      hn::StoreU(hn::IfThenElseZero(ok, hn::Div(hn::Sub(hn::Mul(s.dWV[a], safeW), hn::Mul(s.dW[a], s.sumWV)), w2)), d,
                 out[a]);
  }
}

// Compiled once with and once without gradients: their six accumulators would otherwise stay live
// (and spill) in the values-only batches too.
template <bool gradient, size_t kLanes>
void SampleBatchFor(const FieldView& view, const uint32_t* brickIds, uint32_t brickCount, SampleBatch& batch) {
  using D = hn::CappedTag<float, kLanes>;
  const D d;
  using V = hn::Vec<D>;
  const size_t lanes = hn::Lanes(d);
  const V one = hn::Set(d, 1.f), zero = hn::Zero(d);
  // Positions beyond count, up to the end of the last vector, repeat the last one, so that whole
  // vectors are loaded.
  const int padded = int((size_t(batch.count) + lanes - 1) / lanes * lanes);
  for (int i = batch.count; i < padded; ++i) {
    const int last = batch.count > 0 ? batch.count - 1 : 0;
    batch.x[i] = batch.x[last], batch.y[i] = batch.y[last], batch.z[i] = batch.z[last];
  }
  for (size_t base = 0; base < size_t(batch.count); base += lanes) {
    const V p[3] = {hn::LoadU(d, batch.x + base), hn::LoadU(d, batch.y + base), hn::LoadU(d, batch.z + base)};
    BatchSums<D> s;
    s.sumW = zero, s.sumWV = zero, s.v0 = zero;
    for (int a = 0; a < 3; ++a)
      s.dW[a] = zero, s.dWV[a] = zero;
    s.haveRef = one < zero; // all false
    for (uint32_t k = 0; k < brickCount; ++k) {
      const Brick& brick = view.bricks[brickIds[k]];
      const V invW = hn::Set(d, inverseWidth(brick.level));
      BrickHats<D> h;
      if (!BrickSupport(d, brick, p, invW, h)) continue; // no lane lies in this brick's support
      BrickFactors(d, brick, invW, h);
      CornerIndex<D> ci;
      IndexCorners(d, brick, h, ci);
      V c0[2][2], c1[2][2];
      FetchCorners(d, view.values + brick.valueOffset, ci, c0, c1);
      // The reference value: the first brick that has cells on every axis gives its first cell
      // (the lower one where it exists).
      const hn::Mask<D> newRef = hn::AndNot(s.haveRef, h.any);
      s.v0 = hn::IfThenElse(newRef, hn::IfThenElse(ci.above, c1[0][0], c0[0][0]), s.v0);
      s.haveRef = hn::Or(s.haveRef, newRef);
      AddCorners<gradient>(h, c0, c1, s);
    }
    StoreSums<gradient>(d, s, batch, base);
  }
}

// A field's packed gradient (gradient_pack.h), each corner's bits decoded into unpackGradient's
// floats: each mantissa's field shifted to the top of the word and the word converted (the bits
// below add the fraction the packer rounded against), and the scale 2^(e + base - 23) built from
// the exponent bits and the brick's bias.
template <class D> struct PackedCorner { hn::Vec<D> m[3], scale; };

template <class D> HWY_INLINE PackedCorner<D> DecodePacked(D d, hn::Vec<D> bits, hn::Vec<hn::RebindToSigned<D>> bias) {
  const hn::RebindToSigned<D> di;
  using VI = hn::Vec<decltype(di)>;
  const VI u = hn::BitCast(di, bits);
  PackedCorner<D> c;
  c.m[0] = hn::ConvertTo(d, u);
  c.m[1] = hn::ConvertTo(d, hn::ShiftLeft<9>(u));
  c.m[2] = hn::ConvertTo(d, hn::ShiftLeft<18>(u));
  c.scale = hn::BitCast(d, hn::Add(hn::ShiftLeft<23>(hn::And(u, hn::Set(di, 31))), bias));
  return c;
}

// The packed gradient's sums of one brick, row by row (each row's two corners decoded, their
// scales folded into the x hat factors that the three components share), then along y and z.
// Without a reference value: the components are quantised far above float round-off.
template <class D>
HWY_INLINE void AddPackedCorners(D d, const BrickHats<D>& h, const hn::Vec<D> (&b0)[2][2], const hn::Vec<D> (&b1)[2][2],
                                 hn::Vec<hn::RebindToSigned<D>> bias, hn::Vec<D> (&sum)[3]) {
  using V = hn::Vec<D>;
  V ex[3][2][2];
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y) {
      const PackedCorner<D> q0 = DecodePacked(d, b0[z][y], bias), q1 = DecodePacked(d, b1[z][y], bias);
      const V w0 = hn::Mul(h.h0[0], q0.scale), w1 = hn::Mul(h.h1[0], q1.scale);
      for (int a = 0; a < 3; ++a)
        ex[a][z][y] = hn::MulAdd(w1, q1.m[a], hn::Mul(w0, q0.m[a]));
    }
  for (int a = 0; a < 3; ++a) {
    V eyz[2];
    for (int z = 0; z < 2; ++z)
      eyz[z] = hn::MulAdd(h.h1[1], ex[a][z][1], hn::Mul(h.h0[1], ex[a][z][0]));
    sum[a] = hn::Add(sum[a], hn::MulAdd(h.h1[2], eyz[1], hn::Mul(h.h0[2], eyz[0])));
  }
}

// sampleShadedBatch: the value's sums as SampleBatchFor's (with kValue; else only their
// weights), and the packed gradient's over the same brick factors and corner indices.
template <bool kValue, size_t kLanes>
void SampleShadedFor(const FieldView& view, const PackedGradientView& packed, const uint32_t* brickIds,
                     uint32_t brickCount, const SampleBatch& batch, float* const* out, int32_t* valid) {
  using D = hn::CappedTag<float, kLanes>;
  const D d;
  const hn::RebindToSigned<D> di;
  using V = hn::Vec<D>;
  const size_t lanes = hn::Lanes(d);
  const V one = hn::Set(d, 1.f), zero = hn::Zero(d);
  alignas(64) float pos[3][2 * kSampleBatch];
  const int padded = int((size_t(batch.count) + lanes - 1) / lanes * lanes);
  for (int i = 0; i < padded; ++i) {
    const int j = std::min(i, batch.count > 0 ? batch.count - 1 : 0);
    pos[0][i] = batch.x[j], pos[1][i] = batch.y[j], pos[2][i] = batch.z[j];
  }
  const float* pairs = reinterpret_cast<const float*>(packed.cells); // gradients moved as bits, never as floats
  for (size_t base = 0; base < size_t(batch.count); base += lanes) {
    const V p[3] = {hn::Load(d, pos[0] + base), hn::Load(d, pos[1] + base), hn::Load(d, pos[2] + base)};
    BatchSums<D> s;
    s.sumW = zero, s.sumWV = zero, s.v0 = zero;
    s.haveRef = one < zero; // all false
    V g[3] = {zero, zero, zero};
    for (uint32_t k = 0; k < brickCount; ++k) {
      const Brick& brick = view.bricks[brickIds[k]];
      const V invW = hn::Set(d, inverseWidth(brick.level));
      BrickHats<D> h;
      if (!BrickSupport(d, brick, p, invW, h)) continue;
      BrickFactors(d, brick, invW, h);
      CornerIndex<D> ci;
      IndexCorners(d, brick, h, ci);
      V c0[2][2], c1[2][2], b0[2][2], b1[2][2];
      FetchCornersWithGradients(d, pairs + 2 * size_t(brick.valueOffset), ci, c0, c1, b0, b1);
      if constexpr (kValue) {
        const hn::Mask<D> newRef = hn::AndNot(s.haveRef, h.any);
        s.haveRef = hn::Or(s.haveRef, newRef);
        s.v0 = hn::IfThenElse(newRef, hn::IfThenElse(ci.above, c1[0][0], c0[0][0]), s.v0);
        AddCorners<false>(h, c0, c1, s);
      } else {
        const V wx = hn::Add(h.h0[0], h.h1[0]), wy = hn::Add(h.h0[1], h.h1[1]), wz = hn::Add(h.h0[2], h.h1[2]);
        s.sumW = hn::MulAdd(wx, hn::Mul(wy, wz), s.sumW);
      }
      AddPackedCorners(d, h, b0, b1, hn::Set(di, packed.scaleBias[brickIds[k]]), g);
    }
    const hn::Mask<D> ok = s.sumW > zero;
    const V safeW = hn::IfThenElse(ok, s.sumW, one);
    if constexpr (kValue) hn::StoreU(hn::IfThenElseZero(ok, hn::Add(s.v0, hn::Div(s.sumWV, safeW))), d, out[0] + base);
    if (valid) hn::StoreU(hn::VecFromMask(di, hn::RebindMask(di, ok)), di, valid + base);
    for (int a = 0; a < 3; ++a) // whole vectors: padded <= kSampleBatch
      hn::StoreU(hn::IfThenElseZero(ok, hn::Div(g[a], safeW)), d, out[1 + a] + base);
  }
}

void SampleShadedBatchImpl(const FieldView& view, const PackedGradientView& packed, bool withValue,
                           const uint32_t* brickIds, uint32_t brickCount, const SampleBatch& batch, float* const* out,
                           int32_t* valid) {
  if (batch.count <= 4) {
    if (withValue)
      SampleShadedFor<true, 4>(view, packed, brickIds, brickCount, batch, out, valid);
    else
      SampleShadedFor<false, 4>(view, packed, brickIds, brickCount, batch, out, valid);
  } else if (withValue) {
    SampleShadedFor<true, kSampleBatch>(view, packed, brickIds, brickCount, batch, out, valid);
  } else {
    SampleShadedFor<false, kSampleBatch>(view, packed, brickIds, brickCount, batch, out, valid);
  }
}

void SampleBricksBatchImpl(const FieldView& view, const uint32_t* brickIds, uint32_t brickCount, SampleBatch& batch,
                           bool gradient) {
  if (batch.count <= 4) {
    if (gradient)
      SampleBatchFor<true, 4>(view, brickIds, brickCount, batch);
    else
      SampleBatchFor<false, 4>(view, brickIds, brickCount, batch);
  } else if (gradient)
    SampleBatchFor<true, kSampleBatch>(view, brickIds, brickCount, batch);
  else
    SampleBatchFor<false, kSampleBatch>(view, brickIds, brickCount, batch);
}

void SampleBatchImpl(const FieldView& view, uint32_t regionIndex, SampleBatch& batch, bool gradient) {
  const Region& region = view.regions[regionIndex];
  SampleBricksBatchImpl(view, view.brickIds + region.brickBegin, region.brickCount, batch, gradient);
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

} // namespace HWY_NAMESPACE
} // namespace exa
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "exabricks/core/simd_dispatch.h"

namespace exa {

HWY_EXPORT(SampleBatchImpl);
HWY_EXPORT(SampleBricksBatchImpl);
HWY_EXPORT(SampleShadedBatchImpl);
HWY_EXPORT(TargetName);

void sampleRegionBatch(const FieldView& view, uint32_t regionIndex, SampleBatch& batch, bool gradient) {
  HWY_DYNAMIC_DISPATCH(SampleBatchImpl)(view, regionIndex, batch, gradient);
}

void sampleBricksBatch(const FieldView& view, const uint32_t* brickIds, uint32_t brickCount, SampleBatch& batch,
                       bool gradient) {
  HWY_DYNAMIC_DISPATCH(SampleBricksBatchImpl)(view, brickIds, brickCount, batch, gradient);
}

SampleRegionBatchFunction sampleRegionBatchFunction() {
  return chosenBatchFunction(HWY_DISPATCH_TABLE(SampleBatchImpl));
}

SampleBricksBatchFunction sampleBricksBatchFunction() {
  return chosenBatchFunction(HWY_DISPATCH_TABLE(SampleBricksBatchImpl));
}

void sampleShadedBatch(const FieldView& view, const PackedGradientView& gradients, bool withValue,
                       const uint32_t* brickIds, uint32_t brickCount, const SampleBatch& batch, float* const* out,
                       int32_t* valid) {
  HWY_DYNAMIC_DISPATCH(SampleShadedBatchImpl)(view, gradients, withValue, brickIds, brickCount, batch, out, valid);
}

SampleShadedBatchFunction sampleShadedBatchFunction() {
  return chosenBatchFunction(HWY_DISPATCH_TABLE(SampleShadedBatchImpl));
}

const char* batchTargetName() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

std::vector<std::string> batchTargets() {
  static const std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets(); // before any mock
  std::vector<std::string> names;
  for (int64_t t : targets)
    names.push_back(hwy::TargetName(t));
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
