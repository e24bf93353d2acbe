// Basis-method reconstruction (paper eqs. 1-3) straight from a region's bricks, with the exact
// derivative. Header-only and free of allocation, exceptions and virtual calls so that a GPU
// path can share it; `Real` is float for rendering and double where exactness matters.
//
// Each cell C of width w has centre c = corner + w/2 and weight H_C(p) = prod_a h(|c_a - p_a|/w)
// with h(x) = max(1 - x, 0). The reconstruction is B(p) = sum H_C v_C / sum H_C; with no weight,
// there is no value. Its gradient is the quotient rule applied to both sums, with
//   dh(|c_a - p_a| / w) / dp_a = -sign(p_a - c_a) / w,
// i.e. +1/w while p lies below the centre and -1/w above it. Where that derivative jumps (at a
// centre or at a support face), we use the one-sided derivative towards +axis: a point exactly
// on a centre gets -1/w, a point exactly on the lower support face gets +1/w.
//
// The sums are kept relative to the first cell's value v0 (B = v0 + sum H (v - v0) / sum H): the
// same quotient, but a constant field reconstructs exactly with an exactly zero gradient, and a
// nearly constant one without the cancellation that would turn round-off into gradients.
#pragma once

#include "exabricks/amr/regions.h"

#include <cstring>

