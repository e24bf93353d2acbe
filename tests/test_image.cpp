#include "exabricks/core/error.h"
#include "exabricks/io/image.h"

#include <gtest/gtest.h>

#include <filesystem>

using namespace exa;
namespace fs = std::filesystem;

namespace {
std::string tmpPath(const std::string& name) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "image";
  fs::create_directories(dir);
  return (dir / name).string();
}

Image gradientImage() {
  Image img(17, 9);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float a = float(x) / 16.f;
      img.at(x, y) = {0.8f * a * float(y) / 8.f, 0.3f * a, 0.05f * a, a};
    }
  return img;
}
} // namespace

TEST(Image, SrgbRoundTrip) {
  for (int i = 0; i <= 100; ++i) EXPECT_NEAR(srgbToLinear(linearToSrgb(i / 100.f)), i / 100.f, 1e-5f);
  EXPECT_FLOAT_EQ(linearToSrgb(1.f), 1.f);
  EXPECT_NEAR(linearToSrgb(0.5f), 0.7354f, 1e-3f);
}

TEST(Image, PngRoundTripWithAlphaAndBackground) {
  const Image img = gradientImage();
  writePng(tmpPath("a.png"), img, true);
  const Image back = readPng(tmpPath("a.png"));
  ASSERT_EQ(back.width, img.width);
  ASSERT_EQ(back.height, img.height);
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    EXPECT_NEAR(back.pixels[i].w, img.pixels[i].w, 0.51f / 255.f);
    EXPECT_NEAR(back.pixels[i].x, img.pixels[i].x, 1.5f / 255.f);
  }
  // Over a background: c + (1 - a) bg.
  const vec3f bg(0.2f, 0.4f, 0.6f);
  writePng(tmpPath("b.png"), img, false, bg);
  const Image over = readPng(tmpPath("b.png"));
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    EXPECT_EQ(over.pixels[i].w, 1.f);
    EXPECT_NEAR(over.pixels[i].z, img.pixels[i].z + (1 - img.pixels[i].w) * bg.z, 1.5f / 255.f);
  }
}

TEST(Image, PfmRoundTripIsExact) {
  const Image img = gradientImage();
  writePfm(tmpPath("c.pfm"), img);
  const Image back = readPfm(tmpPath("c.pfm"));
  for (size_t i = 0; i < img.pixels.size(); ++i) EXPECT_EQ(back.pixels[i].x, img.pixels[i].x);
}

TEST(Image, FailedWritesLeaveNothingAndBadFilesAreNamed) {
  EXPECT_THROW(writePng(tmpPath("missing/dir/x.png"), gradientImage(), false), Error);
  EXPECT_FALSE(fs::exists(tmpPath("missing")));
  writePfm(tmpPath("d.pfm"), gradientImage());
  fs::resize_file(tmpPath("d.pfm"), 100);
  try {
    readPfm(tmpPath("d.pfm"));
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos);
  }
  EXPECT_THROW(readPng(tmpPath("d.pfm")), Error);
}
