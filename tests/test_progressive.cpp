// The progressive view the interactive front ends share: its passes add up to the N-sample
// render of the frame, a change starts them over, a cancelled pass is not counted, and drafts
// are sized to their time budget; the device falls back to the CPU for a scene it cannot draw
// and is tried again with the next.
#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/workflows/progressive.h"

#include <gtest/gtest.h>

#include <atomic>

using namespace exa;

namespace {

SceneDocument documentOf(const Model& m, int spp) {
  SceneDocument doc;
  doc.scene = Scene::volumeOf(defaultTransferFunction("viridis"), m.fieldNames[0]);
  doc.frame.width = 48;
  doc.frame.height = 40;
  doc.frame.samplesPerPixel = spp;
  const box3d b = m.worldBounds();
  doc.frame.camera.lookAt = (b.lower + b.upper) * 0.5;
  doc.frame.camera.position = (b.lower + b.upper) * 0.5 + vec3d(0.3, 0.4, 1.5) * length(b.size());
  return doc;
}

} // namespace

TEST(Progressive, PassesAddUpToTheRenderOfTheFrame) {
  const Model m = buildModel(generateScene({"blobs", 20000, 1, 3}));
  Renderer renderer(m);
  ProgressiveView view(renderer, "cpu");
  const SceneDocument doc = documentOf(m, 4);
  EXPECT_TRUE(view.show(doc));
  int passes = 0;
  while (view.refine(PassControl()))
    ++passes;
  EXPECT_EQ(passes, 4);
  EXPECT_TRUE(view.complete());
  EXPECT_FALSE(view.refine(PassControl())) << "a complete view adds no pass";
  const Image want = renderer.render(doc.frame);
  float alpha = 0.f;
  for (const vec4f& p : want.pixels)
    alpha += p.w;
  ASSERT_GT(alpha / float(want.pixels.size()), 0.05f) << "the view shows the data";
  EXPECT_EQ(view.buffer().resolve().pixels, want.pixels);

  // The same document again keeps the passes; another starts over.
  EXPECT_FALSE(view.show(doc));
  EXPECT_EQ(view.passes(), 4);
  SceneDocument other = doc;
  other.scene.shading = Shading::None;
  EXPECT_TRUE(view.show(other));
  EXPECT_EQ(view.passes(), 0);

  // A cancelled pass is not counted, and the refinement starts over.
  ASSERT_TRUE(view.refine(PassControl()));
  std::atomic<bool> cancel{true};
  PassControl cancelled;
  cancelled.cancel = &cancel;
  EXPECT_FALSE(view.refine(cancelled));
  EXPECT_EQ(view.passes(), 0);
}

TEST(Progressive, DraftsAreSmallerAndSizedToTheirBudget) {
  const Model m = buildModel(generateScene({"blobs", 20000, 1, 3}));
  Renderer renderer(m);
  DraftPolicy policy;
  policy.divisor = 4;
  ProgressiveView view(renderer, "cpu", policy);
  view.show(documentOf(m, 2));
  const Frame draft = view.draftFrame();
  EXPECT_EQ(draft.width, 12);
  EXPECT_EQ(draft.height, 10);
  EXPECT_EQ(draft.samplesPerPixel, 1);
  EXPECT_FLOAT_EQ(draft.rate, 0.5f);
  EXPECT_FALSE(view.draftIsCurrent());
  FrameBuffer buffer;
  ASSERT_TRUE(view.renderDraft(draft, buffer, PassControl()));
  EXPECT_TRUE(view.draftIsCurrent());
  EXPECT_EQ(buffer.width(), 12);

  // Four times the budget's time: half the pixels per axis; a quarter: twice; near it: the same.
  EXPECT_EQ(nextDraftDivisor(4, 1024, 1024, 256.0 * 256.0, 0.4, 0.1, 16), 8);
  EXPECT_EQ(nextDraftDivisor(4, 1024, 1024, 256.0 * 256.0, 0.025, 0.1, 16), 2);
  EXPECT_EQ(nextDraftDivisor(4, 1024, 1024, 256.0 * 256.0, 0.12, 0.1, 16), 4);
  EXPECT_EQ(nextDraftDivisor(4, 1024, 1024, 256.0 * 256.0, 100.0, 0.1, 16), 16);
  EXPECT_EQ(nextDraftDivisor(4, 1024, 1024, 256.0 * 256.0, 1e-6, 0.1, 16), 1);
}

