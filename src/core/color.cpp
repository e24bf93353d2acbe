#include "exabricks/core/color.h"

#include <cmath>

namespace exa {

float linearToSrgb(float c) {
  if (!(c > 0.f)) return 0.f; // also NaN
  if (c >= 1.f) return 1.f;
  const double d = c;
  return float(d <= 0.0031308 ? 12.92 * d : 1.055 * std::pow(d, 1.0 / 2.4) - 0.055);
}

float srgbToLinear(float c) {
  if (!(c > 0.f)) return 0.f;
  if (c >= 1.f) return 1.f;
  const double d = c;
  return float(d <= 0.04045 ? d / 12.92 : std::pow((d + 0.055) / 1.055, 2.4));
}

} // namespace exa
