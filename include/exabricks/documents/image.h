// Image files: images (core/image.h) written as 8-bit or 16-bit sRGB PNG (with alpha, or
// composited over a background colour), JPEG, float PFM or OpenEXR (linear, premultiplied alpha),
// and the 8-bit PNG and PFM read back.
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

/// A 16-bit sRGB PNG in memory: RGBA with straight alpha (keepAlpha), else RGB composited over
/// `background` (linear RGB).
std::vector<unsigned char> encodePng16(const Image& image, bool keepAlpha, const vec3f& background = vec3f(0.f));
/// Writes a 16-bit sRGB PNG atomically (encodePng16).
void writePng16(const std::string& path, const Image& image, bool keepAlpha, const vec3f& background = vec3f(0.f));

/// An OpenEXR file in memory: the image as it is (linear RGB, premultiplied by alpha, for
/// compositing), four 32-bit float channels A, B, G, R in uncompressed scan lines.
std::vector<unsigned char> encodeExr(const Image& image);
/// Writes an OpenEXR file atomically (encodeExr).
void writeExr(const std::string& path, const Image& image);

/// The image file formats a picture is saved in.
enum class ImageFormat { Png, Png16, Jpeg, Exr, Pfm };
/// The format of an output path by its extension (.png: 8 or 16 bits as `pngBits` says, .jpg /
/// .jpeg, .exr, .pfm; no extension: PNG); throws exa::UsageError naming the path otherwise, or
/// when `pngBits` is neither 8 nor 16.
ImageFormat imageFormatFor(const std::string& path, int pngBits = 8);
/// Whether the format keeps alpha (PNG when asked, OpenEXR always).
bool formatKeepsAlpha(ImageFormat format);
/// Writes the image in the format: PNG with alpha (keepAlpha) or over `background`; JPEG and PFM
/// over `background`; OpenEXR as it is (premultiplied alpha).
void writeImage(const std::string& path, const Image& image, ImageFormat format, bool keepAlpha,
                const vec3f& background = vec3f(0.f));

/// Reads an 8-bit PNG back to linear premultiplied pixels (for regression tests).
Image readPng(const std::string& path);

/// Reads a PFM written by writePfm (alpha 1).
Image readPfm(const std::string& path);

} // namespace exa
