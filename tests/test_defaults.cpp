// The first picture: default field, transfer-function defaults adapted to the data, warnings
// for requests that can never show anything, and default renders of real data that are neither
// blank nor saturated.
#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/documents/image.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/legends.h"
#include "exabricks/render/overlay.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <set>

using namespace exa;
namespace fs = std::filesystem;

namespace {

/// 32^3 finest cells with values from f(x, y, z), in fields named as given.
Model uniformModel(const std::vector<std::string>& names, float (*f)(int, int, int)) {
  CellSet s;
  for (const std::string& n : names)
    s.fields.push_back({n, {}});
  for (int z = 0; z < 32; ++z)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        s.cells.push_back({vec3i(x, y, z), 0});
        for (Field& fld : s.fields)
          fld.values.push_back(f(x, y, z));
      }
  return buildModel(std::move(s));
}

fs::path sharedData() {
  const char* env = std::getenv("EXABRICKS_DATA");
  return env ? fs::path(env) : fs::path(EXABRICKS_SOURCE_DIR) / ".." / "shared" / "data";
}

} // namespace

TEST(Defaults, TheDefaultFieldIsTheDensity) {
  auto one = [](int, int, int) { return 1.f; };
  EXPECT_EQ(uniformModel({"Dark_Matter_Density", "Density", "Temperature"}, one).requireField(""), 1);
  EXPECT_EQ(uniformModel({"pres", "dens"}, one).requireField(""), 1);
  EXPECT_EQ(uniformModel({"phi", "temp"}, one).requireField(""), 0); // first in file order
  EXPECT_EQ(uniformModel({"radius", "scalar"}, one).requireField(""), 1);
}

TEST(Defaults, AwkwardFieldsGetPicturesThatShowThem) {
  auto first = [](const DefaultChoices& c) { return c.notes.empty() ? std::string() : c.notes[0]; };
  // Constant (exactly, and within a float step of 101325): nothing drawn, and said.
  const Model exact = uniformModel({"RhoRT"}, [](int, int, int) { return 101325.f; });
  const Model oneStep =
      uniformModel({"RhoRT"}, [](int x, int, int) { return x < 16 ? 101325.f : std::nextafter(101325.f, 2e5f); });
  for (const Model* model : {&exact, &oneStep}) {
    const Model& constant = *model;
    const DefaultChoices c =
        adaptTransferFunction(constant, DatasetInfo::of(constant), 0, defaultTransferFunction(), true, true);
    EXPECT_NE(first(c).find("'RhoRT' is constant (101325)"), std::string::npos) << first(c);
    for (const OpacityPoint& p : c.tf.opacity)
      EXPECT_EQ(p.alpha, 0.f);
  }
  // Both signs: a diverging map centred on zero, opaque at both ends, transparent at zero.
  const Model signedField = uniformModel({"velx"}, [](int x, int, int) { return float(x - 12); });
  DefaultChoices c =
      adaptTransferFunction(signedField, DatasetInfo::of(signedField), 0, defaultTransferFunction(), true, true);
  EXPECT_EQ(c.tf.colorMap.name, "cool-to-warm");
  EXPECT_EQ(c.tf.valueRange.lower, -c.tf.valueRange.upper);
  EXPECT_EQ(c.tf.valueRange.upper, 19.f);
  EXPECT_GT(c.tf.atNormalized(0.f).w, 0.f);
  EXPECT_GT(c.tf.atNormalized(1.f).w, 0.f);
  EXPECT_EQ(c.tf.atNormalized(0.5f).w, 0.f);
  // Not with a colour map asked for, nor for one sign far weaker than the other.
  c = adaptTransferFunction(signedField, DatasetInfo::of(signedField), 0, defaultTransferFunction(), true, true,
                            nullptr, false);
  EXPECT_EQ(c.tf.colorMap.name, "viridis");
  const Model mostlyPositive = uniformModel({"f"}, [](int x, int, int) { return x == 0 ? -0.01f : float(x); });
  c = adaptTransferFunction(mostlyPositive, DatasetInfo::of(mostlyPositive), 0, defaultTransferFunction(), true, true);
  EXPECT_EQ(c.tf.colorMap.name, "viridis");
  // Exact zeros beside positive values over four decades: logarithmic over the positive values.
  const Model dark = uniformModel({"Dark_Matter_Density"}, [](int x, int y, int z) {
    if ((x * 7 + y * 3 + z) % 97 == 0) return 0.f;
    const float r2 = float((x - 16) * (x - 16) + (y - 16) * (y - 16) + (z - 16) * (z - 16));
    return std::pow(10.f, 4.f * std::exp(-r2 / 40.f));
  });
  c = adaptTransferFunction(dark, DatasetInfo::of(dark), 0, defaultTransferFunction(), true, true);
  EXPECT_TRUE(c.tf.logScale) << first(c);
  EXPECT_NE(first(c).find("besides exact zeros"), std::string::npos) << first(c);
  EXPECT_GT(c.tf.valueRange.lower, 0.f);
}

