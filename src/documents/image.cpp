#include "exabricks/documents/image.h"

#include "exabricks/core/error.h"
#include "exabricks/core/files.h"

#include "exabricks/core/byte_order.h"

// Debian's libstb ships the stb implementations compiled into libstb.so, so only the
// declarations are included here (no STB_*_IMPLEMENTATION).
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace exa {

namespace {

/// Nearest 8-bit value of v in [0, 1] (clamped; NaN gives 0).
unsigned char toByte(float v) {
  if (!(v > 0.f)) return 0;
  if (v >= 1.f) return 255;
  return (unsigned char)std::lround(v * 255.f);
}

void appendBytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<unsigned char>*>(context);
  const auto* p = static_cast<const unsigned char*>(data);
  out->insert(out->end(), p, p + size);
}

void checkImage(const std::string& path, const Image& image) {
  if (image.width < 1 || image.height < 1 || image.pixels.size() != size_t(image.width) * size_t(image.height))
    fail(path, ": cannot write an empty or inconsistent image (", image.width, "x", image.height, ", ",
         image.pixels.size(), " pixels)");
}

/// Linear RGB of a premultiplied pixel over an opaque background.
vec3f over(const vec4f& p, const vec3f& background) {
  const float rest = 1.f - std::clamp(p.w, 0.f, 1.f);
  return {p.x + rest * background.x, p.y + rest * background.y, p.z + rest * background.z};
}

void appendLittleEndian(std::vector<char>& out, float f) {
  // Bytes of the little-endian form: loading them with the host's swap rule gives them back.
  const uint32_t bits = std::bit_cast<uint32_t>(f);
  unsigned char host[4];
  std::memcpy(host, &bits, 4);
  const uint32_t le = io::loadScalar<uint32_t>(host, io::needsSwap(false));
  char b[4];
  std::memcpy(b, &le, 4);
  out.insert(out.end(), b, b + 4);
}

} // namespace

unsigned char srgbByte(float linear) {
  // The byte toByte(linearToSrgb(c)) would give, without a pow per channel: the function is
  // non-decreasing in c, so the byte is the number of thresholds at or below c, where threshold k
  // is the smallest float whose byte is k (found once by bisection over the float bit patterns).
  static const std::array<float, 256> thresholds = [] {
    std::array<float, 256> t{};
    t[0] = -std::numeric_limits<float>::infinity();
    for (int k = 1; k < 256; ++k) {
      uint32_t lo = 0, hi = std::bit_cast<uint32_t>(1.f); // byte(lo) < k <= byte(hi) = 255
      while (hi - lo > 1) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (toByte(linearToSrgb(std::bit_cast<float>(mid))) >= k)
          hi = mid;
        else
          lo = mid;
      }
      t[size_t(k)] = std::bit_cast<float>(hi);
    }
    return t;
  }();
  if (!(linear > 0.f)) return 0; // also NaN
  return (unsigned char)(std::upper_bound(thresholds.begin() + 1, thresholds.end(), linear) - thresholds.begin() - 1);
}

std::vector<unsigned char> toSrgb8(const Image& image, const vec3f& background) {
  std::vector<unsigned char> bytes(image.pixels.size() * 3);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, image.pixels.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const vec3f c = over(image.pixels[i], background);
      bytes[3 * i] = srgbByte(c.x);
      bytes[3 * i + 1] = srgbByte(c.y);
      bytes[3 * i + 2] = srgbByte(c.z);
    }
  });
  return bytes;
}

std::vector<unsigned char> encodePng(const Image& image, bool keepAlpha, const vec3f& background) {
  checkImage("PNG image", image);
  const int channels = keepAlpha ? 4 : 3;
  std::vector<unsigned char> bytes;
  if (keepAlpha) {
    bytes.resize(image.pixels.size() * 4);
    for (size_t i = 0; i < image.pixels.size(); ++i) {
      // PNG alpha is straight (not premultiplied); a transparent pixel has no colour to keep.
      const vec4f& p = image.pixels[i];
      unsigned char* out = bytes.data() + i * 4;
      const float a = std::isnan(p.w) ? 0.f : std::clamp(p.w, 0.f, 1.f);
      const float inv = a > 0.f ? 1.f / a : 0.f;
      out[0] = srgbByte(p.x * inv);
      out[1] = srgbByte(p.y * inv);
      out[2] = srgbByte(p.z * inv);
      out[3] = toByte(a);
    }
  } else {
    bytes = toSrgb8(image, background);
  }
  std::vector<unsigned char> png;
  if (!stbi_write_png_to_func(appendBytes, &png, image.width, image.height, channels, bytes.data(),
                              image.width * channels))
    fail("PNG encoding failed");
  return png;
}

void writePng(const std::string& path, const Image& image, bool keepAlpha, const vec3f& background) {
  checkImage(path, image);
  const std::vector<unsigned char> png = encodePng(image, keepAlpha, background);
  writeFileAtomic(path, png.data(), png.size());
}

