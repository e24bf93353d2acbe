// The volume path tracer against independent truth: transmittance through a homogeneous slab
// (analytic) and through a two-level field (quadrature of the reconstruction), a white furnace
// (albedo 1 returns the environment's radiance), and without scattering the ray marcher's image;
// bad settings refused with the key named.
#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

using namespace exa;

namespace {

/// 32 x 32 x 32 lattice units of cells whose value depends on z only: finest cells below
/// z = split, cells of width 2 above it.
Model slab(const std::function<float(float)>& valueAtZ, int split = 32) {
  CellSet s;
  s.fields.push_back({"f", {}});
  for (int z = 0; z < 32; ++z)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        if (z < split) {
          s.cells.push_back({vec3i(x, y, z), 0});
          s.fields[0].values.push_back(valueAtZ(float(z) + 0.5f));
        } else if (x % 2 == 0 && y % 2 == 0 && (z - split) % 2 == 0) {
          s.cells.push_back({vec3i(x, y, z), 1});
          s.fields[0].values.push_back(valueAtZ(float(z) + 1.f));
        }
  return buildModel(std::move(s));
}

/// 32 x 32 x 32 finest cells of one field, each valued f(its centre).
Model finestCube(const char* field, const std::function<float(const vec3f&)>& f) {
  CellSet cells;
  cells.fields.push_back({field, {}});
  for (int z = 0; z < 32; ++z)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        cells.cells.push_back({vec3i(x, y, z), 0});
        cells.fields[0].values.push_back(f(vec3f(float(x), float(y), float(z)) + vec3f(0.5f)));
      }
  return buildModel(std::move(cells));
}

/// Opacity per finest cell rising linearly from `low` at value 0 to `high` at value 1 (scale 1),
/// colour white.
TransferFunction ramp(float low, float high) {
  TransferFunction tf;
  tf.colorMap.positions = {0.f, 1.f};
  tf.colorMap.colors = {vec3f(1.f), vec3f(1.f)};
  tf.opacity = {{0.f, low}, {1.f, high}};
  tf.valueRange = range1f{0.f, 1.f};
  tf.opacityScale = 1.f;
  return tf;
}

/// Looking down -z through the slab, orthographic, 64 x 64 pixels over the inner 12 x 12 units.
Frame downZ(int spp) {
  Frame f;
  f.width = f.height = 64;
  f.samplesPerPixel = spp;
  f.camera.orthographic = true;
  f.camera.position = vec3d(16.0, 16.0, 80.0);
  f.camera.lookAt = vec3d(16.0, 16.0, 16.0);
  f.camera.up = vec3d(0.0, 1.0, 0.0);
  f.camera.orthoHeight = 12.0;
  return f;
}

Scene pathScene(const TransferFunction& tf) {
  Scene s = Scene::volumeOf(tf, "f");
  s.shading = Shading::None;
  s.integration.integrator = Integrator::PathTrace;
  s.pathTracing.albedo = 0.f;
  s.pathTracing.environment = vec3f(0.f);
  return s;
}

/// The radiance of the paths that met something (the premultiplied colour's sum over the alpha's),
/// and the share of the pixels they cover (the mean alpha).
struct Radiance {
  vec3d color;
  double covered;
};

Radiance radianceWhereMet(const Image& img) {
  vec3d sum(0.0);
  double alpha = 0.0;
  for (const vec4f& p : img.pixels) {
    sum = sum + vec3d(p.x, p.y, p.z);
    alpha += p.w;
  }
  return {sum * (1.0 / alpha), alpha / double(img.pixels.size())};
}

/// The mean red radiance over all pixels (paths that leave without meeting anything add 0).
double meanRed(const Image& img) {
  double sum = 0.0;
  for (const vec4f& p : img.pixels)
    sum += p.x;
  return sum / double(img.pixels.size());
}

double meanAlpha(const Image& img) {
  double sum = 0.0;
  for (const vec4f& p : img.pixels)
    sum += p.w;
  return sum / double(img.pixels.size());
}

