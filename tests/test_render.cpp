#include "datasets.h"
#include "exabricks/amr/gradients.h"
#include "exabricks/documents/image.h"
#include "exabricks/render/renderer.h"
#include "render_setup.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

using namespace exa;
using namespace exa::test;

namespace {

/// A 16^3 box of value 1 made of cells of the given levels along x (each level a slab).
CellSet constantSlabs(const std::vector<int>& levels) {
  CellSet s;
  s.fields.push_back({"scalar", {}});
  int x0 = 0;
  for (int level : levels) {
    const int w = 1 << level;
    for (int z = 0; z < 16; z += w)
      for (int y = 0; y < 16; y += w)
        for (int x = 0; x < 16; x += w) {
          s.cells.push_back({vec3i(x0 + x, y, z), level});
          s.fields[0].values.push_back(1.f);
        }
    x0 += 16;
  }
  return s;
}

TransferFunction constantOpacity(float alpha) {
  TransferFunction tf;
  tf.colorMap = builtinColorMap("grayscale");
  tf.opacity = {{0.f, alpha}, {1.f, alpha}};
  tf.valueRange = range1f{0.f, 2.f};
  return tf;
}

RenderSetup smallOptions(int size = 48) {
  RenderSetup o;
  o.frame.width = o.frame.height = size;
  o.scene.shading = Shading::None;
  o.scene.integration.earlyTermination = false;
  return o;
}

/// Looks along +x through the middle of the data.
Camera alongX(const Model& m) {
  const box3i b = m.cellBounds();
  Camera c;
  c.orthographic = true;
  c.position = vec3d(b.lower.x - 50.0, 8.0, 8.0);
  c.lookAt = vec3d(b.upper.x, 8.0, 8.0);
  c.up = vec3d(0, 0, 1);
  c.orthoHeight = 8.0;
  return c;
}

double meanAbsDiff(const Image& a, const Image& b) {
  double d = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i)
    d += std::abs(a.pixels[i].x - b.pixels[i].x) + std::abs(a.pixels[i].y - b.pixels[i].y) +
         std::abs(a.pixels[i].z - b.pixels[i].z) + std::abs(a.pixels[i].w - b.pixels[i].w);
  return d / double(a.pixels.size());
}

/// The blobs scene used by several tests, built once.
const Model& blobsModel() {
  static const Model model = buildModel(generateScene({"blobs", 20000, 3, 4}));
  return model;
}

/// The default framing of the data from the given direction.
Camera framed(const Model& m, double azimuth, double elevation) {
  const box3i b = m.cellBounds();
  return Camera::frame(box3d(vec3d(b.lower), vec3d(b.upper)), azimuth, elevation, 40, false);
}

double maxAbsDiff(const Image& a, const Image& b) {
  double d = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i)
    for (float e : {a.pixels[i].x - b.pixels[i].x, a.pixels[i].y - b.pixels[i].y, a.pixels[i].z - b.pixels[i].z})
      d = std::max(d, double(std::abs(e)));
  return d;
}

bool identical(const Image& a, const Image& b) {
  for (size_t i = 0; i < a.pixels.size(); ++i)
    if (a.pixels[i].x != b.pixels[i].x || a.pixels[i].y != b.pixels[i].y || a.pixels[i].z != b.pixels[i].z ||
        a.pixels[i].w != b.pixels[i].w)
      return false;
  return true;
}

} // namespace

TEST(Render, HomogeneousSlabTransmittanceIsExponential) {
  // Opacity is per finest cell width: sigma = -ln(1 - alpha) / finest width. The basis
  // reconstruction carries the value to the edge of the supports, half a cell beyond the cells.
  for (const std::vector<int>& levels : {std::vector<int>{0}, std::vector<int>{1, 0, 2}}) {
    const Model m = buildModel(constantSlabs(levels));
    const float alpha = 0.02f;
    SceneRenderer r(m, 0, smallOptions());
    r.setTransferFunction(constantOpacity(alpha));
    const Image img = r.render(alongX(m));
    const int finestLevel = *std::min_element(levels.begin(), levels.end());
    const int coarseFirst = levels.front(), coarseLast = levels.back();
    const double length = 16.0 * double(levels.size()) + 0.5 * (1 << coarseFirst) + 0.5 * (1 << coarseLast);
    const double sigma = -std::log(1.0 - alpha) / double(1 << finestLevel);
    const double expected = 1.0 - std::exp(-sigma * length);
    const vec4f centre = img.at(img.width / 2, img.height / 2);
    EXPECT_NEAR(centre.w, expected, 0.01 * expected) << "levels " << levels.size();
  }
}