TEST(Defaults, TransparentOverTheBackgroundAndLogWhereTheDataAsksForIt) {
  // A low background (0.1) filling most of the volume, a sphere of higher values.
  const Model low = uniformModel({"f"}, [](int x, int y, int z) {
    const float r2 = float((x - 16) * (x - 16) + (y - 16) * (y - 16) + (z - 16) * (z - 16));
    return r2 < 64.f ? 0.1f + (1.f - r2 / 64.f) : 0.1f;
  });
  const DatasetInfo info = DatasetInfo::of(low);
  DefaultChoices c = adaptTransferFunction(low, info, 0, defaultTransferFunction(), true, true);
  EXPECT_FALSE(c.tf.logScale);
  EXPECT_GT(c.tf.valueRange.lower, 0.1f); // the background lies below the range: transparent
  EXPECT_EQ(c.tf.valueRange.upper, info.valueRanges[0].upper);
  TransferFunction scaled = c.tf; // opacity scale "auto" (0) is the renderer's to resolve
  scaled.opacityScale = 1.f;
  EXPECT_EQ(scaled.lookup(0.1f).w, 0.f);
  EXPECT_GT(scaled.lookup(1.0f).w, 0.f);
  ASSERT_EQ(c.notes.size(), 2u); // the exposure, the range
  EXPECT_NE(c.notes[0].find("exposure"), std::string::npos);
  // A high background (1.0, like a volume fraction) with a hole of low values: the ramp runs
  // towards low values.
  const Model high = uniformModel({"volFrac"}, [](int x, int y, int z) {
    return (x - 16) * (x - 16) + (y - 16) * (y - 16) < 25 && z > 4 ? 0.f : 1.f;
  });
  c = adaptTransferFunction(high, DatasetInfo::of(high), 0, defaultTransferFunction(), true, true);
  scaled = c.tf;
  scaled.opacityScale = 1.f;
  EXPECT_EQ(scaled.lookup(1.f).w, 0.f);
  EXPECT_GT(scaled.lookup(0.f).w, 0.f);
  // Log-normal "densities" over eight decades, most of the volume near the bottom: log mapping.
  std::mt19937 rng(3);
  static std::vector<float> cosmic;
  std::lognormal_distribution<float> ln(0.f, 2.5f);
  for (int i = 0; i < 32 * 32 * 32; ++i)
    cosmic.push_back(std::min(1e4f, std::max(1e-4f, ln(rng))));
  cosmic[0] = 1e-4f, cosmic[1] = 1e4f;
  const Model web =
      uniformModel({"Density"}, [](int x, int y, int z) { return cosmic[size_t((z * 32 + y) * 32 + x)]; });
  c = adaptTransferFunction(web, DatasetInfo::of(web), 0, defaultTransferFunction(), true, true);
  EXPECT_TRUE(c.tf.logScale);
  c = adaptTransferFunction(web, DatasetInfo::of(web), 0, defaultTransferFunction(), false, true);
  EXPECT_FALSE(c.tf.logScale); // --linear
  // A range given is kept.
  TransferFunction given = defaultTransferFunction();
  given.valueRange = range1f{0.2f, 0.5f};
  c = adaptTransferFunction(low, info, 0, given, true, true);
  EXPECT_EQ(c.tf.valueRange, given.valueRange);
  EXPECT_EQ(c.tf.opacity, given.opacity);
}