/// The iso-surface of radius 9 of a distance field around the centre of finestCube("r", ...),
/// grey (albedo 0.5) and diffuse, without the volume.
Scene greySphere() {
  Scene s = pathScene(ramp(0.f, 0.f));
  s.layers[0].field = "r";
  s.volume = false;
  s.iso.values = {9.f};
  s.iso.colors = {vec3f(0.5f)};
  return s;
}

} // namespace

TEST(PathTrace, TransmittanceThroughAHomogeneousSlabIsAnalytic) {
  // Every cell absorbs 5 % per finest width. The basis reaches half a cell beyond the outer cells'
  // faces (hat radius one width around each centre), so the ray crosses 33 widths: 0.95^33 stays.
  const Model m = slab([](float) { return 0.5f; });
  Renderer r(m, DatasetInfo::of(m));
  r.setScene(pathScene(ramp(0.05f, 0.05f)));
  const int spp = 8;
  const Image img = r.render(downZ(spp));
  const double want = 1.0 - std::pow(0.95, 33.0);
  const double n = double(img.pixels.size()) * spp;
  const double sigma = std::sqrt(want * (1.0 - want) / n);
  EXPECT_NEAR(meanAlpha(img), want, 4.0 * sigma) << "want " << want << " +- " << sigma;
}

TEST(PathTrace, TransmittanceThroughTwoLevelsEqualsAQuadratureOfTheReconstruction) {
  // Finest cells below z = 16 with a value rising along z, cells of width 2 above it with
  // another; the extinction follows the reconstruction (blended across the level boundary).
  auto value = [](float z) { return z < 16.f ? 0.2f + 0.02f * z : 0.9f; };
  const Model m = slab(value, 16);
  const DatasetInfo info = DatasetInfo::of(m);
  const TransferFunction tf = ramp(0.01f, 0.12f);
  Renderer r(m, info);
  r.setScene(pathScene(tf));
  const int spp = 8;
  const Image img = r.render(downZ(spp));
  // The optical depth along the slab's axis by the midpoint rule on the reconstruction, over
  // z in [-2, 34] (the basis reaches beyond the cells' faces; no value beyond it).
  double depth = 0.0;
  const int steps = 36000;
  const double dz = 36.0 / steps;
  for (int k = 0; k < steps; ++k) {
    const double z = -2.0 + (k + 0.5) * dz;
    double v;
    vec3d g;
    if (!m.sampleWorld(0, vec3d(16.0, 16.0, z), v, g)) continue;
    const double alpha = tf.lookup(float(v)).w;
    depth += -std::log(1.0 - alpha) / double(info.referenceWidth) * dz;
  }
  const double want = 1.0 - std::exp(-depth);
  const double n = double(img.pixels.size()) * spp;
  const double sigma = std::sqrt(want * (1.0 - want) / n);
  EXPECT_NEAR(meanAlpha(img), want, 4.0 * sigma) << "want " << want << " +- " << sigma;
}

TEST(PathTrace, SingleScatteringOfTheSunIsAnalytic) {
  // A homogeneous slab lit by the sun from straight above and seen from above, one scattering
  // event (bounces 1), isotropic: L = albedo I / (4 pi) (1 - exp(-2 sigma D)) / 2 over the
  // slab's depth D (33 widths, as above). The sun's shadow rays are ratio-tracked.
  const Model m = slab([](float) { return 0.5f; });
  const DatasetInfo info = DatasetInfo::of(m);
  Renderer r(m, info);
  Scene s = pathScene(ramp(0.05f, 0.05f));
  s.pathTracing.albedo = 0.7f;
  s.pathTracing.bounces = 1;
  s.pathTracing.sunDirection = vec3f(0.f, 0.f, -1.f);
  s.pathTracing.sunIntensity = 10.f;
  s.pathTracing.sunAngle = 0.f;
  r.setScene(s);
  const double red = meanRed(r.render(downZ(16)));
  const double sigma = -std::log(0.95) / double(info.referenceWidth);
  const double want = 0.7 * 10.0 / (4.0 * M_PI) * (1.0 - std::exp(-2.0 * sigma * 33.0)) / 2.0;
  EXPECT_NEAR(red, want, 0.02 * want);
}

