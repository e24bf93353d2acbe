// Transfer functions against independent truth: published colours of the maps (at positions
// other than the anchors the implementation uses), brute-force scans for maxOpacity, and
// hand-written files in both formats.
#include "exabricks/core/error.h"
#include "exabricks/documents/image.h"
#include "exabricks/documents/transfer_function_file.h"
#include "exabricks/render/sample_math.h"
#include "exabricks/render/transfer_function.h"

#include <gtest/gtest.h>

#include <cmath>
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

/// 8-bit sRGB of a linear colour, unrounded.
vec3f srgb255(const vec3f& c) {
  return {255.f * linearToSrgb(c.x), 255.f * linearToSrgb(c.y), 255.f * linearToSrgb(c.z)};
}

void expectSrgbNear(const vec3f& linear, int r, int g, int b, float tolerance) {
  const vec3f s = srgb255(linear);
  EXPECT_NEAR(s.x, float(r), tolerance);
  EXPECT_NEAR(s.y, float(g), tolerance);
  EXPECT_NEAR(s.z, float(b), tolerance);
}

/// Inverse of the normalisation, written independently: the value that maps to t.
float valueAt(const TransferFunction& tf, double t) {
  const double lo = tf.valueRange.lower, hi = tf.valueRange.upper;
  if (tf.logScale) return float(lo * std::pow(hi / lo, t));
  return float(lo + t * (hi - lo));
}

} // namespace

TEST(ColorMap, BuiltinsAreWellFormedAndInterpolateTheirPoints) {
  ASSERT_EQ(builtinColorMapNames().size(), 6u);
  for (const std::string& name : builtinColorMapNames()) {
    SCOPED_TRACE(name);
    const ColorMap m = builtinColorMap(name);
    EXPECT_EQ(m.name, name);
    ASSERT_EQ(m.positions.size(), m.colors.size());
    ASSERT_GE(m.positions.size(), 2u);
    EXPECT_EQ(m.positions.front(), 0.f);
    EXPECT_EQ(m.positions.back(), 1.f);
    for (size_t i = 1; i < m.positions.size(); ++i)
      EXPECT_GT(m.positions[i], m.positions[i - 1]);
    EXPECT_EQ(m.at(-1.f), m.colors.front());
    EXPECT_EQ(m.at(2.f), m.colors.back());
    EXPECT_EQ(m.at(std::nanf("")), m.colors.front());
    for (size_t i = 0; i < m.positions.size(); ++i) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(m.at(m.positions[i])[c], m.colors[i][c], 1e-6f);
        EXPECT_GE(m.colors[i][c], 0.f);
        EXPECT_LE(m.colors[i][c], 1.f);
      }
      // Linear interpolation: the midpoint of two control points is the mean of their colours.
      if (i + 1 < m.positions.size()) {
        const vec3f mid = m.at(0.5f * (m.positions[i] + m.positions[i + 1]));
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(mid[c], 0.5f * (m.colors[i][c] + m.colors[i + 1][c]), 1e-5f);
      }
    }
  }
}

TEST(ColorMap, PerceptualMapsBrightenMonotonically) {
  for (const char* name : {"viridis", "plasma", "inferno", "magma", "grayscale"}) {
    SCOPED_TRACE(name);
    const ColorMap m = builtinColorMap(name);
    float previous = -1.f;
    for (int i = 0; i <= 1000; ++i) {
      const float l = luminance(m.at(float(i) / 1000.f));
      EXPECT_GT(l, previous) << "luminance does not rise at " << i;
      previous = l;
    }
  }
}