TEST(Defaults, ExposureShowsTheTopOfTheColourMapThroughWhatSurroundsIt) {
  // A ball of values falling from 1.1 at its centre to a background of 0.1, of several radii:
  // the first picture's opacity scale makes a ray through the centre nearly opaque, its colour
  // the top of the colour map's, while rays through the outer shell stay translucent.
  for (int radius : {4, 8, 12}) {
    SCOPED_TRACE(radius);
    static int r;
    r = radius;
    const Model ball = uniformModel({"f"}, [](int x, int y, int z) {
      const float d2 = float((x - 16) * (x - 16) + (y - 16) * (y - 16) + (z - 16) * (z - 16));
      return d2 < float(r * r) ? 0.1f + (1.f - d2 / float(r * r)) : 0.1f;
    });
    const DatasetInfo info = DatasetInfo::of(ball);
    const DefaultChoices c = adaptTransferFunction(ball, info, 0, defaultTransferFunction(), true, true);
    ASSERT_GT(c.tf.opacityScale, 0.f);
    Renderer renderer(ball, info);
    Scene scene;
    scene.layers = {VolumeLayer{"f", c.tf}};
    scene.shading = Shading::None;
    renderer.setScene(scene);
    Frame frame;
    frame.width = frame.height = 33;
    frame.jitter = false;
    frame.camera.orthographic = true;
    frame.camera.position = vec3d(16.5, 16.5, -40.0);
    frame.camera.lookAt = vec3d(16.5, 16.5, 16.5);
    frame.camera.up = vec3d(0, 1, 0);
    frame.camera.orthoHeight = 16.5;
    const Image img = renderer.render(frame);
    const vec4f centre = img.at(16, 16);
    EXPECT_GT(centre.w, 0.9f) << "a ray through the centre stays translucent";
    // The colour map's position whose colour is nearest the centre's (un-premultiplied).
    const vec3f seen = vec3f(centre.x, centre.y, centre.z) * (1.f / centre.w);
    float nearest = 0.f, best = 1e30f;
    for (int k = 0; k <= 100; ++k) {
      const vec3f d = c.tf.colorMap.at(k / 100.f) - seen;
      if (dot(d, d) < best) best = dot(d, d), nearest = k / 100.f;
    }
    EXPECT_GE(nearest, 0.8f) << "the centre shows the colour map at " << nearest << ", not its top";
    // Through the shell, three quarters out: translucent, and less opaque than the centre.
    const vec4f shell = img.at(16 + r * 3 / 4, 16);
    EXPECT_LT(shell.w, 0.95f);
    EXPECT_LT(shell.w, centre.w - 0.02f);
    EXPECT_GT(shell.w, 0.01f);
  }
}

