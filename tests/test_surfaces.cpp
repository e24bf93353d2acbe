// Surfaces and effects against analytic truth: iso-surfaces of linear and radial fields, meshes
// hiding the volume, clipping removing exactly a half-space, ambient occlusion in a corner and
// on an open plane, colouring by a second field and the multi-field combination rule. Per-pixel
// depth limits are tested in test_depth_limit.cpp.
#include "datasets.h"
#include "errors.h"
#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/documents/mesh.h"
#include "exabricks/render/renderer.h"
#include "reference.h"
#include "render_setup.h"
#include "surface_scenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace exa;
using namespace exa::test;

TEST(Surfaces, LinearFieldIsoSurfaceIsThePlane) {
  // f = a . lattice centre; with a world transform the plane in world space is
  // a . (w - origin) / scale = c.
  const vec3d a(0.3, 0.2, 0.1);
  CellSet cells = uniformCells(32, {"f"}, [&](const vec3d& p) { return dot(a, p); });
  cells.world.origin = vec3d(-3.0, 4.0, 1.0);
  cells.world.scale = vec3d(2.0, 1.0, 0.5);
  BuildOptions bo;
  bo.bricks.maxBrickWidth = 8; // many bricks and regions, so that the iso set is a true subset
  const Model m = buildModel(std::move(cells), bo);
  SceneRenderer r(m, 0, surfaceOptions(8));
  r.setTransferFunction(invisible());
  const float iso = 8.f;
  IsoSurfaces is;
  is.field = r.field(0);
  is.values = {iso};
  r.setIsoSurfaces(is);
  EXPECT_GT(r.isoRegions(), 0u);
  EXPECT_LT(r.isoRegions(), m.regions.regions.size());
  const vec3d worldNormal = normalize(a / m.world.scale);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int i = 0; i < 400; ++i) {
    // Rays from outside towards random interior points.
    const vec3d target = m.world.toWorld(vec3d(16.0 + 10 * u(rng), 16.0 + 10 * u(rng), 16.0 + 10 * u(rng)));
    const vec3d dir = normalize(test::draw3(u, rng) + vec3d(0.01));
    const vec3d org = target - dir * 200.0;
    SurfaceHit hit;
    if (!r.pick(org, dir, hit)) continue;
    const vec3d lat = m.world.toLattice(hit.position);
    if (reduceMin(lat) < 1.0 || reduceMax(lat) > 31.0) continue; // exact only away from the border
    ++hits;
    EXPECT_EQ(hit.kind, SurfaceHit::Iso);
    // Distance from the plane in lattice units along the gradient: root finding is to 1e-3 of
    // the cell width.
    const double distance = std::abs(dot(a, lat) - iso) / length(a);
    EXPECT_LT(distance, 1.5e-3) << "hit " << lat.x << "," << lat.y << "," << lat.z;
    EXPECT_GT(std::abs(dot(vec3d(hit.normal), worldNormal)), 1.0 - 1e-5);
    EXPECT_LE(dot(vec3d(hit.normal), dir), 0.0); // faces the viewer
  }
  EXPECT_GT(hits, 100);
}

TEST(Surfaces, RadialFieldIsoSurfaceIsASphere) {
  const vec3d centre(31.3, 32.6, 30.9);
  const Model m = buildModel(radialTwoLevels(centre, 26.0));
  SceneRenderer r(m, 0, surfaceOptions(8));
  r.setTransferFunction(invisible());
  const float radius = 20.f;
  IsoSurfaces is;
  is.field = r.field(0);
  is.values = {radius, 40.f}; // the second lies mostly outside the data
  r.setIsoSurfaces(is);
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  double worstRadius = 0, worstAngle = 0;
  int hits = 0;
  for (int i = 0; i < 300; ++i) {
    const vec3d dir = normalize(test::draw3(g, rng));
    // Aim at points within 15 units of the centre: the ray crosses the sphere.
    const vec3d aim = centre + test::draw3(g, rng) * 5.0;
    const vec3d org = aim - dir * 60.0; // well outside the sphere
    SurfaceHit hit;
    if (!r.pick(org, dir, hit)) continue;
    if (hit.index != 0) continue;
    ++hits;
    const vec3d toHit = hit.position - centre;
    worstRadius = std::max(worstRadius, std::abs(length(toHit) - radius));
    // Seen from outside, the normal points outwards.
    worstAngle = std::max(worstAngle, std::acos(std::min(1.0, dot(vec3d(hit.normal), normalize(toHit)))));
  }
  EXPECT_GT(hits, 150);
  RecordProperty("worst_radius_error", std::to_string(worstRadius));
  RecordProperty("worst_normal_degrees", std::to_string(worstAngle * 180.0 / M_PI));
  // Trilinear-like reconstruction of |p - c| deviates by about w^2 / (8 r) from the sphere.
  EXPECT_LT(worstRadius, 0.03);
  EXPECT_LT(worstAngle * 180.0 / M_PI, 3.0);
}

