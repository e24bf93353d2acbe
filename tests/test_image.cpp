// Image files: sRGB transfer against its defining formula, PNG round trips through 8-bit
// quantisation, exact PFM round trips and byte layout, and atomic writes.
#include "exabricks/core/color.h"
#include "exabricks/core/error.h"
#include "exabricks/documents/image.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <random>

using namespace exa;
namespace fs = std::filesystem;

namespace {

fs::path tmpDir() {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "image";
  fs::create_directories(dir);
  return dir;
}

std::string tmpPath(const std::string& name) { return (tmpDir() / name).string(); }

/// Premultiplied pixels with alpha from 0 to 1 across and colour varying down.
Image gradientImage() {
  Image img(17, 9);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float a = float(x) / 16.f;
      img.at(x, y) = {0.8f * a * float(y) / 8.f, 0.3f * a, 0.05f * a, a};
    }
  return img;
}

/// The 8-bit sRGB code a linear value was stored as (exact for what readPng returns).
float srgbCode(float linear) { return linearToSrgb(linear) * 255.f; }

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

size_t temporaryFilesIn(const fs::path& dir) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir))
    n += e.path().filename().string().find(".tmp") != std::string::npos;
  return n;
}

} // namespace

TEST(Image, SrgbTransferFollowsTheStandard) {
  // Independent double-precision formulas of IEC 61966-2-1.
  auto encode = [](double c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055; };
  auto decode = [](double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); };
  for (int i = 0; i <= 1000; ++i) {
    const double c = i / 1000.0;
    EXPECT_NEAR(linearToSrgb(float(c)), encode(c), 1e-6);
    EXPECT_NEAR(srgbToLinear(float(c)), decode(c), 1e-6);
    EXPECT_NEAR(srgbToLinear(linearToSrgb(float(c))), c, 1e-6);
  }
  EXPECT_EQ(linearToSrgb(0.f), 0.f);
  EXPECT_EQ(linearToSrgb(1.f), 1.f);
  EXPECT_EQ(srgbToLinear(1.f), 1.f);
  EXPECT_NEAR(linearToSrgb(0.5f), 0.735357f, 1e-5f);
  EXPECT_NEAR(srgbToLinear(0.5f), 0.214041f, 1e-5f);
  // The two pieces meet.
  EXPECT_NEAR(linearToSrgb(0.0031308f), 0.04045f, 1e-6f);
  // Outside [0, 1] clamps; NaN gives 0.
  EXPECT_EQ(linearToSrgb(-1.f), 0.f);
  EXPECT_EQ(linearToSrgb(7.f), 1.f);
  EXPECT_EQ(srgbToLinear(2.f), 1.f);
  EXPECT_EQ(linearToSrgb(NAN), 0.f);
}

TEST(Image, PngWithAlphaRoundTripsWithinQuantisation) {
  Image img = gradientImage();
  img.at(3, 3) = {0.4f, 0.2f, 0.1f, 0.f}; // transparent: no colour survives, and no NaN
  img.at(4, 3) = {2.f, -1.f, 0.5f, 0.5f}; // out-of-range colour clamps
  const std::string path = tmpPath("alpha.png");
  writePng(path, img, true);
  const Image back = readPng(path);
  ASSERT_EQ(back.width, img.width);
  ASSERT_EQ(back.height, img.height);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      SCOPED_TRACE(testing::Message() << x << "," << y);
      const vec4f& o = img.at(x, y);
      const vec4f& b = back.at(x, y);
      EXPECT_NEAR(b.w, o.w, 0.5f / 255.f + 1e-6f);
      if (o.w == 0.f) {
        EXPECT_EQ(b.x, 0.f);
        EXPECT_EQ(b.w, 0.f);
        continue;
      }
      // Un-premultiplied colour, compared in 8-bit sRGB codes: within half a step.
      for (int c = 0; c < 3; ++c) {
        const float original = std::clamp((&o.x)[c] / o.w, 0.f, 1.f);
        const float stored = (&b.x)[c] / b.w;
        EXPECT_NEAR(srgbCode(stored), srgbCode(original), 0.5f + 1e-3f) << "channel " << c;
        EXPECT_NEAR(srgbCode(stored), std::round(srgbCode(stored)), 1e-3f);
      }
    }
}

