// Byte-order decoding shared by the binary readers (meshes, VTK, AMReX FABs) and image files.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace exa::io {

/// Whether data stored in the given byte order must be swapped on this host.
constexpr bool needsSwap(bool storedBigEndian) {
  return storedBigEndian ? std::endian::native != std::endian::big : std::endian::native != std::endian::little;
}

/// A value of type T read from unaligned bytes, swapped when `swap`.
template <typename T> T loadScalar(const unsigned char* p, bool swap) {
  unsigned char bytes[sizeof(T)];
  if (swap)
    for (size_t i = 0; i < sizeof(T); ++i)
      bytes[i] = p[sizeof(T) - 1 - i];
  else
    std::memcpy(bytes, p, sizeof(T));
  T v;
  std::memcpy(&v, bytes, sizeof(T));
  return v;
}

/// An unsigned integer of `size` bytes (1..8) in the given byte order.
inline uint64_t loadUnsigned(const unsigned char* p, size_t size, bool storedBigEndian) {
  uint64_t v = 0;
  for (size_t i = 0; i < size; ++i)
    v |= uint64_t(p[storedBigEndian ? size - 1 - i : i]) << (8 * i);
  return v;
}

} // namespace exa::io
