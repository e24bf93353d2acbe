// The CUDA back end's entry points, in plain C++ (no CUDA types): built by nvcc from
// cuda/gpu_api.cu where the build has CUDA, else answered by gpu_api_none.cpp ("built without
// CUDA"). Device memory is handed around as opaque pointers.
#pragma once

#include "denoise_filter.h"
#include "device_trace.h"

#include "exabricks/render/renderer.h"

#include <cstdint>

namespace exa::gpu {

/// Whether a GPU can be used, with its name and memory (of the GPU this process uses,
/// cudaDeviceOfProcess).
CudaStatus status();
/// Device memory for `what` (named in the error when the GPU has too little left).
void* allocate(uint64_t bytes, const char* what);
void release(void* p) noexcept;
/// Page-locked host memory (the GPU copies into it at full speed), and its release.
void* allocateHost(uint64_t bytes);
void releaseHost(void* p) noexcept;
void copyToDevice(void* device, const void* host, uint64_t bytes);
/// Counters a pass adds up on the device (RayCounts summed, and the rays).
struct PassCounts {
  unsigned long long rays = 0, samples = 0, isoSamples = 0, aoRays = 0, surfaceHits = 0;
  double kernelSeconds = 0; ///< measured with events around the kernel
};
/// One pass of the selected tiles: traceSample for every pixel into `deviceColors` (width x
/// height vec4f on the device), copied to `hostColors`; waits for the GPU. `deviceCounts` is a
/// PassCounts on the device.
void tracePass(const TraceView& view, int tilesX, int tileBegin, int tileEnd, int tileStride, void* deviceColors,
               void* deviceCounts, vec4f* hostColors, PassCounts& counts);

/// The denoiser's levels (denoise_filter.h) on the GPU, from and back into `level`: host arrays
/// of the images' size, as are the images' own arrays and `first` (the passes' variance
/// estimate). Waits for the GPU.
void denoiseLevels(const DenoiseImages& images, const DenoiseLevel& level, const float* first, int levels);

} // namespace exa::gpu
