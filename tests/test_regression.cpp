// Image regression. Debug views are deterministic and compared tightly; the shaded volume is
// stochastic (jittered) and compared with a noise-aware metric: the mean of the 5x5 box-filtered
// absolute difference. On failure the rendered, reference and difference images are written to
// the build tree. Regenerate references with:
//   EXABRICKS_UPDATE_REFERENCES=1 build/tests/exabricks_tests --gtest_filter='Regression.*'
#include "exabricks/amr/scenes.h"
#include "exabricks/documents/image.h"
#include "exabricks/documents/mesh.h"
#include "exabricks/render/renderer.h"
#include "render_setup.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;

namespace {

const Model& regressionModel() {
  static const Model model = buildModel(generateScene({"blobs", 30000, 2, 4}));
  return model;
}

Image renderView(DebugView debug, Shading shading, int spp) {
  const Model& m = regressionModel();
  RenderSetup o;
  o.frame.width = o.frame.height = 96;
  o.scene.debug = debug;
  o.scene.shading = shading;
  o.frame.samplesPerPixel = spp;
  SceneRenderer r(m, 0, o);
  TransferFunction tf;
  tf.colorMap = builtinColorMap("viridis");
  tf.opacity = {{0.f, 0.f}, {0.2f, 0.f}, {0.6f, 0.1f}, {1.f, 0.6f}};
  r.setTransferFunction(tf);
  const box3i b = m.cellBounds();
  return r.render(Camera::frame(box3d(vec3d(b.lower), vec3d(b.upper)), 35, 25, 40, false));
}

/// Per-pixel absolute difference over RGB, composited over black.
std::vector<float> difference(const Image& a, const Image& b) {
  std::vector<float> d(a.pixels.size());
  for (size_t i = 0; i < d.size(); ++i)
    d[i] = (std::abs(a.pixels[i].x - b.pixels[i].x) + std::abs(a.pixels[i].y - b.pixels[i].y) +
            std::abs(a.pixels[i].z - b.pixels[i].z)) /
           3.f;
  return d;
}

void saveFailure(const std::string& name, const Image& got, const Image& ref, const std::vector<float>& diff) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "regression-failures";
  fs::create_directories(dir);
  writePng((dir / (name + "-rendered.png")).string(), got, false);
  writePng((dir / (name + "-reference.png")).string(), ref, false);
  Image d(got.width, got.height);
  for (size_t i = 0; i < diff.size(); ++i) {
    const float v = std::min(1.f, 10.f * diff[i]);
    d.pixels[i] = {v, v, v, 1.f};
  }
  writePng((dir / (name + "-diff.png")).string(), d, false);
  ADD_FAILURE() << "images written to " << dir.string();
}

/// Compares with the stored reference (or rewrites it when asked). `noisy` selects the metric.
void compareWithReference(const std::string& name, const Image& got, bool noisy) {
  const fs::path refPath = fs::path(EXABRICKS_REFERENCE_DIR) / (name + ".png");
  if (std::getenv("EXABRICKS_UPDATE_REFERENCES")) {
    writePng(refPath.string(), got, false);
    GTEST_SKIP() << "reference rewritten: " << refPath.string();
  }
  ASSERT_TRUE(fs::exists(refPath)) << "missing reference " << refPath.string();
  // The reference went through 8-bit sRGB: compare against the same quantisation.
  const fs::path tmp = fs::path(EXABRICKS_TEST_TMP) / (name + "-quantised.png");
  fs::create_directories(tmp.parent_path());
  writePng(tmp.string(), got, false);
  const Image quantised = readPng(tmp.string());
  const Image ref = readPng(refPath.string());
  ASSERT_EQ(ref.width, got.width);
  ASSERT_EQ(ref.height, got.height);
  const std::vector<float> diff = difference(quantised, ref);
  if (!noisy) {
    size_t bad = 0;
    for (float d : diff)
      bad += d > 2.f / 255.f;
    if (double(bad) > 0.005 * double(diff.size())) {
      saveFailure(name, quantised, ref, diff);
      FAIL() << bad << " of " << diff.size() << " pixels differ";
    }
    return;
  }
  // Noise-aware: box-filter both images 5x5, then take the mean absolute difference.
  auto filtered = [&](const Image& img) {
    Image out(img.width, img.height);
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        vec4f s;
        int n = 0;
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= img.width || yy >= img.height) continue;
            const vec4f& p = img.at(xx, yy);
            s.x += p.x, s.y += p.y, s.z += p.z, s.w += p.w;
            ++n;
          }
        out.at(x, y) = {s.x / n, s.y / n, s.z / n, s.w / n};
      }
    return out;
  };
  const std::vector<float> fd = difference(filtered(quantised), filtered(ref));
  double mean = 0;
  for (float d : fd)
    mean += d;
  mean /= double(fd.size());
  if (mean > 0.004) {
    saveFailure(name, quantised, ref, diff);
    FAIL() << "mean filtered difference " << mean;
  }
}

} // namespace

TEST(Regression, DebugViewLevel) {
  compareWithReference("debug-level", renderView(DebugView::Level, Shading::None, 1), false);
}
TEST(Regression, DebugViewRegion) {
  compareWithReference("debug-region", renderView(DebugView::Region, Shading::None, 1), false);
}
TEST(Regression, DebugViewBrick) {
  compareWithReference("debug-brick", renderView(DebugView::Brick, Shading::None, 1), false);
}
TEST(Regression, DebugViewSteps) {
  compareWithReference("debug-steps", renderView(DebugView::Steps, Shading::None, 1), false);
}
TEST(Regression, ShadedVolume) {
  compareWithReference("shaded-volume", renderView(DebugView::None, Shading::Analytic, 4), true);
}

TEST(Regression, CombinedScene) {
  // Volume + iso-surface coloured by a second field + mesh floor + clipping plane + ambient
  // occlusion, in one image.
  const Model& m = regressionModel();
  ASSERT_GE(m.fieldNames.size(), 2u);
  const box3i b = m.cellBounds();
  const box3d wb(vec3d(b.lower), vec3d(b.upper));
  RenderSetup o;
  o.frame.width = o.frame.height = 96;
  o.frame.samplesPerPixel = 2;
  o.scene.ao.rays = 2;
  const vec3d centre = (wb.lower + wb.upper) * 0.5;
  o.scene.clip.planes = {{centre, vec3d(1.0, 1.0, 0.0)}};
  SceneRenderer r(m, 0, o);
  TransferFunction tf;
  tf.colorMap = builtinColorMap("viridis");
  tf.opacity = {{0.f, 0.f}, {0.3f, 0.f}, {0.6f, 0.05f}, {1.f, 0.3f}};
  r.setTransferFunction(tf);
  IsoSurfaces iso;
  iso.field = r.field(0);
  iso.values = {0.5f};
  iso.colorField = r.field(1);
  iso.colorTf.colorMap = builtinColorMap("cool-to-warm");
  r.setIsoSurfaces(iso);
  TriangleMesh floor;
  const float z = float(wb.lower.z) - 1.f, lo = float(wb.lower.x) - 40.f, hi = float(wb.upper.x) + 40.f;
  floor.vertices = {{lo, lo, z}, {hi, lo, z}, {hi, hi, z}, {lo, hi, z}};
  floor.triangles = {vec3i(0, 1, 2), vec3i(0, 2, 3)};
  r.addMesh(floor, vec3f(0.7f, 0.7f, 0.7f));
  const Image img = r.render(Camera::frame(wb, 35, 25, 40, false));
  compareWithReference("combined-scene", img, true);
}
