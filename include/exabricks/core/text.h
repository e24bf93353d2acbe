// Reading numbers from text given by people (options, request parameters).
#pragma once

#include <cmath>
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

} // namespace exa
