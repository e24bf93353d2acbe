// The CUDA back end against the CPU renderer, on a GPU (ctest label gpu): every feature within
// the bound of device_scenes.h, N passes against N passes, what setScene copies, device memory.
// Each test skips, saying why, where no GPU can be used.
#include "device_scenes.h"

#include "exabricks/core/error.h"

#include <gtest/gtest.h>

#include <cstdio>

namespace exa {
namespace {

using namespace device_test;

// Skips the calling test where no GPU can be used.
#define REQUIRE_GPU()                                                                                                  \
  do {                                                                                                                 \
    const CudaStatus status = cudaStatus();                                                                            \
    if (!status.problem.empty()) GTEST_SKIP() << "skipped: " << status.problem;                                        \
  } while (false)

TEST(Gpu, EveryFeatureEqualsTheCpu) {
  REQUIRE_GPU();
  expectEveryVariantLikeTheCpu(Device::Cuda, [](const RenderStats& s) { return s.samples + s.isoSamples; });
}

TEST(Gpu, PassesEqualTheCpuPasses) {
  REQUIRE_GPU();
  const Model m = deviceTestModel();
  const DatasetInfo info = DatasetInfo::of(m);
  Scene scene;
  scene.layers[0].tf.valueRange = info.valueRanges[0];
  Frame frame = deviceTestFrame(m, 200, 150);
  Renderer cpu(m, info), gpu(m, info);
  cpu.setScene(scene);
  gpu.setScene(scene);
  gpu.setDevice(Device::Cuda);
  FrameBuffer a(frame.width, frame.height), b(frame.width, frame.height);
  for (int passes : {1, 4, 8}) {
    ASSERT_TRUE(gpu.renderPasses(frame, a, passes));
    ASSERT_TRUE(cpu.renderPasses(frame, b, passes));
    const ImageDifference d = difference(a.resolve(), b.resolve());
    std::printf("%d passes: %s\n", passes, describe(d).c_str());
    EXPECT_TRUE(withinBound(d)) << passes << " passes: " << describe(d);
  }
}

TEST(Gpu, ASceneChangeCopiesOnlyWhatChanged) {
  REQUIRE_GPU();
  const Model m = deviceTestModel();
  const DatasetInfo info = DatasetInfo::of(m);
  Renderer r(m, info);
  r.setDevice(Device::Cuda);
  Scene scene;
  const SceneUpdate first = r.setScene(scene);
  const DeviceMemory memory = r.deviceMemory();
  for (const auto& [name, bytes] : memory.structures)
    std::printf("  %-32s %10llu bytes\n", name.c_str(), (unsigned long long)bytes);
  EXPECT_GT(first.deviceBytes, m.fieldValues[0].size() * sizeof(float));
  scene.layers[0].tf.opacityScale = 0.5f;
  const SceneUpdate tf = r.setScene(scene);
  std::printf("first scene: %llu bytes in %.3f s; transfer-function change: %llu bytes\n",
              (unsigned long long)first.deviceBytes, first.deviceSeconds, (unsigned long long)tf.deviceBytes);
  EXPECT_GT(tf.deviceBytes, 0u);
  EXPECT_LT(tf.deviceBytes, first.deviceBytes / 4);
  const SceneUpdate same = r.setScene(scene);
  EXPECT_EQ(same.deviceBytes, 0u);
  scene.iso.values = {info.valueRanges[0].lower + 0.5f * (info.valueRanges[0].upper - info.valueRanges[0].lower)};
  const SceneUpdate iso = r.setScene(scene);
  EXPECT_LT(iso.deviceBytes, first.deviceBytes / 4);
  EXPECT_GT(r.deviceMemory().total(), memory.total() / 2);
}

} // namespace
} // namespace exa
