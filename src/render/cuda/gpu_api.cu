// The CUDA back end: device memory, and a pass as one kernel launch with a thread per pixel
// running traceSample (device_trace.h), the per-ray code the portable back end runs on CPU
// threads. The pass's TraceView lives in constant memory (every thread reads the same settings).
#include "gpu_api.h"

#include "exabricks/core/error.h"

#include <cuda_runtime.h>

#include <string>

namespace exa::gpu {
namespace {

__constant__ alignas(16) unsigned char traceViewBytes[sizeof(TraceView)];

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) fail("CUDA: ", what, ": ", cudaGetErrorString(e));
}

// The GPU this process uses, made current on the calling thread (CUDA's current device is per
// host thread, and the renderer is reached from several).
int useDevice() {
  static const int device = [] {
    int count = 0;
    if (cudaGetDeviceCount(&count) != cudaSuccess) {
      cudaGetLastError();
      return 0;
    }
    return cudaDeviceOfProcess(count);
  }();
  cudaSetDevice(device);
  return device;
}

// 64 threads a block and at least 8 blocks an SM: at most 128 registers a thread; 10 blocks (94
// registers, no spills) for the common one-layer smooth volume. Measured on an H100 and an H200,
// fewer registers with spills were slower or no faster.
template <bool Surfaces, bool SmoothOne, bool Path = false>
__global__ void __launch_bounds__(64, (SmoothOne && !Surfaces) ? 10 : 8)
    traceKernel(int tilesX, int tileBegin, int tileEnd, int tileStride, vec4f* colors, PassCounts* counts) {
  const TraceView& v = *reinterpret_cast<const TraceView*>(traceViewBytes);
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x), y = int(blockIdx.y * blockDim.y + threadIdx.y);
  const bool first = threadIdx.x == 0 && threadIdx.y == 0;
  // The block's counts in shared memory, then one atomic per counter and block.
  __shared__ unsigned long long block[5]; // rays, samples, iso samples, occlusion rays, surface hits
  if (first)
    for (int i = 0; i < 5; ++i)
      block[i] = 0;
  __syncthreads();
  if (x < v.frame.width && y < v.frame.height && tileSelected(x, y, tilesX, tileBegin, tileEnd, tileStride)) {
    RayCounts c;
    colors[size_t(y) * size_t(v.frame.width) + size_t(x)] =
        Path ? tracePathSample<Surfaces>(v, x, y, c) : traceSample<Surfaces, SmoothOne>(v, x, y, c);
    atomicAdd(&block[0], 1ull);
    atomicAdd(&block[1], (unsigned long long)c.samples);
    if (c.isoSamples) atomicAdd(&block[2], (unsigned long long)c.isoSamples);
    if (c.aoRays) atomicAdd(&block[3], (unsigned long long)c.aoRays);
    if (c.surfaceHits) atomicAdd(&block[4], (unsigned long long)c.surfaceHits);
  }
  __syncthreads();
  if (first) {
    atomicAdd(&counts->rays, block[0]);
    atomicAdd(&counts->samples, block[1]);
    atomicAdd(&counts->isoSamples, block[2]);
    atomicAdd(&counts->aoRays, block[3]);
    atomicAdd(&counts->surfaceHits, block[4]);
  }
}

__global__ void denoiseVarianceKernel(DenoiseImages im, DenoiseLevel in, const float* first, float* variance) {
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x), y = int(blockIdx.y * blockDim.y + threadIdx.y);
  if (x < im.width && y < im.height)
    variance[size_t(y) * size_t(im.width) + size_t(x)] = denoiseVariance(im, in, first, x, y);
}

__global__ void denoiseLevelKernel(DenoiseImages im, DenoiseLevel in, const float* variance, int step,
                                   DenoiseLevel out) {
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x), y = int(blockIdx.y * blockDim.y + threadIdx.y);
  if (x < im.width && y < im.height) denoiseLevelPixel(im, in, variance, step, x, y, out);
}

