// Images with more than 8 bits per channel: 16-bit sRGB PNG and OpenEXR (linear, premultiplied
// alpha, 32-bit float channels, uncompressed scan lines), for printing and for compositing.
#include "exabricks/documents/image.h"

#include "exabricks/core/color.h"
#include "exabricks/core/error.h"
#include "exabricks/core/files.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

namespace exa {
namespace {

void checkSize(const std::string& what, const Image& image) {
  if (image.width < 1 || image.height < 1 || image.pixels.size() != size_t(image.width) * size_t(image.height))
    fail(what, ": cannot write an empty or inconsistent image (", image.width, "x", image.height, ")");
}

/// Nearest 16-bit value of v in [0, 1] (clamped; NaN gives 0).
uint16_t toWord(float v) {
  if (!(v > 0.f)) return 0;
  if (v >= 1.f) return 65535;
  return uint16_t(std::lround(double(v) * 65535.0));
}

void putBig32(std::vector<unsigned char>& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8)
    out.push_back(static_cast<unsigned char>(v >> shift));
}

void pngChunk(std::vector<unsigned char>& png, const char type[4], const std::vector<unsigned char>& data) {
  putBig32(png, uint32_t(data.size()));
  const size_t start = png.size();
  png.insert(png.end(), type, type + 4);
  png.insert(png.end(), data.begin(), data.end());
  const uLong crc = crc32(0L, png.data() + start, uInt(png.size() - start));
  putBig32(png, uint32_t(crc));
}

/// The scan lines of a 16-bit PNG, each with filter byte 0, big-endian samples.
std::vector<unsigned char> png16Rows(const Image& image, bool keepAlpha, const vec3f& background) {
  const int channels = keepAlpha ? 4 : 3;
  const size_t rowBytes = 1 + size_t(image.width) * size_t(channels) * 2;
  std::vector<unsigned char> rows(rowBytes * size_t(image.height));
  for (int y = 0; y < image.height; ++y) {
    unsigned char* out = rows.data() + size_t(y) * rowBytes;
    *out++ = 0;
    for (int x = 0; x < image.width; ++x) {
      const vec4f& p = image.pixels[size_t(y) * size_t(image.width) + size_t(x)];
      const float a = std::isnan(p.w) ? 0.f : std::clamp(p.w, 0.f, 1.f);
      vec3f c;
      if (keepAlpha) { // straight alpha, as PNG defines it
        const float inv = a > 0.f ? 1.f / a : 0.f;
        c = vec3f(p.x * inv, p.y * inv, p.z * inv);
      } else {
        c = vec3f(p.x + (1.f - a) * background.x, p.y + (1.f - a) * background.y, p.z + (1.f - a) * background.z);
      }
      const uint16_t v[4] = {toWord(linearToSrgb(c.x)), toWord(linearToSrgb(c.y)), toWord(linearToSrgb(c.z)),
                             toWord(a)};
      for (int k = 0; k < channels; ++k) {
        *out++ = static_cast<unsigned char>(v[k] >> 8);
        *out++ = static_cast<unsigned char>(v[k] & 255u);
      }
    }
  }
  return rows;
}

template <typename T> void putLittle(std::vector<unsigned char>& out, T value) {
  static_assert(std::is_trivially_copyable_v<T>);
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
  out.insert(out.end(), b, b + sizeof(T));
}

void exrAttribute(std::vector<unsigned char>& out, const char* name, const char* type,
                  const std::vector<unsigned char>& value) {
  out.insert(out.end(), name, name + std::strlen(name) + 1);
  out.insert(out.end(), type, type + std::strlen(type) + 1);
  putLittle<int32_t>(out, int32_t(value.size()));
  out.insert(out.end(), value.begin(), value.end());
}

/// The header of a single-part scan-line file with channels A, B, G, R (32-bit float).
std::vector<unsigned char> exrHeader(const Image& image) {
  std::vector<unsigned char> h = {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0};
  std::vector<unsigned char> channels;
  for (const char* name : {"A", "B", "G", "R"}) { // alphabetical, as the format requires
    channels.insert(channels.end(), name, name + 2);
    putLittle<int32_t>(channels, 2); // FLOAT
    for (int k = 0; k < 4; ++k)
      channels.push_back(0); // pLinear, reserved
    putLittle<int32_t>(channels, 1);
    putLittle<int32_t>(channels, 1);
  }
  channels.push_back(0);
  exrAttribute(h, "channels", "chlist", channels);
  exrAttribute(h, "compression", "compression", {0}); // none
  std::vector<unsigned char> window;
  for (int32_t v : {0, 0, image.width - 1, image.height - 1})
    putLittle<int32_t>(window, v);
  exrAttribute(h, "dataWindow", "box2i", window);
  exrAttribute(h, "displayWindow", "box2i", window);
  exrAttribute(h, "lineOrder", "lineOrder", {0}); // increasing y
  std::vector<unsigned char> one, center;
  putLittle<float>(one, 1.f);
  putLittle<float>(center, 0.f);
  putLittle<float>(center, 0.f);
  exrAttribute(h, "pixelAspectRatio", "float", one);
  exrAttribute(h, "screenWindowCenter", "v2f", center);
  exrAttribute(h, "screenWindowWidth", "float", one);
  h.push_back(0); // end of the header
  return h;
}

} // namespace