TEST(PathTrace, ForwardScatteringTowardsTheSunIsAnalytic) {
  // The same slab with the sun behind it (its light travels towards the camera) and forward
  // scattering g = 0.6: single scattering gives L = albedo I p(1) sigma D exp(-sigma D), with the
  // Henyey-Greenstein p(1) = (1 - g^2) / (4 pi (1 - g)^3).
  const Model m = slab([](float) { return 0.5f; });
  const DatasetInfo info = DatasetInfo::of(m);
  Renderer r(m, info);
  Scene s = pathScene(ramp(0.02f, 0.02f));
  s.pathTracing.albedo = 0.7f;
  s.pathTracing.bounces = 1;
  s.pathTracing.anisotropy = 0.6f;
  s.pathTracing.sunDirection = vec3f(0.f, 0.f, 1.f);
  s.pathTracing.sunIntensity = 2.f;
  s.pathTracing.sunAngle = 0.f;
  r.setScene(s);
  const double red = meanRed(r.render(downZ(16)));
  const double sigma = -std::log(0.98) / double(info.referenceWidth), depth = sigma * 33.0, g = 0.6;
  const double phase = (1.0 - g * g) / (4.0 * M_PI * std::pow(1.0 - g, 3.0));
  const double want = 0.7 * 2.0 * phase * depth * std::exp(-depth);
  EXPECT_NEAR(red, want, 0.02 * want);
}

TEST(PathTrace, AWhiteFurnaceReturnsTheEnvironment) {
  // Albedo 1, white medium of any density, uniform environment: every path that meets the
  // medium leaves it with the environment's radiance.
  const Model m = slab([](float z) { return z / 32.f; });
  Renderer r(m, DatasetInfo::of(m));
  Scene s = pathScene(ramp(0.02f, 0.3f));
  s.pathTracing.albedo = 1.f;
  s.pathTracing.bounces = 1000;
  s.pathTracing.environment = vec3f(0.5f, 0.25f, 1.f);
  s.pathTracing.anisotropy = 0.5f;
  r.setScene(s);
  const Radiance got = radianceWhereMet(r.render(downZ(16)));
  ASSERT_GT(got.covered, 0.5);
  EXPECT_NEAR(got.color.x, 0.5, 0.01);
  EXPECT_NEAR(got.color.y, 0.25, 0.005);
  EXPECT_NEAR(got.color.z, 1.0, 0.02);
}

TEST(PathTrace, ALayersOwnAlbedoReplacesTheScenes) {
  // The furnace again with the scene's albedo 0 and the layer's albedo 1 at every value.
  const Model m = slab([](float z) { return z / 32.f; });
  Renderer r(m, DatasetInfo::of(m));
  TransferFunction tf = ramp(0.02f, 0.3f);
  tf.albedo = {{0.f, 1.f}, {1.f, 1.f}};
  Scene s = pathScene(tf);
  s.pathTracing.albedo = 0.f;
  s.pathTracing.bounces = 1000;
  s.pathTracing.environment = vec3f(0.5f, 0.25f, 1.f);
  r.setScene(s);
  const Radiance got = radianceWhereMet(r.render(downZ(16)));
  ASSERT_GT(got.covered, 0.5);
  EXPECT_NEAR(got.color.x, 0.5, 0.01);
  EXPECT_NEAR(got.color.z, 1.0, 0.02);
}