TEST(Render, ConstantFieldAcrossLevelsHasNoSeams) {
  const Model m = buildModel(constantSlabs({2, 0, 1, 3}));
  SceneRenderer r(m, 0, smallOptions(64));
  r.setTransferFunction(constantOpacity(0.03f));
  // Every ray along x crosses the same thickness: all pixels covering the interior agree.
  Camera c = alongX(m);
  c.orthoHeight = 12.0;
  const Image img = r.render(c);
  float lo = 1.f, hi = 0.f;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      lo = std::min(lo, img.at(x, y).w);
      hi = std::max(hi, img.at(x, y).w);
    }
  EXPECT_GT(lo, 0.5f);
  EXPECT_LT(hi - lo, 1e-4f);
}

TEST(Render, RaisingTheRateConverges) {
  CellSet cells = generateScene({"shells", 20000, 1, 4});
  const Model m = buildModel(std::move(cells));
  TransferFunction tf;
  tf.colorMap = builtinColorMap("viridis");
  tf.opacity = {{0.f, 0.f}, {0.5f, 0.05f}, {0.6f, 0.6f}, {1.f, 0.1f}};
  const Camera cam = framed(m, 30, 20);
  std::vector<Image> images;
  for (float rate : {0.5f, 1.f, 2.f, 4.f, 8.f}) {
    RenderSetup o = smallOptions(64);
    o.frame.rate = rate;
    o.frame.jitter = false;
    o.scene.shading = Shading::Analytic;
    SceneRenderer r(m, 0, o);
    r.setTransferFunction(tf);
    images.push_back(r.render(cam));
  }
  double previous = 1e30;
  for (size_t i = 1; i < images.size(); ++i) {
    const double d = meanAbsDiff(images[i - 1], images[i]);
    EXPECT_LT(d, previous) << "doubling to rate index " << i;
    previous = d;
  }
}

TEST(Render, SpaceSkippingAndTraversalsGiveTheSameImage) {
  const Model& m = blobsModel();
  TransferFunction tf;
  tf.colorMap = builtinColorMap("plasma");
  tf.opacity = {{0.f, 0.f}, {0.8f, 0.f}, {0.9f, 0.3f}, {1.f, 0.8f}}; // hides 80 % of the range
  const Camera cam = framed(m, 40, 30);
  RenderSetup base = smallOptions(64);
  base.scene.shading = Shading::Analytic;
  Image reference;
  size_t allRegions = 0, visibleRegions = 0;
  for (int variant = 0; variant < 4; ++variant) {
    RenderSetup o = base;
    o.scene.integration.spaceSkipping = variant % 2 == 0;
    o.scene.integration.autoTraversal = false;
    o.scene.integration.traversal = variant < 2 ? TraversalKind::KdTree : TraversalKind::Embree;
    SceneRenderer r(m, 0, o);
    r.setTransferFunction(tf);
    RenderStats stats;
    const Image img = r.render(cam, &stats);
    if (variant == 0) {
      reference = img;
      visibleRegions = r.visibleRegions();
    } else if (variant == 2) {
      EXPECT_TRUE(identical(reference, img)) << "variant " << variant; // the same segments
    } else {
      // Without skipping, the transparent regions' samples (alpha 0) also fill the batches that
      // join consecutive segments, so the sums are grouped otherwise: equal to round-off.
      EXPECT_LT(maxAbsDiff(reference, img), 1e-6) << "variant " << variant;
    }
    if (variant == 1) allRegions = r.visibleRegions();
  }
  EXPECT_LT(visibleRegions, allRegions) << "skipping removed no region";
}

