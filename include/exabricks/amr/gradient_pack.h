// Smooth shading's gradient fields packed into 32 bits per cell: three signed 9-bit mantissas
// sharing a 5-bit exponent above a per-brick base, so that a cell's gradient is one load where it
// was three. A component is q 2^(base + e) exactly (|q| <= 255), with the largest of a cell's
// three in [128, 255] (8 significant bits and a sign: every component within 1/255 of the
// largest); a cell more than 2^31 times smaller than its brick's largest, or below 2^-96, keeps
// fewer bits, down to zero. Layout: x in bits 23-31, y 14-22, z 5-13, e 0-4 (two's complement
// mantissas at the top of each field's shift, so that masking gives q 2^23 as an int).
#pragma once

#include "exabricks/core/math.h"

#include <cmath>
#include <cstdint>
#include <cstring>

namespace exa {

/// Lowest brick base exponent: the decoded scale 2^(base + e - 23) stays a normal float.
constexpr int kGradientBaseMin = -103;

/// The exponent E of a cell's gradient: its largest component rounds to [128, 255] 2^E
/// (kGradientBaseMin for zero).
inline int packedGradientExponent(const vec3f& g) {
  float m = 0.f;
  for (int a = 0; a < 3; ++a)
    if (std::isfinite(g[a])) m = std::max(m, std::abs(g[a]));
  if (!(m > 0.f)) return kGradientBaseMin;
  const int E = std::ilogb(m) - 7;
  return std::lrint(std::ldexp(m, -E)) > 255 ? E + 1 : E;
}

/// A brick's base exponent from its cells' largest packedGradientExponent.
inline int gradientBase(int largestExponent) { return std::max(largestExponent - 31, kGradientBaseMin); }

/// The float bits the decoder adds to e << 23 for a brick of base `base`: 2^(base - 23) as bits.
inline int32_t gradientScaleBias(int base) { return int32_t(uint32_t(base - 23 + 127) << 23); }

/// One cell's gradient packed above base `base` (gradientBase of its brick).
inline uint32_t packGradient(const vec3f& g, int base) {
  const int E = std::min(std::max(packedGradientExponent(g), base), base + 31);
  int32_t q[3];
  for (int a = 0; a < 3; ++a) {
    const float c = std::isfinite(g[a]) ? g[a] : 0.f;
    q[a] = int32_t(std::max(-255l, std::min(255l, std::lrint(std::ldexp(c, -E)))));
  }
  const uint32_t e = uint32_t(E - base);
  return (uint32_t(q[0]) << 23) | ((uint32_t(q[1]) & 511u) << 14) | ((uint32_t(q[2]) & 511u) << 5) | e;
}

/// The decoded gradient (the floats the vectorised reconstruction uses) of packed bits `u` from a
/// brick with scale bias `bias` (gradientScaleBias).
EXA_HOST_DEVICE inline vec3f unpackGradient(uint32_t u, int32_t bias) {
  const uint32_t scaleBits = ((u & 31u) << 23) + uint32_t(bias);
  float scale;
  std::memcpy(&scale, &scaleBits, sizeof scale);
  const float x = float(int32_t(u & 0xFF800000u)), y = float(int32_t((u << 9) & 0xFF800000u)),
              z = float(int32_t((u << 18) & 0xFF800000u));
  return vec3f(x * scale, y * scale, z * scale);
}

} // namespace exa