TEST(ColorMap, MatchesPublishedColours) {
  // Ends and the quarter points of the published maps (viridisLite's 5-colour palettes). The
  // quarter points lie between the implementation's anchors, so they test the interpolation.
  struct Expect {
    const char* map;
    float t;
    int r, g, b;
  } expect[] = {
      {"viridis", 0.f, 0x44, 0x01, 0x54},   {"viridis", 0.25f, 0x3b, 0x52, 0x8b}, {"viridis", 0.5f, 0x21, 0x90, 0x8c},
      {"viridis", 0.75f, 0x5d, 0xc8, 0x63}, {"viridis", 1.f, 0xfd, 0xe7, 0x25},   {"plasma", 0.f, 0x0d, 0x08, 0x87},
      {"plasma", 0.25f, 0x7e, 0x03, 0xa8},  {"plasma", 0.5f, 0xcc, 0x46, 0x78},   {"plasma", 0.75f, 0xf8, 0x94, 0x41},
      {"plasma", 1.f, 0xf0, 0xf9, 0x21},    {"inferno", 0.f, 0x00, 0x00, 0x04},   {"inferno", 0.25f, 0x56, 0x10, 0x6e},
      {"inferno", 0.5f, 0xbb, 0x37, 0x54},  {"inferno", 0.75f, 0xf9, 0x8c, 0x0a}, {"inferno", 1.f, 0xfc, 0xff, 0xa4},
      {"magma", 0.f, 0x00, 0x00, 0x04},     {"magma", 0.25f, 0x51, 0x12, 0x7c},   {"magma", 0.5f, 0xb6, 0x36, 0x79},
      {"magma", 0.75f, 0xfb, 0x88, 0x61},   {"magma", 1.f, 0xfc, 0xfd, 0xbf},     {"grayscale", 0.f, 0, 0, 0},
      {"grayscale", 1.f, 255, 255, 255},
  };
  for (const Expect& e : expect) {
    SCOPED_TRACE(std::string(e.map) + " at " + std::to_string(e.t));
    const vec3f c = builtinColorMap(e.map).at(e.t);
    const bool end = e.t == 0.f || e.t == 1.f;
    expectSrgbNear(c, e.r, e.g, e.b, end ? 0.01f : 5.f);
  }
  // grayscale is linear in linear RGB.
  EXPECT_NEAR(builtinColorMap("grayscale").at(0.25f).y, 0.25f, 1e-6f);
}

TEST(ColorMap, CoolToWarmFollowsMorelandsTable) {
  // Moreland's published diverging map at eighths, 8-bit sRGB. The implementation computes the
  // map in Msh space from the two ends only.
  const int table[9][3] = {{59, 76, 192},   {98, 130, 234},  {141, 176, 254}, {184, 208, 249}, {221, 221, 221},
                           {245, 196, 173}, {244, 154, 123}, {222, 96, 77},   {180, 4, 38}};
  const ColorMap m = builtinColorMap("cool-to-warm");
  EXPECT_GE(m.positions.size(), 17u);
  for (int i = 0; i <= 8; ++i) {
    SCOPED_TRACE(i);
    expectSrgbNear(m.at(float(i) / 8.f), table[i][0], table[i][1], table[i][2], 1.5f);
  }
  // Diverging: brightest in the middle, darker towards both ends, no colour jumps (the
  // steepest stretch, at the dark red end, moves about 10 codes per 1/200).
  float peak = 0.f, peakAt = -1.f;
  for (int i = 0; i <= 200; ++i) {
    const float l = luminance(m.at(float(i) / 200.f));
    if (l > peak) peak = l, peakAt = float(i) / 200.f;
  }
  EXPECT_NEAR(peakAt, 0.5f, 0.03f);
  for (int i = 1; i <= 200; ++i) {
    const vec3f a = srgb255(m.at(float(i - 1) / 200.f)), b = srgb255(m.at(float(i) / 200.f));
    EXPECT_LT(std::abs(a.x - b.x) + std::abs(a.y - b.y) + std::abs(a.z - b.z), 20.f) << i;
  }
}

TEST(ColorMap, UnknownNameListsTheBuiltins) {
  try {
    builtinColorMap("jet");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("jet"), std::string::npos) << m;
    for (const std::string& name : builtinColorMapNames())
      EXPECT_NE(m.find(name), std::string::npos) << m;
  }
}

