// The library as callers use it: scene changes between frames, progressive passes, tiles,
// cancellation, allocation, explicit dataset values and scene files. The per-sample functions
// are tested on their own in test_sample_math.cpp.
#include "datasets.h"
#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/documents/scene_file.h"
#include "exabricks/render/renderer.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <thread>

// Every allocation through operator new in this test program is counted. (GCC cannot see that
// these replacements pair malloc with free.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
namespace {
std::atomic<uint64_t> gAllocations{0};
}
namespace {
void* countedAllocation(std::size_t size) noexcept {
  gAllocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size ? size : 1);
}
} // namespace
// Every unaligned form, so that what one form allocates another frees consistently.
void* operator new(std::size_t size) {
  if (void* p = countedAllocation(size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  if (void* p = countedAllocation(size)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return countedAllocation(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return countedAllocation(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

using namespace exa;
using namespace exa::test;

namespace {

/// Two fields over the blobs scene (the second a function of the first), built once.
const Model& model() {
  static const Model m = [] {
    CellSet cells = generateScene({"blobs", 20000, 5, 4});
    Field second{"second", {}};
    for (float v : cells.fields[0].values)
      second.values.push_back(1.f - v * v);
    cells.fields.push_back(second);
    return buildModel(std::move(cells));
  }();
  return m;
}

Frame smallFrame(int w = 40, int h = 32) {
  const box3i b = model().cellBounds();
  Frame f;
  f.width = w;
  f.height = h;
  f.camera = Camera::frame(box3d(vec3d(b.lower), vec3d(b.upper)), 30, 25, 40, false);
  return f;
}

Scene baseScene() {
  Scene s;
  s.layers[0].field = "scalar";
  s.layers[0].tf.opacity = {{0.f, 0.f}, {0.4f, 0.1f}, {1.f, 0.6f}};
  return s;
}

TriangleMesh floorMesh() {
  const box3i b = model().cellBounds();
  const float z = float(b.lower.z) + 2.f, lo = float(b.lower.x) - 5.f, hi = float(b.upper.x) + 5.f;
  TriangleMesh m;
  m.vertices = {{lo, lo, z}, {hi, lo, z}, {hi, hi, z}, {lo, hi, z}};
  m.triangles = {vec3i(0, 1, 2), vec3i(0, 2, 3)};
  return m;
}

bool identical(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) return false;
  for (size_t i = 0; i < a.pixels.size(); ++i)
    if (!(a.pixels[i] == b.pixels[i])) return false;
  return true;
}

double maxAbsDiff(const Image& a, const Image& b) {
  double d = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i)
    for (float e : {a.pixels[i].x - b.pixels[i].x, a.pixels[i].y - b.pixels[i].y, a.pixels[i].z - b.pixels[i].z,
                    a.pixels[i].w - b.pixels[i].w})
      d = std::max(d, double(std::abs(e)));
  return d;
}

Image freshRender(const Scene& s, const Frame& f) {
  Renderer r(model());
  r.setScene(s);
  return r.render(f);
}

} // namespace

// --- Scene changes --------------------------------------------------------------------------

TEST(Library, EachSceneChangeEqualsAFreshRendererAndRebuildsOnlyWhatItNeeds) {
  const Frame frame = smallFrame();
  struct Change {
    const char* name;
    void (*apply)(Scene&);
    bool volume, iso, meshes;
    bool showsInImage = true;
  };
  const Change changes[] = {
      {"transfer function", [](Scene& s) { s.layers[0].tf.colorMap = builtinColorMap("magma"); }, true, false, false},
      {"opacity",
       [](Scene& s) {
         s.layers[0].tf.opacity = {{0.f, 0.f}, {0.8f, 0.f}, {1.f, 1.f}};
       },
       true, false, false},
      {"value range",
       [](Scene& s) {
         s.layers[0].tf.valueRange = range1f{0.2f, 0.7f};
       },
       true, false, false},
      {"second layer",
       [](Scene& s) {
         s.layers.push_back({"second", defaultTransferFunction("inferno")});
       },
       true, false, false},
      {"iso-values",
       [](Scene& s) {
         s.iso.values = {0.35f, 0.6f};
       },
       false, true, false},
      {"iso colour field", [](Scene& s) { s.iso.colorField = "second"; }, false, true, false},
      {"mesh",
       [](Scene& s) {
         s.meshes.push_back({std::make_shared<TriangleMesh>(floorMesh()), vec3f(0.3f, 0.6f, 0.2f), ""});
       },
       false, false, true},
      {"clip plane",
       [](Scene& s) {
         s.clip.planes = {{vec3d(20.0, 20.0, 20.0), vec3d(1.0, 0.5, 0.0)}};
       },
       false, false, false},
      {"light",
       [](Scene& s) {
         s.light.headlight = false;
         s.light.terms.specular = 0.6f;
       },
       false, false, false},
      {"shading", [](Scene& s) { s.shading = Shading::None; }, false, false, false},
      {"ambient occlusion", [](Scene& s) { s.ao.rays = 3; }, false, false, false},
      // Space skipping is exact: the traversal is rebuilt, the image stays the same.
      {"space skipping", [](Scene& s) { s.integration.spaceSkipping = false; }, true, false, false, false},
  };
  Scene start = baseScene();
  start.iso.values = {0.5f};
  for (const Change& c : changes) {
    SCOPED_TRACE(c.name);
    Renderer r(model());
    r.setScene(start);
    const Image before = r.render(frame);
    Scene changed = start;
    c.apply(changed);
    const SceneUpdate u = r.setScene(changed);
    EXPECT_EQ(u.volume, c.volume);
    EXPECT_EQ(u.iso, c.iso);
    EXPECT_EQ(u.meshes, c.meshes);
    const Image after = r.render(frame);
    EXPECT_TRUE(identical(after, freshRender(changed, frame)));
    EXPECT_EQ(!identical(after, before), c.showsInImage);
    // Setting the same scene again rebuilds nothing.
    const SceneUpdate again = r.setScene(changed);
    EXPECT_FALSE(again.volume || again.iso || again.meshes);
  }
}

TEST(Library, AnInvalidSceneLeavesTheCurrentOneInPlace) {
  Renderer r(model());
  const Scene good = baseScene();
  r.setScene(good);
  const Image before = r.render(smallFrame());
  Scene bad = good;
  bad.layers[0].field = "no-such-field";
  EXPECT_THROW(r.setScene(bad), Error);
  bad = good;
  bad.clip.planes = {{vec3d(0.0), vec3d(0.0)}};
  EXPECT_THROW(r.setScene(bad), Error);
  EXPECT_TRUE(identical(before, r.render(smallFrame())));
}

// --- Progressive passes ---------------------------------------------------------------------

TEST(Library, NPassesEqualOneRenderWithNSamplesForAnyThreadCount) {
  Scene s = baseScene();
  s.iso.values = {0.55f};
  s.ao.rays = 2;
  Frame f = smallFrame(37, 29); // partial tiles at the edges
  f.samplesPerPixel = 5;
  Renderer r(model());
  r.setScene(s);
  const Image whole = r.render(f);
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    FrameBuffer buffer(f.width, f.height);
    Image progressive;
    for (int i = 0; i < f.samplesPerPixel; ++i) {
      Frame pass = f;
      pass.frameIndex = i;
      EXPECT_TRUE(r.renderPass(pass, buffer));
      EXPECT_EQ(buffer.passes(), uint32_t(i + 1));
      buffer.resolve(progressive);
    }
    EXPECT_TRUE(identical(progressive, whole)) << threads << " threads";
    EXPECT_EQ(buffer.stats().rays, uint64_t(f.width * f.height * f.samplesPerPixel));
  }
}

TEST(Library, InterleavedTileSharesAddUpToTheWholePass) {
  Renderer r(model());
  r.setScene(baseScene());
  const Frame f = smallFrame(70, 40);
  FrameBuffer whole(f.width, f.height), shared(f.width, f.height);
  r.renderPass(f, whole);
  for (int share = 0; share < 3; ++share) {
    PassControl c;
    c.tileBegin = share;
    c.tileStride = 3;
    r.renderPass(f, shared, c);
  }
  EXPECT_TRUE(identical(whole.resolve(), shared.resolve()));
  EXPECT_EQ(shared.passes(), 1u);
  EXPECT_EQ(whole.stats().samples, shared.stats().samples);
}

TEST(Library, ACancelledPassAddsOnlyWholeTiles) {
  Renderer r(model());
  r.setScene(baseScene());
  const Frame f = smallFrame(96, 80); // 6 x 5 tiles
  FrameBuffer reference(f.width, f.height);
  r.renderPass(f, reference);
  const Image want = reference.resolve();

  for (int stopAfter : {0, 1, 7}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    std::atomic<bool> cancel{stopAfter == 0};
    PassControl c;
    c.cancel = &cancel;
    c.progress = [&](uint64_t done, uint64_t) {
      if (done >= uint64_t(stopAfter)) cancel = true;
    };
    FrameBuffer buffer(f.width, f.height);
    EXPECT_FALSE(r.renderPass(f, buffer, c));
    const Image got = buffer.resolve();
    int rendered = 0;
    for (int t = 0; t < buffer.tileCount(); ++t) {
      const uint32_t n = buffer.tilePasses(t);
      ASSERT_LE(n, 1u);
      rendered += int(n);
      const int tx = t % buffer.tilesX(), ty = t / buffer.tilesX();
      for (int y = ty * kRenderTile; y < std::min(f.height, (ty + 1) * kRenderTile); ++y)
        for (int x = tx * kRenderTile; x < std::min(f.width, (tx + 1) * kRenderTile); ++x)
          ASSERT_TRUE(got.at(x, y) == (n ? want.at(x, y) : vec4f()));
    }
    EXPECT_EQ(rendered, stopAfter);
    EXPECT_EQ(buffer.stats().tiles, uint64_t(stopAfter));
  }

  // Cancelled from another thread while the pass runs: still whole tiles, in time.
  Frame big = smallFrame(512, 512);
  big.rate = 4.f;
  FrameBuffer buffer(big.width, big.height);
  std::atomic<bool> cancel{false};
  PassControl c;
  c.cancel = &cancel;
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    cancel = true;
  });
  const bool complete = r.renderPass(big, buffer, c);
  stopper.join();
  EXPECT_FALSE(complete);
  uint32_t passes = 0;
  for (int t = 0; t < buffer.tileCount(); ++t)
    passes += buffer.tilePasses(t);
  EXPECT_LT(passes, uint32_t(buffer.tileCount()));
}

TEST(Library, PassesAllocateNothingOnceTheBufferHasItsSize) {
  Scene s = baseScene();
  s.iso.values = {0.5f};
  s.iso.colorField = "second";
  s.meshes.push_back({std::make_shared<TriangleMesh>(floorMesh()), vec3f(0.5f), ""});
  s.ao.rays = 2;
  s.clip.planes = {{vec3d(30.0, 30.0, 30.0), vec3d(1.0, 1.0, 0.0)}};
  for (DebugView debug : {DebugView::None, DebugView::Steps}) {
    s.debug = debug;
    Renderer r(model());
    r.setScene(s);
    Frame f = smallFrame(48, 48);
    f.samplesPerPixel = 4;
    FrameBuffer buffer(f.width, f.height);
    std::atomic<bool> cancel{false};
    uint64_t calls = 0;
    PassControl c;
    c.cancel = &cancel;
    c.progress = [&](uint64_t, uint64_t) { ++calls; };
    r.renderPass(f, buffer, c); // the first pass may warm up thread-local state
    const uint64_t before = gAllocations.load();
    for (int i = 1; i < 4; ++i) {
      f.frameIndex = i;
      r.renderPass(f, buffer, c);
    }
    EXPECT_EQ(gAllocations.load() - before, 0u);
    // The counter sees allocations: a whole render() allocates its buffer and image.
    const uint64_t beforeRender = gAllocations.load();
    r.render(f);
    EXPECT_GT(gAllocations.load() - beforeRender, 0u);
    EXPECT_GT(calls, 0u);
    EXPECT_GT(buffer.stats().samples, 0u);
  }
}

TEST(Library, PreviewFramesAreSmallerAndCheaper) {
  Renderer r(model());
  r.setScene(baseScene());
  const Frame full = smallFrame(128, 96);
  const Frame preview = full.preview(4, 0.5f);
  EXPECT_EQ(preview.width, 32);
  EXPECT_EQ(preview.height, 24);
  RenderStats fs, ps;
  r.render(full, &fs);
  r.render(preview, &ps);
  EXPECT_LT(ps.samples * 20, fs.samples);
  EXPECT_EQ(full.preview(1000, 1.f).width, 1);
}

// --- Dataset-wide values ---------------------------------------------------------------------

TEST(Library, DatasetValuesAreExplicitInputs) {
  const Frame f = smallFrame();
  const Scene s = baseScene();
  const DatasetInfo info = DatasetInfo::of(model());
  Renderer implicit(model()), explicitInfo(model(), info);
  implicit.setScene(s);
  explicitInfo.setScene(s);
  EXPECT_TRUE(identical(implicit.render(f), explicitInfo.render(f)));
  // A renderer given the values of a larger dataset (a wider range, a coarser opacity
  // reference) renders with them, not with what it derives itself.
  DatasetInfo wider = info;
  wider.valueRanges[0] = range1f{info.valueRanges[0].lower - 1.f, info.valueRanges[0].upper + 1.f};
  Renderer widerR(model(), wider);
  widerR.setScene(s);
  Scene explicitRange = s;
  explicitRange.layers[0].tf.valueRange = wider.valueRanges[0];
  EXPECT_TRUE(identical(widerR.render(f), freshRender(explicitRange, f)));
  DatasetInfo scaled = info;
  scaled.defaultOpacityScale = info.defaultOpacityScale * 0.25f;
  Renderer scaledR(model(), scaled);
  scaledR.setScene(s);
  Scene explicitScale = s;
  explicitScale.layers[0].tf.opacityScale = scaled.defaultOpacityScale;
  EXPECT_TRUE(identical(scaledR.render(f), freshRender(explicitScale, f)));
  DatasetInfo broken = info;
  broken.valueRanges.pop_back();
  EXPECT_THROW(Renderer(model(), broken), Error);
}

// --- Scene files ----------------------------------------------------------------------------

TEST(Library, SceneJsonRoundTripsEverySetting) {
  SceneDocument doc;
  doc.input = "data/plt00100";
  Scene& s = doc.scene;
  s.layers = {{"scalar", defaultTransferFunction("inferno")}, {"second", TransferFunction()}};
  s.layers[0].tf.opacity = {{0.f, 0.f}, {0.5f, 0.25f}, {1.f, 1.f}};
  s.layers[0].tf.valueRange = range1f{0.125f, 0.75f};
  s.layers[0].tf.logScale = true;
  s.layers[1].tf.colorMap.name = "custom";
  s.layers[1].tf.colorMap.positions = {0.f, 1.f};
  s.layers[1].tf.colorMap.colors = {vec3f(0.f), vec3f(1.f)};
  s.layers[1].tf.opacityScale = 0.5f;
  s.volume = false;
  s.iso.field = "second";
  s.iso.values = {0.25f, 0.5f};
  s.iso.colors = {vec3f(1.f, 0.f, 0.f)};
  s.iso.colorField = "scalar";
  s.meshes.push_back({std::make_shared<TriangleMesh>(floorMesh()), vec3f(0.25f, 0.5f, 1.f), ""});
  s.clip.planes = {{vec3d(1.0, 2.0, 3.0), vec3d(0.0, 0.0, -1.0)}};
  s.clip.box = box3d(vec3d(-1.0), vec3d(40.0, 41.0, 42.0));
  s.clip.meshes = true;
  s.light.headlight = false;
  s.light.direction = vec3f(1.f, -2.f, 0.5f);
  s.light.terms.specular = 0.5f;
  s.shading = Shading::Central;
  s.ao = {4, 2.5f, true};
  s.integration.sampling = Sampling::Fixed;
  s.integration.autoTraversal = false;
  s.integration.traversal = TraversalKind::Embree;
  s.integration.earlyTermination = false;
  s.integration.spaceSkipping = false;
  s.integration.terminationOpacity = 0.9f;
  s.debug = DebugView::Region;
  s.background = vec3f(0.f, 0.f, 0.f);
  s.keepAlpha = true;
  doc.frame = smallFrame(64, 48);
  doc.frame.samplesPerPixel = 3;
  doc.frame.rate = 2.f;
  doc.frame.seed = 99;
  doc.frame.jitter = false;
  const std::string text = writeSceneJson(doc);
  const SceneDocument back = readSceneJson(text, "scene.json");
  EXPECT_EQ(writeSceneJson(back), text);
  EXPECT_EQ(back.input, doc.input);
  EXPECT_TRUE(back.hasCamera);
  EXPECT_EQ(back.scene.layers, s.layers);
  EXPECT_EQ(back.scene.clip, s.clip);
  EXPECT_EQ(back.scene.integration, s.integration);
  EXPECT_EQ(back.scene.iso.values, s.iso.values);
  EXPECT_EQ(back.scene.meshes.size(), 1u);
  EXPECT_EQ(back.scene.meshes[0].mesh->triangles, s.meshes[0].mesh->triangles);
  EXPECT_EQ(back.frame.camera.position, doc.frame.camera.position);
  EXPECT_EQ(back.frame.seed, 99u);
  // Renders from the read scene equal renders from the original.
  Scene r1 = s, r2 = back.scene;
  r1.debug = r2.debug = DebugView::None;
  r1.volume = r2.volume = true;
  EXPECT_LT(maxAbsDiff(freshRender(r1, doc.frame), freshRender(r2, back.frame)), 1e-6);
}

TEST(Library, SceneFilesWithRendererOptionsStillRead) {
  // Scene files once carried the march's measurement switches; they read with a note and change
  // nothing of the scene.
  testing::internal::CaptureStderr();
  const SceneDocument d = readSceneJson(
      "{\"integration\": {\"vectorized\": false, \"lazy_gradients\": false, \"join_segments\": false}}", "old.json");
  const std::string log = testing::internal::GetCapturedStderr();
  EXPECT_EQ(d.scene.integration, Integration());
  EXPECT_NE(log.find("old.json: \"integration.vectorized\" is ignored"), std::string::npos) << log;
  EXPECT_EQ(writeSceneJson(d).find("vectorized"), std::string::npos);
  // Still checked as what they were.
  EXPECT_THROW(readSceneJson("{\"integration\": {\"vectorized\": 3}}", "old.json"), Error);
}

TEST(Library, SceneJsonErrorsNameTheSourceAndTheKey) {
  auto message = [](const std::string& text) {
    try {
      readSceneJson(text, "view.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("{\"bogus\": 1}").find("view.json: unknown key \"bogus\""), std::string::npos);
  EXPECT_NE(message("{\"light\": {\"ambiant\": 1}}").find("\"light.ambiant\""), std::string::npos);
  EXPECT_NE(message("{\"frame\": {\"width\": \"wide\"}}").find("\"frame.width\" must be a number"), std::string::npos);
  EXPECT_NE(message("{\"frame\": {\"width\": 0}}").find("\"frame.width\" must be an integer in 1..32768, not 0"),
            std::string::npos);
  EXPECT_NE(message("{\"shading\": \"phong\"}").find("choose from"), std::string::npos);
  EXPECT_NE(
      message("{\"layers\": [{\"transfer_function\": {\"colormap\": \"nope\"}}]}").find("layers[0].transfer_function"),
      std::string::npos);
  EXPECT_NE(message("{\"camera\": {\"position\": [1, 1, 1], \"look_at\": [1, 1, 1]}}").find("degenerate camera"),
            std::string::npos);
  EXPECT_NE(message("[1, 2").find("invalid JSON"), std::string::npos);
  // Meshes named by file are read by the io layer, with errors naming the file.
  const SceneDocument named = readSceneJson("{\"meshes\": [{\"file\": \"/no/such/mesh.obj\"}]}", "view.json");
  ASSERT_EQ(named.scene.meshes.size(), 1u);
  EXPECT_FALSE(named.scene.meshes[0].mesh);
  Scene withMesh = named.scene;
  try {
    loadSceneMeshes(withMesh, "view.json");
    ADD_FAILURE() << "a missing mesh file must be an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/no/such/mesh.obj"), std::string::npos);
  }
  // Any subset of keys is a scene; the rest keep their defaults.
  const SceneDocument d = readSceneJson("{\"iso\": {\"values\": [0.5]}}", "view.json");
  EXPECT_EQ(d.scene.iso.values, std::vector<float>{0.5f});
  EXPECT_FALSE(d.hasCamera);
  EXPECT_EQ(d.scene.layers.size(), 1u);
}
