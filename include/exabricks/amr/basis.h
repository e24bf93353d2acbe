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
#include "exabricks/core/color.h"

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

/// Where a point falls in a brick: per axis the (at most two) cells whose hat holds it, with
/// their hat factors h and derivatives dh (paper eq. 1).
template <typename Real> struct BrickStencil {
  int idx[3][2];
  Real h[3][2], dh[3][2];
  int count[3];

  EXA_HOST_DEVICE inline BrickStencil(const Brick& brick, const vec3<Real>& p) {
    const Real invW = Real(inverseWidth(brick.level));
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
  }
  EXA_HOST_DEVICE inline bool empty() const { return count[0] == 0 || count[1] == 0 || count[2] == 0; }
  /// Index within the brick's values of the row (iy, iz) of the stencil.
  EXA_HOST_DEVICE inline size_t row(const Brick& brick, int iy, int iz) const {
    return size_t(brick.size.x) * (size_t(idx[1][iy]) + size_t(brick.size.y) * idx[2][iz]);
  }
};

/// Running sums of the quotient B = sumWV / sumW and of their derivatives.
template <typename Real> struct BasisAccumulator {
  Real sumW = 0, sumWV = 0; ///< sum H, sum H (v - v0)
  vec3<Real> dSumW{Real(0)}, dSumWV{Real(0)};
  Real v0 = 0; ///< reference value: the first cell's
  bool haveReference = false;

  /// Adds every cell of `brick` whose support holds p (lattice units).
  EXA_HOST_DEVICE inline void addBrick(const Brick& brick, const float* brickValues, const vec3<Real>& p,
                                       bool withGradient) {
    const BrickStencil<Real> st(brick, p);
    const float* values = brickValues + brick.valueOffset;
    if (!haveReference && !st.empty()) setReference(Real(values[st.row(brick, 0, 0) + size_t(st.idx[0][0])]));
    for (int iz = 0; iz < st.count[2]; ++iz)
      for (int iy = 0; iy < st.count[1]; ++iy) {
        const float* row = values + st.row(brick, iy, iz);
        for (int ix = 0; ix < st.count[0]; ++ix)
          addCell(Real(row[st.idx[0][ix]]), st.h[0][ix], st.h[1][iy], st.h[2][iz], st.dh[0][ix], st.dh[1][iy],
                  st.dh[2][iz], withGradient);
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

/// A field and three more that share its bricks (smooth shading's gradient fields) reconstructed
/// at once: cell values interleaved (value, gx, gy, gz), the same weights and, per channel, the
/// same sums in the same order as BasisAccumulator's (without derivatives).
struct BasisAccumulator4 {
  float sumW = 0.f;
  vec4f sumWV, v0;
  bool haveReference = false;

  /// Adds every cell of `brick` whose support holds p. Both cells of each axis's stencil are
  /// visited, the second one again with weight 0 where only one lies in the brick: the sums gain
  /// exact zeros, so they equal BasisAccumulator's, with a fixed loop of eight cells (fewer
  /// branches for a GPU's warps) and 32-bit indices within the brick.
  EXA_HOST_DEVICE inline void addBrick(const Brick& brick, const vec4f* brickValues, const vec3f& p) {
    const vec4f* values = brickValues + brick.valueOffset;
    addBrickWith(
        brick, [values](uint32_t i) { return loadVec4(values + i); }, p);
  }

  /// The same with the brick's cells' four values from load(index within the brick).
  template <class Load> EXA_HOST_DEVICE inline void addBrickWith(const Brick& brick, const Load& load, const vec3f& p) {
    const float invW = inverseWidth(brick.level);
    int cell[3][2];
    float h[3][2];
    for (int a = 0; a < 3; ++a) {
      // As BrickStencil: the position in cell-centre units and the cells on either side.
      const float q = (p[a] - float(brick.lower[a])) * invW - 0.5f;
      const int truncated = int(q);
      const int i0 = truncated - (q < float(truncated) ? 1 : 0);
      const float f = q - float(i0);
      const int n = brick.size[a];
      const bool first = i0 >= 0 && i0 < n, second = i0 + 1 >= 0 && i0 + 1 < n;
      if (!first && !second) return;
      cell[a][0] = first ? i0 : i0 + 1;
      h[a][0] = first ? 1.f - f : f;
      cell[a][1] = first && second ? i0 + 1 : cell[a][0];
      h[a][1] = first && second ? f : 0.f;
    }
    const uint32_t nx = uint32_t(brick.size.x), nxy = nx * uint32_t(brick.size.y);
    if (!haveReference) {
      v0 = load(uint32_t(cell[0][0]) + nx * uint32_t(cell[1][0]) + nxy * uint32_t(cell[2][0]));
      haveReference = true;
    }
    for (int iz = 0; iz < 2; ++iz)
      for (int iy = 0; iy < 2; ++iy) {
        const uint32_t row = nx * uint32_t(cell[1][iy]) + nxy * uint32_t(cell[2][iz]);
        const float hyz = h[1][iy] * h[2][iz];
        for (int ix = 0; ix < 2; ++ix) {
          const vec4f v = load(row + uint32_t(cell[0][ix])) - v0;
          const float weight = h[0][ix] * hyz;
          sumW += weight;
          sumWV += weight * v;
        }
      }
  }
  EXA_HOST_DEVICE inline bool valid() const { return sumW > 0.f; }
  EXA_HOST_DEVICE inline vec4f value() const {
    return {v0.x + sumWV.x / sumW, v0.y + sumWV.y / sumW, v0.z + sumWV.z / sumW, v0.w + sumWV.w / sumW};
  }
};

/// Reconstructs four interleaved fields (BasisAccumulator4) at p from the bricks of region
/// `regionIndex` of `view`; false where no cell has weight.
EXA_HOST_DEVICE inline bool sampleRegion4(const FieldView& view, const vec4f* values, uint32_t regionIndex,
                                          const vec3f& p, vec4f& out) {
  const Region& region = view.regions[regionIndex];
  BasisAccumulator4 acc;
  for (uint32_t k = 0; k < region.brickCount; ++k)
    acc.addBrick(view.bricks[view.brickIds[region.brickBegin + k]], values, p);
  if (!acc.valid()) return false;
  out = acc.value();
  return true;
}

/// Index of the region that holds p (lattice units), or kNoRegion. Points on a split plane go
/// to the upper side, which holds every cell whose support contains them. The descent may start
/// at a node `from` that regionSubtree gave for a box holding p.
template <typename Real>
EXA_HOST_DEVICE inline uint32_t locateRegion(const FieldView& view, const vec3<Real>& p, uint32_t from = 0) {
  if (!view.nodes) return kNoRegion;
  for (int a = 0; a < 3; ++a)
    if (!(p[a] >= Real(view.bounds.lower[a]) && p[a] <= Real(view.bounds.upper[a]))) return kNoRegion;
  uint32_t n = from;
  while (view.nodes[n].axis != kLeafAxis) {
    const RegionKdNode& node = view.nodes[n];
    n = node.index + (p[int(node.axis)] >= Real(node.pos) ? 1u : 0u);
  }
  return view.nodes[n].index;
}

/// The deepest k-d node that every point of the closed box `box` descends through: locating
/// points of the box may start there (the root where the tree is empty).
inline uint32_t regionSubtree(const FieldView& view, const box3f& box) {
  uint32_t n = 0;
  while (view.nodes && view.nodes[n].axis != kLeafAxis) {
    const RegionKdNode& node = view.nodes[n];
    const int a = int(node.axis);
    if (box.upper[a] < node.pos)
      n = node.index;
    else if (box.lower[a] >= node.pos)
      n = node.index + 1;
    else
      break;
  }
  return n;
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

/// The range of the values of the cells whose hat is positive at p (lattice units): every value
/// the reconstruction weighs there (empty outside every support).
inline range1f weighedValueRange(const FieldView& view, const vec3d& p) {
  range1f r;
  const uint32_t regionIndex = locateRegion(view, p);
  if (regionIndex == kNoRegion) return r;
  const Region& region = view.regions[regionIndex];
  for (uint32_t k = 0; k < region.brickCount; ++k) {
    const Brick& brick = view.bricks[view.brickIds[region.brickBegin + k]];
    const BrickStencil<double> st(brick, p);
    for (int iz = 0; iz < st.count[2]; ++iz)
      for (int iy = 0; iy < st.count[1]; ++iy)
        for (int ix = 0; ix < st.count[0]; ++ix)
          if (st.h[0][ix] * st.h[1][iy] * st.h[2][iz] > 0.0)
            r.extend(view.values[brick.valueOffset + st.row(brick, iy, iz) + size_t(st.idx[0][ix])]);
  }
  return r;
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