void writeJpeg(const std::string& path, const Image& image, const vec3f& background, int quality) {
  checkImage(path, image);
  if (quality < 1 || quality > 100) fail(path, ": JPEG quality ", quality, " is outside 1..100");
  const std::vector<unsigned char> bytes = toSrgb8(image, background);
  std::vector<unsigned char> jpeg;
  if (!stbi_write_jpg_to_func(appendBytes, &jpeg, image.width, image.height, 3, bytes.data(), quality))
    fail(path, ": JPEG encoding failed");
  writeFileAtomic(path, jpeg.data(), jpeg.size());
}

void writePfm(const std::string& path, const Image& image, const vec3f& background) {
  checkImage(path, image);
  // A negative scale marks little-endian data.
  const std::string header = "PF\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n-1.0\n";
  std::vector<char> out(header.begin(), header.end());
  out.reserve(header.size() + image.pixels.size() * 12);
  // PFM stores rows bottom to top.
  for (int y = image.height - 1; y >= 0; --y)
    for (int x = 0; x < image.width; ++x) {
      const vec3f c = over(image.at(x, y), background);
      appendLittleEndian(out, c.x);
      appendLittleEndian(out, c.y);
      appendLittleEndian(out, c.z);
    }
  writeFileAtomic(path, out.data(), out.size());
}

Image readPng(const std::string& path) {
  const std::vector<char> file = readFile(path);
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (file.size() < 8 || std::memcmp(file.data(), signature, 8) != 0) fail(path, ": not a PNG file");
  if (file.size() > size_t(INT32_MAX)) fail(path, ": PNG file too large");
  int w = 0, h = 0, n = 0;
  unsigned char* data =
      stbi_load_from_memory(reinterpret_cast<const unsigned char*>(file.data()), int(file.size()), &w, &h, &n, 4);
  if (!data) {
    const char* why = stbi_failure_reason();
    fail(path, ": cannot decode PNG: ", why ? why : "unknown error");
  }
  Image image(w, h);
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const unsigned char* p = data + 4 * i;
    const float a = float(p[3]) / 255.f;
    image.pixels[i] = {srgbToLinear(float(p[0]) / 255.f) * a, srgbToLinear(float(p[1]) / 255.f) * a,
                       srgbToLinear(float(p[2]) / 255.f) * a, a};
  }
  stbi_image_free(data);
  return image;
}

Image readPfm(const std::string& path) {
  const std::vector<char> bytes = readFile(path);
  size_t pos = 0;
  auto token = [&]() {
    while (pos < bytes.size() && std::isspace((unsigned char)bytes[pos]))
      ++pos;
    const size_t start = pos;
    while (pos < bytes.size() && !std::isspace((unsigned char)bytes[pos]))
      ++pos;
    return std::string(bytes.data() + start, bytes.data() + pos);
  };
  const std::string magic = token();
  if (magic != "PF" && magic != "Pf") fail(path, ": not a PFM file (no PF or Pf header)");
  const int channels = magic == "PF" ? 3 : 1;
  long long w = 0, h = 0;
  double scale = 0;
  try {
    size_t used = 0;
    const std::string ws = token(), hs = token(), ss = token();
    w = std::stoll(ws, &used);
    if (used != ws.size()) throw std::invalid_argument(ws);
    h = std::stoll(hs, &used);
    if (used != hs.size()) throw std::invalid_argument(hs);
    scale = std::stod(ss, &used);
    if (used != ss.size()) throw std::invalid_argument(ss);
  } catch (const std::logic_error&) {
    fail(path, ": corrupt PFM header");
  }
  if (w < 1 || h < 1 || w > 32768 || h > 32768 || !std::isfinite(scale) || scale == 0)
    fail(path, ": corrupt PFM header (", w, "x", h, ", scale ", scale, ")");
  // Exactly one whitespace character separates the header from the data.
  if (pos >= bytes.size()) fail(path, ": truncated PFM data");
  ++pos;
  const size_t needed = size_t(w) * size_t(h) * size_t(channels) * 4;
  if (bytes.size() - pos < needed)
    fail(path, ": truncated PFM data (", bytes.size() - pos, " bytes, ", needed, " needed)");
  // The sign of the scale gives the byte order: negative little-endian, positive big-endian.
  const bool swap = io::needsSwap(scale > 0);
  auto next = [&]() {
    const float v = io::loadScalar<float>(reinterpret_cast<const unsigned char*>(bytes.data() + pos), swap);
    pos += 4;
    return v;
  };
  Image image{int(w), int(h)};
  for (int y = int(h) - 1; y >= 0; --y)
    for (int x = 0; x < int(w); ++x) {
      const float r = next();
      const float g = channels == 3 ? next() : r;
      const float b = channels == 3 ? next() : r;
      image.at(x, y) = {r, g, b, 1.f};
    }
  return image;
}

} // namespace exa