TEST(Render, SameImageForAnyThreadCount) {
  const Model& m = blobsModel();
  TransferFunction tf;
  tf.colorMap = builtinColorMap("magma");
  tf.opacity = {{0.f, 0.f}, {1.f, 0.2f}};
  const Camera cam = framed(m, 10, 10);
  RenderSetup o = smallOptions(40);
  o.frame.samplesPerPixel = 3;
  o.scene.shading = Shading::Analytic;
  SceneRenderer r(m, 0, o);
  r.setTransferFunction(tf);
  Image one;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = r.render(cam);
  }
  EXPECT_TRUE(identical(one, r.render(cam)));
}

TEST(Render, GradientModesAgreeOnASmoothField) {
  // Analytic and central-difference shading differ only by the gradient's accuracy.
  const Model& m = blobsModel();
  TransferFunction tf;
  tf.colorMap = builtinColorMap("viridis");
  tf.opacity = {{0.f, 0.f}, {1.f, 0.3f}};
  const Camera cam = framed(m, 10, 10);
  std::vector<Image> images;
  for (Shading s : {Shading::Analytic, Shading::Central, Shading::Smooth, Shading::None}) {
    RenderSetup o = smallOptions(48);
    o.scene.shading = s;
    SceneRenderer r(m, 0, o);
    r.setTransferFunction(tf);
    images.push_back(r.render(cam));
  }
  const double central = meanAbsDiff(images[0], images[1]);
  const double none = meanAbsDiff(images[0], images[3]);
  EXPECT_LT(central, 0.5 * none) << "analytic shading should be far closer to central differences than to no shading";
}

TEST(Render, AutomaticTraversalFollowsVisibility) {
  const Model& m = blobsModel();
  SceneRenderer r(m, 0, smallOptions(16));
  TransferFunction tf;
  tf.colorMap = builtinColorMap("viridis");
  tf.opacity = {{0.f, 0.2f}, {1.f, 0.2f}};
  r.setTransferFunction(tf);
  EXPECT_EQ(r.traversalInUse(), TraversalKind::KdTree);
  tf.opacity = {{0.f, 0.f}, {0.97f, 0.f}, {1.f, 0.5f}};
  r.setTransferFunction(tf);
  EXPECT_LT(r.visibleRegions(), m.regions.regions.size() / 10);
  EXPECT_EQ(r.traversalInUse(), TraversalKind::Embree);
}

