// Small datasets shared by the property tests: the generator's scenes at several seeds, the
// same data moved to negative and far-apart coordinates, and hand-made corner cases.
#pragma once

#include "exabricks/amr/scenes.h"
#include "reference.h"

#include <string>
#include <vector>

namespace exa::test {

/// Three draws in a fixed order (z, then y, then x, the order the tests' sequences were made
/// in): the order in which a call's arguments are evaluated differs between compilers.
template <typename Dist, typename Rng> vec3d draw3(Dist& d, Rng& rng) {
  const double z = d(rng), y = d(rng), x = d(rng);
  return {x, y, z};
}

struct NamedCells {
  std::string name;
  CellSet cells;
};

/// Moves every cell by `offset` (a multiple of the coarsest width keeps them aligned).
inline CellSet translated(CellSet s, const vec3i& offset) {
  for (Cell& c : s.cells)
    c.lower = c.lower + offset;
  return s;
}

/// Two copies of a scene far apart, the second shifted into negative coordinates.
inline CellSet farApart(const CellSet& s) {
  CellSet out = s;
  const CellSet moved = translated(s, vec3i(-(1 << 20), 1 << 16, -4096));
  out.cells.insert(out.cells.end(), moved.cells.begin(), moved.cells.end());
  for (size_t f = 0; f < out.fields.size(); ++f)
    out.fields[f].values.insert(out.fields[f].values.end(), moved.fields[f].values.begin(),
                                moved.fields[f].values.end());
  return out;
}

inline std::vector<NamedCells> smallDatasets() {
  std::vector<NamedCells> out;
  out.push_back({"blobs", generateScene({"blobs", 3000, 1, 4})});
  out.push_back({"blobs-seed7", generateScene({"blobs", 2000, 7, 3})});
  out.push_back({"shells", generateScene({"shells", 4000, 2, 4})});
  out.push_back({"ramp", generateScene({"ramp", 3000, 3, 4})});
  out.push_back({"ramp-far", farApart(generateScene({"ramp", 800, 5, 3}))});
  out.push_back({"shells-negative", translated(generateScene({"shells", 1500, 4, 3}), vec3i(-64, -128, -8))});
  // One coarse cell beside fine ones: a level jump of three with a hole next to it.
  out.push_back({"jump", makeCells({{{vec3i(0, 0, 0), 3}, 1.f},
                                    {{vec3i(8, 0, 0), 0}, 2.f},
                                    {{vec3i(9, 0, 0), 0}, 3.f},
                                    {{vec3i(8, 1, 0), 0}, 4.f},
                                    {{vec3i(8, 0, 1), 0}, 5.f},
                                    {{vec3i(16, 0, 0), 1}, 6.f}})});
  out.push_back({"single", makeCells({{{vec3i(-4, 4, 12), 2}, 0.5f}})});
  return out;
}

} // namespace exa::test
