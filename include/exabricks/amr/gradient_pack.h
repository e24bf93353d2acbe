// Smooth shading's gradient fields packed into 32 bits per cell: three signed 9-bit mantissas
// sharing a 5-bit exponent above a per-brick base, so that a cell's gradient is one load where it
// was three. A component is within half a unit of q 2^(base + e) (|q| <= 256), with the largest of
// a cell's three in [128, 255] units (8 significant bits and a sign: every component within 1/255
// of the largest); a cell more than 2^31 times smaller than its brick's largest, or below 2^-96,
// keeps fewer bits, down to zero. Layout: x in bits 23-31, y 14-22, z 5-13, e 0-4 (two's complement
// mantissas). A component is decoded by shifting its field to the top of the word and converting
// the whole word, without masking: the bits below the field add a fraction of a unit, which the
// packer knows and rounds the field against (the fields below first).
#pragma once

#include "exabricks/core/math.h"

#include <cmath>
#include <cstdint>
#include <cstring>

namespace exa {

/// Lowest brick base exponent: the decoded scale 2^(base + e - 23) stays a normal float.
constexpr int kGradientBaseMin = -103;

/// 2^e, exactly, for e in [-1022, 1023]: the packer's scalings by powers of two as one
/// multiplication each (ldexp's library calls took about a quarter of the fields' build).
inline double exactPowerOfTwo(int e) {
  const uint64_t bits = uint64_t(e + 1023) << 52;
  double p;
  std::memcpy(&p, &bits, sizeof p);
  return p;
}

/// The exponent E of a cell's gradient: its largest component rounds to [128, 255] 2^E
/// (kGradientBaseMin for zero).
inline int packedGradientExponent(const vec3f& g) {
  float m = 0.f;
  for (int a = 0; a < 3; ++a)
    if (std::isfinite(g[a])) m = std::max(m, std::abs(g[a]));
  if (!(m > 0.f)) return kGradientBaseMin;
  uint32_t bits;
  std::memcpy(&bits, &m, sizeof bits);
  // ilogb(m): the exponent bits of a normal float (the library call for subnormals).
  const int E = (bits >= 0x00800000u ? int(bits >> 23) - 127 : std::ilogb(m)) - 7;
  return std::lrint(double(m) * exactPowerOfTwo(-E)) > 255 ? E + 1 : E;
}

/// A brick's base exponent from its cells' largest packedGradientExponent.
inline int gradientBase(int largestExponent) { return std::max(largestExponent - 31, kGradientBaseMin); }

/// The float bits the decoder adds to e << 23 for a brick of base `base`: 2^(base - 23) as bits.
inline int32_t gradientScaleBias(int base) { return int32_t(uint32_t(base - 23 + 127) << 23); }

/// One cell's gradient packed above base `base` (gradientBase of its brick): e, then z, y and x,
/// each mantissa rounded against the fraction of its unit that the bits already placed below it
/// add when it is decoded (unpackGradient), so that the decoded component is within half a unit.
inline uint32_t packGradient(const vec3f& g, int base) {
  const int E = std::min(std::max(packedGradientExponent(g), base), base + 31);
  const double unit = exactPowerOfTwo(-E);
  uint32_t u = uint32_t(E - base);
  for (int a = 2; a >= 0; --a) {
    const int shift = 23 - 9 * a; // where the field starts: x 23, y 14, z 5
    const double c = std::isfinite(g[a]) ? double(g[a]) : 0.;
    const double below = double(u) * exactPowerOfTwo(-shift);
    const long q = std::max(-256l, std::min(255l, std::lrint(c * unit - below)));
    u |= (uint32_t(q) & 511u) << shift;
  }
  return u;
}

/// The decoded gradient (the floats the vectorised reconstruction uses) of packed bits `u` from a
/// brick with scale bias `bias` (gradientScaleBias): each field shifted to the top of the word
/// and the word converted (rounded to the nearest float), then scaled by 2^(base + e - 23).
EXA_HOST_DEVICE inline vec3f unpackGradient(uint32_t u, int32_t bias) {
  const uint32_t scaleBits = ((u & 31u) << 23) + uint32_t(bias);
  float scale;
  std::memcpy(&scale, &scaleBits, sizeof scale);
  const float x = float(int32_t(u)), y = float(int32_t(u << 9)), z = float(int32_t(u << 18));
  return vec3f(x * scale, y * scale, z * scale);
}

} // namespace exa