TEST(Defaults, ManySmallDenseStructuresReachTheEndOfTheColourMap) {
  // Eight 2-cell haloes over a smooth background: their few central cells reach 1000, the
  // rest of the volume stays near 1. The colour map ends where the densest sight lines reach,
  // below the very highest value, and says so.
  const Model web = uniformModel({"density"}, [](int x, int y, int z) {
    const int cx = (x % 16) - 8, cy = (y % 16) - 8, cz = (z % 16) - 8;
    const float d2 = float(cx * cx + cy * cy + cz * cz);
    return 1.f + 0.5f * std::sin(0.3f * float(x + 2 * y)) + 1000.f * std::exp(-d2);
  });
  const DatasetInfo info = DatasetInfo::of(web);
  const DefaultChoices c = adaptTransferFunction(web, info, 0, defaultTransferFunction(), true, true);
  EXPECT_LT(c.tf.valueRange.upper, 0.9f * info.valueRanges[0].upper);
  EXPECT_GT(c.tf.valueRange.upper, c.tf.valueRange.lower);
  bool said = false;
  for (const std::string& n : c.notes)
    said = said || n.find("the colour map ends at") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(Defaults, ASeriesRangeKeepsEachStepsBackgroundTransparent) {
  // A step adapted to [1, 2] with the background below 1.2 (transparent low end): a series
  // reaching 0.5 .. 3 moves the opaque end out by the series' excess and keeps the low end.
  TransferFunction step = defaultTransferFunction();
  step.valueRange = range1f{1.2f, 1.8f};
  step.opacity = {{0.f, 0.f}, {1.f, 1.f}};
  TransferFunction w = widenedForSeries(step, range1f{1.f, 2.f}, range1f{0.5f, 3.f});
  EXPECT_EQ(w.valueRange.lower, 1.2f);
  EXPECT_FLOAT_EQ(w.valueRange.upper, 2.8f);
  // Opaque towards low values: the low end moves, the high (background) end stays.
  step.opacity = {{0.f, 1.f}, {1.f, 0.f}};
  w = widenedForSeries(step, range1f{1.f, 2.f}, range1f{0.5f, 3.f});
  EXPECT_FLOAT_EQ(w.valueRange.lower, 0.7f);
  EXPECT_EQ(w.valueRange.upper, 1.8f);
  // Ends left at the step's own ends take the series' ends; logarithmic: by the same factor.
  step.valueRange = range1f{1.f, 2.f};
  w = widenedForSeries(step, range1f{1.f, 2.f}, range1f{0.5f, 3.f});
  EXPECT_EQ(w.valueRange, (range1f{0.5f, 3.f}));
  step.logScale = true;
  step.opacity = {{0.f, 0.f}, {1.f, 1.f}};
  step.valueRange = range1f{10.f, 1000.f};
  w = widenedForSeries(step, range1f{1.f, 1e4f}, range1f{0.5f, 1e5f});
  EXPECT_EQ(w.valueRange.lower, 10.f);
  EXPECT_FLOAT_EQ(w.valueRange.upper, 1e4f);
  // Centred on zero stays centred.
  step = defaultTransferFunction();
  step.valueRange = range1f{-2.f, 2.f};
  w = widenedForSeries(step, range1f{-1.f, 2.f}, range1f{-5.f, 3.f});
  EXPECT_EQ(w.valueRange, (range1f{-5.f, 5.f}));
}

TEST(Defaults, RequestsThatCanNeverShowAnythingAreNamed) {
  const Model m = uniformModel({"f", "g"}, [](int x, int, int) { return float(x) / 31.f - 2.f; });
  const DatasetInfo info = DatasetInfo::of(m);
  Scene s = Scene::volumeOf(defaultTransferFunction(), "f");
  EXPECT_TRUE(sceneWarnings(s, m, info).empty());
  s.iso.values = {5.f};
  s.layers[0].tf.valueRange = range1f{10.f, 20.f};
  s.layers[0].tf.logScale = true;
  const std::vector<std::string> w = sceneWarnings(s, m, info);
  ASSERT_EQ(w.size(), 3u);
  auto has = [&](const char* part) {
    for (const std::string& x : w)
      if (x.find(part) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("iso-value 5 lies outside the range of 'f'"));
  EXPECT_TRUE(has("excludes all of 'f'"));
  EXPECT_TRUE(has("no positive values"));
  Scene none;
  none.volume = false;
  EXPECT_EQ(sceneWarnings(none, m, info).size(), 1u);

  // Settings that do nothing with the integrator chosen: path tracing's with the marcher, and a
  // path tracer that lets no light leave the volume (zero bounces, no emission).
  Scene marched = Scene::volumeOf(defaultTransferFunction(), "f");
  marched.pathTracing.sunIntensity = 3.f;
  ASSERT_EQ(sceneWarnings(marched, m, info).size(), 1u);
  EXPECT_NE(sceneWarnings(marched, m, info)[0].find("do nothing with the ray marcher"), std::string::npos);
  marched.pathTracing = PathTracing{};
  marched.layers[0].tf.albedo = {{0.f, 0.5f}, {1.f, 0.9f}};
  EXPECT_EQ(sceneWarnings(marched, m, info).size(), 1u);
  Scene traced = Scene::volumeOf(defaultTransferFunction(), "f");
  traced.integration.integrator = Integrator::PathTrace;
  traced.pathTracing.sunIntensity = 3.f;
  EXPECT_TRUE(sceneWarnings(traced, m, info).empty());
  traced.pathTracing.bounces = 0;
  ASSERT_EQ(sceneWarnings(traced, m, info).size(), 1u);
  EXPECT_NE(sceneWarnings(traced, m, info)[0].find("zero bounces without emission"), std::string::npos);
  traced.pathTracing.emission = 0.5f;
  EXPECT_TRUE(sceneWarnings(traced, m, info).empty());
  Image empty(4, 4);
  EXPECT_TRUE(imageIsEmpty(empty));
  empty.at(1, 2).w = 0.01f;
  EXPECT_FALSE(imageIsEmpty(empty));
}

TEST(Defaults, DefaultRendersOfRealDataShowTheData) {
  // Every shared sample and the embedded dataset, rendered by the command line with no option
  // but the size: some pixels show the data, some the background, and the colours vary.
  std::vector<std::string> inputs{""};
  for (const char* sub : {"amrex/advection_3d/plt_drop", "amrex/advection_3d/plt_small", "amrex/pele_eb_3d/plt_eb_3d",
                          "amrex/pelelm_3lev_3d/example_plt_3d"})
    if (fs::exists(sharedData() / sub)) inputs.push_back((sharedData() / sub).string());
  if (inputs.size() == 1)
    std::printf("shared samples not found at %s (set EXABRICKS_DATA): the embedded dataset only\n",
                sharedData().string().c_str());
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "defaults";
  fs::create_directories(dir);
  for (const std::string& input : inputs) {
    SCOPED_TRACE(input.empty() ? "embedded dataset" : input);
    const fs::path out = dir / "default.png";
    fs::remove(out);
    const std::string cmd = std::string(EXABRICKS_CLI) + " -q render " + (input.empty() ? "" : "'" + input + "'") +
                            " -o '" + out.string() + "' --size 96x96";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const Image img = readPng(out.string());
    int shown = 0, saturated = 0;
    double sum = 0, sum2 = 0;
    for (const vec4f& p : img.pixels) {
      const double lum = 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
      if (lum > 0.004) {
        ++shown;
        sum += lum;
        sum2 += lum * lum;
      }
      if (p.x > 0.995f && p.y > 0.995f && p.z > 0.995f) ++saturated;
    }
    const double n = double(img.pixels.size());
    EXPECT_GT(shown / n, 0.02) << "blank";
    EXPECT_LT(shown / n, 0.98) << "no background left";
    EXPECT_LT(saturated / n, 0.05) << "saturated";
    const double mean = sum / std::max(shown, 1),
                 spread = std::sqrt(std::max(0.0, sum2 / std::max(shown, 1) - mean * mean));
    // (plt_eb_3d's density is two values, 0 in the obstacle and 1.18 around it: its picture is
    // the obstacle, unshaded inside, with a spread of 0.005.)
    EXPECT_GT(spread, 0.004) << "a flat picture";
    std::printf("%s: %.1f %% shown, luminance %.3f +- %.3f\n", input.empty() ? "embedded" : input.c_str(),
                100.0 * shown / n, mean, spread);
  }
}

TEST(Overlay, LegendsKeepClearOfEachOtherAtSmallSizes) {
  // 200 x 150 with three annotation lines, one far too long: the lines fit the width, the colour
  // bar (title included) starts below them, and an outline keeps off the bar's boxes.
  Image img(200, 150);
  const std::string longLine = "<default: blobs scene, 200000 cells, seed 1> and more words than fit";
  const std::string fitted = fitText(longLine, img.width - 12, 1);
  EXPECT_LE(textWidth(fitted, 1), img.width - 12);
  EXPECT_EQ(fitted.substr(fitted.size() - 3), "...");
  EXPECT_EQ(fitText("short", 100, 1), "short");
  const int top = linesHeight(3, img);
  TransferFunction tf = defaultTransferFunction();
  tf.valueRange = range1f{0.f, 1.f};
  const ColorBarLayout bar = colorBarLayout(img, tf, "a long field title", top);
  for (const PixelRect& r : bar.boxes)
    EXPECT_GE(r.y0, top);
  const Camera camera = Camera::frame(box3d(vec3d(0.0), vec3d(1.0)), 30, 25, 40, false);
  drawBoxOutline(img, camera, box3d(vec3d(-0.5), vec3d(1.5)), vec3f(0.5f), bar.boxes);
  int outline = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      bool inBar = false;
      for (const PixelRect& r : bar.boxes)
        inBar = inBar || r.contains(x, y);
      if (img.at(x, y).w == 0.f) continue;
      EXPECT_FALSE(inBar) << "outline on the bar at " << x << ", " << y;
      ++outline;
    }
  EXPECT_GT(outline, 100);
}

TEST(Overlay, TheColourBarDrawsOverThePictureWithoutErasingIt) {
  // A lit picture (random colours everywhere) with the legends of a log-mapped field with a long
  // title, at several sizes, with and without the annotation: adding the colour bar changes no
  // pixel outside the boxes it reports, and those boxes are a small part of the picture.
  Model model = uniformModel({"Density"}, [](int x, int y, int z) { return 1.f + float(x + y + z); });
  model.fieldUnits = {"code units"};
  const DatasetInfo info = DatasetInfo::of(model);
  Scene scene;
  scene.layers = {VolumeLayer{"Density", defaultTransferFunction()}};
  scene.layers[0].tf.logScale = true;
  Frame frame;
  frame.camera = Camera::frame(model.world.toWorld(model.cellBounds()), 30, 25, 40, false);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{800, 800}, {512, 512}, {200, 150}})
    for (bool annotate : {false, true}) {
      SCOPED_TRACE(strCat(w, "x", h, annotate ? " annotated" : ""));
      Image picture(w, h);
      for (vec4f& p : picture.pixels)
        p = vec4f(u(rng), u(rng), u(rng), 1.f);
      Image without = picture, with = picture;
      scene.legends = {false, annotate, false};
      EXPECT_TRUE(drawLegends(scene, frame, model, info, {"plt00100"}, without).empty());
      scene.legends = {true, annotate, false};
      const std::vector<PixelRect> boxes = drawLegends(scene, frame, model, info, {"plt00100"}, with);
      ASSERT_FALSE(boxes.empty());
      size_t inside = 0, changed = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          bool inBar = false;
          for (const PixelRect& r : boxes)
            inBar = inBar || r.contains(x, y);
          inside += inBar;
          const vec4f &a = without.at(x, y), &b = with.at(x, y);
          const bool same = a.x == b.x && a.y == b.y && a.z == b.z && a.w == b.w;
          if (!inBar && !same && ++changed <= 3) ADD_FAILURE() << "pixel " << x << ", " << y << " changed";
          if (inBar && !same) ++changed;
        }
      EXPECT_GT(changed, 0u) << "no colour bar drawn";
      EXPECT_LT(double(inside) / (double(w) * h), 0.12) << "the colour bar's boxes cover too much";
    }
}