TEST(ColorMap, StepsAndEmptyMaps) {
  ColorMap m;
  m.positions = {0.f, 0.5f, 0.5f, 1.f};
  m.colors = {vec3f(0.f), vec3f(0.2f), vec3f(0.8f), vec3f(1.f)};
  EXPECT_NEAR(m.at(0.25f).x, 0.1f, 1e-6f);
  EXPECT_EQ(m.at(0.5f).x, 0.8f); // the right-hand side of a step
  EXPECT_NEAR(m.at(0.4999f).x, 0.2f, 1e-3f);
  EXPECT_NEAR(m.at(0.75f).x, 0.9f, 1e-6f);
  const ColorMap none;
  EXPECT_EQ(none.at(0.25f), vec3f(0.25f));
  EXPECT_EQ(none.at(7.f), vec3f(1.f));
}

TEST(TransferFunction, NormalizeLinear) {
  TransferFunction tf;
  EXPECT_EQ(tf.normalize(123.f), 0.5f); // no range yet
  tf.valueRange = {2.f, 6.f};
  EXPECT_FLOAT_EQ(tf.normalize(4.f), 0.5f);
  EXPECT_FLOAT_EQ(tf.normalize(3.f), 0.25f);
  EXPECT_EQ(tf.normalize(2.f), 0.f);
  EXPECT_EQ(tf.normalize(6.f), 1.f);
  EXPECT_EQ(tf.normalize(-10.f), 0.f);
  EXPECT_EQ(tf.normalize(10.f), 1.f);
  EXPECT_EQ(tf.normalize(INFINITY), 1.f);
  EXPECT_EQ(tf.normalize(-INFINITY), 0.f);
  EXPECT_FALSE(std::isnan(tf.normalize(NAN)));
  tf.valueRange = {3.f, 3.f};
  EXPECT_EQ(tf.normalize(3.f), 0.5f);
  EXPECT_EQ(tf.normalize(2.f), 0.f);
  EXPECT_EQ(tf.normalize(4.f), 1.f);
  tf.valueRange = {-3e38f, 3e38f}; // the width overflows float but not the double arithmetic
  EXPECT_FLOAT_EQ(tf.normalize(0.f), 0.5f);
}

TEST(TransferFunction, NormalizeLog) {
  TransferFunction tf;
  tf.logScale = true;
  tf.valueRange = {1.f, 1000.f};
  EXPECT_NEAR(tf.normalize(10.f), 1.f / 3.f, 1e-6f);
  EXPECT_NEAR(tf.normalize(100.f), 2.f / 3.f, 1e-6f);
  EXPECT_NEAR(tf.normalize(std::sqrt(10.f)), 1.f / 6.f, 1e-6f);
  EXPECT_EQ(tf.normalize(0.5f), 0.f);
  EXPECT_EQ(tf.normalize(0.f), 0.f);
  EXPECT_EQ(tf.normalize(-1.f), 0.f);
  EXPECT_EQ(tf.normalize(5000.f), 1.f);
  // A range reaching zero is cut six decades below its top.
  tf.valueRange = {0.f, 100.f};
  EXPECT_NEAR(tf.normalize(1e-4f), 0.f, 1e-6f);
  EXPECT_NEAR(tf.normalize(1.f), 4.f / 6.f, 1e-6f);
  EXPECT_EQ(tf.normalize(0.f), 0.f);
  // Nothing positive in the range: positive values lie above it.
  tf.valueRange = {-5.f, -1.f};
  EXPECT_EQ(tf.normalize(-2.f), 0.f);
  EXPECT_EQ(tf.normalize(2.f), 1.f);
}

