// Runs the per-sample headers on the GPU and on the host over the same rays and compares: the
// device colours must equal the host's within float rounding (the device contracts multiply-adds
// into FMAs), and iso-surface crossings must agree. Prints "skipped: ..." without a CUDA device.
//   device_check INPUTS.bin   (written by exabricks_write_device_inputs)
#include "device_inputs.h"

#include <chrono>
#include <cmath>
#include <cstdio>

namespace {

template <typename T> T* toDevice(const std::vector<T>& v) {
  T* p = nullptr;
  if (cudaMalloc(&p, v.size() * sizeof(T) + 1) != cudaSuccess) throw std::runtime_error("cudaMalloc failed");
  cudaMemcpy(p, v.data(), v.size() * sizeof(T), cudaMemcpyHostToDevice);
  return p;
}

} // namespace

int main(int argc, char** argv) {
  using namespace exa;
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s INPUTS.bin\n", argv[0]);
    return 2;
  }
  int devices = 0;
  if (cudaGetDeviceCount(&devices) != cudaSuccess || devices == 0) {
    std::printf("skipped: no CUDA device\n");
    return 0;
  }
  cudaDeviceProp prop{};
  cudaGetDeviceProperties(&prop, 0);
  const DeviceInputs d = DeviceInputs::read(argv[1]);
  const int n = int(d.rays.size());

  const DeviceRayInputs device =
      d.view(toDevice(d.bricks), toDevice(d.values), toDevice(d.regions), toDevice(d.brickIds), toDevice(d.nodes),
             toDevice(d.visible), toDevice(d.table));
  Ray* rays = toDevice(d.rays);
  vec4f* colors = nullptr;
  float* iso = nullptr;
  cudaMalloc(&colors, size_t(n) * sizeof(vec4f));
  cudaMalloc(&iso, size_t(n) * sizeof(float));
  integrateRaysDevice(device, rays, n, colors, iso); // warm-up
  const auto t0 = std::chrono::steady_clock::now();
  const int rc = integrateRaysDevice(device, rays, n, colors, iso);
  const double deviceSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (rc != 0) {
    std::printf("FAIL: kernel error %d (%s)\n", rc, cudaGetErrorString(cudaError_t(rc)));
    return 1;
  }
  std::vector<vec4f> deviceColors(static_cast<size_t>(n));
  std::vector<float> deviceIso(static_cast<size_t>(n));
  cudaMemcpy(deviceColors.data(), colors, size_t(n) * sizeof(vec4f), cudaMemcpyDeviceToHost);
  cudaMemcpy(deviceIso.data(), iso, size_t(n) * sizeof(float), cudaMemcpyDeviceToHost);

  std::vector<vec4f> hostColors(static_cast<size_t>(n));
  std::vector<float> hostIso(static_cast<size_t>(n));
  const auto t1 = std::chrono::steady_clock::now();
  integrateRaysHost(d.hostView(), d.rays.data(), n, hostColors.data(), hostIso.data());
  const double hostSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();

  double maxDiff = 0, sumDiff = 0;
  int isoMismatch = 0, nonEmpty = 0, isoHits = 0;
  for (int i = 0; i < n; ++i) {
    const vec4f a = deviceColors[size_t(i)], b = hostColors[size_t(i)];
    const double diff = std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z), std::abs(a.w - b.w)});
    maxDiff = std::max(maxDiff, diff);
    sumDiff += diff;
    nonEmpty += b.w > 0.f;
    isoHits += hostIso[size_t(i)] >= 0.f;
    const bool bothMiss = deviceIso[size_t(i)] < 0.f && hostIso[size_t(i)] < 0.f;
    if (!bothMiss && !(std::abs(deviceIso[size_t(i)] - hostIso[size_t(i)]) <= 1e-2f)) ++isoMismatch;
  }
  std::printf("device %s: %d rays (%d with colour, %d iso crossings)\n", prop.name, n, nonEmpty, isoHits);
  std::printf("colour difference device vs host: max %.3g, mean %.3g\n", maxDiff, sumDiff / n);
  std::printf("iso crossings that differ by more than 0.01 cell: %d\n", isoMismatch);
  std::printf("time: device %.3f ms, host (one thread) %.1f ms\n", deviceSeconds * 1e3, hostSeconds * 1e3);
  const bool ok = nonEmpty > n / 20 && maxDiff < 1e-3 && isoMismatch <= n / 1000;
  std::printf("%s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}
