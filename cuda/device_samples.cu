// The per-sample headers compiled for the GPU: basis reconstruction, the k-d region walk,
// transfer-function lookup, opacity correction, shading, compositing and the iso root search,
// in one kernel that integrates rays through a model's regions. It checks that those headers
// stay device-ready (no exceptions, allocation, virtual calls or host-only tables) and, where a
// GPU is present, that a device ray equals the same code run on the host.
#include "exabricks/accel/traversal.h"
#include "exabricks/amr/basis.h"
#include "exabricks/core/random.h"
#include "exabricks/render/sample_math.h"

#include "device_samples.h"

namespace exa {

/// One ray's premultiplied colour: fixed steps of `dt` through the visible regions, shaded
/// with the analytic gradient, plus the nearest crossing of `isoValue` (or -1).
EXA_HOST_DEVICE inline vec4f integrateRay(const DeviceRayInputs& in, const Ray& ray, float& isoT) {
  vec4f acc;
  isoT = -1.f;
  const vec3f light = ray.dir, halfVector = ray.dir;
  walkRegionTree(in.tree, ray, [&](const Segment& seg) {
    for (float t = seg.t0 + 0.5f * in.dt; t < seg.t1; t += in.dt) {
      const vec3f p = ray.org + ray.dir * t;
      float v;
      vec3f g;
      if (!sampleRegion(in.field, seg.region, p, v, &g)) continue;
      const vec4f rgba = tfLookup(in.table, v);
      if (rgba.w >= 0.f) continue;
      const vec3f c = shadeVolumeSample(rgba.rgb(), g, light, halfVector, in.shading, in.fadeScale);
      compositeBehind(acc, c, correctedOpacity(rgba.w, in.dt, in.invReferenceWidth));
      if (isoT < 0.f) {
        float vn;
        const float tn = t + in.dt;
        if (sampleRegion(in.field, seg.region, ray.org + ray.dir * tn, vn) &&
            (v >= in.isoValue) != (vn >= in.isoValue)) {
          auto value = [&](float tt, float& out) {
            return sampleRegion(in.field, seg.region, ray.org + ray.dir * tt, out);
          };
          isoT = refineCrossing(value, t, tn, v, vn, in.isoValue, v >= in.isoValue, 1e-3f);
        }
      }
    }
    return true;
  });
  return acc;
}

__global__ void integrateRaysKernel(DeviceRayInputs in, const Ray* rays, int count, vec4f* colors, float* isoT) {
  const int i = int(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count) return;
  PixelRandom rng(i, 0, 0, 1);
  (void)rng.next();
  colors[i] = integrateRay(in, rays[i], isoT[i]);
}

void integrateRaysHost(const DeviceRayInputs& in, const Ray* rays, int count, vec4f* colors, float* isoT) {
  for (int i = 0; i < count; ++i)
    colors[i] = integrateRay(in, rays[i], isoT[i]);
}

} // namespace exa

namespace exa {

int integrateRaysDevice(const DeviceRayInputs& in, const Ray* rays, int count, vec4f* colors, float* isoT) {
  const int block = 128;
  integrateRaysKernel<<<(count + block - 1) / block, block>>>(in, rays, count, colors, isoT);
  return int(cudaDeviceSynchronize());
}

} // namespace exa