TEST(PathTrace, ALayersAlbedoCurveIsReadAtTheValue) {
  // A homogeneous slab of value 0.25 under the sun: the layer's albedo curve, 0 at value 0 rising
  // to 1 at 0.5, gives 0.5 there, so the picture equals the scene's albedo 0.5 (the same paths,
  // up to rounding of the extinction-weighted mean).
  const Model m = slab([](float) { return 0.25f; });
  Renderer r(m, DatasetInfo::of(m));
  auto render = [&](float sceneAlbedo, const std::vector<OpacityPoint>& curve) {
    TransferFunction tf = ramp(0.05f, 0.05f);
    tf.albedo = curve;
    Scene s = pathScene(tf);
    s.pathTracing.albedo = sceneAlbedo;
    s.pathTracing.sunDirection = vec3f(0.2f, 0.1f, -1.f);
    s.pathTracing.sunIntensity = 4.f;
    s.pathTracing.environment = vec3f(0.3f);
    r.setScene(s);
    return r.render(downZ(4));
  };
  const Image byScene = render(0.5f, {});
  const Image byCurve = render(0.f, {{0.f, 0.f}, {0.5f, 1.f}});
  const Image absorbing = render(0.f, {});
  double diff = 0.0, dark = 0.0;
  for (size_t i = 0; i < byScene.pixels.size(); ++i) {
    diff += std::fabs(byScene.pixels[i].x - byCurve.pixels[i].x);
    dark += byScene.pixels[i].x - absorbing.pixels[i].x;
  }
  const double n = double(byScene.pixels.size());
  EXPECT_LT(diff / n, 1e-3 * meanRed(byScene)) << "mean |difference| " << diff / n;
  EXPECT_GT(dark / n, 0.5 * meanRed(byScene)); // the scattered light is most of the picture
}

TEST(PathTrace, ASkyGradientLightsASphereFromAbove) {
  // A grey diffuse sphere (albedo 0.5) under a sky that is `h` at the horizon, `z` at the zenith
  // (the camera's up, +y) and 2h - z at the nadir: radiance linear in the sine of the elevation,
  // L(d) = h + (z - h) d.y, so a surface of normal n reflects 0.5 (h + (z - h) 2/3 n.y). The
  // view (12 units across) lies inside the sphere's disc (radius 9): n.y = y / 9 averages 1/3
  // over the upper half of the picture and -1/3 over the lower half.
  const Model m = finestCube("r", [](const vec3f& c) { return length(c - vec3f(16.f)); });
  Renderer r(m, DatasetInfo::of(m));
  Scene s = greySphere();
  const float h = 0.5f, z = 0.9f;
  s.pathTracing.environment = vec3f(h);
  s.pathTracing.sky = vec3f(z);
  s.pathTracing.ground = vec3f(2.f * h - z);
  r.setScene(s);
  const Image img = r.render(downZ(16));
  auto half = [&](bool upper) {
    Image part = img;
    part.pixels.clear();
    for (int y = 0; y < img.height; ++y)
      if ((y < img.height / 2) == upper)
        for (int x = 0; x < img.width; ++x)
          part.pixels.push_back(img.pixels[size_t(y) * size_t(img.width) + size_t(x)]);
    return radianceWhereMet(part).color.x;
  };
  const double slope = double(z - h) * 2.0 / 3.0 / 3.0;
  EXPECT_NEAR(half(true), 0.5 * (h + slope), 0.005);
  EXPECT_NEAR(half(false), 0.5 * (h - slope), 0.005);
}

TEST(PathTrace, AConvexDiffuseSurfaceReflectsItsAlbedoTimesTheEnvironment) {
  // An iso-surface sphere, grey (albedo 0.5) and diffuse, under a uniform environment and
  // nothing else: every bounce off a convex surface sees the sky, so it shows 0.5 times the
  // environment's radiance.
  const Model m = finestCube("r", [](const vec3f& c) { return length(c - vec3f(16.f)); });
  Renderer r(m, DatasetInfo::of(m));
  Scene s = greySphere();
  s.pathTracing.environment = vec3f(1.f, 0.5f, 0.25f);
  r.setScene(s);
  const Radiance got = radianceWhereMet(r.render(downZ(8)));
  ASSERT_GT(got.covered, 0.3);
  EXPECT_NEAR(got.color.x, 0.5, 0.01);
  EXPECT_NEAR(got.color.y, 0.25, 0.005);
  EXPECT_NEAR(got.color.z, 0.125, 0.003);
}

