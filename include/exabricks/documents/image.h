// Image files: images (core/image.h) written as 8-bit sRGB PNG (with alpha, or composited over a
// background colour) or as float PFM, and read back.
#pragma once

#include "exabricks/core/image.h"

#include <string>
#include <vector>

namespace exa {

/// 8-bit sRGB RGB bytes of an image composited over `background` (linear RGB), row by row from
/// the top: what PNG (without alpha) and JPEG files hold.
std::vector<unsigned char> toSrgb8(const Image& image, const vec3f& background = vec3f(0.f));
/// One channel's 8-bit sRGB value, equal to rounding linearToSrgb(linear) * 255 (clamped; NaN 0).
unsigned char srgbByte(float linear);

/// An 8-bit sRGB PNG in memory, as writePng writes it.
std::vector<unsigned char> encodePng(const Image& image, bool keepAlpha, const vec3f& background = vec3f(0.f));

/// Writes an 8-bit sRGB PNG atomically. With keepAlpha the PNG has an alpha channel
/// (un-premultiplied colour); otherwise pixels are composited over `background` (linear RGB).
void writePng(const std::string& path, const Image& image, bool keepAlpha, const vec3f& background = vec3f(0.f));

/// Writes an 8-bit sRGB JPEG (composited over `background`) atomically.
void writeJpeg(const std::string& path, const Image& image, const vec3f& background = vec3f(0.f), int quality = 92);

/// Writes the RGB channels (composited over `background`) as a little-endian float PFM, atomically.
void writePfm(const std::string& path, const Image& image, const vec3f& background = vec3f(0.f));

/// Reads an 8-bit PNG back to linear premultiplied pixels (for regression tests).
Image readPng(const std::string& path);

/// Reads a PFM written by writePfm (alpha 1).
Image readPfm(const std::string& path);

} // namespace exa