TEST(Surfaces, IsoRegionSetFollowsTheIsoValues) {
  const Model m = buildModel(radialTwoLevels(vec3d(32.0), 20.0));
  SceneRenderer r(m, 0, surfaceOptions(8));
  r.setTransferFunction(invisible());
  IsoSurfaces is;
  is.field = r.field(0);
  is.values = {10.f};
  r.setIsoSurfaces(is);
  const size_t one = r.isoRegions();
  size_t expected = 0;
  for (const range1f& v : m.regions.valueRanges[0])
    expected += v.lower <= 10.f && 10.f <= v.upper;
  EXPECT_EQ(one, expected);
  is.values = {10.f, 25.f};
  r.setIsoSurfaces(is);
  EXPECT_GT(r.isoRegions(), one);
  is.values = {1000.f};
  r.setIsoSurfaces(is);
  EXPECT_EQ(r.isoRegions(), 0u);
  SurfaceHit hit;
  EXPECT_FALSE(r.pick(vec3d(32, 32, -50), vec3d(0, 0, 1), hit));
}

TEST(Surfaces, MeshInFrontHidesTheVolume) {
  CellSet cells = uniformCells(16, {"f"}, [](const vec3d& p) { return p.x / 16.0; });
  const Model m = buildModel(std::move(cells));
  RenderSetup o = surfaceOptions(32);
  const Camera cam = ortho(vec3d(8.0), vec3d(0, 0, 1), vec3d(0, 1, 0), 20.0);
  // A quad in front of the volume (z = -1) covering the whole view.
  const TriangleMesh front = quad({-20, -20, -1}, {40, -20, -1}, {40, 40, -1}, {-20, 40, -1});
  SceneRenderer both(m, 0, o);
  both.setTransferFunction(grayRamp(0.f, 1.f, 0.5f));
  both.addMesh(front, vec3f(0.2f, 0.5f, 0.8f));
  o.scene.volume = false;
  SceneRenderer meshOnly(m, 0, o);
  meshOnly.setTransferFunction(grayRamp(0.f, 1.f, 0.5f));
  meshOnly.addMesh(front, vec3f(0.2f, 0.5f, 0.8f));
  RenderStats st;
  const Image a = both.render(cam, &st);
  EXPECT_EQ(st.samples, 0u); // the volume behind the mesh is never sampled
  EXPECT_EQ(maxAbsDiff(a, meshOnly.render(cam)), 0.0);

  // The same mesh behind the volume: the volume shows in front of it.
  const TriangleMesh back = quad({-20, -20, 17}, {40, -20, 17}, {40, 40, 17}, {-20, 40, 17});
  RenderSetup o2 = surfaceOptions(32);
  SceneRenderer behind(m, 0, o2);
  behind.setTransferFunction(grayRamp(0.f, 1.f, 0.5f));
  behind.addMesh(back, vec3f(0.2f, 0.5f, 0.8f));
  const Image b = behind.render(cam, &st);
  EXPECT_GT(st.samples, 0u);
  EXPECT_GT(maxAbsDiff(a, b), 0.1);
  for (const vec4f& p : b.pixels)
    EXPECT_FLOAT_EQ(p.w, 1.f);
}

