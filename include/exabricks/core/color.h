// Colours: RGBA in float with the usual operators, and the sRGB transfer curve. Colours are
// linear RGB everywhere inside exabricks; sRGB appears only at image and option boundaries.
#pragma once

#include "exabricks/core/math.h"

namespace exa {

/// Four floats: an RGBA colour (premultiplied where an image says so) or any 4-vector.
struct vec4f {
  float x = 0, y = 0, z = 0, w = 0;
  constexpr vec4f() = default;
  EXA_HOST_DEVICE constexpr vec4f(float x_, float y_, float z_, float w_) : x(x_), y(y_), z(z_), w(w_) {}
  EXA_HOST_DEVICE constexpr vec4f(const vec3f& c, float w_) : x(c.x), y(c.y), z(c.z), w(w_) {}
  EXA_HOST_DEVICE constexpr vec3f rgb() const { return {x, y, z}; }
  friend constexpr bool operator==(const vec4f& a, const vec4f& b) = default;
};

EXA_HOST_DEVICE constexpr vec4f operator+(const vec4f& a, const vec4f& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w};
}
EXA_HOST_DEVICE constexpr vec4f operator-(const vec4f& a, const vec4f& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w};
}
EXA_HOST_DEVICE constexpr vec4f operator*(const vec4f& a, float s) { return {a.x * s, a.y * s, a.z * s, a.w * s}; }
EXA_HOST_DEVICE constexpr vec4f operator*(float s, const vec4f& a) { return a * s; }
/// Component by component.
EXA_HOST_DEVICE constexpr vec4f operator*(const vec4f& a, const vec4f& b) {
  return {a.x * b.x, a.y * b.y, a.z * b.z, a.w * b.w};
}
EXA_HOST_DEVICE constexpr vec4f& operator+=(vec4f& a, const vec4f& b) {
  a.x += b.x, a.y += b.y, a.z += b.z, a.w += b.w;
  return a;
}

/// Four floats read at once where the target can: on the GPU one 16-byte load through the
/// read-only cache (`p` must be 16-byte aligned there, as device allocations of vec4f are).
EXA_HOST_DEVICE inline vec4f loadVec4(const vec4f* p) {
#ifdef __CUDA_ARCH__
  const float4 q = __ldg(reinterpret_cast<const float4*>(p));
  return {q.x, q.y, q.z, q.w};
#else
  return *p;
#endif
}

/// The relative luminance of a linear RGB colour (Rec. 709 weights).
EXA_HOST_DEVICE constexpr float luminance(const vec3f& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/// Linear -> sRGB transfer for one channel, clamped to [0, 1] (NaN gives 0).
float linearToSrgb(float c);
/// sRGB -> linear for one channel, clamped to [0, 1].
float srgbToLinear(float c);
inline vec3f srgbToLinear(const vec3f& c) { return {srgbToLinear(c.x), srgbToLinear(c.y), srgbToLinear(c.z)}; }
inline vec3f linearToSrgb(const vec3f& c) { return {linearToSrgb(c.x), linearToSrgb(c.y), linearToSrgb(c.z)}; }

} // namespace exa