TEST(Render, ShadingNeverInventsStructureInAConstantField) {
  // A constant field over three levels, with level jumps, brick and patch edges everywhere, and
  // the same field with one-ulp noise: their gradients are round-off, and every shading mode must
  // draw them exactly as unshaded.
  for (bool noise : {false, true}) {
    SCOPED_TRACE(noise ? "one-ulp noise" : "constant");
    std::mt19937 rng(7);
    CellSet cells;
    cells.fields.push_back({"scalar", {}});
    for (int z = 0; z < 32; z += 4)
      for (int y = 0; y < 32; y += 4)
        for (int x = 0; x < 32; x += 4) {
          const int level = (x + y + z) / 4 % 3;
          const int w = 1 << level;
          for (int dz = 0; dz < 4; dz += w)
            for (int dy = 0; dy < 4; dy += w)
              for (int dx = 0; dx < 4; dx += w) {
                cells.cells.push_back({vec3i(x + dx, y + dy, z + dz), level});
                const int ulps = noise ? int(rng() % 3) - 1 : 0;
                cells.fields[0].values.push_back(ulps == 0 ? 0.3f : std::nextafter(0.3f, ulps > 0 ? 1.f : 0.f));
              }
        }
    BuildOptions bo;
    bo.bricks.maxBrickWidth = 3; // many bricks: their faces cut through the data
    const Model m = buildModel(std::move(cells), bo);
    TransferFunction tf = constantOpacity(0.05f);
    tf.colorMap = builtinColorMap("inferno");
    // The constant field with its own (zero-width) range; the noisy one as part of a field whose
    // range is [0, 1] (the scale shading weights are measured against).
    tf.valueRange = noise ? range1f{0.f, 1.f} : range1f();
    const Camera cam = framed(m, 35, 20);
    auto render = [&](Shading s) {
      RenderSetup o = smallOptions(64);
      o.scene.shading = s;
      o.scene.light.headlight = false;           // a fixed light makes any wrong normal visible
      o.scene.integration.uniformStride = false; // unshaded would stride: the same samples
      SceneRenderer r(m, 0, o);
      r.setTransferFunction(tf);
      return r.render(cam);
    };
    const Image flat = render(Shading::None);
    EXPECT_GT(flat.pixels[32 * 64 + 32].w, 0.1f);
    for (Shading s : {Shading::Analytic, Shading::Central, Shading::Smooth}) {
      const Image shaded = render(s);
      // Exactly for the constant field; for the noisy one, invisibly (a few samples near the
      // data's edge, where the weight sum is small, keep a trace of shading: below 1e-5 here, an
      // 8-bit step is 4e-3).
      if (noise)
        EXPECT_LT(maxAbsDiff(shaded, flat), 1e-5) << int(s);
      else
        EXPECT_TRUE(identical(shaded, flat)) << int(s);
    }
  }
  // A field with structure is still shaded.
  const Model& blobs = blobsModel();
  RenderSetup o = smallOptions(48);
  TransferFunction ramp = constantOpacity(0.05f);
  ramp.valueRange = range1f();
  for (Shading s : {Shading::Analytic, Shading::None}) {
    o.scene.shading = s;
    SceneRenderer r(blobs, 0, o);
    r.setTransferFunction(ramp);
    static Image first;
    const Image img = r.render(framed(blobs, 30, 25));
    if (s == Shading::Analytic)
      first = img;
    else
      EXPECT_GT(meanAbsDiff(first, img), 1e-3);
  }
}

namespace {

/// Luminance of an image, row-major.
std::vector<double> luminance(const Image& img) {
  std::vector<double> l(img.pixels.size());
  for (size_t i = 0; i < l.size(); ++i) {
    const vec4f& p = img.pixels[i];
    l[i] = 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
  }
  return l;
}

/// The power of an image's luminance (rows and columns, each windowed by a Hann window and
/// without its mean) at spatial periods between period / sqrt(2) and period * sqrt(2) pixels:
/// the band around a level's cell period.
double bandPower(const Image& img, double period) {
  const std::vector<double> l = luminance(img);
  const int w = img.width, h = img.height;
  double power = 0;
  for (int pass = 0; pass < 2; ++pass) {
    const int n = pass ? h : w, lines = pass ? w : h;
    const int k0 = int(std::ceil(n / (period * std::sqrt(2.0)))), k1 = int(std::floor(n * std::sqrt(2.0) / period));
    std::vector<double> v(static_cast<size_t>(n));
    for (int line = 0; line < lines; ++line) {
      double mean = 0;
      for (int i = 0; i < n; ++i)
        mean += v[size_t(i)] = pass ? l[size_t(i) * size_t(w) + size_t(line)] : l[size_t(line) * size_t(w) + size_t(i)];
      mean /= n;
      for (int i = 0; i < n; ++i)
        v[size_t(i)] = (v[size_t(i)] - mean) * (0.5 - 0.5 * std::cos(2 * M_PI * i / (n - 1)));
      for (int k = std::max(1, k0); k <= std::min(k1, n / 2); ++k) {
        double re = 0, im = 0;
        for (int i = 0; i < n; ++i) {
          re += v[size_t(i)] * std::cos(2 * M_PI * k * i / n);
          im -= v[size_t(i)] * std::sin(2 * M_PI * k * i / n);
        }
        power += re * re + im * im;
      }
    }
  }
  return power;
}

/// A smooth field with maxima, minima and saddles over the box `b`, at the cells' centres.
void setSmoothField(CellSet& set, const box3l& b) {
  const vec3d extent = vec3d(b.upper - b.lower);
  for (size_t i = 0; i < set.cells.size(); ++i) {
    const Cell& c = set.cells[i];
    const vec3d p = (vec3d(c.lower) + vec3d(0.5 * (1 << c.level)) - vec3d(b.lower)) / extent;
    set.fields[0].values[i] = float(0.5 + 0.35 * std::cos(2 * M_PI * p.x) * std::cos(2 * M_PI * (p.y - 0.1)) *
                                              std::cos(2 * M_PI * (p.z + 0.2)));
  }
}

/// An orthographic camera looking at `centre` along the axis, from outside data of `extent`,
/// its view `size` pixels at two pixels per unit.
Camera alongAxis(int axis, const vec3d& centre, const vec3d& extent, int size) {
  Camera cam;
  cam.orthographic = true;
  vec3d dir(0.0);
  dir[axis] = 1.0;
  cam.position = centre - dir * (4 * std::max({extent.x, extent.y, extent.z}));
  cam.lookAt = centre;
  cam.up = axis == 2 ? vec3d(0, 1, 0) : vec3d(0, 0, 1);
  cam.orthoHeight = 0.25 * size;
  return cam;
}

} // namespace