TEST(Image, PngOverBackgroundComposites) {
  Image img = gradientImage();
  const vec3f bg(0.2f, 0.4f, 0.6f);
  const std::string path = tmpPath("over.png");
  writePng(path, img, false, bg);
  const Image back = readPng(path);
  ASSERT_EQ(back.width, img.width);
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    const vec4f& o = img.pixels[i];
    const vec4f& b = back.pixels[i];
    EXPECT_EQ(b.w, 1.f);
    const float expect[3] = {o.x + (1 - o.w) * bg.x, o.y + (1 - o.w) * bg.y, o.z + (1 - o.w) * bg.z};
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(srgbCode((&b.x)[c]), srgbCode(expect[c]), 0.5f + 1e-3f) << i << " " << c;
  }
  // Fully transparent pixels show the background; opaque ones hide it.
  EXPECT_NEAR(srgbCode(back.at(0, 0).z), std::round(srgbCode(bg.z)), 1e-3f);
  EXPECT_NEAR(srgbCode(back.at(16, 0).z), std::round(srgbCode(img.at(16, 0).z)), 1e-3f);
  // Black background by default: the same pixels as premultiplied colour alone.
  writePng(path, img, false);
  const Image black = readPng(path);
  EXPECT_EQ(black.at(0, 4).x, 0.f);
  EXPECT_NEAR(srgbCode(black.at(16, 8).x), srgbCode(0.8f), 0.5f + 1e-3f);
}

TEST(Image, PfmRoundTripIsExactAndStoredBottomUp) {
  Image img = gradientImage();
  img.at(0, 0) = {12.5f, -3.f, 1e-30f, 1.f}; // floats keep HDR and negative values
  const std::string path = tmpPath("c.pfm");
  writePfm(path, img);
  const Image back = readPfm(path);
  ASSERT_EQ(back.width, img.width);
  ASSERT_EQ(back.height, img.height);
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    EXPECT_EQ(back.pixels[i].x, img.pixels[i].x);
    EXPECT_EQ(back.pixels[i].y, img.pixels[i].y);
    EXPECT_EQ(back.pixels[i].z, img.pixels[i].z);
    EXPECT_EQ(back.pixels[i].w, 1.f);
  }
  // Byte layout: header, then little-endian floats, the bottom row first.
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = "PF\n17 9\n-1.0\n";
  ASSERT_EQ(bytes.size(), header.size() + 17 * 9 * 12);
  EXPECT_EQ(bytes.substr(0, header.size()), header);
  auto floatAt = [&](size_t index) {
    const auto* p = reinterpret_cast<const unsigned char*>(bytes.data() + header.size() + 4 * index);
    const uint32_t bits = uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
  };
  EXPECT_EQ(floatAt(0), img.at(0, 8).x);       // first stored: bottom-left
  EXPECT_EQ(floatAt(3 * (17 * 8) + 0), 12.5f); // last row stored: the top one
  EXPECT_EQ(floatAt(3 * (17 * 8) + 1), -3.f);
  EXPECT_EQ(floatAt(3 * 5 + 1), img.at(5, 8).y);
  // Composited over the background like the PNG.
  writePfm(path, img, vec3f(1.f));
  EXPECT_FLOAT_EQ(readPfm(path).at(4, 2).y, img.at(4, 2).y + (1 - img.at(4, 2).w));
}

TEST(Image, PfmReadsBigEndianAndGreyscale) {
  // Written by hand: a 2x1 big-endian RGB file and a 1x2 little-endian greyscale one.
  auto be = [](float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    return std::string{char(b >> 24), char(b >> 16), char(b >> 8), char(b)};
  };
  auto le = [](float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    return std::string{char(b), char(b >> 8), char(b >> 16), char(b >> 24)};
  };
  const std::string rgb = "PF\n2 1\n1.0\n" + be(1.5f) + be(2.5f) + be(3.5f) + be(-1.f) + be(0.f) + be(0.25f);
  std::ofstream(tmpPath("be.pfm"), std::ios::binary) << rgb;
  const Image a = readPfm(tmpPath("be.pfm"));
  ASSERT_EQ(a.width, 2);
  ASSERT_EQ(a.height, 1);
  EXPECT_EQ(a.at(0, 0).y, 2.5f);
  EXPECT_EQ(a.at(1, 0).x, -1.f);
  EXPECT_EQ(a.at(1, 0).z, 0.25f);
  const std::string grey = "Pf\n1 2\n-1\n" + le(0.75f) + le(0.125f);
  std::ofstream(tmpPath("grey.pfm"), std::ios::binary) << grey;
  const Image g = readPfm(tmpPath("grey.pfm"));
  ASSERT_EQ(g.height, 2);
  EXPECT_EQ(g.at(0, 1).x, 0.75f); // bottom row first
  EXPECT_EQ(g.at(0, 0).z, 0.125f);
}