TEST(Surfaces, ClipPlaneRemovesExactlyOneHalfSpace) {
  CellSet cells = uniformCells(16, {"f"}, [](const vec3d& p) { return (p.x + p.y + p.z) / 48.0; });
  const Model m = buildModel(std::move(cells));
  RenderSetup o = surfaceOptions(40);
  o.scene.shading = Shading::None;
  const Camera cam = ortho(vec3d(8.0), vec3d(0, 0, 1), vec3d(0, 1, 0), 20.0);
  SceneRenderer full(m, 0, o);
  full.setTransferFunction(grayRamp(0.f, 1.f, 0.2f));
  // Remove y > 7.3 (the plane is parallel to the view direction): a pixel is either kept whole
  // or removed whole.
  o.scene.clip.planes = {{vec3d(0.0, 7.3, 0.0), vec3d(0.0, 1.0, 0.0)}};
  SceneRenderer clipped(m, 0, o);
  clipped.setTransferFunction(grayRamp(0.f, 1.f, 0.2f));
  const Image a = full.render(cam), b = clipped.render(cam);
  int kept = 0, removed = 0;
  for (int y = 0; y < o.frame.height; ++y)
    for (int x = 0; x < o.frame.width; ++x) {
      vec3d org, dir;
      cam.ray((x + 0.5) / o.frame.width, (y + 0.5) / o.frame.height, 1.0, org, dir);
      const vec4f &pa = a.at(x, y), &pb = b.at(x, y);
      if (org.y > 7.3 + 1e-6) {
        EXPECT_EQ(pb.w, 0.f);
        ++removed;
      } else {
        EXPECT_EQ(pa.x, pb.x);
        EXPECT_EQ(pa.w, pb.w);
        kept += pa.w > 0.f;
      }
    }
  EXPECT_GT(kept, 100);
  EXPECT_GT(removed, 100);

  // Across the view direction, a plane at z = 8 removes the far half of each ray: the clipped
  // image equals the image of a dataset cut in half at z = 8 (clipped the same way, so that the
  // margin of its supports beyond z = 8 does not count). The opacity is constant, so alpha
  // matches to round-off; colours differ only by the reconstruction just below z = 8.
  CellSet half;
  half.fields.push_back({"f", {}});
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        half.cells.push_back({vec3i(x, y, z), 0});
        half.fields[0].values.push_back(float((x + y + z + 1.5) / 48.0));
      }
  const Model mh = buildModel(std::move(half));
  RenderSetup oh = surfaceOptions(40);
  oh.scene.shading = Shading::None;
  oh.scene.clip.planes = {{vec3d(0.0, 0.0, 8.0), vec3d(0.0, 0.0, 1.0)}};
  SceneRenderer halfRenderer(mh, 0, oh);
  halfRenderer.setTransferFunction(grayRamp(0.f, 1.f, 0.2f));
  o.scene.clip.planes = {{vec3d(0.0, 0.0, 8.0), vec3d(0.0, 0.0, 1.0)}};
  SceneRenderer cut(m, 0, o);
  cut.setTransferFunction(grayRamp(0.f, 1.f, 0.2f));
  const Image c = cut.render(cam), d = halfRenderer.render(cam);
  double alphaDiff = 0, colorDiff = 0, alphaMax = 0;
  for (size_t i = 0; i < c.pixels.size(); ++i) {
    alphaDiff = std::max<double>(alphaDiff, std::abs(c.pixels[i].w - d.pixels[i].w));
    colorDiff = std::max<double>(colorDiff, std::abs(c.pixels[i].x - d.pixels[i].x));
    alphaMax = std::max<double>(alphaMax, c.pixels[i].w);
  }
  EXPECT_GT(alphaMax, 0.5);
  EXPECT_LT(alphaDiff, 1e-4);
  EXPECT_LT(colorDiff, 0.02);

  // A clip box keeps only its inside.
  RenderSetup ob = surfaceOptions(40);
  ob.scene.shading = Shading::None;
  ob.scene.clip.box = box3d(vec3d(-1.0, -1.0, -1.0), vec3d(4.0, 20.0, 20.0));
  SceneRenderer boxed(m, 0, ob);
  boxed.setTransferFunction(grayRamp(0.f, 1.f, 0.2f));
  const Image e = boxed.render(cam);
  for (int y = 0; y < ob.frame.height; ++y)
    for (int x = 0; x < ob.frame.width; ++x) {
      vec3d org, dir;
      cam.ray((x + 0.5) / ob.frame.width, (y + 0.5) / ob.frame.height, 1.0, org, dir);
      if (org.x > 4.0 + 1e-6) {
        EXPECT_EQ(e.at(x, y).w, 0.f);
      }
    }
}

