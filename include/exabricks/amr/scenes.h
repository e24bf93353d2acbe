// Deterministic synthetic AMR datasets from named analytic scenes, at any size. The same scenes
// feed the tests, the benchmarks and the embedded default dataset.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/particles.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace exa {

struct SceneOptions {
  std::string name = "blobs";    ///< one of sceneNames()
  uint64_t targetCells = 200000; ///< approximate number of cells to produce
  uint64_t seed = 1;
  int levels = 4; ///< number of levels (finest 0 .. coarsest levels-1)
  /// Time series (blobs): the blobs move with time; the refinement follows them as they were at
  /// gridTime (negative: at `time`), so steps between two regrids share one hierarchy.
  double time = 0;
  double gridTime = -1;
  int base = 0; ///< base cells per axis (0: chosen to approach targetCells)
};

struct SceneInfo {
  std::string name;
  std::string description;
};

const std::vector<SceneInfo>& sceneList();

/// Generates the scene; cells are ordered by base cell (z, y, x), then depth first.
CellSet generateScene(const SceneOptions& options);

/// The same cells and values in pieces, in order: each piece holds `slabsPerPiece` z-slabs of
/// base cells (the last fewer) and goes to `consume`, which may take its contents. Memory is one
/// piece's. Returns the number of cells; throws when there are none (after the last piece).
uint64_t generateScenePieces(const SceneOptions& options, int slabsPerPiece,
                             const std::function<void(CellSet&)>& consume);

/// The options with the levels and base resolution generateScene would choose made explicit, so
/// that every step of a series has the same lattice.
SceneOptions resolveSceneSize(const SceneOptions& options);

/// Whether the scene has particles (cosmic: dark matter and stars).
bool sceneHasParticles(const SceneOptions& options);
/// The width of the lattice the resolved options' cells cover, [0, width]^3: base cells of the
/// coarsest level, each 2^(levels - 1) finest cells wide.
double sceneLatticeWidth(const SceneOptions& resolved);
/// The scene's particles, `count` of its main species (cosmic: dark matter following the density,
/// count / 25 stars in its haloes), in the lattice coordinates of the cells generateScene makes
/// for the same options; deterministic for a seed. An error for a scene without particles.
ParticleSet generateSceneParticles(const SceneOptions& options, uint64_t count);

/// The dataset commands use when given no input.
CellSet defaultDataset();
constexpr const char* kDefaultDatasetName = "<default: blobs scene, 200000 cells, seed 1>";
/// The input a scene file records for the default dataset (a scene without an input names none).
constexpr const char* kEmbeddedInput = "<embedded>";

} // namespace exa