TEST(Image, FailedWritesLeaveNothing) {
  const std::string missing = tmpPath("missing/dir/x.png");
  const std::string m = errorOf([&] { writePng(missing, gradientImage(), false); });
  EXPECT_NE(m.find(missing), std::string::npos) << m;
  EXPECT_FALSE(fs::exists(tmpPath("missing")));
  EXPECT_THROW(writePfm(tmpPath("missing/x.pfm"), gradientImage()), Error);
  EXPECT_FALSE(fs::exists(tmpPath("missing")));
  // The target is a directory: the temporary file is written, the rename fails, and the
  // temporary file is removed again.
  const fs::path dir = tmpDir() / "atomic";
  fs::remove_all(dir);
  fs::create_directories(dir / "taken.png");
  const std::string taken = (dir / "taken.png").string();
  EXPECT_NE(errorOf([&] { writePng(taken, gradientImage(), true); }).find(taken), std::string::npos);
  EXPECT_NE(errorOf([&] { writePfm(taken, gradientImage()); }).find(taken), std::string::npos);
  EXPECT_EQ(temporaryFilesIn(dir), 0u);
  EXPECT_TRUE(fs::is_directory(taken));
  // Success replaces an existing file and leaves no temporary behind.
  const std::string ok = (dir / "ok.png").string();
  std::ofstream(ok) << "old";
  writePng(ok, gradientImage(), false);
  EXPECT_EQ(readPng(ok).width, 17);
  EXPECT_EQ(temporaryFilesIn(dir), 0u);
  // Empty images are refused before anything is written.
  EXPECT_THROW(writePng((dir / "empty.png").string(), Image(), false), Error);
  EXPECT_FALSE(fs::exists(dir / "empty.png"));
}

TEST(Image, BadFilesAreNamed) {
  writePfm(tmpPath("d.pfm"), gradientImage());
  fs::resize_file(tmpPath("d.pfm"), 100);
  std::string m = errorOf([] { readPfm(tmpPath("d.pfm")); });
  EXPECT_NE(m.find(tmpPath("d.pfm")), std::string::npos) << m;
  EXPECT_NE(m.find("truncated"), std::string::npos) << m;
  std::ofstream(tmpPath("header.pfm")) << "PF\n12 x\n-1.0\n";
  m = errorOf([] { readPfm(tmpPath("header.pfm")); });
  EXPECT_NE(m.find("corrupt PFM header"), std::string::npos) << m;
  std::ofstream(tmpPath("zero.pfm")) << "PF\n1 1\n0\n............";
  EXPECT_NE(errorOf([] { readPfm(tmpPath("zero.pfm")); }).find("corrupt"), std::string::npos);
  std::ofstream(tmpPath("short.pfm")) << "PF\n1 1\n-1.0";
  EXPECT_NE(errorOf([] { readPfm(tmpPath("short.pfm")); }).find("truncated"), std::string::npos);
  m = errorOf([] { readPng(tmpPath("d.pfm")); });
  EXPECT_NE(m.find(tmpPath("d.pfm")), std::string::npos) << m;
  EXPECT_NE(m.find("not a PNG"), std::string::npos) << m;
  writePng(tmpPath("e.png"), gradientImage(), false);
  m = errorOf([] { readPfm(tmpPath("e.png")); });
  EXPECT_NE(m.find("not a PFM"), std::string::npos) << m;
  // A PNG cut short: the signature is right, the decoder fails, and the message says so.
  writePng(tmpPath("cut.png"), gradientImage(), true);
  fs::resize_file(tmpPath("cut.png"), 40);
  m = errorOf([] { readPng(tmpPath("cut.png")); });
  EXPECT_NE(m.find(tmpPath("cut.png")), std::string::npos) << m;
  EXPECT_NE(m.find("PNG"), std::string::npos) << m;
  const std::string none = tmpPath("no-such.png");
  EXPECT_NE(errorOf([&] { readPng(none); }).find(none), std::string::npos);
  EXPECT_NE(errorOf([&] { readPfm(none); }).find(none), std::string::npos);
}

