// The CUDA back end against the CPU renderer, on a GPU (ctest label gpu): every feature within
// the bound of device_scenes.h, N passes against N passes, what setScene copies, device memory.
// Each test skips, saying why, where no GPU can be used.
#include "device_scenes.h"
#include "lit_ball.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/render/denoise.h"

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

// The denoiser's levels as CUDA kernels against the CPU's threads: the same per-pixel code on the
// same path-traced passes and guide gives the same picture and the same tile noise, and a frame
// drawn on the GPU is filtered there.
TEST(Gpu, TheDenoiserEqualsTheCpus) {
  REQUIRE_GPU();
  test::LitBall ball;
  ball.frame.width = 1024;
  ball.frame.height = 768;
  Renderer r(ball.model, DatasetInfo::of(ball.model));
  r.setScene(ball.scene);
  DenoiseGuide guide = renderDenoiseGuide(r, ball.frame);
  EXPECT_EQ(guide.device, Device::Cpu);
  FrameBuffer buffer(ball.frame.width, ball.frame.height);
  ASSERT_TRUE(r.renderPasses(ball.frame, buffer, 6));
  std::vector<float> cpuNoise, gpuNoise;
  Timer timer;
  const Image cpu = denoise(buffer, guide, ball.scene.background, &cpuNoise);
  const double cpuSeconds = timer.seconds();
  guide.device = Device::Cuda;
  denoise(buffer, guide, ball.scene.background); // the first call starts the GPU
  timer.reset();
  const Image gpu = denoise(buffer, guide, ball.scene.background, &gpuNoise);
  std::printf("denoise 1024x768 with its tile noise: CPU threads %.1f ms, GPU %.1f ms\n", 1e3 * cpuSeconds,
              1e3 * timer.seconds());
  const ImageDifference d = difference(gpu, cpu);
  std::printf("denoised on the GPU against the CPU: %s\n", describe(d).c_str());
  EXPECT_TRUE(withinBound(d)) << describe(d);
  EXPECT_NE(cpu.pixels, buffer.resolve().pixels);
  ASSERT_EQ(gpuNoise.size(), cpuNoise.size());
  for (size_t t = 0; t < cpuNoise.size(); ++t)
    EXPECT_NEAR(gpuNoise[t], cpuNoise[t], 1e-3f * std::max(1.f, cpuNoise[t])) << "tile " << t;
  r.setDevice(Device::Cuda);
  EXPECT_EQ(renderDenoiseGuide(r, ball.frame).device, Device::Cuda);
}

} // namespace
} // namespace exa
