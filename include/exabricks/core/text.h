// Numbers and text given by people (options, request parameters) and written for them.
#pragma once

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

namespace exa {

/// The finite number the whole of `text` spells (leading white space allowed, nothing after it);
/// false otherwise (no number, trailing characters, out of range, infinite or NaN).
inline bool parseFiniteNumber(const std::string& text, double& value) {
  size_t used = 0;
  try {
    value = std::stod(text, &used);
  } catch (...) {
    return false;
  }
  return used > 0 && used == text.size() && std::isfinite(value);
}

/// Where a finite `value` is too large for single precision (the renderer's numbers): "1e+40 is
/// beyond single precision (at most 3.4e+38 in magnitude)"; else "".
inline std::string beyondSinglePrecision(double value) {
  if (!std::isfinite(value) || std::abs(value) <= double(std::numeric_limits<float>::max())) return {};
  char buf[64];
  const char* end = std::to_chars(buf, buf + sizeof(buf), value).ptr;
  return std::string(static_cast<const char*>(buf), end) + " is beyond single precision (at most 3.4e+38 in magnitude)";
}

/// `value` as people write it when it holds a single-precision number: the double nearest the
/// shortest decimal that reads back as the same float (0.30000001192092896 becomes 0.3). A value
/// that is no float, or whose own shortest form has at most 9 significant digits (a double people
/// chose), is returned as it is.
inline double withoutFloatNoise(double value) {
  if (!std::isfinite(value) || double(float(value)) != value) return value;
  char buf[64];
  const char* end = std::to_chars(buf, buf + sizeof(buf), value).ptr;
  int digits = 0;
  for (const char* p = buf; p < end && *p != 'e'; ++p)
    if (*p >= '0' && *p <= '9' && (digits > 0 || *p != '0')) ++digits;
  if (digits <= 9) return value;
  end = std::to_chars(buf, buf + sizeof(buf), float(value)).ptr;
  return std::strtod(std::string(static_cast<const char*>(buf), end).c_str(), nullptr);
}

/// A size in bytes as people write it: "2G", "512M", "1.5GiB", "64MB", "300k", "1000000" (K, M,
/// G, T are powers of 1024, with or without "B" or "iB"; a bare number is bytes). False for
/// anything else, or a size that is not a positive whole number of bytes below 2^63.
inline bool parseByteSize(const std::string& text, uint64_t& bytes) {
  size_t used = 0;
  double number = 0;
  try {
    number = std::stod(text, &used);
  } catch (...) {
    return false;
  }
  if (used == 0 || !std::isfinite(number) || number <= 0) return false;
  std::string unit = text.substr(used);
  for (char& c : unit)
    c = char(std::toupper(static_cast<unsigned char>(c)));
  double scale = 1;
  if (!unit.empty() && unit != "B") {
    const std::string prefixes = "KMGT";
    const size_t k = prefixes.find(unit[0]);
    if (k == std::string::npos || !(unit.size() == 1 || unit.substr(1) == "B" || unit.substr(1) == "IB")) return false;
    scale = std::ldexp(1.0, 10 * int(k + 1));
  }
  const double value = std::round(number * scale);
  if (!(value >= 1 && value < std::ldexp(1.0, 63))) return false;
  bytes = uint64_t(value);
  return true;
}

/// A size in bytes for people: "512 B", "3.2 MiB", "1.50 GiB" (three significant digits).
inline std::string formatBytes(uint64_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = double(bytes);
  int u = 0;
  while (v >= 1024 && u < 4)
    v /= 1024, ++u;
  char buf[32];
  std::snprintf(buf, sizeof buf,
                u == 0    ? "%.0f %s"
                : v < 10  ? "%.2f %s"
                : v < 100 ? "%.1f %s"
                          : "%.0f %s",
                v, units[u]);
  return buf;
}

} // namespace exa