std::vector<unsigned char> encodePng16(const Image& image, bool keepAlpha, const vec3f& background) {
  checkSize("16-bit PNG image", image);
  const std::vector<unsigned char> rows = png16Rows(image, keepAlpha, background);
  uLongf packedSize = compressBound(uLong(rows.size()));
  std::vector<unsigned char> packed(packedSize);
  if (compress2(packed.data(), &packedSize, rows.data(), uLong(rows.size()), 6) != Z_OK)
    fail("16-bit PNG encoding failed (zlib)");
  packed.resize(packedSize);
  std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<unsigned char> header;
  putBig32(header, uint32_t(image.width));
  putBig32(header, uint32_t(image.height));
  header.insert(header.end(), {16, static_cast<unsigned char>(keepAlpha ? 6 : 2), 0, 0, 0});
  pngChunk(png, "IHDR", header);
  pngChunk(png, "IDAT", packed);
  pngChunk(png, "IEND", {});
  return png;
}

void writePng16(const std::string& path, const Image& image, bool keepAlpha, const vec3f& background) {
  checkSize(path, image);
  const std::vector<unsigned char> png = encodePng16(image, keepAlpha, background);
  writeFileAtomic(path, png.data(), png.size());
}

std::vector<unsigned char> encodeExr(const Image& image) {
  checkSize("OpenEXR image", image);
  std::vector<unsigned char> exr = exrHeader(image);
  const size_t w = size_t(image.width);
  const size_t blockBytes = 8 + 16 * w; // y, size, then four channels of floats
  uint64_t offset = exr.size() + 8 * size_t(image.height);
  for (int y = 0; y < image.height; ++y, offset += blockBytes)
    putLittle<uint64_t>(exr, offset);
  exr.reserve(exr.size() + blockBytes * size_t(image.height));
  for (int y = 0; y < image.height; ++y) {
    putLittle<int32_t>(exr, y);
    putLittle<int32_t>(exr, int32_t(16 * w));
    const vec4f* row = image.pixels.data() + size_t(y) * w;
    for (float vec4f::*channel : {&vec4f::w, &vec4f::z, &vec4f::y, &vec4f::x}) // A, B, G, R
      for (size_t x = 0; x < w; ++x)
        putLittle<float>(exr, row[x].*channel);
  }
  return exr;
}

ImageFormat imageFormatFor(const std::string& path, int pngBits) {
  if (pngBits != 8 && pngBits != 16) failUsage("PNG bits must be 8 or 16, not ", pngBits);
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext)
    c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".png" || ext.empty()) return pngBits == 16 ? ImageFormat::Png16 : ImageFormat::Png;
  if (ext == ".jpg" || ext == ".jpeg") return ImageFormat::Jpeg;
  if (ext == ".exr") return ImageFormat::Exr;
  if (ext == ".pfm") return ImageFormat::Pfm;
  failUsage(path, ": unknown image format '", ext, "' (write .png, .jpg, .jpeg, .exr or .pfm)");
}

bool formatKeepsAlpha(ImageFormat format) {
  return format == ImageFormat::Png || format == ImageFormat::Png16 || format == ImageFormat::Exr;
}

void writeImage(const std::string& path, const Image& image, ImageFormat format, bool keepAlpha,
                const vec3f& background) {
  switch (format) {
  case ImageFormat::Png:
    return writePng(path, image, keepAlpha, background);
  case ImageFormat::Png16:
    return writePng16(path, image, keepAlpha, background);
  case ImageFormat::Jpeg:
    return writeJpeg(path, image, background);
  case ImageFormat::Exr:
    return writeExr(path, image);
  case ImageFormat::Pfm:
    return writePfm(path, image, background);
  }
}

void writeExr(const std::string& path, const Image& image) {
  checkSize(path, image);
  const std::vector<unsigned char> exr = encodeExr(image);
  writeFileAtomic(path, exr.data(), exr.size());
}

} // namespace exa
