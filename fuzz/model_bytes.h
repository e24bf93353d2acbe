// The model file's framing for the model fuzz target and its seed writer: the payload checksum
// (FNV-1a over little-endian 64-bit words, the tail zero-padded, as src/io/model_file.cpp
// computes it) and a header made to match a payload, so that mutated payloads reach the reader's
// consistency checks instead of stopping at the checksum.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>

namespace fuzz {

constexpr size_t kModelHeaderBytes = 48;

inline uint64_t modelChecksum(const char* p, size_t n) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; i += 8) {
    uint64_t word = 0;
    for (size_t k = 0; k < 8 && i + k < n; ++k)
      word |= uint64_t(static_cast<unsigned char>(p[i + k])) << (8 * k);
    h = (h ^ word) * 0x100000001b3ull;
  }
  return h;
}

/// `bytes` with the header's payload size (bytes 16..23) and checksum (24..31) set to match the
/// payload after the 48-byte header; unchanged when shorter than a header.
inline std::string sealModel(std::string bytes) {
  if (bytes.size() < kModelHeaderBytes) return bytes;
  const uint64_t payload = bytes.size() - kModelHeaderBytes;
  const uint64_t sum = modelChecksum(bytes.data() + kModelHeaderBytes, size_t(payload));
  for (int k = 0; k < 8; ++k) {
    bytes[size_t(16 + k)] = char((payload >> (8 * k)) & 0xff);
    bytes[size_t(24 + k)] = char((sum >> (8 * k)) & 0xff);
  }
  return bytes;
}

} // namespace fuzz