TEST(TransferFunction, NormalizeIsMonotonic) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-20.f, 120.f);
  for (int mode = 0; mode < 4; ++mode) {
    TransferFunction tf;
    tf.logScale = mode >= 2;
    tf.valueRange = mode % 2 ? range1f{0.f, 100.f} : range1f{0.5f, 80.f};
    for (int i = 0; i < 20000; ++i) {
      float a = u(rng), b = u(rng);
      if (a > b) std::swap(a, b);
      const float na = tf.normalize(a), nb = tf.normalize(b);
      EXPECT_LE(na, nb);
      EXPECT_GE(na, 0.f);
      EXPECT_LE(nb, 1.f);
    }
  }
}

TEST(TransferFunction, LookupAtControlPoints) {
  TransferFunction tf;
  tf.colorMap = builtinColorMap("plasma");
  tf.valueRange = {10.f, 20.f};
  tf.opacity = {{0.f, 0.1f}, {0.25f, 0.f}, {0.5f, 0.8f}, {1.f, 0.4f}};
  tf.opacityScale = 0.5f;
  for (const OpacityPoint& p : tf.opacity) {
    const vec4f c = tf.lookup(10.f + 10.f * p.x);
    EXPECT_NEAR(c.w, p.alpha * 0.5f, 1e-6f);
    const vec3f expected = tf.colorMap.at(p.x);
    EXPECT_NEAR(c.x, expected.x, 1e-6f);
    EXPECT_NEAR(c.y, expected.y, 1e-6f);
    EXPECT_NEAR(c.z, expected.z, 1e-6f);
  }
  EXPECT_NEAR(tf.lookup(13.75f).w, 0.5f * 0.4f, 1e-6f); // halfway up the 0 -> 0.8 segment
  EXPECT_NEAR(tf.lookup(0.f).w, 0.05f, 1e-6f);          // clamped to the ends
  EXPECT_NEAR(tf.lookup(99.f).w, 0.2f, 1e-6f);
  // Opacity above 1 after scaling is clamped.
  tf.opacityScale = 4.f;
  EXPECT_EQ(tf.lookup(15.f).w, 1.f);
  // No opacity points: a linear ramp.
  tf.opacity.clear();
  tf.opacityScale = 1.f;
  EXPECT_NEAR(tf.lookup(12.5f).w, 0.25f, 1e-6f);
  EXPECT_EQ(tf.lookup(5.f).w, 0.f);
  EXPECT_EQ(tf.lookup(25.f).w, 1.f);
}

TEST(TransferFunction, MaxOpacityMatchesABruteForceScan) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int trial = 0; trial < 400; ++trial) {
    TransferFunction tf;
    tf.logScale = trial % 4 == 3;
    tf.valueRange = tf.logScale ? range1f{0.01f, 100.f} : range1f{-5.f, 15.f};
    tf.opacityScale = trial % 5 == 0 ? 3.f : 0.5f + u(rng);
    // Control points on a 1/20 grid (so the brute-force scan bounds its own error), with
    // repeated positions (steps) now and then.
    const int n = int(rng() % 7);
    int cell = int(rng() % 4);
    for (int i = 0; i < n && cell <= 20; ++i) {
      tf.opacity.push_back({float(cell) / 20.f, u(rng) < 0.3f ? 0.f : u(rng)});
      cell += int(rng() % 4); // 0 repeats the position
    }
    // Intervals of values, sometimes reaching outside the range or a single value.
    auto value = [&]() { return valueAt(tf, -0.2 + 1.4 * double(u(rng))); };
    float a = value(), b = trial % 7 == 0 ? a : value();
    if (tf.logScale && trial % 8 == 7) a = -1.f; // non-positive values map to 0
    const range1f r{std::min(a, b), std::max(a, b)};

    // Brute force in the normalised domain: every lookup in the interval is at most the
    // answer, and the scan gets within its step times the steepest slope (20 per unit).
    const double t0 = tf.normalize(r.lower), t1 = tf.normalize(r.upper);
    float brute = std::max(tf.lookup(r.lower).w, tf.lookup(r.upper).w);
    const int steps = 20000;
    for (int i = 0; i <= steps; ++i) {
      const double t = t0 + (t1 - t0) * i / steps;
      const float v = std::clamp(valueAt(tf, t), r.lower, r.upper);
      brute = std::max(brute, tf.lookup(v).w);
    }
    const float exact = tf.maxOpacity(r);
    SCOPED_TRACE(trial);
    EXPECT_GE(exact, brute);
    EXPECT_LE(exact, std::min(1.f, brute + 20.f * tf.opacityScale * float(t1 - t0) / steps + 1e-5f));
    EXPECT_LE(exact, 1.f);
  }
}

