#include "exabricks/io/image.h"

#include "exabricks/core/error.h"
#include "exabricks/io/native.h"

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <cmath>
#include <cstdio>
#include <cstring>

namespace exa {

float linearToSrgb(float c) {
  c = std::clamp(c, 0.f, 1.f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.f / 2.4f) - 0.055f;
}

float srgbToLinear(float c) {
  c = std::clamp(c, 0.f, 1.f);
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

namespace {

unsigned char toByte(float v) { return (unsigned char)std::lround(std::clamp(v, 0.f, 1.f) * 255.f); }

void appendBytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<unsigned char>*>(context);
  const auto* p = static_cast<const unsigned char*>(data);
  out->insert(out->end(), p, p + size);
}

void checkImage(const std::string& path, const Image& image) {
  if (image.width < 1 || image.height < 1 ||
      image.pixels.size() != size_t(image.width) * size_t(image.height))
    fail(path, ": cannot write an empty or inconsistent image");
}

} // namespace

void writePng(const std::string& path, const Image& image, bool keepAlpha, const vec3f& background) {
  checkImage(path, image);
  const int channels = keepAlpha ? 4 : 3;
  std::vector<unsigned char> bytes(image.pixels.size() * size_t(channels));
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const vec4f& p = image.pixels[i];
    unsigned char* out = bytes.data() + i * size_t(channels);
    if (keepAlpha) {
      const float a = std::clamp(p.w, 0.f, 1.f);
      const float inv = a > 0.f ? 1.f / a : 0.f;
      out[0] = toByte(linearToSrgb(p.x * inv));
      out[1] = toByte(linearToSrgb(p.y * inv));
      out[2] = toByte(linearToSrgb(p.z * inv));
      out[3] = toByte(a);
    } else {
      const float rest = 1.f - std::clamp(p.w, 0.f, 1.f);
      out[0] = toByte(linearToSrgb(p.x + rest * background.x));
      out[1] = toByte(linearToSrgb(p.y + rest * background.y));
      out[2] = toByte(linearToSrgb(p.z + rest * background.z));
    }
  }
  std::vector<unsigned char> png;
  if (!stbi_write_png_to_func(appendBytes, &png, image.width, image.height, channels, bytes.data(),
                              image.width * channels))
    fail(path, ": PNG encoding failed");
  writeFileAtomic(path, png.data(), png.size());
}

void writePfm(const std::string& path, const Image& image, const vec3f& background) {
  checkImage(path, image);
  const std::string header = "PF\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n-1.0\n";
  std::vector<char> out(header.begin(), header.end());
  out.reserve(header.size() + image.pixels.size() * 12);
  // PFM stores rows bottom to top.
  for (int y = image.height - 1; y >= 0; --y)
    for (int x = 0; x < image.width; ++x) {
      const vec4f& p = image.at(x, y);
      const float rest = 1.f - std::clamp(p.w, 0.f, 1.f);
      const float rgb[3] = {p.x + rest * background.x, p.y + rest * background.y, p.z + rest * background.z};
      const char* b = reinterpret_cast<const char*>(rgb);
      out.insert(out.end(), b, b + sizeof rgb);
    }
  writeFileAtomic(path, out.data(), out.size());
}

Image readPng(const std::string& path) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 4);
  if (!data) fail(path, ": cannot read PNG: ", stbi_failure_reason() ? stbi_failure_reason() : "unknown error");
  Image image(w, h);
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const unsigned char* p = data + 4 * i;
    const float a = p[3] / 255.f;
    image.pixels[i] = {srgbToLinear(p[0] / 255.f) * a, srgbToLinear(p[1] / 255.f) * a,
                       srgbToLinear(p[2] / 255.f) * a, a};
  }
  stbi_image_free(data);
  return image;
}

Image readPfm(const std::string& path) {
  const std::vector<char> bytes = readFile(path);
  size_t pos = 0;
  auto token = [&]() {
    while (pos < bytes.size() && std::isspace((unsigned char)bytes[pos])) ++pos;
    const size_t start = pos;
    while (pos < bytes.size() && !std::isspace((unsigned char)bytes[pos])) ++pos;
    return std::string(bytes.data() + start, bytes.data() + pos);
  };
  if (token() != "PF") fail(path, ": not an RGB PFM file");
  int w = 0, h = 0;
  double scale = 0;
  try {
    w = std::stoi(token());
    h = std::stoi(token());
    scale = std::stod(token());
  } catch (...) {
    fail(path, ": corrupt PFM header");
  }
  ++pos; // the single whitespace after the scale
  if (w < 1 || h < 1 || w > 32768 || h > 32768 || scale == 0) fail(path, ": corrupt PFM header");
  if (bytes.size() - pos < size_t(w) * size_t(h) * 12) fail(path, ": truncated PFM data");
  const bool bigEndian = scale > 0;
  Image image(w, h);
  for (int y = h - 1; y >= 0; --y)
    for (int x = 0; x < w; ++x) {
      float rgb[3];
      for (float& c : rgb) {
        unsigned char b[4];
        std::memcpy(b, bytes.data() + pos, 4);
        if (bigEndian) std::swap(b[0], b[3]), std::swap(b[1], b[2]);
        std::memcpy(&c, b, 4);
        pos += 4;
      }
      image.at(x, y) = {rgb[0], rgb[1], rgb[2], 1.f};
    }
  return image;
}

} // namespace exa
