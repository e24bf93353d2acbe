// Particles drawn as spheres with the volume: depth order against a slab of gas (a sphere in
// front of it hides it, one behind it is dimmed by all of it, one inside by what lies in front of
// its surface), colours and radii from attributes, clipping, and the device path (Device::Portable)
// against the CPU.
#include "errors.h"
#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"
#include "render_setup.h"
#include "surface_scenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace exa;
using namespace exa::test;

namespace {

float channel(const vec4f& v, int c) { return c == 0 ? v.x : c == 1 ? v.y : c == 2 ? v.z : v.w; }

/// One species of the given centres; attribute "mass" and "temperature" per particle.
std::shared_ptr<ParticleSet> speciesOf(const std::vector<vec3d>& centres, const std::vector<double>& mass = {},
                                       const std::vector<double>& temperature = {}) {
  auto set = std::make_shared<ParticleSet>();
  ParticleSpecies s;
  s.name = "stars";
  for (const vec3d& c : centres)
    s.position.insert(s.position.end(), {c.x, c.y, c.z});
  s.attributes.push_back({"mass", mass.empty() ? std::vector<double>(centres.size(), 1.0) : mass, false});
  s.attributes.push_back(
      {"temperature", temperature.empty() ? std::vector<double>(centres.size(), 0.0) : temperature, false});
  set->species.push_back(std::move(s));
  return set;
}

/// A slab of grey gas where z lies in [lo, hi] (field f = z over a 16^3 lattice, opacity only over
/// that band of values).
TransferFunction slab(float lo, float hi, float alpha) {
  TransferFunction tf = grayRamp(0.f, 16.f, alpha);
  tf.opacity = {{0.f, 0.f},         {lo / 16.f - 1e-4f, 0.f}, {lo / 16.f, alpha},
                {hi / 16.f, alpha}, {hi / 16.f + 1e-4f, 0.f}, {1.f, 0.f}};
  return tf;
}

const Camera kDown = ortho(vec3d(8.0, 8.0, 8.0), vec3d(0.0, 0.0, -1.0), vec3d(0.0, 1.0, 0.0), 16.0);

struct SlabScene {
  Model model = buildModel(uniformCells(16, {"f"}, [](const vec3d& p) { return p.z; }));
  RenderSetup setup = surfaceOptions(64);
  SceneRenderer volumeOnly{model, 0, setup};
  SlabScene(float lo, float hi) { volumeOnly.setTransferFunction(slab(lo, hi, 0.15f)); }
  /// The same scene with the particles (radius 1.5, one colour), with or without the volume.
  Image withParticles(const std::shared_ptr<ParticleSet>& set, bool volume, float lo, float hi,
                      Device device = Device::Cpu) {
    SceneRenderer r(model, 0, setup);
    r.renderer.setParticles(set);
    r.scene.volume = volume;
    r.scene.particles.show = true;
    r.scene.particles.radius = 1.5f;
    r.scene.particles.color = vec3f(0.9f, 0.5f, 0.2f);
    r.setTransferFunction(slab(lo, hi, 0.15f));
    if (device != Device::Cpu) r.renderer.setDevice(device);
    return r.render(kDown);
  }
};

} // namespace

TEST(ParticleRender, SpheresInFrontHideTheGasAndSpheresBehindAreDimmedByAllOfIt) {
  SlabScene s(7.f, 9.f);
  // In front of the slab (z = 12), behind it (z = 4): neither touches it.
  const auto set = speciesOf({{4.0, 4.0, 12.0}, {12.0, 12.0, 4.0}});
  const Image gas = s.volumeOnly.render(kDown);
  const Image spheres = s.withParticles(set, false, 7.f, 9.f);
  const Image both = s.withParticles(set, true, 7.f, 9.f);
  int front = 0, behind = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const vec4f &g = gas.at(x, y), &p = spheres.at(x, y), &b = both.at(x, y);
      if (p.w < 1.f) {
        EXPECT_NEAR(b.x, g.x, 1e-5) << x << "," << y; // no sphere: the gas alone
        continue;
      }
      if (x < 32) { // the sphere in front: the gas behind it does not show
        ++front;
        for (int c = 0; c < 4; ++c)
          EXPECT_NEAR(channel(b, c), channel(p, c), 1e-5) << x << "," << y;
      } else { // behind: the whole slab in front of it, composited over the sphere
        ++behind;
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(channel(b, c), channel(g, c) + (1.f - g.w) * channel(p, c), 2e-4) << x << "," << y;
        EXPECT_GT(g.w, 0.1f); // the slab in front is not transparent
      }
    }
  EXPECT_GT(front, 80);
  EXPECT_GT(behind, 80);
}