TEST(Surfaces, AmbientOcclusionDarkensACornerAndLeavesAnOpenPlane) {
  // A tiny volume far away; only meshes are in view.
  CellSet cells = uniformCells(2, {"f"}, [](const vec3d&) { return 0.0; });
  cells.world.origin = vec3d(1000.0);
  const Model m = buildModel(std::move(cells));
  const TriangleMesh floor = quad({-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0});
  const TriangleMesh wall = quad({0, -10, 0}, {0, 10, 0}, {0, 10, 10}, {0, -10, 10});
  const Camera cam = ortho(vec3d(2.0, 0.0, 0.0), normalize(vec3d(-1.0, 0.0, -1.0)), vec3d(0, 0, 1), 8.0);
  auto render = [&](bool withWall, int aoRays) {
    RenderSetup o = surfaceOptions(48);
    o.scene.ao.rays = aoRays;
    o.scene.ao.length = 2.f;
    SceneRenderer r(m, 0, o);
    r.setTransferFunction(invisible());
    r.addMesh(floor, vec3f(0.8f));
    if (withWall) r.addMesh(wall, vec3f(0.8f));
    return r.render(cam);
  };
  // An open plane: no AO ray can hit anything, the image is unchanged.
  EXPECT_EQ(maxAbsDiff(render(false, 0), render(false, 8)), 0.0);
  // The corner: pixels near the wall's foot get darker, far ones stay.
  const Image plain = render(true, 0), occluded = render(true, 16);
  double darkened = 0;
  int unchanged = 0, total = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 48; ++x) {
      vec3d org, dir;
      cam.ray((x + 0.5) / 48, (y + 0.5) / 48, 1.0, org, dir);
      // Where does the pixel land? Intersect with the floor z = 0 and the wall x = 0.
      const double sFloor = -org.z / dir.z, sWall = -org.x / dir.x;
      const double s = std::min(sFloor > 0 ? sFloor : 1e30, sWall > 0 ? sWall : 1e30);
      const vec3d p = org + dir * s;
      const float a = plain.at(x, y).x, b = occluded.at(x, y).x;
      EXPECT_LE(b, a + 1e-6f);
      const double distanceToCorner = std::sqrt(p.x * p.x + p.z * p.z);
      if (distanceToCorner < 0.3 && std::abs(p.y) < 5) darkened = std::max<double>(darkened, (a - b) / a);
      if (distanceToCorner > 2.5 && std::abs(p.y) < 5) {
        ++total;
        unchanged += a == b;
      }
    }
  EXPECT_GT(darkened, 0.15);
  EXPECT_GT(total, 20);
  EXPECT_EQ(unchanged, total);
}

TEST(Surfaces, SecondFieldColoursTheIsoSurface) {
  const vec3d centre(32.0);
  const Model m = buildModel(radialTwoLevels(centre, 26.0));
  RenderSetup o = surfaceOptions(64);
  o.scene.light.terms.ambient = 1.f, o.scene.light.terms.diffuse = 0.f,
  o.scene.light.terms.specular = 0.f; // unlit: the pixel is the surface colour
  SceneRenderer r(m, 0, o);
  r.setTransferFunction(invisible());
  IsoSurfaces is;
  is.field = r.field(0);
  is.values = {20.f};
  is.colorField = r.field(1);
  is.colorTf.colorMap = builtinColorMap("viridis");
  is.colorTf.valueRange = range1f{12.f, 52.f};
  r.setIsoSurfaces(is);
  const Camera cam = ortho(centre, vec3d(0, 0, 1), vec3d(0, 1, 0), 48.0);
  const Image img = r.render(cam);
  const ColorMap viridis = builtinColorMap("viridis");
  int checked = 0;
  for (int y = 0; y < 64; y += 3)
    for (int x = 0; x < 64; x += 3) {
      vec3d org, dir;
      cam.ray((x + 0.5) / 64, (y + 0.5) / 64, 1.0, org, dir);
      SurfaceHit hit;
      if (!r.pick(org, dir, hit)) continue;
      const vec3f expected = viridis.at(float((hit.position.x - 12.0) / 40.0));
      const vec4f& p = img.at(x, y);
      EXPECT_NEAR(p.x, expected.x, 0.01);
      EXPECT_NEAR(p.y, expected.y, 0.01);
      EXPECT_NEAR(p.z, expected.z, 0.01);
      ++checked;
    }
  EXPECT_GT(checked, 50);
}

