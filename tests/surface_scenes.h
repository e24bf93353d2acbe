// Scenes, transfer functions, cameras and comparisons shared by the surface tests
// (test_surfaces.cpp, test_depth_limit.cpp).
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/core/mesh.h"
#include "exabricks/render/renderer.h"
#include "render_setup.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace exa::test {

/// Level-0 cells filling [0, n)^3 with value f(cell centre) in one field per function.
template <typename... F> CellSet uniformCells(int n, const std::vector<std::string>& names, F... fs) {
  CellSet s;
  for (const std::string& name : names)
    s.fields.push_back({name, {}});
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        s.cells.push_back({vec3i(x, y, z), 0});
        const vec3d c(x + 0.5, y + 0.5, z + 0.5);
        size_t i = 0;
        ((s.fields[i++].values.push_back(float(fs(c)))), ...);
      }
  return s;
}

/// Two levels over [0, 64)^3: finest cells where a 2^3 block's centre lies within `fineRadius`
/// of `centre`, cells of width 2 elsewhere; value = distance of the cell centre from `centre`.
inline CellSet radialTwoLevels(const vec3d& centre, double fineRadius) {
  CellSet s;
  s.fields.push_back({"radius", {}});
  s.fields.push_back({"x", {}});
  for (int z = 0; z < 64; z += 2)
    for (int y = 0; y < 64; y += 2)
      for (int x = 0; x < 64; x += 2) {
        const vec3d bc(x + 1.0, y + 1.0, z + 1.0);
        if (length(bc - centre) < fineRadius) {
          for (int k = 0; k < 8; ++k) {
            const vec3i lo(x + (k & 1), y + ((k >> 1) & 1), z + (k >> 2));
            const vec3d c = vec3d(lo) + vec3d(0.5);
            s.cells.push_back({lo, 0});
            s.fields[0].values.push_back(float(length(c - centre)));
            s.fields[1].values.push_back(float(c.x));
          }
        } else {
          s.cells.push_back({vec3i(x, y, z), 1});
          s.fields[0].values.push_back(float(length(bc - centre)));
          s.fields[1].values.push_back(float(bc.x));
        }
      }
  return s;
}

inline TransferFunction grayRamp(float lo, float hi, float alpha) {
  TransferFunction tf;
  tf.colorMap = builtinColorMap("grayscale");
  tf.opacity = {{0.f, alpha}, {1.f, alpha}};
  tf.valueRange = range1f{lo, hi};
  return tf;
}

/// A transfer function that shows nothing (surfaces only).
inline TransferFunction invisible() { return grayRamp(0.f, 1.f, 0.f); }

/// Orthographic camera looking along `dir` at `target`, `height` world units tall.
inline Camera ortho(const vec3d& target, const vec3d& dir, const vec3d& up, double height) {
  Camera c;
  c.orthographic = true;
  c.position = target - dir * 200.0;
  c.lookAt = target;
  c.up = up;
  c.orthoHeight = height;
  return c;
}

/// A quad (two triangles) with corners a, b, c, d in order.
inline TriangleMesh quad(const vec3f& a, const vec3f& b, const vec3f& c, const vec3f& d) {
  TriangleMesh m;
  m.vertices = {a, b, c, d};
  m.triangles = {vec3i(0, 1, 2), vec3i(0, 2, 3)};
  return m;
}

inline double maxAbsDiff(const Image& a, const Image& b) {
  double m = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    m = std::max<double>(m, std::abs(a.pixels[i].x - b.pixels[i].x));
    m = std::max<double>(m, std::abs(a.pixels[i].y - b.pixels[i].y));
    m = std::max<double>(m, std::abs(a.pixels[i].z - b.pixels[i].z));
    m = std::max<double>(m, std::abs(a.pixels[i].w - b.pixels[i].w));
  }
  return m;
}

inline RenderSetup surfaceOptions(int size) {
  RenderSetup o;
  o.frame.width = o.frame.height = size;
  o.scene.integration.earlyTermination = false;
  o.frame.jitter = false;
  return o;
}

} // namespace exa::test