TEST(PathTrace, WithoutScatteringItConvergesToTheRayMarcher) {
  // Emission and absorption only (albedo 0, emission 1, black environment): the expected
  // radiance is the marcher's integral; a blob of varying colour and opacity.
  // Centred on the cell (16, 14, 16) (cell x has its centre at x + 0.5).
  const Model m = finestCube("f", [](const vec3f& c) {
    const vec3f d = c - vec3f(16.5f, 14.5f, 16.5f);
    return std::exp(-dot(d, d) / 60.f);
  });
  TransferFunction tf = defaultTransferFunction();
  tf.valueRange = range1f{0.f, 1.f};
  tf.opacity = {{0.f, 0.f}, {1.f, 0.25f}};
  tf.opacityScale = 1.f;
  Scene march = Scene::volumeOf(tf, "f");
  march.shading = Shading::None;
  march.integration.earlyTermination = false;
  Frame f;
  f.width = f.height = 48;
  f.camera.position = vec3d(60.0, 40.0, 30.0);
  f.camera.lookAt = vec3d(16.0, 16.0, 16.0);
  f.camera.up = vec3d(0.0, 0.0, 1.0);
  f.camera.fovy = 35.0;
  f.rate = 8.f;
  Renderer r(m, DatasetInfo::of(m));
  r.setScene(march);
  const Image want = r.render(f);
  Scene path = march;
  path.integration.integrator = Integrator::PathTrace;
  path.pathTracing.albedo = 0.f;
  path.pathTracing.emission = 1.f;
  path.pathTracing.environment = vec3f(0.f);
  r.setScene(path);
  f.samplesPerPixel = 256;
  f.rate = 1.f;
  const Image got = r.render(f);
  double diff = 0.0, signedDiff = 0.0;
  for (size_t i = 0; i < want.pixels.size(); ++i) {
    const vec4f& a = got.pixels[i];
    const vec4f& b = want.pixels[i];
    for (const double d : {a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w}) {
      diff += std::abs(d);
      signedDiff += d;
    }
  }
  const double n = 4.0 * double(want.pixels.size());
  std::printf("path tracer against the marcher: mean |difference| %.3f/255, mean difference %.3f/255\n",
              255.0 * diff / n, 255.0 * signedDiff / n);
  EXPECT_LT(255.0 * diff / n, 2.0) << "mean |difference| in 1/255 (the paths' noise)";
  EXPECT_LT(std::abs(255.0 * signedDiff / n), 0.3) << "mean difference (bias) in 1/255";
}

TEST(PathTrace, BadSettingsNameTheirKey) {
  auto refused = [](const std::function<void(Scene&)>& change, const char* key) {
    Scene s;
    change(s);
    try {
      s.validate();
      ADD_FAILURE() << key << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  refused([](Scene& s) { s.pathTracing.albedo = 1.5f; }, "pathtrace.albedo");
  refused([](Scene& s) { s.pathTracing.albedo = -0.1f; }, "pathtrace.albedo");
  refused([](Scene& s) { s.pathTracing.anisotropy = 1.f; }, "pathtrace.anisotropy");
  refused([](Scene& s) { s.pathTracing.anisotropy = -1.f; }, "pathtrace.anisotropy");
  refused([](Scene& s) { s.pathTracing.bounces = -1; }, "pathtrace.bounces");
  refused([](Scene& s) { s.pathTracing.sunIntensity = -2.f; }, "pathtrace.sun_intensity");
  refused([](Scene& s) { s.pathTracing.environment = vec3f(1.f, -1.f, 0.f); }, "pathtrace.environment");
  refused([](Scene& s) { s.pathTracing.sunDirection = vec3f(0.f); }, "pathtrace.sun_direction");
  refused([](Scene& s) { s.pathTracing.sky = vec3f(0.f, 0.f, -1.f); }, "pathtrace.sky");
  refused([](Scene& s) { s.pathTracing.ground = vec3f(NAN, 0.f, 0.f); }, "pathtrace.ground");
  refused([](Scene& s) { s.layers[0].tf.albedo = {{0.f, 0.5f}, {1.f, 1.5f}}; }, "albedo point 1");
}