TEST(Render, DefaultShadingDoesNotDrawTheCellLattice) {
  // A smooth field with maxima, minima and saddles (where its gradient vanishes and turns) on
  // the blobs scene's cells of four levels, seen along each axis by an orthographic camera at
  // two pixels per finest cell, so that every level's cells repeat at a fixed period in pixels.
  // The truth: the same field on finest cells only, rendered alike (no coarser cells to show).
  // The measure: the power of the difference from the truth in the bands of periods around the
  // coarser levels' cell widths (bandPower), with the default shading, the exact analytic
  // gradient and no shading. The exact gradient jumps at cell centres and support faces and
  // draws the coarse cells; the default's difference must hold less than a third of its power
  // in every view (measured: 0.8 %, 1.6 % and 24 % for the three axes).
  SceneOptions so;
  so.name = "blobs";
  so.targetCells = 100000;
  so.levels = 4;
  so = resolveSceneSize(so);
  CellSet cells = generateScene(so);
  SceneOptions fine = so;
  fine.levels = 1;
  fine.base = so.base << (so.levels - 1);
  CellSet finest = generateScene(fine);
  ASSERT_EQ(cells.bounds().upper, finest.bounds().upper);
  const box3l b = cells.bounds();
  const vec3d extent = vec3d(b.upper - b.lower);
  for (CellSet* set : {&cells, &finest})
    setSmoothField(*set, b);
  const Model m = buildModel(std::move(cells), BuildOptions{});
  const Model truth = buildModel(std::move(finest), BuildOptions{});
  TransferFunction tf;
  tf.colorMap = builtinColorMap("viridis");
  tf.opacity = {{0.f, 0.f}, {1.f, 0.3f}};
  tf.valueRange = range1f{0.15f, 0.85f};
  // Two pixels per finest cell, centred on the data.
  const int size = 2 * int(std::min({extent.x, extent.y, extent.z}));
  const vec3d centre = vec3d(b.lower) + extent * 0.5;
  EXPECT_EQ(Scene().shading, Shading::Smooth);
  for (int axis = 0; axis < 3; ++axis) {
    const Camera cam = alongAxis(axis, centre, extent, size);
    auto render = [&](const Model& model, Shading s) {
      RenderSetup o = smallOptions(size);
      o.scene.shading = s;
      o.frame.jitter = false;
      SceneRenderer r(model, 0, o);
      r.setTransferFunction(tf);
      return r.render(cam);
    };
    // The difference inside a margin of one coarsest cell (where the data's faces stay out).
    const int margin = 2 << (so.levels - 1);
    auto difference = [&](const Image& a, const Image& ref) {
      Image d(size - 2 * margin, size - 2 * margin);
      for (int y = 0; y < d.height; ++y)
        for (int x = 0; x < d.width; ++x)
          d.at(x, y) = a.at(x + margin, y + margin) - ref.at(x + margin, y + margin);
      return d;
    };
    std::map<Shading, Image> error;
    for (Shading s : {Shading::None, Shading::Smooth, Shading::Analytic})
      error[s] = difference(render(m, s), render(truth, s == Shading::Analytic ? Shading::Smooth : s));
    double smoothSum = 0, analyticSum = 0;
    for (int level = 1; level < so.levels; ++level) {
      const double period = 2 << level;
      const double none = bandPower(error[Shading::None], period);
      const double smooth = bandPower(error[Shading::Smooth], period);
      const double analytic = bandPower(error[Shading::Analytic], period);
      std::printf("axis %d, cells %d wide: power of the difference from the truth: no shading %.4g, default %.4g, "
                  "analytic %.4g\n",
                  axis, 1 << level, none, smooth, analytic);
      smoothSum += smooth, analyticSum += analytic;
    }
    EXPECT_LT(smoothSum, analyticSum / 3) << "axis " << axis;
  }
}