namespace exa {

/// Trivially copyable view of the structures one field is sampled from.
struct FieldView {
  const Brick* bricks = nullptr;
  const float* values = nullptr; ///< brick-ordered values of the field
  const Region* regions = nullptr;
  const uint32_t* brickIds = nullptr;
  const RegionKdNode* nodes = nullptr; ///< null when there are no regions
  box3f bounds;                        ///< lattice box of the k-d tree root
};

/// 1 / 2^level, exact in float (built from the exponent bits; level in 0..kMaxLevel): saves a
/// division per brick and sample.
EXA_HOST_DEVICE inline float inverseWidth(int level) {
  const uint32_t bits = uint32_t(127 - level) << 23;
  float w;
  std::memcpy(&w, &bits, sizeof w);
  return w;
}

/// Running sums of the quotient B = sumWV / sumW and of their derivatives.
template <typename Real> struct BasisAccumulator {
  Real sumW = 0, sumWV = 0; ///< sum H, sum H (v - v0)
  vec3<Real> dSumW{Real(0)}, dSumWV{Real(0)};
  Real v0 = 0; ///< reference value: the first cell's
  bool haveReference = false;

  /// Adds every cell of `brick` whose support holds p (lattice units).
  EXA_HOST_DEVICE inline void addBrick(const Brick& brick, const float* brickValues, const vec3<Real>& p,
                                       bool withGradient) {
    const Real invW = Real(inverseWidth(brick.level));
    int idx[3][2];
    Real h[3][2], dh[3][2];
    int count[3];
    for (int a = 0; a < 3; ++a) {
      // Position in cell-centre units: cell i has its centre at q = i.
      const Real q = (p[a] - Real(brick.lower[a])) * invW - Real(0.5);
      // floor without a libm call on targets lacking a rounding instruction; q is small here
      // (points lie within the brick's support, so -1.5 <= q <= size + 0.5).
      const int truncated = int(q);
      const int i0 = truncated - (q < Real(truncated) ? 1 : 0);
      const Real f = q - Real(i0);
      int n = 0;
      if (i0 >= 0 && i0 < brick.size[a]) {
        idx[a][n] = i0;
        h[a][n] = Real(1) - f;
        dh[a][n] = -invW;
        ++n;
      }
      if (i0 + 1 >= 0 && i0 + 1 < brick.size[a]) {
        idx[a][n] = i0 + 1;
        h[a][n] = f;
        dh[a][n] = invW;
        ++n;
      }
      count[a] = n;
    }
    const float* values = brickValues + brick.valueOffset;
    if (!haveReference && count[0] > 0 && count[1] > 0 && count[2] > 0)
      setReference(Real(
          values[size_t(idx[0][0]) + size_t(brick.size.x) * (size_t(idx[1][0]) + size_t(brick.size.y) * idx[2][0])]));
    for (int iz = 0; iz < count[2]; ++iz)
      for (int iy = 0; iy < count[1]; ++iy) {
        const float* row = values + size_t(brick.size.x) * (size_t(idx[1][iy]) + size_t(brick.size.y) * idx[2][iz]);
        for (int ix = 0; ix < count[0]; ++ix)
          addCell(Real(row[idx[0][ix]]), h[0][ix], h[1][iy], h[2][iz], dh[0][ix], dh[1][iy], dh[2][iz], withGradient);
      }
  }

  /// Sets the reference value; addCell needs one first.
  EXA_HOST_DEVICE inline void setReference(Real value) {
    v0 = value;
    haveReference = true;
  }

  /// Adds one cell of value `value` (after setReference) whose hat has the per-axis factors h
  /// and derivatives dh at the sample point: weight hx hy hz, d/dx weight = dhx hy hz, and so on.
  EXA_HOST_DEVICE inline void addCell(Real value, Real hx, Real hy, Real hz, Real dhx, Real dhy, Real dhz,
                                      bool withGradient) {
    const Real v = value - v0;
    const Real hyz = hy * hz;
    const Real weight = hx * hyz;
    sumW += weight;
    sumWV += weight * v;
    if (withGradient) {
      const vec3<Real> d(dhx * hyz, hx * dhy * hz, hx * hy * dhz);
      dSumW += d;
      dSumWV += d * v;
    }
  }

  EXA_HOST_DEVICE inline bool valid() const { return sumW > Real(0); }
  EXA_HOST_DEVICE inline Real value() const { return v0 + sumWV / sumW; }
  /// Gradient in lattice units (per finest-level cell width).
  EXA_HOST_DEVICE inline vec3<Real> gradient() const { return (dSumWV * sumW - dSumW * sumWV) / (sumW * sumW); }
};

/// Index of the region that holds p (lattice units), or kNoRegion. Points on a split plane go
/// to the upper side, which holds every cell whose support contains them.
template <typename Real> EXA_HOST_DEVICE inline uint32_t locateRegion(const FieldView& view, const vec3<Real>& p) {
  if (!view.nodes) return kNoRegion;
  for (int a = 0; a < 3; ++a)
    if (!(p[a] >= Real(view.bounds.lower[a]) && p[a] <= Real(view.bounds.upper[a]))) return kNoRegion;
  uint32_t n = 0;
  while (view.nodes[n].axis != kLeafAxis) {
    const RegionKdNode& node = view.nodes[n];
    n = node.index + (p[int(node.axis)] >= Real(node.pos) ? 1u : 0u);
  }
  return view.nodes[n].index;
}

/// Reconstructs the field at p (lattice units) from the listed bricks (indices into view.bricks).
/// Returns false where no cell has weight (no value); the gradient is per lattice unit.
template <typename Real>
EXA_HOST_DEVICE inline bool sampleBricks(const FieldView& view, const uint32_t* brickIds, uint32_t brickCount,
                                         const vec3<Real>& p, Real& value, vec3<Real>* gradient = nullptr) {
  BasisAccumulator<Real> acc;
  for (uint32_t k = 0; k < brickCount; ++k)
    acc.addBrick(view.bricks[brickIds[k]], view.values, p, gradient != nullptr);
  if (!acc.valid()) return false;
  value = acc.value();
  if (gradient) *gradient = acc.gradient();
  return true;
}

/// Reconstructs the field at p (lattice units) from the bricks of region `regionIndex`: every
/// brick whose support reaches p when p lies in the region.
template <typename Real>
EXA_HOST_DEVICE inline bool sampleRegion(const FieldView& view, uint32_t regionIndex, const vec3<Real>& p, Real& value,
                                         vec3<Real>* gradient = nullptr) {
  const Region& region = view.regions[regionIndex];
  return sampleBricks(view, view.brickIds + region.brickBegin, region.brickCount, p, value, gradient);
}

/// Locates p's region and reconstructs there; false outside every support.
template <typename Real>
EXA_HOST_DEVICE inline bool sampleField(const FieldView& view, const vec3<Real>& p, Real& value,
                                        vec3<Real>* gradient = nullptr) {
  const uint32_t r = locateRegion(view, p);
  if (r == kNoRegion) return false;
  return sampleRegion(view, r, p, value, gradient);
}

} // namespace exa