TEST(Overlay, TicksTextColourBarOutlineAndProjection) {
  auto near = [](const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
      if (std::abs(a[i] - b[i]) > 1e-9 * std::max(1.0, std::abs(b[i]))) return false;
    return true;
  };
  EXPECT_TRUE(near(colorBarTicks(range1f{0.f, 1.f}, false), {0.0, 0.2, 0.4, 0.6, 0.8, 1.0}));
  EXPECT_TRUE(near(colorBarTicks(range1f{-3.f, 7.f}, false), {-2.0, 0.0, 2.0, 4.0, 6.0}));
  EXPECT_TRUE(near(colorBarTicks(range1f{1e-3f, 10.f}, true), {1e-3, 1e-2, 1e-1, 1.0, 1e1}));
  EXPECT_LE(colorBarTicks(range1f{1e-20f, 1e20f}, true).size(), 7u);
  Image img(200, 150);
  EXPECT_GT(drawText(img, 5, 5, "exabricks 1.5", vec3f(1.f), 1), 40);
  int lit = 0;
  for (const vec4f& p : img.pixels)
    lit += p.w == 1.f;
  EXPECT_GT(lit, 30);
  Image bar(200, 150);
  TransferFunction tf = defaultTransferFunction("viridis");
  tf.valueRange = range1f{0.f, 10.f};
  drawColorBar(bar, tf, "density", vec3f(1.f));
  int right = 0, left = 0;
  for (int y = 0; y < 150; ++y)
    for (int x = 0; x < 200; ++x)
      (x > 140 ? right : left) += bar.at(x, y).w == 1.f;
  EXPECT_GT(right, 500);
  EXPECT_LT(left, right);
  // project() inverts ray(), for both projections.
  for (bool ortho : {false, true}) {
    const Camera c = Camera::frame(box3d(vec3d(0.0), vec3d(4.0, 2.0, 1.0)), 40, 30, 35, ortho);
    vec3d org, dir;
    c.ray(0.3, 0.8, 1.5, org, dir);
    double u, v;
    ASSERT_TRUE(c.project(org + dir * 7.0, 1.5, u, v));
    EXPECT_NEAR(u, 0.3, 1e-9);
    EXPECT_NEAR(v, 0.8, 1e-9);
  }
  Image box(64, 64);
  drawBoxOutline(box, Camera::frame(box3d(vec3d(0.0), vec3d(1.0)), 30, 25, 40, false), box3d(vec3d(0.0), vec3d(1.0)),
                 vec3f(1.f));
  lit = 0;
  for (const vec4f& p : box.pixels)
    lit += p.w == 1.f;
  EXPECT_GT(lit, 100);
}