TEST(Progressive, PassesAtOnceAndPastTheTarget) {
  const Model m = buildModel(generateScene({"blobs", 20000, 1, 3}));
  Renderer renderer(m);
  ProgressiveView view(renderer, "cpu");
  const SceneDocument doc = documentOf(m, 3);
  view.show(doc);
  EXPECT_TRUE(view.refineTo(3, PassControl()));
  EXPECT_EQ(view.passes(), 3);
  EXPECT_TRUE(view.complete());
  EXPECT_EQ(view.buffer().resolve().pixels, renderer.render(doc.frame).pixels);
  EXPECT_TRUE(view.refineTo(2, PassControl())) << "a view holding the passes adds none";
  EXPECT_EQ(view.passes(), 3);

  // Past the target: more samples of the same frame, pass k still at frame index k.
  EXPECT_TRUE(view.refineTo(5, PassControl()));
  EXPECT_EQ(view.passes(), 5);
  EXPECT_EQ(view.buffer().passes(), 5u);
  FrameBuffer five(doc.frame.width, doc.frame.height);
  ASSERT_TRUE(renderer.renderPasses(doc.frame, five, 5));
  EXPECT_EQ(view.buffer().resolve().pixels, five.resolve().pixels);

  // A cancel before or within a pass: not counted; the buffer keeps what it held until the
  // next pass starts the refinement over.
  std::atomic<bool> cancel{true};
  PassControl cancelled;
  cancelled.cancel = &cancel;
  EXPECT_FALSE(view.refineTo(6, cancelled));
  EXPECT_EQ(view.passes(), 0);
  EXPECT_EQ(view.buffer().passes(), 5u);
  EXPECT_EQ(view.buffer().resolve().pixels, five.resolve().pixels);
  ASSERT_TRUE(view.refineTo(3, PassControl()));
  EXPECT_EQ(view.buffer().passes(), 3u);
  EXPECT_EQ(view.buffer().resolve().pixels, renderer.render(doc.frame).pixels);
}

TEST(Progressive, SceneAndFrameApartAsTogether) {
  const Model m = buildModel(generateScene({"blobs", 20000, 1, 3}));
  Renderer renderer(m);
  ProgressiveView view(renderer, "cpu");
  SceneDocument doc = documentOf(m, 2);
  EXPECT_TRUE(view.show(doc));
  ASSERT_TRUE(view.refineTo(2, PassControl()));
  EXPECT_FALSE(view.showScene(doc.scene).volume) << "the same scene rebuilds nothing";
  EXPECT_FALSE(view.showFrame(doc.frame));
  EXPECT_EQ(view.passes(), 2);

  // A new scene starts over, and until the next pass the buffer holds the last passes.
  Scene other = doc.scene;
  other.layers[0].tf.colorMap = builtinColorMap("inferno");
  EXPECT_TRUE(view.showScene(other).volume);
  EXPECT_EQ(view.passes(), 0);
  EXPECT_EQ(view.buffer().passes(), 2u);
  ASSERT_TRUE(view.refineTo(2, PassControl()));
  EXPECT_EQ(view.shown().scene.layers[0].tf.colorMap, other.layers[0].tf.colorMap);
  EXPECT_EQ(view.buffer().resolve().pixels, renderer.render(doc.frame).pixels);

  // A new frame starts over; so does another size, with the buffer resized at the next pass.
  Frame moved = doc.frame;
  moved.camera.position.x += 1.0;
  EXPECT_TRUE(view.showFrame(moved));
  EXPECT_FALSE(view.show(SceneDocument{"", other, moved}));
  moved.width = 20;
  EXPECT_TRUE(view.showFrame(moved));
  EXPECT_EQ(view.buffer().width(), 48);
  ASSERT_TRUE(view.refine(PassControl()));
  EXPECT_EQ(view.buffer().width(), 20);
}

TEST(Progressive, MeshesByTheirDataAndTheDepthLimitByItsValues) {
  const Model m = buildModel(generateScene({"blobs", 20000, 1, 3}));
  Renderer renderer(m);
  ProgressiveView view(renderer, "cpu");
  SceneDocument doc = documentOf(m, 1);
  const box3d b = m.worldBounds();
  auto mesh = std::make_shared<TriangleMesh>();
  const vec3f lo(b.lower), hi(b.upper), mid((b.lower + b.upper) * 0.5);
  mesh->vertices = {vec3f(lo.x, lo.y, mid.z), vec3f(hi.x, lo.y, mid.z), vec3f(hi.x, hi.y, mid.z)};
  mesh->triangles = {vec3i(0, 1, 2)};
  doc.scene.meshes.push_back({mesh, vec3f(0.5f), ""});
  EXPECT_TRUE(view.show(doc));
  // An equal copy of the mesh is the same scene; another triangle is not.
  SceneDocument copied = doc;
  copied.scene.meshes[0].mesh = std::make_shared<TriangleMesh>(*mesh);
  EXPECT_FALSE(view.show(copied));
  auto moved = std::make_shared<TriangleMesh>(*mesh);
  moved->vertices[0].x += 1.f;
  copied.scene.meshes[0].mesh = moved;
  EXPECT_TRUE(view.show(copied));

  // The depth limit: the view keeps a copy, and its values (and planarity) are part of the frame.
  std::vector<float> limit(size_t(doc.frame.width) * size_t(doc.frame.height), 1e30f);
  Frame limited = doc.frame;
  limited.depthLimit = limit.data();
  EXPECT_TRUE(view.showFrame(limited));
  std::vector<float> same = limit;
  limited.depthLimit = same.data();
  EXPECT_FALSE(view.showFrame(limited)) << "the same values elsewhere";
  EXPECT_NE(view.shown().frame.depthLimit, same.data());
  same[7] = 0.f;
  EXPECT_TRUE(view.showFrame(limited));
  limited.depthLimitPlanar = true;
  EXPECT_TRUE(view.showFrame(limited));
  same.assign(same.size(), -1.f); // the caller's array may change: the view renders its copy
  ASSERT_TRUE(view.refine(PassControl()));
  same.assign(same.size(), 1e30f);
  same[7] = 0.f;
  Frame want = limited;
  want.depthLimit = same.data();
  EXPECT_EQ(view.buffer().resolve().pixels, renderer.render(want).pixels);
  EXPECT_TRUE(view.showFrame(doc.frame)) << "no limit is another frame";
}

