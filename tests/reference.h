// Independent truth for the tests: brute-force reconstruction over every input cell, written
// without bricks or regions.
#pragma once

#include "exabricks/amr/cells.h"

#include <cmath>

namespace exa::test {

struct Reference {
  bool valid = false;
  double value = 0;
  vec3d gradient{0.0};
  bool nearKink = false; ///< some contributing cell has the point near a centre or support face
};

/// Sums the hat weights of every cell at p (lattice units), in double precision. Derivatives
/// use the one-sided derivative towards +axis where the hat has a kink, as the library does.
inline Reference bruteForce(const CellSet& set, int field, const vec3d& p, double kinkEps = 0) {
  double sw = 0, swv = 0;
  vec3d dsw(0.0), dswv(0.0);
  bool near = false;
  const std::vector<float>& values = set.fields[size_t(field)].values;
  for (size_t i = 0; i < set.cells.size(); ++i) {
    const Cell& c = set.cells[i];
    const double w = c.width();
    double h[3], dh[3];
    bool inside = true;
    for (int a = 0; a < 3 && inside; ++a) {
      const double d = (p[a] - (c.lower[a] + 0.5 * w)) / w; // signed distance in widths
      if (d < -1 || d >= 1) {
        inside = false;
        break;
      }
      if (std::abs(d) < kinkEps || std::abs(std::abs(d) - 1) < kinkEps) near = true;
      h[a] = 1 - std::abs(d);
      dh[a] = (d >= 0 ? -1.0 : 1.0) / w;
    }
    if (!inside) continue;
    const double wgt = h[0] * h[1] * h[2];
    const vec3d dw(dh[0] * h[1] * h[2], h[0] * dh[1] * h[2], h[0] * h[1] * dh[2]);
    sw += wgt;
    swv += wgt * values[i];
    dsw += dw;
    dswv += dw * double(values[i]);
  }
  Reference r;
  r.nearKink = near;
  if (sw <= 0) return r;
  r.valid = true;
  r.value = swv / sw;
  r.gradient = (dswv * sw - dsw * swv) / (sw * sw);
  return r;
}

/// Cells from a list of (lower, level, value).
inline CellSet makeCells(const std::vector<std::pair<Cell, float>>& list) {
  CellSet s;
  s.fields.push_back({"scalar", {}});
  for (const auto& [c, v] : list) {
    s.cells.push_back(c);
    s.fields[0].values.push_back(v);
  }
  return s;
}

} // namespace exa::test
