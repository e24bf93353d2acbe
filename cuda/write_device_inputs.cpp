// Writes the inputs of the device check (cuda/device_check.cu): the embedded default dataset's
// first field with its regions and k-d tree, the default transfer function as the marcher's
// table, and the rays of a camera framing the data (in lattice space, where the marcher works).
//   exabricks_write_device_inputs OUT.bin [WIDTH]
#include "device_inputs.h"

#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/transfer_function.h"

#include <cstdio>
#include <cstdlib>

int main(int argc, char** argv) {
  using namespace exa;
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s OUT.bin [WIDTH]\n", argv[0]);
    return 2;
  }
  const int width = argc > 2 ? std::atoi(argv[2]) : 256;
  const Model model = buildModel(defaultDataset());
  const DatasetInfo info = DatasetInfo::of(model);
  const int field = model.requireField("");
  const FieldView view = model.view(field);

  TransferFunction tf = defaultTransferFunction();
  tf.valueRange = info.valueRanges[size_t(field)];
  tf.opacityScale = info.defaultOpacityScale;

  DeviceInputs d;
  d.bricks = model.bricks;
  d.values = model.fieldValues[size_t(field)].toVector();
  d.regions = model.regions.regions;
  d.brickIds = model.regions.brickIds;
  d.nodes = model.regions.nodes;
  for (size_t r = 0; r < d.regions.size(); ++r)
    d.visible.push_back(tf.maxOpacity(model.regions.valueRanges[size_t(field)][r]) > 0.f ? 1 : 0);
  d.table = tabulateTransferFunction(tf);
  DeviceInputsHeader& h = d.header;
  h.bounds = view.bounds;
  h.tfRange = tf.valueRange;
  h.logScale = 0;
  h.fastLinear = 1;
  h.tfLower = tf.valueRange.lower;
  h.tfScale = 1.f / (tf.valueRange.upper - tf.valueRange.lower);
  h.dt = 0.5f;
  h.invReferenceWidth = 1.f / info.referenceWidth;
  h.isoValue = 0.5f * (tf.valueRange.lower + tf.valueRange.upper);
  h.fadeScale = info.referenceWidth / (tf.valueRange.upper - tf.valueRange.lower);

  const box3i cb = model.cellBounds();
  const Camera camera = Camera::frame(box3d(vec3d(cb.lower), vec3d(cb.upper)), 30, 25, 40, false);
  for (int y = 0; y < width; ++y)
    for (int x = 0; x < width; ++x) {
      vec3d org, dir;
      camera.ray((x + 0.5) / width, (y + 0.5) / width, 1.0, org, dir);
      Ray ray;
      ray.org = vec3f(org);
      ray.dir = vec3f(normalize(dir));
      d.rays.push_back(ray);
    }
  d.write(argv[1]);
  std::printf("%s: %zu bricks, %zu regions (%zu visible), %zu rays\n", argv[1], d.bricks.size(), d.regions.size(),
              size_t(std::count(d.visible.begin(), d.visible.end(), 1)), d.rays.size());
  return 0;
}