TEST(Progressive, ANamedDeviceFallsBackForAScene) {
  // The portable device runs the GPU's per-ray code on the CPU, with the GPU back end's limits.
  const Model m = buildModel(generateScene({"blobs", 20000, 1, 3}));
  Renderer renderer(m);
  ProgressiveView view(renderer, "portable");
  const SceneDocument doc = documentOf(m, 1);
  EXPECT_TRUE(view.show(doc));
  EXPECT_EQ(renderer.device(), Device::Portable);
  ASSERT_TRUE(view.refine(PassControl()));

  // A scene the device cannot draw: shown on the CPU, and an error says why.
  SceneDocument debug = doc;
  debug.scene.debug = DebugView::Level;
  EXPECT_THROW(view.show(debug), DeviceFallbackError);
  EXPECT_EQ(renderer.device(), Device::Cpu);
  EXPECT_EQ(view.shown().scene.debug, DebugView::Level);
  EXPECT_EQ(view.passes(), 0);
  EXPECT_FALSE(view.show(debug)) << "the same scene stays on the CPU, without another error";
  ASSERT_TRUE(view.refine(PassControl()));
  EXPECT_EQ(view.buffer().resolve().pixels, renderer.render(debug.frame).pixels);

  // The next scene that differs goes back to the device, and its passes start over there.
  EXPECT_TRUE(view.show(doc));
  EXPECT_EQ(renderer.device(), Device::Portable);
  ASSERT_TRUE(view.refine(PassControl()));
  EXPECT_FALSE(view.show(doc));
  EXPECT_EQ(view.passes(), 1);

  // Another choice moves the renderer with the next scene shown, the same scene included.
  view.setDevice("cpu");
  EXPECT_TRUE(view.show(doc)) << "passes on another device start over";
  EXPECT_EQ(renderer.device(), Device::Cpu);
  view.setDevice("portable");
  EXPECT_TRUE(view.show(doc));
  EXPECT_EQ(renderer.device(), Device::Portable);
  view.setDevice("cpu");
  EXPECT_NO_THROW(view.show(debug)) << "the choice applies before the scene";
  EXPECT_EQ(renderer.device(), Device::Cpu);
  EXPECT_THROW(view.setDevice("gpu"), Error);
  EXPECT_EQ(view.device(), "cpu");
}

TEST(Progressive, AutoTriesTheGpuAgainWithALaterScene) {
  if (!cudaStatus().problem.empty()) GTEST_SKIP() << "no GPU: " << cudaStatus().problem;
  const Model m = buildModel(generateScene({"blobs", 20000, 1, 3}));
  Renderer renderer(m);
  ProgressiveView view(renderer, "auto");
  const SceneDocument doc = documentOf(m, 1);
  EXPECT_TRUE(view.show(doc));
  EXPECT_EQ(renderer.device(), Device::Cuda);
  SceneDocument debug = doc;
  debug.scene.debug = DebugView::Level;
  EXPECT_NO_THROW(view.show(debug)) << "auto falls back without an error";
  EXPECT_EQ(renderer.device(), Device::Cpu);
  EXPECT_FALSE(view.show(debug));
  EXPECT_EQ(renderer.device(), Device::Cpu);
  EXPECT_TRUE(view.show(doc));
  EXPECT_EQ(renderer.device(), Device::Cuda) << "a later scene the GPU can draw goes back to it";
  ASSERT_TRUE(view.refine(PassControl()));

  // A first scene the GPU cannot draw starts on the CPU; the next one moves to the GPU.
  Renderer other(m);
  ProgressiveView fresh(other, "auto");
  EXPECT_NO_THROW(fresh.show(debug));
  EXPECT_EQ(other.device(), Device::Cpu);
  EXPECT_TRUE(fresh.show(doc));
  EXPECT_EQ(other.device(), Device::Cuda);
}