TEST(ParticleRender, ASphereInsideTheGasIsDimmedByTheGasInFrontOfItsSurface) {
  SlabScene s(4.f, 12.f);
  const vec3d centre(8.0, 8.0, 8.0);
  const auto set = speciesOf({centre});
  const Image spheres = s.withParticles(set, false, 4.f, 12.f);
  const Image both = s.withParticles(set, true, 4.f, 12.f);
  // The pixel nearest the sphere's centre: its ray meets the sphere's top at z = 9.5 (within
  // the half pixel's curvature); the gas in front of it is the slab clipped below that.
  double sx = 0, sy = 0, n = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      if (spheres.at(x, y).w >= 1.f) sx += x, sy += y, n += 1;
  ASSERT_GT(n, 100);
  const int cx = int(std::lround(sx / n)), cy = int(std::lround(sy / n));
  SurfaceHit hit;
  {
    SceneRenderer r(s.model, 0, s.setup);
    r.renderer.setParticles(set);
    r.scene.particles.show = true;
    r.scene.particles.radius = 1.5f;
    r.setTransferFunction(slab(4.f, 12.f, 0.15f));
    ASSERT_TRUE(r.pick(vec3d(centre.x, centre.y, 100.0), vec3d(0, 0, -1), hit));
    EXPECT_EQ(hit.kind, SurfaceHit::Particle);
    EXPECT_NEAR(hit.position.z, 9.5, 1e-5);
    EXPECT_NEAR(hit.normal.z, 1.0, 1e-5);
  }
  RenderSetup clipped = s.setup;
  clipped.scene.clip.planes = {{vec3d(0.0, 0.0, 9.5), vec3d(0.0, 0.0, -1.0)}};
  SceneRenderer front(s.model, 0, clipped);
  front.setTransferFunction(slab(4.f, 12.f, 0.15f));
  const vec4f g = front.render(kDown).at(cx, cy), p = spheres.at(cx, cy), b = both.at(cx, cy);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(channel(b, c), channel(g, c) + (1.f - g.w) * channel(p, c), 3e-3);
  const vec4f whole = s.volumeOnly.render(kDown).at(cx, cy);
  EXPECT_GT(g.w, 0.05f);
  EXPECT_LT(g.w, whole.w); // some of the slab lies behind the surface
}

TEST(ParticleRender, ColoursAndRadiiFromAttributesAndOneSpeciesOnly) {
  const Model m = buildModel(uniformCells(16, {"f"}, [](const vec3d&) { return 0.0; }));
  RenderSetup o = surfaceOptions(64);
  o.scene.volume = false;
  o.scene.light.terms = {1.f, 0.f, 0.f, 1.f}; // ambient only: a sphere shows its colour
  SceneRenderer r(m, 0, o);
  auto set = speciesOf({{4.0, 8.0, 8.0}, {12.0, 8.0, 8.0}}, {1.0, 8.0}, {0.0, 1.0});
  ParticleSpecies other = set->species[0];
  other.name = "gas";
  other.position = {8.0, 2.0, 8.0};
  for (ParticleAttribute& a : other.attributes)
    a.values.resize(1);
  set->species.push_back(other);
  r.renderer.setParticles(set);
  r.scene.particles.show = true;
  r.scene.particles.species = "stars";
  r.scene.particles.radius = 2.f;
  r.scene.particles.radiusBy = "mass";
  r.scene.particles.colorBy = "temperature";
  r.scene.particles.colorTf = defaultTransferFunction("viridis");
  r.renderer.setScene(r.scene);
  EXPECT_EQ(r.renderer.particleCount(), 2u);
  // Radius 2 x cbrt(m / 8): 1 and 2. A ray 1.5 from each centre misses the first, meets the second.
  SurfaceHit hit;
  EXPECT_FALSE(r.pick(vec3d(4.0, 9.5, 100.0), vec3d(0, 0, -1), hit));
  ASSERT_TRUE(r.pick(vec3d(12.0, 9.5, 100.0), vec3d(0, 0, -1), hit));
  EXPECT_NEAR(hit.position.z, 8.0 + std::sqrt(4.0 - 2.25), 1e-5);
  EXPECT_FALSE(r.pick(vec3d(8.0, 2.0, 100.0), vec3d(0, 0, -1), hit)); // the other species is not drawn
  // Colours: the map's ends at temperature 0 and 1 (the attribute's range).
  const Image im = r.render(kDown);
  const ColorMap viridis = builtinColorMap("viridis");
  auto near = [](const vec4f& a, const vec3f& b) {
    return std::abs(a.x - b.x) < 1e-4 && std::abs(a.y - b.y) < 1e-4 && std::abs(a.z - b.z) < 1e-4;
  };
  EXPECT_TRUE(near(im.at(16, 32), viridis.at(0.f))) << im.at(16, 32).x << " " << im.at(16, 32).y;
  EXPECT_TRUE(near(im.at(48, 32), viridis.at(1.f))) << im.at(48, 32).x << " " << im.at(48, 32).y;
  // Errors name the species or attribute and keep the scene.
  Scene bad = r.scene;
  bad.particles.colorBy = "metallicity";
  expectIn(errorOf([&] { r.renderer.setScene(bad); }), {"color_by", "no particle attribute 'metallicity'", "mass"});
  bad = r.scene;
  bad.particles.species = "dark_matter";
  expectIn(errorOf([&] { r.renderer.setScene(bad); }), {"no particle species 'dark_matter'", "stars, gas"});
  EXPECT_EQ(r.renderer.particleCount(), 2u);
  // Clipping with the meshes' flag.
  r.scene.clip.planes = {{vec3d(8.0, 0.0, 0.0), vec3d(1.0, 0.0, 0.0)}};
  r.scene.clip.meshes = true;
  r.renderer.setScene(r.scene);
  EXPECT_FALSE(r.pick(vec3d(12.0, 8.0, 100.0), vec3d(0, 0, -1), hit));
  EXPECT_TRUE(r.pick(vec3d(4.0, 8.0, 100.0), vec3d(0, 0, -1), hit));
}

