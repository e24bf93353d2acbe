#include "exabricks/core/error.h"
#include "exabricks/io/image.h"
#include "exabricks/render/transfer_function.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

using namespace exa;
namespace fs = std::filesystem;

namespace {

std::string writeTemp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "tf";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}

std::string readError(const std::string& path) {
  try {
    readTransferFunction(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

float luminance(const vec3f& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

} // namespace

TEST(ColorMap, BuiltinsInterpolateAndPerceptualOnesBrighten) {
  for (const std::string& name : builtinColorMapNames()) {
    SCOPED_TRACE(name);
    const ColorMap m = builtinColorMap(name);
    ASSERT_EQ(m.positions.size(), m.colors.size());
    EXPECT_EQ(m.positions.front(), 0.f);
    EXPECT_EQ(m.positions.back(), 1.f);
    EXPECT_EQ(m.at(-1.f), m.colors.front());
    EXPECT_EQ(m.at(2.f), m.colors.back());
    for (size_t i = 0; i < m.positions.size(); ++i)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(m.at(m.positions[i])[c], m.colors[i][c], 1e-6f);
    if (name == "cool-to-warm") continue;
    float previous = -1.f;
    for (int i = 0; i <= 100; ++i) {
      const float l = luminance(m.at(i / 100.f));
      EXPECT_GE(l, previous - 1e-6f) << "luminance falls at " << i;
      previous = l;
    }
  }
  EXPECT_THROW(builtinColorMap("jet"), Error);
}

TEST(TransferFunction, NormalizeLinearAndLog) {
  TransferFunction tf;
  tf.valueRange = {2.f, 6.f};
  EXPECT_FLOAT_EQ(tf.normalize(4.f), 0.5f);
  EXPECT_FLOAT_EQ(tf.normalize(-10.f), 0.f);
  EXPECT_FLOAT_EQ(tf.normalize(10.f), 1.f);
  tf.logScale = true;
  tf.valueRange = {1.f, 1000.f};
  EXPECT_NEAR(tf.normalize(10.f), 1.f / 3.f, 1e-6f);
  EXPECT_FLOAT_EQ(tf.normalize(-1.f), 0.f);
  tf.valueRange = {3.f, 3.f};
  EXPECT_FLOAT_EQ(tf.normalize(3.f), 0.5f);
}

TEST(TransferFunction, MaxOpacityIsExactOverAnyInterval) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int trial = 0; trial < 200; ++trial) {
    TransferFunction tf;
    tf.valueRange = {-5.f, 15.f};
    tf.logScale = trial % 4 == 3;
    if (tf.logScale) tf.valueRange = {0.01f, 100.f};
    tf.opacityScale = 0.5f + u(rng);
    const int n = 1 + int(rng() % 6);
    float x = 0.f;
    for (int i = 0; i < n; ++i) {
      x = std::min(1.f, x + u(rng) * 0.4f);
      tf.opacity.push_back({x, u(rng) < 0.3f ? 0.f : u(rng)});
    }
    const float a = tf.valueRange.lower + u(rng) * (tf.valueRange.upper - tf.valueRange.lower);
    const float b = tf.valueRange.lower + u(rng) * (tf.valueRange.upper - tf.valueRange.lower);
    const range1f r{std::min(a, b), std::max(a, b)};
    float brute = 0.f;
    for (int i = 0; i <= 20000; ++i) brute = std::max(brute, tf.lookup(r.lower + (r.upper - r.lower) * i / 20000.f).w);
    const float exact = tf.maxOpacity(r);
    EXPECT_GE(exact, brute - 1e-6f);
    EXPECT_LE(exact, brute + 2e-3f);
  }
  TransferFunction zero;
  zero.opacity = {{0.f, 0.f}, {0.5f, 0.f}, {0.6f, 1.f}};
  zero.valueRange = {0.f, 1.f};
  EXPECT_EQ(zero.maxOpacity({0.1f, 0.5f}), 0.f);
  EXPECT_GT(zero.maxOpacity({0.1f, 0.51f}), 0.f);
  EXPECT_EQ(zero.maxOpacity(range1f{}), 0.f);
}

TEST(TransferFunction, ParaViewPreset) {
  const std::string path = writeTemp("pv.json", R"([{"Name": "Test", "ColorSpace": "RGB",
    "RGBPoints": [10, 0, 0, 0,  20, 1, 0.5, 0,  30, 1, 1, 1],
    "Points": [10, 0, 0.5, 0,  30, 0.8, 0.5, 0]}])");
  const TransferFunction tf = readTransferFunction(path);
  EXPECT_EQ(tf.valueRange.lower, 10.f);
  EXPECT_EQ(tf.valueRange.upper, 30.f);
  EXPECT_EQ(tf.colorMap.name, "Test");
  const vec4f mid = tf.lookup(20.f);
  EXPECT_NEAR(mid.x, 1.f, 1e-6f);
  EXPECT_NEAR(mid.y, srgbToLinear(0.5f), 1e-6f);
  EXPECT_NEAR(mid.w, 0.4f, 1e-6f);
}

TEST(TransferFunction, ExabricksJson) {
  const std::string path = writeTemp("ex.json", R"({"colormap": "magma", "opacity": [[0, 0], [0.5, 0], [1, 1]],
    "range": [0, 4], "log": false, "opacity_scale": 0.5})");
  const TransferFunction tf = readTransferFunction(path);
  EXPECT_EQ(tf.colorMap.name, "magma");
  EXPECT_FLOAT_EQ(tf.lookup(3.f).w, 0.25f);
  EXPECT_EQ(tf.maxOpacity({0.f, 2.f}), 0.f);
  const std::string custom = writeTemp("custom.json", R"({"colormap": {"points": [[0, 0, 0, 0], [1, 1, 1, 1]]}})");
  EXPECT_FLOAT_EQ(readTransferFunction(custom).colorMap.at(1.f).x, 1.f);
}

TEST(TransferFunction, BadFilesAreRejectedClearly) {
  struct Case {
    const char* name;
    const char* text;
    const char* expect;
  } cases[] = {
      {"syntax.json", "{\"colormap\": ", "invalid JSON"},
      {"unknown.json", R"({"colour": "viridis"})", "unknown key"},
      {"name.json", R"({"colormap": "rainbow"})", "unknown colour map"},
      {"rgb4.json", R"({"RGBPoints": [0, 0, 0]})", "RGBPoints"},
      {"order.json", R"({"RGBPoints": [1, 0, 0, 0, 0, 1, 1, 1]})", "must not decrease"},
      {"range01.json", R"({"RGBPoints": [0, 0, 0, 2, 1, 1, 1, 1]})", "outside [0, 1]"},
      {"opacity.json", R"({"opacity": [[0, 0], [0.5]]})", "[x, alpha]"},
      {"badrange.json", R"({"range": [3, 1]})", "below"},
      {"scalar.json", "42", "expected"},
  };
  for (const Case& c : cases) {
    const std::string path = writeTemp(c.name, c.text);
    const std::string m = readError(path);
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find(c.expect), std::string::npos) << c.name << ": " << m;
  }
  EXPECT_NE(readError("/no/such/tf.json").find("cannot open"), std::string::npos);
}