TEST(Image, SrgbBytesWithoutPowEqualTheDirectConversion) {
  auto direct = [](float c) -> int {
    const float v = exa::linearToSrgb(c);
    if (!(v > 0.f)) return 0;
    if (v >= 1.f) return 255;
    return int(std::lround(v * 255.f));
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.1f, 1.2f);
  for (int i = 0; i < 1000000; ++i) {
    const float c = u(rng);
    ASSERT_EQ(int(exa::srgbByte(c)), direct(c)) << c;
  }
  // At every step of the output: the floats just below and above each boundary.
  for (int k = 1; k < 256; ++k) {
    uint32_t lo = 0, hi = std::bit_cast<uint32_t>(1.f);
    while (hi - lo > 1) {
      const uint32_t mid = lo + (hi - lo) / 2;
      (direct(std::bit_cast<float>(mid)) >= k ? hi : lo) = mid;
    }
    for (uint32_t b = hi - 3; b <= hi + 3; ++b)
      ASSERT_EQ(int(exa::srgbByte(std::bit_cast<float>(b))), direct(std::bit_cast<float>(b))) << k;
  }
  for (float c : {0.f, -0.f, 1.f, 2.f, std::numeric_limits<float>::infinity(), -1.f,
                  std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::denorm_min()})
    EXPECT_EQ(int(exa::srgbByte(c)), direct(c)) << c;
}

