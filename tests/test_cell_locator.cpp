// The cell-location baseline must reconstruct exactly what the region-based sampler does: the
// same cells, weights and gradients, only found differently.
#include "datasets.h"
#include "exabricks/amr/cell_locator.h"
#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"
#include "render_setup.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace exa;
using namespace exa::test;

namespace {

struct Scale {
  float value = 1.f;    ///< magnitude of the field's values
  float gradient = 1.f; ///< bound on gradient components: value spread over the finest width
};

Scale scaleOf(const Model& m) {
  float lo = INFINITY, hi = -INFINITY;
  for (float v : m.fieldValues[0])
    lo = std::min(lo, v), hi = std::max(hi, v);
  int finest = kMaxLevel;
  for (const Brick& b : m.bricks)
    finest = std::min(finest, b.level);
  Scale s;
  s.value = std::max({1.f, std::abs(lo), std::abs(hi)});
  s.gradient = std::max(1.f, (hi - lo) / float(1 << finest));
  return s;
}

/// Compares the locator with sampleField at p; returns whether p had a value.
bool compareAt(const Model& m, const CellLocator& locator, const vec3f& p, const Scale& scale,
               const std::string& dataset) {
  float want = 0.f, got = 0.f;
  vec3f wantGrad, gotGrad;
  const bool wantOk = sampleField(m.view(0), p, want, &wantGrad);
  const bool gotOk = locator.sample(0, p, got, &gotGrad);
  const std::string where =
      dataset + " at (" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
  EXPECT_EQ(gotOk, wantOk) << where;
  if (gotOk && wantOk) {
    EXPECT_NEAR(got, want, 2e-5f * scale.value) << "value " << where;
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(gotGrad[a], wantGrad[a], 2e-4f * std::max(scale.gradient, std::abs(wantGrad[a])))
          << "gradient[" << a << "] " << where;
    // Value only gives the same value.
    float alone = 0.f;
    EXPECT_TRUE(locator.sample(0, p, alone));
    EXPECT_EQ(alone, got) << where;
  }
  return gotOk;
}

} // namespace

TEST(CellLocator, TreeHasOneBrickPerLeaf) {
  for (const NamedCells& d : smallDatasets()) {
    CellSet cells = d.cells;
    const Model m = buildModel(std::move(cells));
    const CellLocator locator(m);
    // Bricks come from a k-d tree, so planes that cut no brick separate them down to one each.
    EXPECT_EQ(locator.nodeCount(), 2 * m.bricks.size() - 1) << d.name;
  }
}

TEST(CellLocator, RandomPointsMatchRegionSampling) {
  std::mt19937 rng(11);
  for (const NamedCells& d : smallDatasets()) {
    CellSet cells = d.cells;
    const Model m = buildModel(std::move(cells));
    const CellLocator locator(m);
    const Scale scale = scaleOf(m);
    const box3f b = m.regions.bounds;
    size_t valid = 0;
    // Points in the bounds of the supports and a little beyond, and in each brick's support.
    for (int i = 0; i < 3000; ++i) {
      vec3f p;
      if (i % 2 == 0) {
        for (int a = 0; a < 3; ++a) {
          const float margin = 0.05f * (b.upper[a] - b.lower[a]) + 1.f;
          std::uniform_real_distribution<float> u(b.lower[a] - margin, b.upper[a] + margin);
          p[a] = u(rng);
        }
      } else {
        const Brick& brick = m.bricks[rng() % m.bricks.size()];
        const box3i bb = brick.bounds();
        const float half = 0.5f * float(brick.cellWidth());
        for (int a = 0; a < 3; ++a) {
          std::uniform_real_distribution<float> u(float(bb.lower[a]) - half, float(bb.upper[a]) + half);
          p[a] = u(rng);
        }
      }
      valid += compareAt(m, locator, p, scale, d.name);
    }
    EXPECT_GT(valid, 1000u) << d.name;
  }
}