namespace {

/// Pixels drawn by `text`, as a string of 0/1 per pixel of a canvas that holds it.
std::string textPixels(const std::string& text, bool glyphByGlyph) {
  Image img(textWidth(text, 1) + 8, 16);
  if (!glyphByGlyph) {
    drawText(img, 2, 2, text, vec3f(1.f), 1);
  } else {
    int x = 2;
    for (char c : text)
      x += drawText(img, x, 2, std::string(1, c), vec3f(1.f), 1);
  }
  std::string lit;
  for (const vec4f& p : img.pixels)
    lit += p.w == 1.f ? '1' : '0';
  return lit;
}

} // namespace

TEST(Overlay, TickLabelsAreDistinctAndNearTheirTicks) {
  // Narrow, wide, negative and logarithmic ranges: every label distinct from its neighbours and
  // nearer its tick than half the way to the next; 2 to 7 ticks on a linear bar, 2 to 5 on a log
  // bar under two decades.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> exponent(-12.0, 12.0), unit(-1.0, 1.0), decades(0.02, 1.99);
  std::vector<std::pair<range1f, bool>> cases = {{{1500.f, 1500.5f}, false},
                                                 {{101325.f, std::nextafter(101325.f, 2e5f)}, false},
                                                 {{298.f, 1529.f}, true},
                                                 {{-8.8e-4f, -8e-4f}, false}};
  for (int i = 0; i < 2000; ++i) {
    const double a = unit(rng) * std::pow(10.0, exponent(rng));
    const double width = std::abs(a) * std::pow(10.0, -std::abs(exponent(rng)) / 2) + 1e-30;
    cases.push_back({range1f{float(a), float(a + width)}, false});
    const double lo = std::pow(10.0, exponent(rng));
    cases.push_back({range1f{float(lo), float(lo * std::pow(10.0, decades(rng)))}, true});
  }
  for (const auto& [range, logScale] : cases) {
    if (!(range.upper > range.lower)) continue;
    const std::vector<double> ticks = colorBarTicks(range, logScale);
    const std::vector<std::string> labels = colorBarLabels(ticks, logScale);
    const std::string what = strCat(logScale ? "log " : "", "[", range.lower, ", ", range.upper, "]");
    ASSERT_EQ(labels.size(), ticks.size()) << what;
    ASSERT_GE(ticks.size(), 2u) << what;
    if (logScale && std::log10(double(range.upper) / double(range.lower)) < 2.0) {
      EXPECT_LE(ticks.size(), 5u) << what;
    } else if (!logScale) {
      EXPECT_LE(ticks.size(), 7u) << what;
    }
    const bool logMapped = logScale; // (Clang 14 cannot capture a structured binding)
    auto at = [logMapped](double v) { return logMapped ? std::log10(v) : v; };
    const double slack = 1e-5 * (double(range.upper) - double(range.lower)) +
                         1e-6 * std::max(std::abs(double(range.lower)), std::abs(double(range.upper)));
    for (size_t i = 0; i < ticks.size(); ++i) {
      EXPECT_GE(ticks[i], double(range.lower) - slack) << what;
      EXPECT_LE(ticks[i], double(range.upper) + slack) << what;
      if (i > 0) {
        EXPECT_NE(labels[i], labels[i - 1]) << what;
      }
      const double shown = std::strtod(labels[i].c_str(), nullptr);
      const double step = at(ticks[std::min(i + 1, ticks.size() - 1)]) - at(ticks[i > 0 ? i - 1 : 0]);
      const double gap = i > 0 && i + 1 < ticks.size() ? step / 2 : step;
      EXPECT_LT(std::abs(at(shown) - at(ticks[i])), gap / 2) << what << ": '" << labels[i] << "' for " << ticks[i];
    }
  }
  // The cases users met: six ticks of a half-unit range, a field over one float32 step, a
  // temperature over less than a decade.
  EXPECT_EQ(colorBarLabels(colorBarTicks({1500.f, 1500.5f}, false), false),
            (std::vector<std::string>{"1500.0", "1500.1", "1500.2", "1500.3", "1500.4", "1500.5"}));
  EXPECT_EQ(colorBarLabels(colorBarTicks({0.f, 1.f}, false), false),
            (std::vector<std::string>{"0.0", "0.2", "0.4", "0.6", "0.8", "1.0"}));
  EXPECT_EQ(colorBarLabels(colorBarTicks({-3.f, 7.f}, false), false),
            (std::vector<std::string>{"-2", "0", "2", "4", "6"}));
  EXPECT_EQ(colorBarLabels(colorBarTicks({298.f, 1529.f}, true), true), (std::vector<std::string>{"500", "1000"}));
}

