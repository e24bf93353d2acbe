// The device back ends' per-ray path (device_trace.h) on CPU threads (Device::Portable) against
// the CPU renderer's batches: the same images within the bound the GPU is held to, for every
// feature; progressive passes and tiles; refusals and device selection.
#include "device_scenes.h"

#include "exabricks/core/error.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace exa {
namespace {

using namespace device_test;

TEST(Device, ThePortablePathDrawsEveryFeatureLikeTheCpu) {
  expectEveryVariantLikeTheCpu(Device::Portable, [](const RenderStats& s) { return s.rays; });
}

TEST(Device, PassesAndTilesAddUpAsOnTheCpu) {
  const Model m = deviceTestModel();
  const DatasetInfo info = DatasetInfo::of(m);
  Scene scene;
  scene.layers[0].tf.valueRange = info.valueRanges[0];
  Frame frame = deviceTestFrame(m, 70, 50);
  frame.samplesPerPixel = 4;
  Renderer cpu(m, info), dev(m, info);
  cpu.setScene(scene);
  dev.setScene(scene);
  dev.setDevice(Device::Portable);
  EXPECT_EQ(dev.device(), Device::Portable);
  // Two passes of every other tile, then two of the rest: the sums of four passes everywhere.
  FrameBuffer a(frame.width, frame.height), b(frame.width, frame.height);
  for (int pass = 0; pass < 4; ++pass) {
    Frame f = frame;
    f.frameIndex = pass;
    PassControl even, odd;
    even.tileStride = odd.tileStride = 2;
    odd.tileBegin = 1;
    ASSERT_TRUE(dev.renderPass(f, a, even));
    ASSERT_TRUE(dev.renderPass(f, a, odd));
    ASSERT_TRUE(cpu.renderPass(f, b));
  }
  const ImageDifference d = difference(a.resolve(), b.resolve());
  EXPECT_TRUE(withinBound(d)) << describe(d);
  EXPECT_EQ(a.stats().rays, uint64_t(4) * uint64_t(frame.width) * uint64_t(frame.height));
  // A cancelled pass adds nothing.
  std::atomic<bool> cancel{true};
  PassControl c;
  c.cancel = &cancel;
  FrameBuffer e(frame.width, frame.height);
  EXPECT_FALSE(dev.renderPasses(frame, e, 2, c));
  EXPECT_EQ(e.passes(), 0u);
}

TEST(Device, RefusesWhatTheDeviceDoesNotDraw) {
  const Model m = deviceTestModel();
  Renderer r(m);
  Scene scene;
  r.setScene(scene);
  r.setDevice(Device::Portable);
  Scene debug = scene;
  debug.debug = DebugView::Level;
  try {
    r.setScene(debug);
    FAIL() << "a debug view was accepted on the device";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("debug views"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(device cpu)"), std::string::npos) << e.what();
  }
  EXPECT_EQ(r.scene().debug, DebugView::None) << "the refused scene replaced the current one";
  Scene cells = scene;
  cells.integration.reconstruction = Reconstruction::CellLocation;
  EXPECT_THROW(r.setScene(cells), Error);
  // On the CPU the scene is drawn; moving it to the device is refused and leaves it on the CPU,
  // and "auto" falls back to the CPU.
  Renderer cpu(m);
  cpu.setScene(debug);
  EXPECT_THROW(cpu.setDevice(Device::Portable), Error);
  EXPECT_EQ(cpu.device(), Device::Cpu);
  EXPECT_EQ(selectDevice(cpu, "auto"), Device::Cpu);
}

TEST(Device, DeviceNamesResolveAndCudaWithoutAGpuSaysWhy) {
  EXPECT_EQ(resolveDevice("cpu"), Device::Cpu);
  EXPECT_EQ(resolveDevice("portable"), Device::Portable);
  EXPECT_THROW(resolveDevice("gpu0"), Error);
  const CudaStatus s = cudaStatus();
  if (s.problem.empty()) {
    EXPECT_EQ(resolveDevice("auto"), Device::Cuda);
    GTEST_SKIP() << "a GPU is present (" << s.name << "): the refusal without one is not testable here";
  }
  EXPECT_EQ(resolveDevice("auto"), Device::Cpu);
  try {
    resolveDevice("cuda");
    FAIL() << "--device cuda accepted without a GPU";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the cuda device cannot be used"), std::string::npos) << e.what();
  }
  const Model m = deviceTestModel();
  Renderer r(m);
  EXPECT_THROW(r.setDevice(Device::Cuda), Error);
  EXPECT_EQ(r.device(), Device::Cpu);
}

TEST(Device, ProcessesOfANodeSplitItsGpus) {
  const char* names[] = {"EXABRICKS_CUDA_DEVICE", "OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "PMI_LOCAL_RANK",
                         "SLURM_LOCALID"};
  std::vector<std::pair<std::string, std::string>> saved;
  for (const char* n : names)
    if (const char* v = std::getenv(n)) saved.emplace_back(n, v);
  for (const char* n : names)
    unsetenv(n);
  EXPECT_EQ(cudaDeviceOfProcess(4), 0); // one process
  setenv("OMPI_COMM_WORLD_LOCAL_RANK", "5", 1);
  EXPECT_EQ(cudaDeviceOfProcess(4), 1); // local rank 5 of a node with 4 GPUs
  EXPECT_EQ(cudaDeviceOfProcess(1), 0);
  EXPECT_EQ(cudaDeviceOfProcess(0), 0);
  unsetenv("OMPI_COMM_WORLD_LOCAL_RANK");
  setenv("SLURM_LOCALID", "2", 1);
  EXPECT_EQ(cudaDeviceOfProcess(2), 0);
  EXPECT_EQ(cudaDeviceOfProcess(3), 2);
  setenv("SLURM_LOCALID", "x", 1); // not a number: ignored
  EXPECT_EQ(cudaDeviceOfProcess(3), 0);
  setenv("EXABRICKS_CUDA_DEVICE", "1", 1); // the user's choice first
  setenv("SLURM_LOCALID", "2", 1);
  EXPECT_EQ(cudaDeviceOfProcess(3), 1);
  for (const char* n : names)
    unsetenv(n);
  for (const auto& [n, v] : saved)
    setenv(n.c_str(), v.c_str(), 1);
}

} // namespace
} // namespace exa
