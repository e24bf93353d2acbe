// Small value types for lattice and world geometry.
//
// Integer types (vec3i, box3i) live on the finest-level cell lattice; float types (vec3f, box3f)
// are used for lattice positions of samples and for world space. Boxes are half-open on the
// integer lattice ([lower, upper) in cells) and closed in float space unless stated otherwise.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#if defined(__CUDACC__)
#define EXA_HOST_DEVICE __host__ __device__
#else
#define EXA_HOST_DEVICE
#endif

namespace exa {

/// a / b rounded towards minus infinity (b != 0): the lattice cell of width b that holds a.
EXA_HOST_DEVICE constexpr int64_t floorDiv(int64_t a, int64_t b) {
  return a / b - ((a % b != 0) && ((a < 0) != (b < 0)));
}

/// The smaller and the larger of two numbers that are not NaN: one instruction on the CPU too,
/// where fminf and fmaxf (whose rules for NaN a compare does not follow) are calls.
EXA_HOST_DEVICE constexpr float minOf(float a, float b) { return a < b ? a : b; }
EXA_HOST_DEVICE constexpr float maxOf(float a, float b) { return a > b ? a : b; }

template <typename T> struct vec3 {
  T x{}, y{}, z{};
  constexpr vec3() = default;
  EXA_HOST_DEVICE constexpr explicit vec3(T s) : x(s), y(s), z(s) {}
  EXA_HOST_DEVICE constexpr vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  template <typename U> EXA_HOST_DEVICE constexpr explicit vec3(const vec3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}
  EXA_HOST_DEVICE constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  EXA_HOST_DEVICE constexpr const T& operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  friend constexpr bool operator==(const vec3& a, const vec3& b) = default;
};

using vec3i = vec3<int32_t>;
using vec3l = vec3<int64_t>;
using vec3f = vec3<float>;
using vec3d = vec3<double>;

#define EXA_VEC_BINOP(op)                                                                                              \
  template <typename T> EXA_HOST_DEVICE constexpr vec3<T> operator op(const vec3<T>& a, const vec3<T>& b) {            \
    return {a.x op b.x, a.y op b.y, a.z op b.z};                                                                       \
  }                                                                                                                    \
  template <typename T> EXA_HOST_DEVICE constexpr vec3<T> operator op(const vec3<T>& a, T s) {                         \
    return {a.x op s, a.y op s, a.z op s};                                                                             \
  }                                                                                                                    \
  template <typename T> EXA_HOST_DEVICE constexpr vec3<T> operator op(T s, const vec3<T>& a) {                         \
    return {s op a.x, s op a.y, s op a.z};                                                                             \
  }
EXA_VEC_BINOP(+)
EXA_VEC_BINOP(-)
EXA_VEC_BINOP(*)
EXA_VEC_BINOP(/)
#undef EXA_VEC_BINOP

template <typename T> EXA_HOST_DEVICE constexpr vec3<T> operator-(const vec3<T>& a) { return {-a.x, -a.y, -a.z}; }
template <typename T> EXA_HOST_DEVICE constexpr vec3<T>& operator+=(vec3<T>& a, const vec3<T>& b) {
  a = a + b;
  return a;
}
template <typename T> EXA_HOST_DEVICE constexpr vec3<T>& operator*=(vec3<T>& a, T s) {
  a = a * s;
  return a;
}
template <typename T> EXA_HOST_DEVICE constexpr vec3<T> min(const vec3<T>& a, const vec3<T>& b) {
  return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
template <typename T> EXA_HOST_DEVICE constexpr vec3<T> max(const vec3<T>& a, const vec3<T>& b) {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}
template <typename T> EXA_HOST_DEVICE constexpr T dot(const vec3<T>& a, const vec3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T> EXA_HOST_DEVICE constexpr vec3<T> cross(const vec3<T>& a, const vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T> EXA_HOST_DEVICE inline T length(const vec3<T>& a) { return std::sqrt(dot(a, a)); }
template <typename T> EXA_HOST_DEVICE inline vec3<T> normalize(const vec3<T>& a) {
  const T l = length(a);
  return l > T(0) ? a * (T(1) / l) : a;
}
template <typename T> EXA_HOST_DEVICE constexpr T reduceMin(const vec3<T>& a) {
  return std::min(a.x, std::min(a.y, a.z));
}
template <typename T> EXA_HOST_DEVICE constexpr T reduceMax(const vec3<T>& a) {
  return std::max(a.x, std::max(a.y, a.z));
}
/// Index of the largest component (first one on ties).
template <typename T> EXA_HOST_DEVICE constexpr int argMax(const vec3<T>& a) {
  return (a.x >= a.y && a.x >= a.z) ? 0 : (a.y >= a.z ? 1 : 2);
}

/// Axis-aligned box. For integer lattice boxes `upper` is exclusive; for float boxes the box is
/// the closed set [lower, upper].
template <typename T> struct box3 {
  vec3<T> lower{std::numeric_limits<T>::max()};
  vec3<T> upper{std::numeric_limits<T>::lowest()};
  constexpr box3() = default;
  EXA_HOST_DEVICE constexpr box3(const vec3<T>& lo, const vec3<T>& hi) : lower(lo), upper(hi) {}
  EXA_HOST_DEVICE constexpr bool empty() const {
    return !(lower.x < upper.x && lower.y < upper.y && lower.z < upper.z);
  }
  EXA_HOST_DEVICE constexpr vec3<T> size() const { return upper - lower; }
  EXA_HOST_DEVICE constexpr void extend(const vec3<T>& p) {
    lower = min(lower, p);
    upper = max(upper, p);
  }
  EXA_HOST_DEVICE constexpr void extend(const box3& b) {
    lower = min(lower, b.lower);
    upper = max(upper, b.upper);
  }
  friend constexpr bool operator==(const box3& a, const box3& b) = default;
};
using box3i = box3<int32_t>;
using box3l = box3<int64_t>;
using box3f = box3<float>;
using box3d = box3<double>;

/// Closed scalar interval [lower, upper]; empty when lower > upper.
struct range1f {
  float lower = std::numeric_limits<float>::infinity();
  float upper = -std::numeric_limits<float>::infinity();
  EXA_HOST_DEVICE constexpr bool empty() const { return lower > upper; }
  EXA_HOST_DEVICE constexpr void extend(float v) {
    lower = v < lower ? v : lower;
    upper = v > upper ? v : upper;
  }
  EXA_HOST_DEVICE constexpr void extend(const range1f& r) {
    lower = r.lower < lower ? r.lower : lower;
    upper = r.upper > upper ? r.upper : upper;
  }
  friend constexpr bool operator==(const range1f& a, const range1f& b) = default;
};

/// World placement of the integer lattice: world = origin + scale * lattice, scale being the
/// world size of one finest-level lattice unit per axis.
struct WorldTransform {
  vec3d origin{0.0};
  vec3d scale{1.0};
  EXA_HOST_DEVICE vec3d toWorld(const vec3d& lattice) const { return origin + scale * lattice; }
  EXA_HOST_DEVICE vec3d toLattice(const vec3d& world) const { return (world - origin) / scale; }
  /// A lattice box in world coordinates.
  template <typename T> EXA_HOST_DEVICE box3d toWorld(const box3<T>& lattice) const {
    return box3d(toWorld(vec3d(lattice.lower)), toWorld(vec3d(lattice.upper)));
  }
  bool isIdentity() const { return origin == vec3d(0.0) && scale == vec3d(1.0); }
  friend bool operator==(const WorldTransform& a, const WorldTransform& b) = default;
};

} // namespace exa