namespace {

uint32_t big32(const unsigned char* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

/// The chunks of a PNG (type, data), their CRCs checked with zlib's.
std::vector<std::pair<std::string, std::vector<unsigned char>>> pngChunks(const std::vector<unsigned char>& png) {
  const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  EXPECT_EQ(std::memcmp(png.data(), signature, 8), 0);
  std::vector<std::pair<std::string, std::vector<unsigned char>>> chunks;
  for (size_t at = 8; at + 12 <= png.size();) {
    const uint32_t length = big32(png.data() + at);
    const std::string type(reinterpret_cast<const char*>(png.data() + at + 4), 4);
    const unsigned char* data = png.data() + at + 8;
    EXPECT_EQ(big32(data + length), uint32_t(crc32(crc32(0L, Z_NULL, 0), png.data() + at + 4, uInt(length + 4))))
        << type;
    chunks.emplace_back(type, std::vector<unsigned char>(data, data + length));
    at += 12 + length;
  }
  return chunks;
}

} // namespace

TEST(Image, Png16HoldsSixteenBitSrgbWithStraightAlpha) {
  const Image img = gradientImage();
  for (bool alpha : {true, false}) {
    const vec3f background(0.2f, 0.4f, 0.6f);
    const auto chunks = pngChunks(encodePng16(img, alpha, background));
    ASSERT_EQ(chunks.size(), 3u);
    ASSERT_EQ(chunks[0].first, "IHDR");
    const std::vector<unsigned char>& h = chunks[0].second;
    EXPECT_EQ(big32(h.data()), uint32_t(img.width));
    EXPECT_EQ(big32(h.data() + 4), uint32_t(img.height));
    EXPECT_EQ(h[8], 16);            // bit depth
    EXPECT_EQ(h[9], alpha ? 6 : 2); // RGBA or RGB
    EXPECT_EQ(chunks[2].first, "IEND");
    const int channels = alpha ? 4 : 3;
    const size_t rowBytes = 1 + size_t(img.width) * size_t(channels) * 2;
    std::vector<unsigned char> rows(rowBytes * size_t(img.height));
    uLongf size = uLongf(rows.size());
    ASSERT_EQ(uncompress(rows.data(), &size, chunks[1].second.data(), uLong(chunks[1].second.size())), Z_OK);
    ASSERT_EQ(size, rows.size());
    for (int y = 0; y < img.height; ++y) {
      const unsigned char* row = rows.data() + size_t(y) * rowBytes;
      EXPECT_EQ(row[0], 0); // no filter
      for (int x = 0; x < img.width; ++x) {
        const vec4f p = img.at(x, y);
        const float inv = p.w > 0.f ? 1.f / p.w : 0.f;
        const vec3f c =
            alpha ? vec3f(p.x * inv, p.y * inv, p.z * inv) : vec3f(p.x, p.y, p.z) + background * (1.f - p.w);
        const float expected[4] = {linearToSrgb(c.x), linearToSrgb(c.y), linearToSrgb(c.z), p.w};
        for (int k = 0; k < channels; ++k) {
          const unsigned char* s = row + 1 + (size_t(x) * size_t(channels) + size_t(k)) * 2;
          const float got = float(uint32_t(s[0]) << 8 | s[1]) / 65535.f;
          EXPECT_NEAR(got, std::clamp(expected[k], 0.f, 1.f), 0.5f / 65535.f + 1e-6f) << x << "," << y << " " << k;
        }
      }
    }
  }
}

TEST(Image, ExrHoldsTheLinearPremultipliedImageExactly) {
  Image img = gradientImage();
  img.at(3, 2) = {2.5f, 1e-8f, 0.f, 0.25f}; // beyond 1 and tiny: kept as they are
  const std::vector<unsigned char> exr = encodeExr(img);
  auto i32 = [&](size_t at) {
    int32_t v;
    std::memcpy(&v, exr.data() + at, 4);
    return v;
  };
  ASSERT_GT(exr.size(), 8u);
  EXPECT_EQ(exr[0], 0x76);
  EXPECT_EQ(exr[1], 0x2f);
  EXPECT_EQ(exr[2], 0x31);
  EXPECT_EQ(exr[3], 0x01);
  EXPECT_EQ(i32(4), 2); // version 2, single-part scan lines
  // The header's attributes by name, each a type and a size.
  std::map<std::string, std::pair<std::string, std::vector<unsigned char>>> attributes;
  size_t at = 8;
  while (exr.at(at) != 0) {
    const std::string name(reinterpret_cast<const char*>(exr.data() + at));
    at += name.size() + 1;
    const std::string type(reinterpret_cast<const char*>(exr.data() + at));
    at += type.size() + 1;
    const int32_t size = i32(at);
    at += 4;
    attributes[name] = {type, std::vector<unsigned char>(exr.begin() + long(at), exr.begin() + long(at) + size)};
    at += size_t(size);
  }
  ++at;
  for (const char* required : {"channels", "compression", "dataWindow", "displayWindow", "lineOrder",
                               "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth"})
    EXPECT_EQ(attributes.count(required), 1u) << required;
  EXPECT_EQ(attributes["compression"].second, std::vector<unsigned char>{0});
  EXPECT_EQ(attributes["channels"].first, "chlist");
  EXPECT_EQ(attributes["channels"].second.size(), 4u * 18u + 1u); // A, B, G, R: name, type, flags, sampling
  // The offset table, then one block per scan line: y, size, A, B, G and R of every pixel.
  const size_t w = size_t(img.width);
  for (int y = 0; y < img.height; ++y) {
    uint64_t offset;
    std::memcpy(&offset, exr.data() + at + 8 * size_t(y), 8);
    ASSERT_EQ(i32(offset), y);
    ASSERT_EQ(i32(offset + 4), int32_t(16 * w));
    for (size_t x = 0; x < w; ++x) {
      const vec4f p = img.at(int(x), y);
      const float expected[4] = {p.w, p.z, p.y, p.x};
      for (size_t c = 0; c < 4; ++c) {
        float v;
        std::memcpy(&v, exr.data() + offset + 8 + 4 * (c * w + x), 4);
        EXPECT_EQ(std::bit_cast<uint32_t>(v), std::bit_cast<uint32_t>(expected[c])) << x << "," << y;
      }
    }
  }
  EXPECT_EQ(exr.size(), at + 8 * size_t(img.height) + size_t(img.height) * (8 + 16 * w));
}

TEST(Image, FormatsFollowTheExtension) {
  EXPECT_EQ(imageFormatFor("a.png"), ImageFormat::Png);
  EXPECT_EQ(imageFormatFor("a.PNG", 16), ImageFormat::Png16);
  EXPECT_EQ(imageFormatFor("a.jpeg"), ImageFormat::Jpeg);
  EXPECT_EQ(imageFormatFor("a.exr"), ImageFormat::Exr);
  EXPECT_EQ(imageFormatFor("a.pfm"), ImageFormat::Pfm);
  EXPECT_EQ(imageFormatFor("/dev/stdout"), ImageFormat::Png);
  EXPECT_NE(errorOf([] { imageFormatFor("a.gif"); }).find("a.gif: unknown image format '.gif'"), std::string::npos);
  EXPECT_NE(errorOf([] { imageFormatFor("a.png", 12); }).find("8 or 16"), std::string::npos);
  EXPECT_TRUE(formatKeepsAlpha(ImageFormat::Exr));
  EXPECT_FALSE(formatKeepsAlpha(ImageFormat::Jpeg));
}
