// Images: linear-RGB, premultiplied-alpha float pixels, row 0 at the top; written as 8-bit sRGB
// PNG (with alpha, or composited over a background colour) or as float PFM.
#pragma once

#include "exabricks/render/transfer_function.h"

#include <string>
#include <vector>

namespace exa {

struct Image {
  int width = 0, height = 0;
  std::vector<vec4f> pixels; ///< width * height, row-major, row 0 at the top

  Image() = default;
  Image(int w, int h) : width(w), height(h), pixels(size_t(w) * size_t(h)) {}
  vec4f& at(int x, int y) { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
  const vec4f& at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

/// Linear -> sRGB transfer for one channel in [0, 1].
float linearToSrgb(float c);
float srgbToLinear(float c);

/// Writes an 8-bit sRGB PNG atomically. With keepAlpha the PNG has an alpha channel
/// (un-premultiplied colour); otherwise pixels are composited over `background` (linear RGB).
void writePng(const std::string& path, const Image& image, bool keepAlpha,
              const vec3f& background = vec3f(0.f));

/// Writes the RGB channels (composited over `background`) as a little-endian float PFM, atomically.
void writePfm(const std::string& path, const Image& image, const vec3f& background = vec3f(0.f));

/// Reads an 8-bit PNG back to linear premultiplied pixels (for regression tests).
Image readPng(const std::string& path);

/// Reads a PFM written by writePfm (alpha 1).
Image readPfm(const std::string& path);

} // namespace exa