TEST(ParticleRender, ARadiusInPixelsIsMeasuredAtTheLookAtPointsDistance) {
  const Model m = buildModel(uniformCells(16, {"f"}, [](const vec3d&) { return 0.0; }));
  RenderSetup o = surfaceOptions(64);
  o.scene.volume = false;
  SceneRenderer r(m, 0, o);
  r.renderer.setParticles(speciesOf({{8.0, 8.0, 8.0}}));
  r.scene.particles.show = true;
  r.scene.particles.radius = 0.5f; // replaced by the radius in pixels
  r.scene.particles.radiusPixels = 6.f;
  // The sphere's radius as rays straight down find it (bisection on their offset from the centre).
  auto radiusFound = [&](const Camera& camera) {
    Frame frame;
    frame.camera = camera;
    frame.width = frame.height = 64;
    Scene placed = r.scene;
    resolveParticleRadius(placed, frame);
    r.renderer.setScene(placed);
    double hit = 0.0, miss = 8.0;
    SurfaceHit h;
    for (int i = 0; i < 40; ++i) {
      const double mid = 0.5 * (hit + miss);
      (r.pick(vec3d(8.0 + mid, 8.0, 100.0), vec3d(0, 0, -1), h) ? hit : miss) = mid;
    }
    return hit;
  };
  // Orthographic, 16 world units over 64 pixels: 6 pixels are 1.5.
  EXPECT_NEAR(radiusFound(kDown), 1.5, 1e-4);
  const Image im = r.render(kDown);
  int lit = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      lit += im.at(x, y).w > 0.5f;
  EXPECT_NEAR(lit, M_PI * 36, 12);           // a disc of 6 pixels' radius
  EXPECT_EQ(r.scene.particles.radius, 0.5f); // the scene itself keeps its settings
  // Perspective, fovy 40, at distances 92 and 46: the world radius follows the distance.
  for (double distance : {92.0, 46.0}) {
    Camera c;
    c.position = vec3d(8.0, 8.0, 8.0 + distance);
    c.lookAt = vec3d(8.0);
    c.fovy = 40.0;
    EXPECT_NEAR(radiusFound(c), 6.0 * 2.0 * distance * std::tan(20.0 * M_PI / 180.0) / 64.0, 1e-4) << distance;
  }
}

TEST(ParticleRender, TheDevicePathDrawsTheSameParticles) {
  SlabScene s(6.f, 10.f);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 16.0);
  std::vector<vec3d> centres;
  std::vector<double> mass, temperature;
  for (int i = 0; i < 400; ++i) {
    centres.push_back({u(rng), u(rng), u(rng)});
    mass.push_back(u(rng) + 0.1);
    temperature.push_back(u(rng));
  }
  const auto set = speciesOf(centres, mass, temperature);
  for (bool volume : {false, true}) {
    SCOPED_TRACE(volume);
    const Image cpu = s.withParticles(set, volume, 6.f, 10.f);
    const Image portable = s.withParticles(set, volume, 6.f, 10.f, Device::Portable);
    RecordProperty(volume ? "max_abs_diff_with_volume" : "max_abs_diff", std::to_string(maxAbsDiff(cpu, portable)));
    EXPECT_LT(maxAbsDiff(cpu, portable), 1.0 / 255.0);
  }
}