TEST(Overlay, EveryTickLabelIsDrawnWhole) {
  // Ranges over many magnitudes, both signs, linear and logarithmic: each tick label drawn as
  // one string must light exactly the pixels of its glyphs drawn one by one.
  std::mt19937 rng(7);
  std::vector<range1f> ranges = {{0.f, 100.f},    {1e3f, 1e7f},         {-8.88e8f, 8.88e8f},
                                 {1e-30f, 1e30f}, {-0.0088f, -0.0008f}, {13222500.f, 88888888.f},
                                 {1e-12f, 8e-3f}};
  std::uniform_real_distribution<double> exponent(-30.0, 30.0), unit(-1.0, 1.0);
  for (int i = 0; i < 400; ++i) {
    const double a = unit(rng) * std::pow(10.0, exponent(rng)),
                 b = a + std::abs(unit(rng)) * std::pow(10.0, exponent(rng));
    ranges.push_back(range1f{float(a), float(b)});
  }
  std::set<std::string> labels = {"-8.88e+38", "888", "-0.000888", "1e-308", "-inf", "nan"};
  for (const range1f& r : ranges)
    for (bool logScale : {false, true})
      for (const std::string& label : colorBarLabels(colorBarTicks(r, logScale), logScale))
        labels.insert(label);
  EXPECT_GT(labels.size(), 300u);
  for (const std::string& label : labels) {
    const std::string whole = textPixels(label, false), glyphs = textPixels(label, true);
    EXPECT_EQ(whole, glyphs) << "label '" << label << "' is not drawn whole";
    EXPECT_NE(whole.find('1'), std::string::npos) << label;
  }
  // Text of any length and of the densest glyphs, as titles and annotations are.
  std::string dense;
  for (int i = 0; i < 40; ++i)
    dense += "8B@#$%&WM";
  EXPECT_EQ(textPixels(dense, false), textPixels(dense, true));
}
