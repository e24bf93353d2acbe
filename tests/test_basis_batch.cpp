// The vectorised sampling path against the scalar reference: batches of reconstructions equal
// basis.h's sampleRegion to float round-off (values against its float form, gradients as close to
// its double-precision form as the float form is), and renders with SIMD batches equal the scalar
// renders within the stated bound.
#include "datasets.h"

#include "exabricks/amr/basis_batch.h"
#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/shade_batch.h"
#include "exabricks/render/transfer_function.h"

#include <functional>
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <random>
#include <vector>

namespace exa {
namespace {

/// Runs `body` once with every instruction set the CPU has, then returns to the best.
template <typename Body> void forEveryTarget(Body&& body) {
  for (const std::string& target : batchTargets()) {
    ASSERT_TRUE(useBatchTarget(target)) << target;
    ASSERT_EQ(std::string(batchTargetName()), target);
    SCOPED_TRACE("instruction set " + target);
    body();
  }
  EXPECT_TRUE(useBatchTarget(""));
  EXPECT_FALSE(useBatchTarget("no such target"));
}

TEST(BasisBatch, EqualsTheScalarReconstruction) {
  // Bricks one cell wide along x and wider ones: the batches load x-neighbours as pairs where a
  // brick has two cells or more along x, one by one otherwise.
  int narrow = 0, wide = 0;
  forEveryTarget([&] {
    for (const test::NamedCells& d : test::smallDatasets()) {
      const Model m = buildModel(CellSet(d.cells));
      for (const Brick& brick : m.bricks)
        ++(brick.size.x == 1 ? narrow : wide);
      const FieldView view = m.view(0);
      std::mt19937 rng(11);
      std::uniform_real_distribution<float> u(0.f, 1.f);
      std::uniform_int_distribution<int> pickRegion(0, int(m.regions.regions.size()) - 1);
      for (int trial = 0; trial < 300; ++trial) {
        const uint32_t r = uint32_t(pickRegion(rng));
        const box3f b = m.regions.regions[r].bounds();
        SampleBatch batch, reference;
        batch.count = 1 + trial % kSampleBatch;
        for (int i = 0; i < batch.count; ++i) {
          // Inside the region, on its faces and on cell centres and faces now and then.
          vec3f p;
          for (int a = 0; a < 3; ++a) {
            const float t = trial % 7 == 0 ? float(i % 3) * 0.5f : u(rng);
            p[a] = b.lower[a] + t * (b.upper[a] - b.lower[a]);
            if (trial % 5 == 0) p[a] = std::round(p[a] * 2.f) * 0.5f;
          }
          batch.x[i] = p.x, batch.y[i] = p.y, batch.z[i] = p.z;
        }
        reference = batch;
        for (bool gradient : {false, true}) {
          sampleRegionBatch(view, r, batch, gradient);
          sampleRegionBatchScalar(view, r, reference, gradient);
          for (int i = 0; i < batch.count; ++i) {
            ASSERT_EQ(batch.valid[i] != 0, reference.valid[i] != 0) << d.name << " region " << r << " sample " << i;
            if (!reference.valid[i]) continue;
            const float v = reference.value[i];
            EXPECT_NEAR(batch.value[i], v, 2e-6f * (1.f + std::abs(v))) << d.name;
            if (!gradient) continue;
            // Gradients against the reconstruction in double precision: the batch's is as close as
            // the scalar float reference's, up to float round-off (2e-5). Where the positions keep
            // few bits of fraction, the two float forms round differently. The quotient rule
            // divides by the total weight squared: at the edge of the supports, where the total
            // weight is small against its derivative, round-off grows by their ratio.
            const Region& region = m.regions.regions[r];
            BasisAccumulator<double> truth;
            for (uint32_t k = 0; k < region.brickCount; ++k)
              truth.addBrick(m.bricks[m.regions.brickIds[region.brickBegin + k]], view.values,
                             vec3d(batch.x[i], batch.y[i], batch.z[i]), true);
            ASSERT_TRUE(truth.valid());
            const vec3d truthGradient = truth.gradient();
            const float g[3] = {reference.gx[i], reference.gy[i], reference.gz[i]};
            const float h[3] = {batch.gx[i], batch.gy[i], batch.gz[i]};
            const double scale =
                1.0 + std::abs(truthGradient.x) + std::abs(truthGradient.y) + std::abs(truthGradient.z);
            const double condition =
                (std::abs(truth.dSumW.x) + std::abs(truth.dSumW.y) + std::abs(truth.dSumW.z)) / truth.sumW;
            const double tolerance = 2e-5 * scale + 8.0 * FLT_EPSILON * condition * (1.0 + std::abs(truth.value()));
            for (int a = 0; a < 3; ++a)
              EXPECT_LE(std::abs(h[a] - truthGradient[a]), std::abs(g[a] - truthGradient[a]) + tolerance)
                  << d.name << " axis " << a;
          }
        }
      }
    }
  });
  EXPECT_GT(narrow, 0);
  EXPECT_GT(wide, 0);
}

TEST(BasisBatch, UnionOfRegionListsEqualsEachSamplesOwnRegion) {
  // A batch that joins the samples of several regions is reconstructed over the ascending union
  // of their brick lists; every sample must get what its own region's list gives it in a batch
  // of its own (the bricks of the other regions reach none of it), to float round-off. (The
  // batch against the scalar reference is the test above.)
  forEveryTarget([&] {
    for (const test::NamedCells& d : test::smallDatasets()) {
      const Model m = buildModel(CellSet(d.cells));
      const FieldView view = m.view(0);
      const auto& regions = m.regions.regions;
      std::mt19937 rng(5);
      std::uniform_real_distribution<float> u(0.f, 1.f);
      std::uniform_int_distribution<int> pickRegion(0, int(regions.size()) - 1);
      int joined = 0, compared = 0;
      for (int trial = 0; trial < 200; ++trial) {
        // Up to four regions along a random line through the data, one to eight samples each.
        SampleBatch batch;
        uint32_t owner[kSampleBatch];
        std::vector<uint32_t> ids;
        batch.count = 0;
        for (int part = 0; part < 4 && batch.count < kSampleBatch; ++part) {
          const uint32_t r = uint32_t(pickRegion(rng));
          const box3f b = regions[r].bounds();
          const int n = std::min(1 + int(u(rng) * 8.f), kSampleBatch - batch.count);
          for (int i = 0; i < n; ++i) {
            vec3f p;
            for (int a = 0; a < 3; ++a)
              p[a] = b.lower[a] + u(rng) * (b.upper[a] - b.lower[a]);
            const int k = batch.count++;
            batch.x[k] = p.x, batch.y[k] = p.y, batch.z[k] = p.z;
            owner[k] = r;
          }
          ids.insert(ids.end(), m.regions.brickIds.begin() + regions[r].brickBegin,
                     m.regions.brickIds.begin() + regions[r].brickBegin + regions[r].brickCount);
          joined += part > 0;
        }
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
        for (bool gradient : {false, true}) {
          SampleBatch out = batch;
          sampleBricksBatch(view, ids.data(), uint32_t(ids.size()), out, gradient);
          for (int i = 0; i < batch.count; ++i) {
            // Only positions strictly inside their region. On a face a brick of the neighbour may
            // have its support's edge: no weight, but the hat's one-sided slope there (the region
            // takes the slope from its side). Float round-off puts positions on faces and beyond
            // them where few bits of fraction are left (ramp-far).
            const box3f b = regions[owner[i]].bounds();
            const vec3f p(batch.x[i], batch.y[i], batch.z[i]);
            if (!(p.x > b.lower.x && p.y > b.lower.y && p.z > b.lower.z && p.x < b.upper.x && p.y < b.upper.y &&
                  p.z < b.upper.z))
              continue;
            ++compared;
            SampleBatch own = batch;
            own.count = 1;
            own.x[0] = batch.x[i], own.y[0] = batch.y[i], own.z[0] = batch.z[i];
            sampleRegionBatch(view, owner[i], own, gradient);
            ASSERT_EQ(out.valid[i] != 0, own.valid[0] != 0) << d.name << " sample " << i;
            if (!own.valid[0]) continue;
            EXPECT_NEAR(out.value[i], own.value[0], 2e-6f * (1.f + std::abs(own.value[0]))) << d.name;
            if (!gradient) continue;
            const float scale = 1.f + std::abs(own.gx[0]) + std::abs(own.gy[0]) + std::abs(own.gz[0]);
            EXPECT_NEAR(out.gx[i], own.gx[0], 2e-5f * scale) << d.name;
            EXPECT_NEAR(out.gy[i], own.gy[0], 2e-5f * scale) << d.name;
            EXPECT_NEAR(out.gz[i], own.gz[0], 2e-5f * scale) << d.name;
          }
        }
      }
      EXPECT_GT(joined, 100) << d.name;
      EXPECT_GT(compared, 1000) << d.name;
    }
  });
}

TEST(ShadeBatch, EqualsTheScalarFunctions) {
  // Tables over a linear range, a logarithmic one reaching below zero and a single value (the
  // last two take normalizeValue lane by lane).
  struct Case {
    range1f range;
    bool logScale;
  };
  const Case cases[] = {{{-2.f, 3.f}, false}, {{-1.f, 100.f}, true}, {{0.5f, 0.5f}, false}};
  forEveryTarget([&] {
    for (const Case& tc : cases) {
      TransferFunction tf;
      tf.colorMap = builtinColorMap(builtinColorMapNames().front());
      tf.opacity = {{0.f, 0.f}, {0.3f, 0.f}, {0.6f, 0.8f}, {1.f, 0.2f}}; // a transparent band
      tf.valueRange = tc.range;
      tf.logScale = tc.logScale;
      tf.opacityScale = 3.f;
      const std::vector<vec4f> table = tabulateTransferFunction(tf);
      TfTableView view;
      view.entries = table.data();
      view.range = tc.range;
      view.logScale = tc.logScale;
      view.fastLinear = !tc.logScale && tc.range.upper > tc.range.lower;
      view.lower = tc.range.lower;
      view.scale = view.fastLinear ? 1.f / (tc.range.upper - tc.range.lower) : 0.f;
      std::mt19937 rng(5);
      std::uniform_real_distribution<float> u(0.f, 1.f);
      for (int trial = 0; trial < 400; ++trial) {
        SCOPED_TRACE("trial " + std::to_string(trial));
        SampleBatch batch;
        batch.count = 1 + trial % kSampleBatch;
        float lengths[kSampleBatch];
        for (int i = 0; i < batch.count; ++i) {
          // Values beyond both ends of the range, gradients from zero through the fade band
          // (relative change 1e-5..1e-4 per cell) to strong.
          batch.value[i] = -4.f + 110.f * u(rng) * u(rng);
          if (i % 7 == 3) batch.value[i] = 0.f;
          batch.valid[i] = (trial + i) % 5 != 0;
          const float magnitude = std::pow(10.f, -8.f + 9.f * u(rng));
          batch.gx[i] = magnitude * (u(rng) - 0.5f), batch.gy[i] = magnitude * (u(rng) - 0.5f);
          batch.gz[i] = i % 6 == 1 ? 0.f : magnitude * (u(rng) - 0.5f);
          if (i % 9 == 4) batch.gx[i] = batch.gy[i] = batch.gz[i] = 0.f;
          // Squared lengths below or beyond the normal floats (the quotients, not the estimates):
          if (i == 2 && trial % 11 == 5) batch.gx[i] = 3e-21f, batch.gy[i] = -1e-21f;
          if (i == 0 && trial % 13 == 6) batch.gz[i] = 3e19f;
          lengths[i] = 0.01f + 2.f * u(rng);
        }
        TfBatch vectors, reference;
        const bool anyVector = tfLookupBatch(view, batch, vectors);
        const bool anyReference = tfLookupBatchScalar(view, batch, reference);
        EXPECT_EQ(anyVector, anyReference);
        for (int i = 0; i < batch.count; ++i) {
          EXPECT_NEAR(vectors.r[i], reference.r[i], 1e-6f) << i;
          EXPECT_NEAR(vectors.g[i], reference.g[i], 1e-6f) << i;
          EXPECT_NEAR(vectors.b[i], reference.b[i], 1e-6f) << i;
          EXPECT_NEAR(vectors.logT[i], reference.logT[i], 1e-5f * (1.f + std::abs(reference.logT[i]))) << i;
        }
        VolumeShadeParams p;
        p.invReferenceWidth = 0.5f + u(rng);
        p.shade = trial % 4 != 0;
        p.gradientScale = vec3f(1.f, 0.5f, 2.f);
        p.light = normalize(vec3f(0.3f, -0.5f, 0.8f));
        p.halfVector = normalize(vec3f(0.1f, 0.2f, 1.f));
        p.fadeByValue = trial % 3 == 0;
        float fades[kSampleBatch]; // per sample: a batch may join regions of several widths
        for (int i = 0; i < kSampleBatch; ++i)
          fades[i] = (p.fadeByValue ? 2.f : 0.4f) * (1.f + 0.5f * float(i % 3));
        p.fadeWidth = fades;
        ShadedBatch shaded, expected;
        shadeVolumeBatch(batch, reference, lengths, p, shaded);
        shadeVolumeBatchScalar(batch, reference, lengths, p, expected);
        for (int i = 0; i < batch.count; ++i) {
          EXPECT_NEAR(shaded.alpha[i], expected.alpha[i], 1e-6f) << i;
          EXPECT_NEAR(shaded.r[i], expected.r[i], 2e-6f * (1.f + std::abs(expected.r[i]))) << i;
          EXPECT_NEAR(shaded.g[i], expected.g[i], 2e-6f * (1.f + std::abs(expected.g[i]))) << i;
          EXPECT_NEAR(shaded.b[i], expected.b[i], 2e-6f * (1.f + std::abs(expected.b[i]))) << i;
        }
      }
    }
  });
}

TEST(ShadeBatch, PlacementEqualsTheScalarMarch) {
  // Segments from a fraction of a step to many batches long, near the origin and where t is so
  // large that float resolution runs out (the scalar march's own steps take over there).
  forEveryTarget([&] {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int placed = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      SCOPED_TRACE("trial " + std::to_string(trial));
      const float dt = std::pow(10.f, -2.f + 3.f * u(rng));
      const float rho = u(rng);
      const float scale = trial % 10 == 9 ? 1e7f : trial % 10 == 8 ? 1e4f : 10.f;
      const float t0 = trial % 5 == 4 ? std::floor(scale * u(rng) / dt) * dt : scale * u(rng);
      const float steps = trial % 3 == 0 ? 3.f * u(rng) : 60.f * u(rng);
      const float t1 = trial % 17 == 0 ? t0 : t0 + steps * dt;
      const vec3f org(u(rng) - 0.5f, 3.f * u(rng), -2.f), dir = normalize(vec3f(u(rng), u(rng) - 0.5f, 1.f));
      SegmentMarch vector(t0, t1, rho, dt), scalar(t0, t1, rho, dt);
      for (int round = 0; round < 100; ++round) {
        // Every other batch already holds samples (of earlier segments): placement appends.
        SampleBatch a, b;
        alignas(64) float la[2 * kSampleBatch], lb[2 * kSampleBatch];
        const int first = round % 2 == 1 ? std::min(int(u(rng) * kSampleBatch), kSampleBatch - 1) : 0;
        a.count = b.count = first;
        for (int i = 0; i < first; ++i)
          a.x[i] = a.y[i] = a.z[i] = la[i] = -7.f;
        const int n = placeSamples(org, dir, vector, a, la);
        const int m = placeSamplesScalar(org, dir, scalar, b, lb);
        ASSERT_EQ(n, m);
        ASSERT_EQ(a.count, first + n);
        ASSERT_LE(a.count, kSampleBatch);
        ASSERT_EQ(vector.a, scalar.a);
        ASSERT_EQ(vector.k, scalar.k);
        for (int i = 0; i < first; ++i) {
          ASSERT_EQ(a.x[i], -7.f);
          ASSERT_EQ(a.y[i], -7.f);
          ASSERT_EQ(a.z[i], -7.f);
          ASSERT_EQ(la[i], -7.f);
        }
        for (int i = first; i < first + n; ++i) {
          EXPECT_EQ(la[i], lb[i]) << i;
          // Exact where both contract org + dir t into one rounding; one more otherwise.
          const float tol = 2.f * FLT_EPSILON * (1.f + std::abs(vector.a));
          EXPECT_NEAR(a.x[i], b.x[i], tol) << i;
          EXPECT_NEAR(a.y[i], b.y[i], tol) << i;
          EXPECT_NEAR(a.z[i], b.z[i], tol) << i;
        }
        placed += n;
        if (n == 0) break;
      }
      if (scale < 1e4f) {
        EXPECT_FALSE(vector.a < vector.end) << "the march stopped before the segment's end";
      }
    }
    EXPECT_GT(placed, 20000);
  });
}

float worstDifference(const Image& a, const Image& b) {
  float worst = 0.f;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const vec4f d = a.pixels[i] - b.pixels[i];
    worst = std::max({worst, std::abs(d.x), std::abs(d.y), std::abs(d.z), std::abs(d.w)});
  }
  return worst;
}