TEST(TransferFunction, MaxOpacityEdgeCases) {
  TransferFunction tf;
  tf.opacity = {{0.f, 0.f}, {0.5f, 0.f}, {0.6f, 1.f}};
  tf.valueRange = {0.f, 1.f};
  EXPECT_EQ(tf.maxOpacity({0.1f, 0.5f}), 0.f);
  EXPECT_GT(tf.maxOpacity({0.1f, 0.51f}), 0.f);
  EXPECT_EQ(tf.maxOpacity({-4.f, 0.2f}), 0.f);
  EXPECT_EQ(tf.maxOpacity({0.55f, 7.f}), 1.f);
  EXPECT_EQ(tf.maxOpacity(range1f{}), 0.f); // empty
  EXPECT_EQ(tf.maxOpacity({0.7f, 0.6f}), 0.f);
  // Steps: at a repeated x the last point is the value there, the first one is approached from
  // below, and one between them is never taken.
  tf.opacity = {{0.f, 0.f}, {0.5f, 0.f}, {0.5f, 0.9f}, {0.7f, 0.f}, {1.f, 0.f}};
  EXPECT_EQ(tf.maxOpacity({0.5f, 0.7f}), 0.9f);
  EXPECT_EQ(tf.maxOpacity({0.2f, 0.5f}), 0.9f);
  EXPECT_EQ(tf.maxOpacity({0.2f, 0.49f}), 0.f);
  EXPECT_EQ(tf.maxOpacity({0.71f, 1.f}), 0.f);
  tf.opacity = {{0.f, 0.f}, {0.5f, 0.8f}, {0.5f, 0.1f}, {1.f, 0.1f}};
  EXPECT_EQ(tf.maxOpacity({0.5f, 1.f}), 0.1f);
  EXPECT_GT(tf.maxOpacity({0.49f, 1.f}), 0.7f);
  tf.opacity = {{0.f, 0.6f}, {0.f, 0.2f}, {0.4f, 0.3f}, {0.4f, 1.f}, {0.4f, 0.f}, {1.f, 0.f}};
  EXPECT_EQ(tf.lookup(0.f).w, 0.2f);
  EXPECT_EQ(tf.lookup(0.4f).w, 0.f);
  EXPECT_EQ(tf.maxOpacity({0.f, 1.f}), 0.3f);
  EXPECT_EQ(tf.maxOpacity({-1.f, 0.f}), 0.2f);
  // A thin spike between two samples of any scan.
  tf.opacity = {{0.f, 0.f}, {0.3f, 0.f}, {0.30001f, 0.7f}, {0.30002f, 0.f}};
  EXPECT_FLOAT_EQ(tf.maxOpacity({0.f, 1.f}), 0.7f);
  // The default ramp.
  tf.opacity.clear();
  EXPECT_FLOAT_EQ(tf.maxOpacity({0.2f, 0.4f}), 0.4f);
}

