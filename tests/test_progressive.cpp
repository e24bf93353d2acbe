// The progressive view the interactive front ends share: its passes add up to the N-sample
// render of the frame, a change starts them over, a cancelled pass is not counted, and drafts
// are sized to their time budget.
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
