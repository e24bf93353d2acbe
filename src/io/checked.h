// Bounds on what a file declares, checked before anything is converted or allocated: integers
// from numbers stored as text or floating point, declared sizes against the bytes present, and
// allocations that name the file and the size when memory runs out. Every reader uses these.
#pragma once

#include "exabricks/core/error.h"

#include <cmath>
#include <cstdint>
#include <new>
#include <string>
#include <vector>

namespace exa::io {

/// The largest factor by which zlib's deflate shrinks data (1032:1 for long runs), rounded up:
/// a compressed block of n bytes never inflates to more than kMaxInflate * n + kMaxInflate.
constexpr uint64_t kMaxInflate = 1040;

/// True when `v` is an integer within [lo, hi] (false for NaN and infinities); stores it in
/// `out`. Nothing outside the range reaches the conversion.
inline bool integerIn(double v, int64_t lo, int64_t hi, int64_t& out) {
  if (!(v >= double(lo) && v <= double(hi)) || v != std::floor(v) || v >= 9223372036854775808.0) return false;
  out = int64_t(v);
  return out >= lo && out <= hi;
}

/// An integer read from a file: fails with "`what()` is V, not an integer in LO..HI" otherwise.
/// `what()` names the file, the record and the quantity.
template <typename What> int64_t checkedInteger(double v, int64_t lo, int64_t hi, What&& what) {
  int64_t out = 0;
  if (!integerIn(v, lo, hi, out)) fail(what(), " is ", v, ", not an integer in ", lo, "..", hi);
  return out;
}

/// a * b, or false when the product exceeds `limit` (both non-negative).
inline bool productWithin(uint64_t a, uint64_t b, uint64_t limit, uint64_t& out) {
  if (a != 0 && b > limit / a) return false;
  out = a * b;
  return out <= limit;
}

/// Cells of an extent (each axis >= 0), or false when the count exceeds `limit`.
inline bool cellCountWithin(int64_t x, int64_t y, int64_t z, uint64_t limit, uint64_t& out) {
  if (x < 0 || y < 0 || z < 0) return false;
  uint64_t xy = 0;
  return productWithin(uint64_t(x), uint64_t(y), limit, xy) && productWithin(xy, uint64_t(z), limit, out);
}

/// Fails unless `count` items of `itemBytes` bytes each fit in the `present` bytes of the file:
/// "WHERE: declares N values of B bytes (T bytes), but only P bytes are present". Overflow-safe.
void requireBytes(uint64_t count, uint64_t itemBytes, uint64_t present, const std::string& where);

/// Reports an allocation that failed: "WHERE: cannot allocate N bytes (out of memory)".
[[noreturn]] void failAllocation(uint64_t bytes, const std::string& where);

/// `n` value-initialised elements; running out of memory (or a size beyond what a vector can
/// hold) fails naming `where()` and the size.
template <typename T, typename Where> std::vector<T> allocate(uint64_t n, Where&& where) {
  if (n > std::vector<T>().max_size())
    failAllocation(n * double(sizeof(T)) > 1.8e19 ? UINT64_MAX : n * sizeof(T), where());
  try {
    return std::vector<T>(static_cast<size_t>(n));
  } catch (const std::bad_alloc&) {
    failAllocation(n * sizeof(T), where());
  } catch (const std::length_error&) {
    failAllocation(n * sizeof(T), where());
  }
}

/// Reserves room for `n` more elements, failing like allocate().
template <typename Container, typename Where> void reserveMore(Container& v, uint64_t n, Where&& where) {
  using T = typename Container::value_type;
  if (n > v.max_size() - v.size()) failAllocation(UINT64_MAX, where());
  try {
    v.reserve(v.size() + static_cast<size_t>(n));
  } catch (const std::bad_alloc&) {
    failAllocation((v.size() + n) * sizeof(T), where());
  } catch (const std::length_error&) {
    failAllocation((v.size() + n) * sizeof(T), where());
  }
}

} // namespace exa::io