TEST(TransferFunction, ParaViewPresetArray) {
  const std::string path = writeTemp("pv.json", R"([{"Name": "Test", "ColorSpace": "Diverging",
    "NanColor": [1, 1, 0], "Creator": "hand",
    "RGBPoints": [10, 0, 0, 0,  20, 1, 0.5, 0,  30, 1, 1, 1],
    "Points": [10, 0, 0.5, 0,  30, 0.8, 0.5, 0]},
    {"Name": "Second", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1]}])");
  const TransferFunction tf = readTransferFunction(path);
  EXPECT_EQ(tf.valueRange.lower, 10.f);
  EXPECT_EQ(tf.valueRange.upper, 30.f);
  EXPECT_FALSE(tf.logScale);
  EXPECT_EQ(tf.colorMap.name, "Test");
  ASSERT_EQ(tf.colorMap.positions.size(), 3u);
  EXPECT_EQ(tf.colorMap.positions[0], 0.f);
  EXPECT_EQ(tf.colorMap.positions[1], 0.5f);
  EXPECT_EQ(tf.colorMap.positions[2], 1.f);
  const vec4f mid = tf.lookup(20.f);
  EXPECT_NEAR(mid.x, 1.f, 1e-6f);
  EXPECT_NEAR(mid.y, srgbToLinear(0.5f), 1e-6f); // sRGB in the file, linear inside
  EXPECT_NEAR(mid.z, 0.f, 1e-6f);
  EXPECT_NEAR(mid.w, 0.4f, 1e-6f);
  EXPECT_NEAR(tf.lookup(15.f).y, 0.5f * srgbToLinear(0.5f), 1e-6f);
}

TEST(TransferFunction, ParaViewPresetObjectWithOpacityBeyondTheColours) {
  // Opacity points outside the colour range are cut at its ends, keeping their values there.
  const std::string path = writeTemp("pv-object.json", R"({"Name": 7,
    "RGBPoints": [0, 0.2, 0.2, 0.2,  4, 0.4, 0.4, 0.4],
    "Points": [-4, 0, 0.5, 0,  2, 1, 0.5, 0,  8, 0, 0.5, 0]})");
  const TransferFunction tf = readTransferFunction(path);
  EXPECT_EQ(tf.colorMap.name, "preset");
  EXPECT_EQ(tf.valueRange, (range1f{0.f, 4.f}));
  ASSERT_GE(tf.opacity.size(), 3u);
  EXPECT_EQ(tf.opacity.front().x, 0.f);
  EXPECT_EQ(tf.opacity.back().x, 1.f);
  EXPECT_NEAR(tf.lookup(0.f).w, 2.f / 3.f, 1e-6f);
  EXPECT_NEAR(tf.lookup(2.f).w, 1.f, 1e-6f);
  EXPECT_NEAR(tf.lookup(4.f).w, 2.f / 3.f, 1e-6f);
  EXPECT_NEAR(tf.lookup(1.f).w, 5.f / 6.f, 1e-6f);
  // Without "Points" the opacity is the default ramp.
  const std::string plain = writeTemp("pv-plain.json", R"({"RGBPoints": [-1, 0, 0, 0, 1, 1, 1, 1]})");
  const TransferFunction ramp = readTransferFunction(plain);
  EXPECT_TRUE(ramp.opacity.empty());
  EXPECT_NEAR(ramp.lookup(0.f).w, 0.5f, 1e-6f);
  EXPECT_NEAR(ramp.lookup(0.f).x, 0.5f, 1e-6f); // halfway between linear 0 and 1
}