/// Device memory released with its owner.
struct DeviceArray {
  void* p = nullptr;
  DeviceArray(uint64_t bytes, const char* what) : p(allocate(bytes, what)) {}
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() { release(p); }
  template <typename T> T* as() const { return static_cast<T*>(p); }
};

} // namespace

CudaStatus status() {
  CudaStatus s;
  s.built = true;
  const cudaError_t e = cudaGetDeviceCount(&s.devices);
  if (e != cudaSuccess || s.devices == 0) {
    s.devices = 0;
    // Say what is missing in words: without a driver the runtime reports an "insufficient"
    // driver version, which reads as if an update would do.
    std::string why;
    if (e == cudaErrorInsufficientDriver)
      why = "no NVIDIA driver was found, or it is older than this build's CUDA runtime needs";
    else if (e == cudaErrorNoDevice || e == cudaSuccess)
      why = "no NVIDIA GPU was found";
    else
      why = cudaGetErrorString(e);
    s.problem = "no usable CUDA GPU (" + why + ")";
    cudaGetLastError();
    return s;
  }
  const int device = useDevice();
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, device) == cudaSuccess) s.name = prop.name;
  if (s.devices > 1) s.name += " (GPU " + std::to_string(device) + " of " + std::to_string(s.devices) + ")";
  size_t freeBytes = 0, totalBytes = 0;
  if (cudaMemGetInfo(&freeBytes, &totalBytes) == cudaSuccess) s.freeBytes = freeBytes, s.totalBytes = totalBytes;
  return s;
}

void* allocate(uint64_t bytes, const char* what) {
  useDevice();
  size_t freeBytes = 0, totalBytes = 0;
  check(cudaMemGetInfo(&freeBytes, &totalBytes), "querying memory");
  if (bytes + (64u << 20) > freeBytes)
    fail("the GPU has ", freeBytes >> 20, " MiB free of ", totalBytes >> 20, " MiB, too little for ", what, " (",
         (bytes + (1u << 20) - 1) >> 20, " MiB)");
  void* p = nullptr;
  check(cudaMalloc(&p, bytes > 0 ? bytes : 1), what);
  return p;
}

void release(void* p) noexcept {
  useDevice();
  if (p) cudaFree(p);
}

void* allocateHost(uint64_t bytes) {
  useDevice();
  void* p = nullptr;
  check(cudaMallocHost(&p, bytes > 0 ? bytes : 1), "page-locked host memory");
  return p;
}

void releaseHost(void* p) noexcept {
  useDevice();
  if (p) cudaFreeHost(p);
}

void copyToDevice(void* device, const void* host, uint64_t bytes) {
  useDevice();
  if (bytes > 0) check(cudaMemcpy(device, host, bytes, cudaMemcpyHostToDevice), "copying to the GPU");
}

