// Structure without values: a patch-based input (AMReX, Chombo, Enzo, VTK overlapping AMR) gives
// its boxes from metadata alone and reads one box's values on demand. A model is built from the
// boxes directly: the cells of each box that no finer box covers become bricks, and each box's
// values are read once into brick order, so no cell record is ever made.
#pragma once

#include "exabricks/amr/model.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace exa {
namespace io {

/// A box of cells of one width. `lower` is in finest-lattice units, `cells` counts cells per
/// axis (so the box spans [lower, lower + cells * width) on the lattice).
struct Patch {
  vec3l lower;
  vec3l cells;
  int64_t width = 1;
  vec3l upper() const { return lower + cells * width; }
  /// Cells of the patch; readers bound `cells` (checkPatchCells) before anything uses this.
  int64_t cellCount() const { return cells.x * cells.y * cells.z; }
};

} // namespace io

/// An input's patches and how to read their values.
struct PatchSource {
  std::string input; ///< the input's path, for messages
  /// Every patch of the levels read, on the finest lattice; a cell is a leaf unless a patch of the
  /// next finer width covers it. The readers have bounded every patch by the bytes of its data.
  std::vector<io::Patch> patches;
  std::vector<std::string> fieldNames; ///< the fields read, in the order asked for
  std::vector<std::string> fieldUnits; ///< per field, empty where unknown
  WorldTransform world;
  SimulationState simulation;
  /// Per patch, 1 where another process holds it (its values are not here): it covers coarser
  /// cells but gives no cells of its own. Empty: every patch is held here.
  std::vector<uint8_t> elsewhere;
  /// Describes patch i in messages: "PATH: level 2 box 7".
  std::function<std::string(size_t)> name;
  /// Reads the values of patch i: one array per field (x fastest, one value per cell of the
  /// patch), replacing what `values` held. Errors name the file and the record.
  std::function<void(size_t, std::vector<std::vector<float>>& values)> read;
  /// Whether `read` may run on several threads at once (a reader of plain files), or only on one
  /// at a time (HDF5).
  bool concurrentReads = false;

  bool heldElsewhere(size_t i) const { return i < elsewhere.size() && elsewhere[i]; }
};

/// Which cells a build from patches keeps. Each rule tests a cell's lattice interval along each
/// axis alone, so the cells of a box that it keeps form a box too.
struct PatchKeep {
  enum class Rule {
    All,         ///< every leaf cell
    Overlapping, ///< cells that overlap `box` (LoadOptions::box)
    Reaching,    ///< cells whose basis support reaches into `box` (a part and its halo)
  };
  Rule rule = Rule::All;
  box3l box;
  /// Whether a cell of width `width` at `lower` along one axis is kept.
  bool along(int axis, int64_t lower, int64_t width) const;
};

/// Builds the model of the patches' leaf cells that `keep` keeps: bricks of at most
/// options.bricks.maxBrickWidth cells per axis cut from each patch less its covered parts, each
/// patch's values read once (only of patches holding kept cells) straight into brick order, then
/// the regions. Equal, cell for cell and value for value, to building the cells a read of the same
/// patches returns. Throws naming both patches where the leaves of two overlap (boxes of one level
/// that overlap, or a level not nested in the next coarser), and none when no cell is kept.
Model buildModelOfPatches(const PatchSource& source, const PatchKeep& keep = {}, const BuildOptions& options = {});

/// The largest factor (a power of two, at most `most`) by which the patches' cells can be merged
/// in blocks of factor^3 that never straddle two patches: every patch's corner and extent are
/// whole multiples of the merged width. 1 when none can.
int64_t alignedMerge(const std::vector<io::Patch>& patches, int64_t most);

/// The patches with their cells merged in blocks of factor^3 (alignedMerge's factor at most):
/// each merged cell holds the mean of its cells, as a level coarser than the patches' own would.
/// For a first picture drawn before the cells themselves.
PatchSource mergedPatches(const PatchSource& source, int64_t factor);

} // namespace exa
