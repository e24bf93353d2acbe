// Numbers and text given by people (options, request parameters) and written for them.
#pragma once

#include <charconv>
#include <cmath>
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

} // namespace exa