void tracePass(const TraceView& view, int tilesX, int tileBegin, int tileEnd, int tileStride, void* deviceColors,
               void* deviceCounts, vec4f* hostColors, PassCounts& counts) {
  useDevice();
  check(cudaMemcpyToSymbol(traceViewBytes, &view, sizeof(TraceView)), "setting the pass");
  check(cudaMemset(deviceCounts, 0, sizeof(PassCounts)), "clearing the counters");
  const dim3 block(8, 8);
  const dim3 grid(unsigned(view.frame.width + 7) / 8, unsigned(view.frame.height + 7) / 8);
  auto* colors = static_cast<vec4f*>(deviceColors);
  auto* passCounts = static_cast<PassCounts*>(deviceCounts);
  cudaEvent_t start, stop;
  check(cudaEventCreate(&start), "timing the pass");
  check(cudaEventCreate(&stop), "timing the pass");
  cudaEventRecord(start);
  const bool surfaces = view.iso || view.meshes || view.particles, smooth = smoothOneLayer(view);
  if (view.pathTrace && surfaces)
    traceKernel<true, false, true><<<grid, block>>>(tilesX, tileBegin, tileEnd, tileStride, colors, passCounts);
  else if (view.pathTrace)
    traceKernel<false, false, true><<<grid, block>>>(tilesX, tileBegin, tileEnd, tileStride, colors, passCounts);
  else if (surfaces && smooth)
    traceKernel<true, true><<<grid, block>>>(tilesX, tileBegin, tileEnd, tileStride, colors, passCounts);
  else if (surfaces)
    traceKernel<true, false><<<grid, block>>>(tilesX, tileBegin, tileEnd, tileStride, colors, passCounts);
  else if (smooth)
    traceKernel<false, true><<<grid, block>>>(tilesX, tileBegin, tileEnd, tileStride, colors, passCounts);
  else
    traceKernel<false, false><<<grid, block>>>(tilesX, tileBegin, tileEnd, tileStride, colors, passCounts);
  cudaEventRecord(stop);
  check(cudaGetLastError(), "launching the pass");
  const size_t pixels = size_t(view.frame.width) * size_t(view.frame.height);
  check(cudaMemcpy(hostColors, deviceColors, pixels * sizeof(vec4f), cudaMemcpyDeviceToHost), "the pass");
  check(cudaMemcpy(&counts, deviceCounts, sizeof(PassCounts), cudaMemcpyDeviceToHost), "the pass's counters");
  float ms = 0.f;
  cudaEventElapsedTime(&ms, start, stop);
  counts.kernelSeconds = 1e-3 * ms;
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
}

void denoiseLevels(const DenoiseImages& images, const DenoiseLevel& level, const float* first, int levels) {
  useDevice();
  const size_t n = size_t(images.width) * size_t(images.height);
  const char* what = "the denoiser's images";
  DeviceArray features(n * kDenoiseFeatures * sizeof(float), what), valid(n, what), unknown(n, what);
  DeviceArray firstVariance(n * sizeof(float), what), variance(n * sizeof(float), what);
  DeviceArray colors(2 * n * sizeof(vec4f), what), probes(2 * n * sizeof(vec3f), what),
      lums(2 * n * sizeof(float), what);
  copyToDevice(features.p, images.features, n * kDenoiseFeatures * sizeof(float));
  copyToDevice(valid.p, images.valid, n);
  copyToDevice(unknown.p, images.unknown, n);
  copyToDevice(firstVariance.p, first, n * sizeof(float));
  copyToDevice(colors.p, level.color, n * sizeof(vec4f));
  copyToDevice(probes.p, level.probe, n * sizeof(vec3f));
  copyToDevice(lums.p, level.lumProbe, n * sizeof(float));
  DenoiseImages im = images;
  im.features = features.as<float>();
  im.valid = valid.as<uint8_t>();
  im.unknown = unknown.as<uint8_t>();
  DenoiseLevel a{colors.as<vec4f>(), probes.as<vec3f>(), lums.as<float>()};
  DenoiseLevel b{a.color + n, a.probe + n, a.lumProbe + n};
  const dim3 block(16, 8);
  const dim3 grid(unsigned(images.width + 15) / 16, unsigned(images.height + 7) / 8);
  for (int l = 0; l < levels; ++l) {
    denoiseVarianceKernel<<<grid, block>>>(im, a, l == 0 ? firstVariance.as<float>() : nullptr, variance.as<float>());
    denoiseLevelKernel<<<grid, block>>>(im, a, variance.as<float>(), 1 << l, b);
    check(cudaGetLastError(), "launching the denoiser");
    const DenoiseLevel t = a;
    a = b;
    b = t;
  }
  check(cudaMemcpy(level.color, a.color, n * sizeof(vec4f), cudaMemcpyDeviceToHost), "the denoised picture");
  check(cudaMemcpy(level.probe, a.probe, n * sizeof(vec3f), cudaMemcpyDeviceToHost), "the denoised picture");
  check(cudaMemcpy(level.lumProbe, a.lumProbe, n * sizeof(float), cudaMemcpyDeviceToHost), "the denoised picture");
}

} // namespace exa::gpu