namespace {

/// The largest difference of smooth shading's gradient fields from central differences of the
/// reconstruction computed independently (Model::sampleWorld, in double precision), one cell
/// width each way, one-sided where a point lies outside the data.
double gradientFieldError(const Model& m) {
  const std::array<std::vector<float>, 3> g =
      cellGradients(m.view(0), m.bricks, m.regions.regions.size(), m.fieldValues[0].size());
  double worst = 0;
  for (const Brick& b : m.bricks) {
    const double w = b.cellWidth();
    uint32_t slot = b.valueOffset;
    for (int z = 0; z < b.size.z; ++z)
      for (int y = 0; y < b.size.y; ++y)
        for (int x = 0; x < b.size.x; ++x, ++slot) {
          const vec3d c = vec3d(b.lower) + (vec3d(x, y, z) + vec3d(0.5)) * w;
          double v0 = 0;
          vec3d unused;
          const bool centre = m.sampleWorld(0, m.world.toWorld(c), v0, unused);
          for (int a = 0; a < 3; ++a) {
            vec3d pp = c, pm = c;
            pp[a] += w;
            pm[a] -= w;
            double vp = 0, vm = 0;
            const bool hp = m.sampleWorld(0, m.world.toWorld(pp), vp, unused);
            const bool hm = m.sampleWorld(0, m.world.toWorld(pm), vm, unused);
            const double expected = hp && hm       ? (vp - vm) / (2 * w)
                                    : hp && centre ? (vp - v0) / w
                                    : hm && centre ? (v0 - vm) / w
                                                   : 0.0;
            worst = std::max(worst, std::abs(double(g[size_t(a)][slot]) - expected));
          }
        }
  }
  return worst;
}

} // namespace

TEST(Render, GradientFieldsAreCentralDifferencesOfTheReconstruction) {
  // On data with level jumps and holes.
  for (const char* name : {"blobs", "shells"}) {
    SCOPED_TRACE(name);
    EXPECT_LT(gradientFieldError(buildModel(generateScene({name, 6000, 3, 4}), BuildOptions{})), 1e-5)
        << "largest difference from central differences of the reconstruction";
  }
}

