// A path-traced test scene and the noise measure of path-traced tests: a ball of scattering
// medium lit by the sun, and the RMS difference of two pictures in 8-bit sRGB steps.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/core/color.h"
#include "exabricks/core/image.h"
#include "exabricks/render/scene.h"
#include "exabricks/render/transfer_function.h"

#include <algorithm>
#include <cmath>

namespace exa::test {

/// A ball of scattering medium lit by the sun, seen from the side: noisy where it is, empty
/// around it.
struct LitBall {
  Model model;
  Scene scene;
  Frame frame;
  LitBall() {
    CellSet cells;
    cells.fields.push_back({"d", {}});
    for (int z = 0; z < 32; ++z)
      for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
          cells.cells.push_back({vec3i(x, y, z), 0});
          const vec3f d = vec3f(float(x), float(y), float(z)) + vec3f(0.5f) - vec3f(16.f);
          cells.fields[0].values.push_back(std::max(0.f, 1.f - length(d) / 10.f));
        }
    model = buildModel(std::move(cells));
    TransferFunction tf;
    tf.colorMap.positions = {0.f, 1.f};
    tf.colorMap.colors = {vec3f(1.f), vec3f(0.9f, 0.6f, 0.3f)};
    tf.opacity = {{0.f, 0.f}, {1.f, 0.2f}};
    tf.valueRange = range1f{0.f, 1.f};
    scene = Scene::volumeOf(tf, "d");
    scene.shading = Shading::None;
    scene.integration.integrator = Integrator::PathTrace;
    scene.pathTracing.albedo = 0.8f;
    scene.pathTracing.bounces = 4;
    scene.pathTracing.sunDirection = vec3f(-1.f, -1.f, -0.5f);
    scene.pathTracing.sunIntensity = 3.f;
    scene.pathTracing.environment = vec3f(0.1f);
    frame.width = frame.height = 64;
    frame.camera.position = vec3d(16.0, 16.0, 90.0);
    frame.camera.lookAt = vec3d(16.0);
    frame.camera.up = vec3d(0.0, 1.0, 0.0);
    frame.camera.fovy = 30.f;
  }
};

/// The RMS difference of two images' 8-bit sRGB colours over black, in 1/255 steps.
inline double rmsSteps(const Image& a, const Image& b) {
  double sum = 0;
  for (size_t p = 0; p < a.pixels.size(); ++p) {
    const vec3f x = linearToSrgb(a.pixels[p].rgb()), y = linearToSrgb(b.pixels[p].rgb());
    for (float d : {x.x - y.x, x.y - y.y, x.z - y.z})
      sum += double(d * 255.f) * double(d * 255.f);
  }
  return std::sqrt(sum / double(3 * a.pixels.size()));
}

} // namespace exa::test
