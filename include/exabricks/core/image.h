// Images: linear-RGB, premultiplied-alpha float pixels, row 0 at the top. Reading and writing
// files is in documents/image.h.
#pragma once

#include "exabricks/core/color.h"

#include <vector>

namespace exa {

struct Image {
  int width = 0, height = 0;
  std::vector<vec4f> pixels; ///< width * height, row-major, row 0 at the top

  Image() = default;
  Image(int w, int h) : width(w), height(h), pixels(size_t(w) * size_t(h)) {}
  vec4f& at(int x, int y) { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
  const vec4f& at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

} // namespace exa