TEST(TransferFunction, ExabricksJson) {
  const std::string path = writeTemp("ex.json", R"({"colormap": "magma",
    "opacity": [[0, 0], [0.5, 0], [1, 1]], "range": [0, 4], "log": false, "opacity_scale": 0.5})");
  const TransferFunction tf = readTransferFunction(path);
  EXPECT_EQ(tf.colorMap.name, "magma");
  EXPECT_EQ(tf.colorMap.colors, builtinColorMap("magma").colors);
  EXPECT_EQ(tf.valueRange, (range1f{0.f, 4.f}));
  EXPECT_FLOAT_EQ(tf.lookup(3.f).w, 0.25f);
  EXPECT_EQ(tf.maxOpacity({0.f, 2.f}), 0.f);
  EXPECT_FLOAT_EQ(tf.maxOpacity({0.f, 4.f}), 0.5f);

  const std::string custom =
      writeTemp("custom.json", R"({"colormap": {"points": [[0, 0, 0, 0], [0.5, 0.5, 0.5, 0.5], [1, 1, 1, 1]]}})");
  const TransferFunction c = readTransferFunction(custom);
  EXPECT_EQ(c.colorMap.name, "custom");
  EXPECT_FLOAT_EQ(c.colorMap.at(1.f).x, 1.f);
  EXPECT_NEAR(c.colorMap.at(0.5f).y, srgbToLinear(0.5f), 1e-6f);

  const std::string log = writeTemp("log.json", R"({"log": true, "range": [0.1, 1000]})");
  const TransferFunction l = readTransferFunction(log);
  EXPECT_TRUE(l.logScale);
  EXPECT_NEAR(l.normalize(10.f), 0.5f, 1e-6f);

  // Everything is optional: viridis, a ramp, the range of the data, the dataset's default
  // opacity scale (0, resolved by the renderer), as for built-in maps.
  const TransferFunction d = readTransferFunction(writeTemp("empty.json", "{}"));
  EXPECT_EQ(d.colorMap.name, "viridis");
  EXPECT_TRUE(d.opacity.empty());
  EXPECT_TRUE(d.valueRange.empty());
  EXPECT_FALSE(d.logScale);
  EXPECT_EQ(d.opacityScale, 0.f);
  EXPECT_EQ(readTransferFunction(writeTemp("auto.json", R"({"opacity_scale": "auto"})")).opacityScale, 0.f);

  // The path tracer's albedo over the normalised value, tabulated as the colour and opacity, and
  // written back.
  const TransferFunction a =
      readTransferFunction(writeTemp("albedo.json", R"({"albedo": [[0, 0.2], [0.5, 1], [1, 1]]})"));
  ASSERT_EQ(a.albedo.size(), 3u);
  const std::vector<float> table = tabulateAlbedo(a);
  ASSERT_EQ(table.size(), size_t(kTfTableSize));
  EXPECT_FLOAT_EQ(table.front(), 0.2f);
  EXPECT_FLOAT_EQ(table.back(), 1.f);
  EXPECT_NEAR(table[size_t(kTfTableSize - 1) / 4], 0.6f, 0.01f);
  EXPECT_TRUE(tabulateAlbedo(d).empty());
  EXPECT_EQ(readTransferFunction(writeTemp("albedo-again.json", transferFunctionJson(a))), a);
}