TEST(Render, GradientFieldsAreBuiltWhereSamplesMayReadThem) {
  // Smooth shading builds a brick's gradient fields once a visible region within the renderer's
  // domain holds the brick: pictures are those of gradient fields built in every brick first.
  const Model& m = blobsModel();
  TransferFunction hiding;
  hiding.colorMap = builtinColorMap("plasma");
  hiding.opacity = {{0.f, 0.f}, {0.8f, 0.f}, {0.9f, 0.3f}, {1.f, 0.8f}};
  TransferFunction showing = hiding;
  showing.opacity = {{0.f, 0.05f}, {1.f, 0.3f}};
  RenderSetup o = smallOptions(64);
  o.scene.shading = Shading::Smooth;
  const Camera cam = framed(m, 40, 30);
  o.frame.camera = cam;
  auto sceneOf = [&](const TransferFunction& tf) {
    Scene s = o.scene;
    s.layers = {VolumeLayer{m.fieldNames[0], tf}};
    return s;
  };

  Renderer lazy(m);
  lazy.setScene(sceneOf(hiding));
  const Image hidingFirst = lazy.render(o.frame);
  ASSERT_NE(lazy.gradients(0), nullptr);
  EXPECT_GT(lazy.gradients(0)->missing, 0u) << "every brick's were built for a transfer function that hides most";
  lazy.setScene(sceneOf(showing));
  const Image showingAfter = lazy.render(o.frame);
  EXPECT_EQ(lazy.gradients(0)->missing, 0u) << "not built where a transfer function shows every region";
  EXPECT_EQ(std::count(lazy.gradients(0)->built.begin(), lazy.gradients(0)->built.end(), 1), int(m.bricks.size()));

  Renderer full(m);
  full.setScene(sceneOf(showing));
  const Image showingFirst = full.render(o.frame);
  full.setScene(sceneOf(hiding));
  EXPECT_TRUE(identical(showingFirst, showingAfter));
  EXPECT_TRUE(identical(hidingFirst, full.render(o.frame)));

  // A domain (the lowest quarter along x), set before the scene or after it, then widened.
  box3i b = m.cellBounds();
  b.upper.x = b.lower.x + (b.upper.x - b.lower.x) / 4;
  const box3d quarter = m.world.toWorld(b);
  Renderer before(m);
  before.setDomain(quarter);
  before.setScene(sceneOf(showing));
  const Image quarterBefore = before.render(o.frame);
  EXPECT_GT(before.gradients(0)->missing, 0u) << "built beyond the domain";
  full.setScene(sceneOf(showing));
  full.setDomain(quarter);
  EXPECT_TRUE(identical(quarterBefore, full.render(o.frame)));
  before.setDomain(box3d());
  EXPECT_TRUE(identical(showingFirst, before.render(o.frame))) << "not built as the domain widened";
}

TEST(Render, UniformRegionsTakeLongerStepsAndKeepThePicture) {
  const Model& m = blobsModel();
  // One colour and a faint opacity over the lower half of the range: the regions whose values
  // all lie there look uniform (and are nearly transparent, as shaded strides need); a ramp above.
  TransferFunction tf;
  tf.colorMap.positions = {0.f, 0.5f, 1.f};
  tf.colorMap.colors = {vec3f(0.1f, 0.3f, 0.6f), vec3f(0.1f, 0.3f, 0.6f), vec3f(0.9f, 0.8f, 0.2f)};
  tf.opacity = {{0.f, 0.0005f}, {0.5f, 0.0005f}, {1.f, 0.6f}};
  tf.valueRange = DatasetInfo::of(m).valueRanges[0];
  const Camera cam = framed(m, 30, 25);
  for (Shading shading : {Shading::Smooth, Shading::None}) {
    SCOPED_TRACE(int(shading));
    Image images[2];
    uint64_t samples[2] = {};
    for (int stride = 0; stride < 2; ++stride) {
      RenderSetup o = smallOptions(96);
      o.scene.shading = shading, o.scene.integration.uniformStride = stride == 1;
      SceneRenderer r(m, 0, o);
      r.setTransferFunction(tf);
      RenderStats stats;
      images[stride] = r.render(cam, &stats), samples[stride] = stats.samples;
    }
    // Fewer samples, the written picture as at the paper's step: unshaded within 1/255; shaded,
    // the gradients' variation averaged over fewer samples in regions of optical depth up to
    // kUniformShadedDepth, within 3/255 in this generated worst case (real data: 1/255 to 2/255).
    EXPECT_LT(double(samples[1]), 0.8 * double(samples[0]));
    const std::vector<unsigned char> a = toSrgb8(images[0]), b = toSrgb8(images[1]); // the same size
    int worst = 0;
    double sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i)
      worst = std::max(worst, std::abs(int(a[i]) - int(b[i]))), sum += std::abs(int(a[i]) - int(b[i]));
    EXPECT_LE(worst, shading == Shading::None ? 1 : 3);
    EXPECT_LT(sum / double(a.size()), 0.1);
  }
}