TEST(CellLocator, CellCentresFacesAndSupportFacesMatch) {
  std::mt19937 rng(5);
  for (const NamedCells& d : smallDatasets()) {
    CellSet cells = d.cells;
    const Model m = buildModel(std::move(cells));
    const CellLocator locator(m);
    const Scale scale = scaleOf(m);
    for (int i = 0; i < 3000; ++i) {
      vec3f p;
      if (i % 3 != 2) {
        // A brick's cell centres, cell faces and support faces, mixed per axis.
        const Brick& brick = m.bricks[rng() % m.bricks.size()];
        const float w = float(brick.cellWidth());
        for (int a = 0; a < 3; ++a) {
          const float corner = float(brick.lower[a]) + w * float(int(rng() % uint32_t(brick.size[a])));
          switch (rng() % 5) {
          case 0:
            p[a] = corner + 0.5f * w;
            break; // centre
          case 1:
            p[a] = corner;
            break; // lower cell face
          case 2:
            p[a] = corner + w;
            break; // upper cell face
          case 3:
            p[a] = corner - 0.5f * w;
            break; // support face below a centre
          default:
            p[a] = corner + 1.5f * w;
            break; // support face above a centre
          }
        }
      } else {
        // Corners and faces of the active brick regions.
        const Region& r = m.regions.regions[rng() % m.regions.regions.size()];
        const box3f rb = r.bounds();
        for (int a = 0; a < 3; ++a) {
          const uint32_t k = rng() % 3;
          p[a] = k == 0 ? rb.lower[a] : k == 1 ? rb.upper[a] : 0.5f * (rb.lower[a] + rb.upper[a]);
        }
      }
      compareAt(m, locator, p, scale, d.name);
    }
  }
}

TEST(CellLocator, NoValueOutsideOrAtInvalidPoints) {
  const Model m = buildModel(generateScene({"blobs", 2000, 2, 3}));
  const CellLocator locator(m);
  float v = 0.f;
  vec3f g;
  const box3f b = m.regions.bounds;
  EXPECT_FALSE(locator.sample(0, b.upper + vec3f(1.f), v, &g));
  EXPECT_FALSE(locator.sample(0, b.lower - vec3f(1.f), v, &g));
  EXPECT_FALSE(locator.sample(0, vec3f(NAN, 0.f, 0.f), v, &g));
  EXPECT_FALSE(locator.sample(0, vec3f(1e30f, -1e30f, 0.f), v, &g));
  EXPECT_TRUE(locator.sample(0, (b.lower + b.upper) * 0.5f, v, &g));
}

TEST(CellLocator, RenderMatchesRegionReconstruction) {
  for (const char* scene : {"blobs", "shells"})
    for (const Shading shading : {Shading::None, Shading::Analytic}) {
      const Model m = buildModel(generateScene({scene, 20000, 3, 4}));
      TransferFunction tf;
      tf.colorMap = builtinColorMap("viridis");
      tf.opacity = {{0.f, 0.f}, {0.3f, 0.05f}, {0.7f, 0.4f}, {1.f, 0.8f}};
      const box3i cb = m.cellBounds();
      const Camera cam = Camera::frame(box3d(vec3d(cb.lower), vec3d(cb.upper)), 35, 20, 40, false);
      RenderSetup o;
      o.frame.width = o.frame.height = 56;
      o.scene.integration.earlyTermination = false;
      o.scene.shading = shading;
      o.scene.integration.autoTraversal = false;
      SceneRenderer regions(m, 0, o);
      regions.setTransferFunction(tf);
      RenderStats regionStats, cellStats;
      const Image want = regions.render(cam, &regionStats);
      o.scene.integration.reconstruction = Reconstruction::CellLocation;
      SceneRenderer cellsRenderer(m, 0, o);
      cellsRenderer.setTransferFunction(tf);
      const Image got = cellsRenderer.render(cam, &cellStats);
      const std::string what = std::string(scene) + (shading == Shading::None ? ", unshaded" : ", shaded");
      EXPECT_EQ(cellStats.samples, regionStats.samples) << what;
      EXPECT_EQ(cellStats.regionsVisited, regionStats.regionsVisited) << what;
      float maxDiff = 0.f, maxAlpha = 0.f;
      size_t above = 0;
      for (size_t i = 0; i < want.pixels.size(); ++i) {
        const vec4f& a = want.pixels[i];
        const vec4f& b = got.pixels[i];
        const float d = std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z), std::abs(a.w - b.w)});
        maxDiff = std::max(maxDiff, d);
        above += d > 1e-4f;
        maxAlpha = std::max(maxAlpha, a.w);
      }
      EXPECT_GT(maxAlpha, 0.1f) << what << ": the image should show something";
      if (shading == Shading::None) {
        // Values agree to float rounding, so do the images.
        EXPECT_LT(maxDiff, 1e-5f) << what;
      } else {
        // The gradient is a quotient of sums; where only small hat weights overlap (beside holes
        // and at the edge of the data) it is ill-conditioned, and summing the same terms in
        // another order moves it visibly. That touches a few samples of a few pixels.
        EXPECT_LE(above, want.pixels.size() / 50) << what;
        EXPECT_LT(maxDiff, 0.05f) << what;
      }
    }
}