TEST(Surfaces, LayersCombineAsSummedOpticalDepth) {
  CellSet cells = uniformCells(
      16, {"a", "b"}, [](const vec3d& p) { return p.x / 16.0; }, [](const vec3d& p) { return p.y / 16.0; });
  const Model m = buildModel(std::move(cells));
  RenderSetup o = surfaceOptions(24);
  o.scene.shading = Shading::None;
  const Camera cam = ortho(vec3d(8.0), normalize(vec3d(0.3, 0.2, 1.0)), vec3d(0, 1, 0), 24.0);
  const float alpha = 0.1f;
  // Two identical layers = one layer with opacity 1 - (1 - alpha)^2.
  SceneRenderer one(m, 0, o), two(m, 0, o);
  one.setTransferFunction(grayRamp(0.f, 1.f, 1.f - (1.f - alpha) * (1.f - alpha)));
  two.setVolumeLayers({{0, grayRamp(0.f, 1.f, alpha)}, {0, grayRamp(0.f, 1.f, alpha)}});
  EXPECT_LT(maxAbsDiff(one.render(cam), two.render(cam)), 2e-3);
  // A transparent second layer changes nothing; a second field's layer does.
  SceneRenderer single(m, 0, o), withClear(m, 0, o), withB(m, 0, o);
  single.setTransferFunction(grayRamp(0.f, 1.f, alpha));
  withClear.setVolumeLayers({{0, grayRamp(0.f, 1.f, alpha)}, {1, grayRamp(0.f, 1.f, 0.f)}});
  TransferFunction red = grayRamp(0.f, 1.f, alpha);
  red.colorMap = builtinColorMap("inferno");
  withB.setVolumeLayers({{0, grayRamp(0.f, 1.f, alpha)}, {1, red}});
  const Image s = single.render(cam);
  EXPECT_LT(maxAbsDiff(s, withClear.render(cam)), 1e-5);
  EXPECT_GT(maxAbsDiff(s, withB.render(cam)), 0.05);
}

TEST(Surfaces, BadSurfaceOptionsAreRejected) {
  CellSet cells = uniformCells(4, {"f"}, [](const vec3d& p) { return p.x; });
  const Model m = buildModel(std::move(cells));
  RenderSetup o = surfaceOptions(8);
  SceneRenderer r(m, 0, o);
  IsoSurfaces is;
  is.field = "nope";
  is.values = {1.f};
  EXPECT_THROW(r.setIsoSurfaces(is), Error);
  is.field = r.field(0);
  is.values = {std::nanf("")};
  EXPECT_THROW(r.setIsoSurfaces(is), Error);
  TriangleMesh bad = quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
  bad.triangles.push_back(vec3i(0, 1, 7));
  EXPECT_THROW(r.addMesh(bad, vec3f(1.f)), Error);
  TriangleMesh nan = quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
  nan.vertices[2].y = std::nanf("");
  EXPECT_THROW(r.addMesh(nan, vec3f(1.f)), Error);
  o.scene.clip.planes = {{vec3d(0.0), vec3d(0.0)}};
  EXPECT_THROW(SceneRenderer(m, 0, o), Error);
}

