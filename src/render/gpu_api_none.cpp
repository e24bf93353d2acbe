// The CUDA entry points of a build without CUDA: the status says so, and nothing else is reached
// (Renderer::setDevice refuses Device::Cuda first).
#include "gpu_api.h"

#include "exabricks/core/error.h"

namespace exa::gpu {

CudaStatus status() {
  CudaStatus s;
  s.problem = "this exabricks was built without CUDA (configure with -DEXABRICKS_CUDA=ON where nvcc is installed)";
  return s;
}

void* allocate(uint64_t, const char*) { fail("this exabricks was built without CUDA"); }
void release(void*) noexcept {}
void* allocateHost(uint64_t) { fail("this exabricks was built without CUDA"); }
void releaseHost(void*) noexcept {}
void copyToDevice(void*, const void*, uint64_t) { fail("this exabricks was built without CUDA"); }
void tracePass(const TraceView&, int, int, int, int, void*, void*, vec4f*, PassCounts&) {
  fail("this exabricks was built without CUDA");
}

void denoiseLevels(const DenoiseImages&, const DenoiseLevel&, const float*, int) {
  fail("this exabricks was built without CUDA");
}

} // namespace exa::gpu
