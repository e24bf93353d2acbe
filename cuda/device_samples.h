// Inputs of the device check: views of one field, its region tree and a transfer-function
// table, all in memory the device can read.
#pragma once

#include "exabricks/accel/traversal.h"
#include "exabricks/amr/basis.h"
#include "exabricks/render/sample_math.h"

namespace exa {

struct DeviceRayInputs {
  FieldView field;
  RegionTreeView tree;
  TfTableView table;
  ShadingTerms shading;
  float dt = 0.5f;
  float invReferenceWidth = 1.f;
  float isoValue = 0.5f;
  float fadeScale = 1.f; ///< cell width / value range, for the shading weight
};

/// The same rays on the host, for comparison.
void integrateRaysHost(const DeviceRayInputs& in, const Ray* rays, int count, vec4f* colors, float* isoT);

} // namespace exa

namespace exa {

/// The same rays on the device: `in` and the arrays point to device memory; launches the kernel
/// and waits for it. Returns the CUDA error code (0 for success).
int integrateRaysDevice(const DeviceRayInputs& in, const Ray* rays, int count, vec4f* colors, float* isoT);

} // namespace exa