TEST(Surfaces, IsoHitsAreTheFirstRootsOfTheBruteForceReconstruction) {
  // Multi-level data with level jumps: every hit must be a root of the reconstruction computed
  // over all cells, and the first one along the ray.
  const CellSet cells = generateScene({"shells", 3000, 2, 4});
  const Model m = buildModel(CellSet(cells));
  SceneRenderer r(m, 0, surfaceOptions(8));
  r.setTransferFunction(invisible());
  range1f range;
  for (float v : cells.fields[0].values)
    range.extend(v);
  const float iso = range.lower + 0.45f * (range.upper - range.lower);
  IsoSurfaces is;
  is.field = r.field(0);
  is.values = {iso};
  r.setIsoSurfaces(is);
  const box3l b = cells.bounds();
  const vec3d lo(b.lower), hi(b.upper), centre = (lo + hi) * 0.5;
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  int rays = 0, agree = 0, hits = 0, grazing = 0;
  for (int i = 0; i < 60; ++i) {
    const vec3d dir = normalize(test::draw3(g, rng));
    const vec3d aim = centre + test::draw3(g, rng) * (0.15 * length(hi - lo));
    const vec3d org = aim - dir * length(hi - lo);
    SurfaceHit hit;
    const bool found = r.pick(org, dir, hit);
    // Dense brute-force walk along the ray: the first two sign changes of value - iso.
    const double step = 0.02;
    double roots[2] = {-1, -1};
    int rootCount = 0;
    bool havePrev = false, prevSide = false;
    for (double s = 0; s < 2.0 * length(hi - lo) && rootCount < 2; s += step) {
      const test::Reference ref = test::bruteForce(cells, 0, org + dir * s);
      if (!ref.valid) {
        havePrev = false;
        continue;
      }
      const bool side = ref.value >= iso;
      if (havePrev && side != prevSide) roots[rootCount++] = s;
      havePrev = true, prevSide = side;
    }
    const double firstRoot = roots[0];
    ++rays;
    if (found) {
      ++hits;
      const test::Reference at = test::bruteForce(cells, 0, hit.position);
      ASSERT_TRUE(at.valid);
      // A root: within the root finder's tolerance times the local slope.
      EXPECT_LT(std::abs(at.value - iso), 2e-3 * length(at.gradient) + 1e-5);
    }
    // The first root of the dense walk is the hit (up to the walk's step). Stepping at half the
    // finest cell width may only miss a grazing double crossing: both roots within one step.
    if (found == (firstRoot >= 0) && (!found || std::abs(hit.distance - firstRoot) < step + 1e-3)) {
      ++agree;
    } else if (rootCount == 2 && (!found || hit.distance > roots[1])) {
      const uint32_t region = locateRegion(m.view(0), vec3f(org + dir * firstRoot));
      ASSERT_NE(region, kNoRegion);
      const double dt = 0.5 * m.regions.regions[region].finestWidth();
      EXPECT_LT(roots[1] - roots[0], dt + 2 * step) << "ray " << i << " missed a crossing wider than a step";
      ++grazing;
      ++agree;
    }
  }
  RecordProperty("grazing_double_crossings", grazing);
  EXPECT_GT(hits, 20);
  EXPECT_EQ(agree, rays);
  EXPECT_LE(grazing, rays / 10);
}

TEST(Surfaces, VolumeAttenuatesAmbientOcclusionWhenAsked) {
  // An opaque 4^3 block standing on a floor: with --ao-volume the floor around it darkens.
  CellSet cells = uniformCells(4, {"f"}, [](const vec3d&) { return 1.0; });
  const Model m = buildModel(std::move(cells));
  const TriangleMesh floor = quad({-20, -20, -0.01f}, {20, -20, -0.01f}, {20, 20, -0.01f}, {-20, 20, -0.01f});
  const Camera cam = ortho(vec3d(2.0, 2.0, 0.0), normalize(vec3d(-0.5, -0.3, -1.0)), vec3d(0, 0, 1), 14.0);
  auto render = [&](bool aoVolume) {
    RenderSetup o = surfaceOptions(40);
    o.scene.ao.rays = 16;
    o.scene.ao.length = 3.f;
    o.scene.ao.volume = aoVolume;
    SceneRenderer r(m, 0, o);
    r.setTransferFunction(grayRamp(0.f, 2.f, 0.9f));
    r.addMesh(floor, vec3f(0.8f));
    return r.render(cam);
  };
  const Image plain = render(false), attenuated = render(true);
  double darkest = 0;
  for (size_t i = 0; i < plain.pixels.size(); ++i) {
    EXPECT_LE(attenuated.pixels[i].x, plain.pixels[i].x + 1e-6f);
    darkest = std::max<double>(darkest, plain.pixels[i].x - attenuated.pixels[i].x);
  }
  EXPECT_GT(darkest, 0.05);
}