TEST(TransferFunction, BadFilesAreRejectedClearly) {
  struct Case {
    const char* name;
    const char* text;
    const char* expect;
  } cases[] = {
      {"syntax.json", "{\"colormap\": ", "invalid JSON"},
      {"syntax-line.json", "{\n\"colormap\": \"viridis\",\n]", "line 3"},
      {"scalar.json", "42", "expected"},
      {"empty-array.json", "[]", "expected"},
      {"unknown.json", R"({"colour": "viridis"})", "unknown key \"colour\""},
      {"name.json", R"({"colormap": "rainbow"})", "unknown colour map 'rainbow'"},
      {"cmtype.json", R"({"colormap": 3})", "\"colormap\" must be"},
      {"cmkey.json", R"({"colormap": {"points": [[0,0,0,0],[1,1,1,1]], "space": "lab"}})", "unknown key \"space\""},
      {"cmpoint.json", R"({"colormap": {"points": [[0,0,0],[1,1,1,1]]}})", "[x, r, g, b]"},
      {"cmorder.json", R"({"colormap": {"points": [[0,0,0,0],[0.6,1,1,1],[0.5,1,1,1],[1,1,1,1]]}})",
       "must not decrease"},
      {"cmends.json", R"({"colormap": {"points": [[0.1,0,0,0],[1,1,1,1]]}})", "x = 0"},
      {"cmcolour.json", R"({"colormap": {"points": [[0,0,0,0],[1,1,1.5,1]]}})", "outside [0, 1]"},
      {"opacity.json", R"({"opacity": [[0, 0], [0.5]]})", "[x, alpha]"},
      {"opacity-order.json", R"({"opacity": [[0.5, 0], [0.2, 1]]})", "must not decrease"},
      {"opacity-alpha.json", R"({"opacity": [[0, -0.5]]})", "outside [0, 1]"},
      {"opacity-type.json", R"({"opacity": [[0, "a"]]})", "must be a number"},
      {"albedo.json", R"({"albedo": [[0, 1.5]]})", "albedo of point 0 = 1.5 is outside [0, 1]"},
      {"albedo-point.json", R"({"albedo": [[0, 1], [1]]})", "albedo point 1 is [1], expected [x, albedo]"},
      {"albedo-order.json", R"({"albedo": [[0.5, 0], [0.2, 1]]})", "albedo x values must not decrease"},
      {"albedo-type.json", R"({"albedo": 0.5})", "\"albedo\" must be [[x, albedo], ...]"},
      {"badrange.json", R"({"range": [3, 1]})", "below"},
      {"range-size.json", R"({"range": [3]})", "[low, high]"},
      {"range-inf.json", R"({"range": [0, 1e999]})", "overflow"},
      {"range-float.json", R"({"range": [0, 1e39]})", "range high: 1e+39 is beyond single precision"},
      {"logrange.json", R"({"log": true, "range": [0, 10]})", "positive"},
      {"logtype.json", R"({"log": "yes"})", "true or false"},
      {"scale.json", R"({"opacity_scale": -1})", "must be positive"},
      {"rgb4.json", R"({"RGBPoints": [0, 0, 0]})", "multiple of 4"},
      {"rgb1.json", R"({"RGBPoints": [0, 0, 0, 0]})", "at least two"},
      {"rgbtype.json", R"({"RGBPoints": "none"})", "RGBPoints"},
      {"norgb.json", R"([{"Name": "Cat", "IndexedColors": [1, 0, 0]}])", "no \"RGBPoints\""},
      {"order.json", R"({"RGBPoints": [1, 0, 0, 0, 0, 1, 1, 1]})", "must not decrease"},
      {"flat.json", R"({"RGBPoints": [1, 0, 0, 0, 1, 1, 1, 1]})", "no value range"},
      {"range01.json", R"({"RGBPoints": [0, 0, 0, 2, 1, 1, 1, 1]})", "outside [0, 1]"},
      {"rgbnull.json", R"({"RGBPoints": [0, 0, 0, null, 1, 1, 1, 1]})", "must be a number"},
      {"points4.json", R"({"RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1], "Points": [0, 1, 0.5]})", "\"Points\""},
      {"points-order.json", R"({"RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1], "Points": [1, 0, 0.5, 0, 0, 1, 0.5, 0]})",
       "must not decrease"},
      {"points-alpha.json", R"({"RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1], "Points": [0, 2, 0.5, 0]})", "outside [0, 1]"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = writeTemp(c.name, c.text);
    const std::string m = readError(path);
    EXPECT_EQ(m.rfind(path + ": ", 0), 0u) << m; // the message starts with the path
    EXPECT_NE(m.find(c.expect), std::string::npos) << m;
  }
  const std::string missing = (fs::path(EXABRICKS_TEST_TMP) / "tf" / "no-such.json").string();
  EXPECT_EQ(readError(missing).rfind(missing + ": cannot open", 0), 0u) << readError(missing);
  const std::string dir = (fs::path(EXABRICKS_TEST_TMP) / "tf").string();
  EXPECT_EQ(readError(dir).rfind(dir + ": cannot open", 0), 0u) << readError(dir);
}
