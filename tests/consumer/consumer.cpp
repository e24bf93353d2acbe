// Renders the embedded default dataset through the installed library and checks the image.
#include "exabricks/io/load.h"
#include "exabricks/render/renderer.h"

#include <cstdio>

int main() {
  const exa::Model model = exa::loadModel("", {});
  exa::Renderer renderer(model);
  renderer.setScene(exa::Scene());
  exa::Frame frame;
  frame.width = frame.height = 32;
  const exa::box3i b = model.cellBounds();
  frame.camera = exa::Camera::frame(exa::box3d(exa::vec3d(b.lower), exa::vec3d(b.upper)), 30, 25, 40, false);
  const exa::Image image = renderer.render(frame);
  float alpha = 0.f;
  for (const exa::vec4f& p : image.pixels)
    alpha += p.w;
  std::printf("mean alpha %.3f\n", alpha / float(image.pixels.size()));
  return alpha > 0.f ? 0 : 1;
}
