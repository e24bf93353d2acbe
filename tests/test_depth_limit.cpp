// Per-pixel depth limits against analytic truth: a limit ends rays as opaque geometry drawn
// elsewhere would, for the volume and for surfaces behind it, and bad limits are refused.
#include "errors.h"
#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"
#include "render_setup.h"
#include "surface_scenes.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace exa;
using namespace exa::test;

TEST(Surfaces, DepthLimitEndsTheVolumeAsAClipPlaneAcrossTheView) {
  CellSet cells = uniformCells(16, {"f"}, [](const vec3d& p) { return (p.x + p.y + p.z) / 48.0; });
  const Model m = buildModel(std::move(cells));
  RenderSetup o = surfaceOptions(40);
  SceneRenderer full(m, 0, o);
  full.setTransferFunction(grayRamp(0.f, 1.f, 0.2f));
  const vec3d dir = normalize(vec3d(0.3, 0.5, 1.0));
  const Camera cam = ortho(vec3d(8.0), dir, vec3d(0, 1, 0), 24.0);
  const double depth = 201.5; // 1.5 beyond the centre of the data
  const Image unlimited = full.render(cam);

  // An orthographic camera: a constant distance along the rays is a plane across the view.
  std::vector<float> limit(size_t(40 * 40), float(depth));
  full.frame.depthLimit = limit.data();
  const Image limited = full.render(cam);
  RenderSetup oc = o;
  oc.scene.clip.planes = {{cam.position + dir * depth, dir}};
  SceneRenderer clipped(m, 0, oc);
  clipped.setTransferFunction(grayRamp(0.f, 1.f, 0.2f));
  const Image byPlane = clipped.render(cam);
  RecordProperty("orthographic_max_abs_diff", std::to_string(maxAbsDiff(limited, byPlane)));
  EXPECT_LT(maxAbsDiff(limited, byPlane), 1e-6);
  EXPECT_GT(maxAbsDiff(limited, unlimited), 0.05);

  // Left half without a limit, right half with it: each half is the matching image.
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 20; ++x)
      limit[size_t(y) * 40 + size_t(x)] = std::numeric_limits<float>::infinity();
  const Image halves = full.render(cam);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) {
      const vec4f &p = halves.at(x, y), &q = x < 20 ? unlimited.at(x, y) : limited.at(x, y);
      EXPECT_EQ(p.x, q.x);
      EXPECT_EQ(p.w, q.w);
    }

  // A perspective camera with planar depths (a z-buffer's): the same plane across the view.
  Camera persp;
  persp.position = vec3d(8.0) - dir * 40.0;
  persp.lookAt = vec3d(8.0);
  persp.up = vec3d(0, 1, 0);
  persp.fovy = 30.0;
  std::fill(limit.begin(), limit.end(), 41.5f);
  full.frame.depthLimitPlanar = true;
  const Image planar = full.render(persp);
  oc.scene.clip.planes = {{persp.position + dir * 41.5, dir}};
  SceneRenderer clippedPersp(m, 0, oc);
  clippedPersp.setTransferFunction(grayRamp(0.f, 1.f, 0.2f));
  const Image byPlanePersp = clippedPersp.render(persp);
  RecordProperty("perspective_planar_max_abs_diff", std::to_string(maxAbsDiff(planar, byPlanePersp)));
  EXPECT_LT(maxAbsDiff(planar, byPlanePersp), 1e-5);
  full.frame.depthLimit = nullptr;
  EXPECT_GT(maxAbsDiff(planar, full.render(persp)), 0.05);

  // Limits beyond the data change nothing.
  std::fill(limit.begin(), limit.end(), 1e6f);
  full.frame.depthLimit = limit.data();
  full.frame.depthLimitPlanar = false;
  EXPECT_EQ(maxAbsDiff(full.render(cam), unlimited), 0.0);
}