Frame referenceFrame(const Model& m) {
  Frame frame;
  frame.width = 120;
  frame.height = 96;
  frame.samplesPerPixel = 2;
  frame.camera = Camera::frame(m.worldBounds(), 30, 20, 40, false);
  return frame;
}

// The renderer's one march (batches of samples, SIMD or lane after lane) against the
// one-sample-at-a-time march of the device back ends (src/render/device_trace.h: traceVolume,
// written from the per-sample headers alone), run on CPU threads (Device::Portable).
TEST(BasisBatch, TheMarchEqualsTheOneSampleReference) {
  const Model m = buildModel(generateScene({"shells", 20000, 3, 4}));
  const DatasetInfo info = DatasetInfo::of(m);
  Renderer renderer(m, info);
  const Frame frame = referenceFrame(m);
  struct Variant {
    const char* name;
    std::function<void(Scene&, RendererOptions&)> set;
  };
  const std::vector<Variant> variants = {
      {"smooth", [](Scene&, RendererOptions&) {}},
      {"unshaded", [](Scene& s, RendererOptions&) { s.shading = Shading::None; }},
      {"analytic", [](Scene& s, RendererOptions&) { s.shading = Shading::Analytic; }},
      {"central", [](Scene& s, RendererOptions&) { s.shading = Shading::Central; }},
      {"log scale", [](Scene& s, RendererOptions&) { s.layers[0].tf.logScale = true; }},
      {"fixed steps", [](Scene& s, RendererOptions&) { s.integration.sampling = Sampling::Fixed; }},
      {"eager gradients", [](Scene& s, RendererOptions& o) { s.shading = Shading::Analytic, o.lazyGradients = false; }},
      {"one batch per segment", [](Scene&, RendererOptions& o) { o.joinSegments = false; }},
      {"scalar lanes", [](Scene&, RendererOptions& o) { o.vectorized = false; }},
      {"two layers",
       [](Scene& s, RendererOptions&) {
         VolumeLayer radius{"radius", defaultTransferFunction("plasma")};
         radius.tf.opacity = {{0.f, 0.f}, {0.6f, 0.f}, {1.f, 0.5f}};
         s.layers.push_back(radius);
       }},
      {"two layers, central",
       [](Scene& s, RendererOptions&) {
         s.layers.push_back(VolumeLayer{"radius", defaultTransferFunction("plasma")});
         s.shading = Shading::Central;
       }},
      {"cell location",
       [](Scene& s, RendererOptions&) { s.integration.reconstruction = Reconstruction::CellLocation; }},
      {"cell location, analytic, two layers",
       [](Scene& s, RendererOptions&) {
         s.integration.reconstruction = Reconstruction::CellLocation;
         s.shading = Shading::Analytic;
         s.layers.push_back(VolumeLayer{"radius", defaultTransferFunction("plasma")});
       }},
  };
  for (const Variant& v : variants) {
    Scene scene;
    scene.layers[0].tf.valueRange = info.valueRanges[0];
    RendererOptions options;
    v.set(scene, options);
    renderer.setScene(scene);
    renderer.setOptions(options);
    RenderStats stats;
    const Image image = renderer.render(frame, &stats);
    EXPECT_GT(stats.samples, 0u) << v.name;
    Image reference;
    if (scene.integration.reconstruction == Reconstruction::CellLocation) {
      // The cell locator sums the weights of the same cells: the regions' one-sample image.
      Scene regions = scene;
      regions.integration.reconstruction = Reconstruction::Regions;
      Renderer one(m, info);
      one.setScene(regions);
      one.setDevice(Device::Portable);
      reference = one.render(frame);
    } else {
      Renderer one(m, info);
      one.setScene(scene);
      one.setDevice(Device::Portable);
      reference = one.render(frame);
    }
    // The bound: per channel 1e-4 (the 8-bit images are equal); round-off in the sums only.
    EXPECT_LE(worstDifference(image, reference), 1e-4f) << v.name;
  }
}

// Surfaces with volume-attenuated ambient occlusion (opacity-only batches), which the reference
// does not draw: SIMD batches against the same batches lane after lane.
TEST(BasisBatch, SurfaceRaysEqualInLanesAndInSimd) {
  const Model m = buildModel(generateScene({"shells", 20000, 3, 4}));
  const DatasetInfo info = DatasetInfo::of(m);
  Renderer renderer(m, info);
  const Frame frame = referenceFrame(m);
  Scene scene;
  scene.layers[0].tf.valueRange = info.valueRanges[0];
  scene.iso.values = {0.5f};
  scene.ao.rays = 2;
  scene.ao.volume = true;
  renderer.setScene(scene);
  RendererOptions lanes;
  lanes.vectorized = false;
  renderer.setOptions(lanes);
  const Image reference = renderer.render(frame);
  renderer.setOptions(RendererOptions());
  RenderStats stats;
  const Image image = renderer.render(frame, &stats);
  EXPECT_GT(stats.aoRays, 0u);
  EXPECT_LE(worstDifference(image, reference), 1e-4f);
}

} // namespace
} // namespace exa
