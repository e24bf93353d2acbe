// Hashing and counter-based random numbers: the same numbers for a pixel and sample index on any
// thread, in any order, on CPU or GPU.
#pragma once

#include "exabricks/core/math.h"

#include <cstdint>

namespace exa {

/// A 64-bit finaliser (the MurmurHash3 mix): every input bit affects every output bit.
EXA_HOST_DEVICE inline uint64_t mixBits(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  return x ^ (x >> 33);
}

/// Deterministic random numbers in [0, 1) for one pixel and one sample (frame) index.
struct PixelRandom {
  uint64_t state;
  EXA_HOST_DEVICE PixelRandom(int x, int y, int sample, uint64_t seed)
      : state(mixBits(seed * 0x9e3779b97f4a7c15ull ^ mixBits((uint64_t(uint32_t(y)) << 32) | uint32_t(x)) ^
                      (uint64_t(sample) << 48))) {}
  EXA_HOST_DEVICE float next() {
    state = mixBits(state + 0x9e3779b97f4a7c15ull);
    return float(state >> 40) * (1.f / 16777216.f);
  }
};

/// A distinct, not too dark colour per id (debug views).
EXA_HOST_DEVICE inline vec3f hashColor(uint32_t id) {
  const uint64_t h = mixBits(uint64_t(id) + 12345);
  return vec3f(0.15f + 0.85f * float(h & 255) / 255.f, 0.15f + 0.85f * float((h >> 8) & 255) / 255.f,
               0.15f + 0.85f * float((h >> 16) & 255) / 255.f);
}

} // namespace exa