TEST(Surfaces, DepthLimitHidesSurfacesBehindIt) {
  const vec3d centre(31.3, 32.6, 30.9);
  const Model m = buildModel(radialTwoLevels(centre, 26.0));
  RenderSetup o = surfaceOptions(32);
  SceneRenderer r(m, 0, o);
  r.setTransferFunction(invisible());
  IsoSurfaces is;
  is.field = r.field(0);
  is.values = {20.f};
  r.setIsoSurfaces(is);
  const Camera cam = ortho(centre, vec3d(0, 0, 1), vec3d(0, 1, 0), 50.0);
  const Image unlimited = r.render(cam);
  // The sphere's front lies 180 (its centre) to 200 (its rim) along the rays: a limit of 190
  // keeps the hits nearer than that and removes the others.
  const float limitDistance = 190.f;
  std::vector<float> limit(size_t(32 * 32), limitDistance);
  r.frame.depthLimit = limit.data();
  const Image limited = r.render(cam);
  int kept = 0, removed = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      vec3d org, dir;
      cam.ray((x + 0.5) / 32, (y + 0.5) / 32, 1.0, org, dir);
      SurfaceHit hit;
      if (!r.pick(org, dir, hit)) {
        EXPECT_EQ(limited.at(x, y).w, 0.f);
        continue;
      }
      if (std::abs(hit.distance - limitDistance) < 0.05) continue; // too close to call
      if (hit.distance < limitDistance) {
        // The iso search steps over the shortened interval: the hit moves by round-off.
        EXPECT_NEAR(limited.at(x, y).x, unlimited.at(x, y).x, 1e-4);
        EXPECT_EQ(limited.at(x, y).w, 1.f);
        ++kept;
      } else {
        EXPECT_EQ(limited.at(x, y).w, 0.f) << x << ", " << y << " hit at " << hit.distance;
        ++removed;
      }
    }
  EXPECT_GT(kept, 20);
  EXPECT_GT(removed, 20);

  // A mesh just beyond the limit disappears, one just before it stays; both with the mesh
  // clipped and not.
  for (bool clipMeshes : {false, true}) {
    RenderSetup om = surfaceOptions(16);
    om.scene.volume = false;
    om.scene.clip.meshes = clipMeshes;
    SceneRenderer meshes(m, 0, om);
    const double z = centre.z - 200.0 + limitDistance;
    meshes.addMesh(quad({-100, -100, float(z + 0.5)}, {200, -100, float(z + 0.5)}, {200, 200, float(z + 0.5)},
                        {-100, 200, float(z + 0.5)}),
                   vec3f(0.8f));
    std::vector<float> meshLimit(size_t(16 * 16), limitDistance);
    meshes.frame.depthLimit = meshLimit.data();
    for (const vec4f& p : meshes.render(cam).pixels)
      EXPECT_EQ(p.w, 0.f);
    std::fill(meshLimit.begin(), meshLimit.end(), limitDistance + 1.f);
    for (const vec4f& p : meshes.render(cam).pixels)
      EXPECT_EQ(p.w, 1.f);
  }
}

TEST(Surfaces, BadDepthLimitsAreRejected) {
  CellSet cells = uniformCells(4, {"f"}, [](const vec3d& p) { return p.x; });
  const Model m = buildModel(std::move(cells));
  SceneRenderer r(m, 0, surfaceOptions(8));
  std::vector<float> limit(64, 1.f);
  r.frame.depthLimit = limit.data();
  limit[8 * 3 + 5] = std::nanf("");
  const Camera cam = ortho(vec3d(2.0), vec3d(0, 0, 1), vec3d(0, 1, 0), 6.0);
  expectIn(errorOf([&] { r.render(cam); }), {"depth limit of pixel (5, 3)", "distance >= 0"});
  limit[8 * 3 + 5] = -1.f;
  expectIn(errorOf([&] { r.render(cam); }), {"depth limit of pixel (5, 3) is -1"});
  limit[8 * 3 + 5] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(errorOf([&] { r.render(cam); }), "no error");
  // A preview at another resolution cannot use the limit; one at the same keeps it.
  EXPECT_EQ(r.frame.preview(2, 0.5f).depthLimit, nullptr);
  EXPECT_EQ(r.frame.preview(1, 0.5f).depthLimit, limit.data());
}
